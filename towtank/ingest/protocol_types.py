"""The protocol's types: the frozen dataclasses a validated protocol is made of.

This module is the leaf of the configuration: it holds only types (and
:func:`channel_map`, the complete channel mapping), no parsing and no file reading. The section
parsers (:mod:`towtank.ingest.sections`, :mod:`towtank.ingest.protocol`) build these objects
from the TOML file; the readers of run files, speed logs and zeros files
(:mod:`towtank.ingest.runfile`, :mod:`towtank.ingest.speedlog`,
:mod:`towtank.ingest.zerofile`) take them. Every name is also importable from
:mod:`towtank.ingest.protocol`, where it has always been.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from towtank.ingest.readers import ReadOptions
from towtank.ingest.schema import (  # noqa: F401 - CAPTIVE_CHANNELS: the readers take it here
    CANONICAL_CHANNELS,
    CAPTIVE_CHANNELS,
    Processing,
    ReportOptions,
    WatchOptions,
)
from towtank.ingest.sheetlayout import SheetOptions
from towtank.reference.air import DEFAULT_RELATIVE_HUMIDITY_PCT, STANDARD_PRESSURE_PA

__all__ = ["Balance", "Campaign", "Captive", "ChannelMap", "Fin", "Model", "Myring", "Protocol",
           "Prototype", "SpeedLog", "TareSource", "Water", "ZeroFile", "channel_map"]


@dataclass(frozen=True)
class TareSource:
    """Where the mounting's force comes from (``[tare]``, docs/formats.md).

    ``sting``: the sheet's sting runs (default); ``table``: a table of tare drag (and lift)
    against speed measured once (``speeds_m_s`` [m/s], ``drag_N``, ``lift_N`` [N]); ``none``:
    nothing is subtracted.
    """

    source: str = "sting"
    table: str = ""
    speeds_m_s: tuple[float, ...] = ()
    drag_N: tuple[float, ...] = ()
    lift_N: tuple[float, ...] = ()


@dataclass(frozen=True)
class Balance:
    """A multi-component dynamometer's calibration: outputs = matrix · inputs (docs/formats.md).

    Parameters
    ----------
    inputs : tuple of str
        Raw columns (e.g. bridge voltages [V]).
    outputs : tuple of str
        Canonical force channels they give (``drag``, ``lift``).
    matrix : tuple of tuples of float
        len(outputs) × len(inputs) interaction matrix [output unit per input unit], cross-talk
        terms included.
    """

    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    matrix: tuple[tuple[float, ...], ...]


@dataclass(frozen=True)
class SpeedLog:
    """The protocol's ``[speed_log]`` (docs/formats.md).

    Parameters
    ----------
    file : str
        Name pattern of the log relative to the data folder; ``{stem}`` (the run file's name
        without extensions), ``{name}`` (its name), ``{dir}`` (its folder in the data folder)
        and ``{run}`` (the run number, ``{run:03d}`` for 001) are filled in.
    time : tuple or None
        (column, gain, offset) of the log's time [s after gain·(raw − offset)]; None: the
        log's own timing (LabVIEW waveform timing, LVM's ``X_Value``, a rate the file states
        or writes in an HDF5 group's name, as a run file's: one file per channel).
    speed : tuple or None
        (column, gain, offset) of the carriage speed [m/s].
    position : tuple or None
        (column, gain, offset) of the carriage position [m] (speed by eq. 3).
    offset_s : float
        Log time + ``offset_s`` = run-file time [s] (eq. 1).
    """

    file: str
    time: tuple[str, float, float] | None
    speed: tuple[str, float, float] | None = None
    position: tuple[str, float, float] | None = None
    offset_s: float = 0.0


@dataclass(frozen=True)
class ZeroFile:
    """The protocol's ``[zeros]``: ``file`` is the name pattern of each run's zeros file,
    relative to the data folder, with ``{stem}``, ``{name}``, ``{dir}`` and ``{run}`` as in
    ``[speed_log]``."""

    file: str


@dataclass(frozen=True)
class ChannelMap:
    """How a canonical channel is found in a run file: value = gain·(raw − offset), where raw
    is the column, or the sum of ``columns`` (a balance with several load cells per force)."""

    column: str
    gain: float = 1.0
    offset: float = 0.0
    columns: tuple[str, ...] = ()
    #: True when [channels] states a gain or an offset (even ``gain = 1.0``): a column in volts
    #: is then taken as calibrated (N per V as given), not refused. Set by the parser from the
    #: keys present; not a protocol key (the [channels] schema does not accept it).
    calibrated: bool = False
    #: The unit the column is recorded in (``unit`` in [channels]): it replaces any unit the
    #: file states and silences the day's note on channels without a unit. Without a gain the
    #: values are converted from it to SI; with a gain it is the raw unit (the gain gives SI).
    unit: str = ""


@dataclass(frozen=True)
class Campaign:
    name: str
    run_sheet: Path
    data_dir: Path
    output_dir: Path
    reference: str = "remus"
    test_date: str | None = None
    #: False for a protocol whose ``[captive] means`` table stands in for the runs and that
    #: leaves out run_sheet and data_dir: both are then the table's path (so that no output
    #: replaces it), and there is no run sheet to read.
    sheet_given: bool = True


#: The run sheet's captive tests (docs/formats.md, "Captive manoeuvring tests"): static drift,
#: rudder angle, rotating arm, pure sway, pure yaw and yaw with drift.
CAPTIVE_TESTS = ("drift", "rudder", "arm", "sway", "yaw", "yaw_drift")
#: The captive tests on the planar motion mechanism (their runs record sway, and yaw).
PMM_TESTS = ("sway", "yaw", "yaw_drift")
#: ``[captive] means_columns``' canonical names: the means table's columns towtank reads.
MEANS_COLUMNS = ("run", "drift_deg", "rudder_deg", "radius_m", "speed", "fx", "fy", "mz")
#: ``[captive] moment_ref``: the derivatives refer to the origin O (moments transferred from
#: balance_x_m), or to the balance's own moment point.
MOMENT_REFS = ("origin", "balance")


@dataclass(frozen=True)
class Captive:
    """The protocol's ``[captive]`` (docs/formats.md, "Captive manoeuvring tests").

    Parameters
    ----------
    moment_ref : str
        ``"origin"``: moments transferred to O; ``"balance"``: kept about the balance point
        (recorded in the provenance).
    means : Path or None
        A table of static-test means as a lab delivers them, instead of run files.
    means_prime : bool
        The table's forces are over ½ρL²U² and its moments over ½ρL³U².
    means_columns : dict
        Canonical name (:data:`MEANS_COLUMNS`) -> the table's column; names not given are
        guessed from the table's header.
    roll_deg : float
        Vertical-plane runs: the roll of the model about its x axis on the rig [deg], +90
        (starboard side down) or -90.
    min_cycles : int
        Fewest whole steady PMM cycles a run needs (3 or more).
    amplitude_tolerance : float
        Largest relative departure of a cycle's sway amplitude from the median cycle's, and of
        the measured frequency and amplitude from the sheet's [-].
    """

    moment_ref: str = "origin"
    means: Path | None = None
    means_prime: bool = False
    means_columns: dict[str, str] = field(default_factory=dict)
    roll_deg: float = 90.0
    min_cycles: int = 3
    amplitude_tolerance: float = 0.05


@dataclass(frozen=True)
class Water:
    """The medium of the tests ([water]) or of the prototype ([prototype.water]).

    ``type`` is ``"fresh"``, ``"sea"`` or ``"air"``; temperature [°C]; salinity [g/kg] (sea
    water); absolute pressure [Pa] and relative humidity [%] (air only: None for water).
    """

    type: str = "fresh"
    temperature_C: float = 15.0
    salinity_g_kg: float | None = None
    pressure_Pa: float | None = None
    relative_humidity_pct: float | None = None

    def __post_init__(self) -> None:
        if self.type == "air":  # air always has its state: the defaults where not given
            if self.pressure_Pa is None:
                object.__setattr__(self, "pressure_Pa", STANDARD_PRESSURE_PA)
            if self.relative_humidity_pct is None:
                object.__setattr__(self, "relative_humidity_pct",
                                   DEFAULT_RELATIVE_HUMIDITY_PCT)

    @property
    def is_air(self) -> bool:
        """True for a gas (air): no free surface, no buoyancy worth a check."""
        return self.type == "air"

    @property
    def medium(self) -> str:
        """The medium in words: "fresh water", "sea water" or "air"."""
        return "air" if self.is_air else f"{self.type} water"


@dataclass(frozen=True)
class Myring:
    """Myring hull description [m, deg]; see :mod:`towtank.reference.geometry`."""

    a: float
    b: float
    c: float
    n: float
    theta_deg: float
    d: float
    a_offset: float = 0.0
    c_offset: float = 0.0


@dataclass(frozen=True)
class Model:
    length_m: float
    diameter_m: float | None
    mass_kg: float
    name: str = "model"
    frontal_area_m2: float | None = None
    lateral_area_m2: float | None = None
    wetted_area_m2: float | None = None
    volume_m3: float | None = None
    scale: float | None = None
    depth_m: float | None = None
    mass_uncertainty_kg: float = 0.0005  # added-mass intervals
    length_uncertainty_m: float = 0.0005  # prime-value intervals
    diameter_uncertainty_m: float = 0.0001  # provenance only: D cancels in every coefficient
    myring: Myring | None = None
    geometry_source: str = "as given in the protocol"
    #: Which of frontal_area_m2, lateral_area_m2, wetted_area_m2, volume_m3 the Myring
    #: description supplied (the protocol did not give them).
    myring_computed: tuple[str, ...] = ()
    #: Captive tests (docs/formats.md, "Captive manoeuvring tests"): the yaw and pitch moments
    #: of inertia about the CG [kg m²] of everything the balance carries, the CG's x from the
    #: origin O [m], the x from O of the balance's moment point [m], the draught [m] (ships:
    #: primes on the L·T basis). None where not given.
    izz_kg_m2: float | None = None
    iyy_kg_m2: float | None = None
    xg_m: float | None = None
    balance_x_m: float | None = None
    draught_m: float | None = None

    @property
    def frontal_area(self) -> float:
        """Frontal area A [m²]: given, or π D²/4; NaN when neither is known (a captive
        model's protocol may leave both out: its resistance coefficients are then not made)."""
        if self.frontal_area_m2 is not None:
            return self.frontal_area_m2
        if self.diameter_m is None:
            return math.nan
        return math.pi * self.diameter_m**2 / 4.0

    @property
    def lateral_area(self) -> float:
        """Projected side area for transverse tows [m²]: given, or L·D; NaN when neither is
        known (a ship given by its frontal area: the quantities on it are not computed)."""
        if self.lateral_area_m2 is not None:
            return self.lateral_area_m2
        if self.diameter_m is None:
            return math.nan
        return self.length_m * self.diameter_m


@dataclass(frozen=True)
class Fin:
    chord_m: float
    span_m: float
    section: str = "NACA0015"
    mounting: Literal["free", "wall"] = "free"  # FIN_MOUNTINGS
    oswald_e: float = 1.0
    x_m: float | None = None
    linear_max_deg: float = 10.0  # largest |angle of attack| of the lift-slope fit [deg]

    @property
    def area(self) -> float:
        """Planform area S = chord × span [m²]."""
        return self.chord_m * self.span_m


@dataclass(frozen=True)
class Prototype:
    length_m: float
    speeds_m_s: tuple[float, ...]
    water: Water
    delta_cf: float = 0.0


@dataclass(frozen=True)
class Protocol:
    path: Path
    campaign: Campaign
    water: Water
    model: Model | None
    fin: Fin | None
    prototype: Prototype | None
    channels: dict[str, ChannelMap]
    processing: Processing
    report: ReportOptions
    warnings: tuple[str, ...] = field(default=())
    read: ReadOptions = field(default_factory=ReadOptions)
    balance: Balance | None = None
    tare: TareSource = field(default_factory=TareSource)
    vehicle: Any = None  # towtank.ingest.vehicle_protocol.Vehicle of a [vehicle] section
    speed_log: SpeedLog | None = None  # [speed_log]: carriage speed from its own file
    zeros: ZeroFile | None = None  # [zeros]: the balance zero from its own file
    sheet: SheetOptions = field(default_factory=SheetOptions)  # [sheet]: a hand-typed sheet
    watch: WatchOptions = field(default_factory=WatchOptions)  # [watch]: towtank watch's timings
    captive: Captive | None = None  # [captive]: captive manoeuvring tests' options

    @property
    def name(self) -> str:
        return self.campaign.name


def channel_map(protocol_channels: dict[str, ChannelMap]) -> dict[str, ChannelMap]:
    """The complete mapping: protocol entries, canonical names for the rest."""
    out = {name: ChannelMap(column=name) for name in CANONICAL_CHANNELS}
    out.update(protocol_channels)
    return out
