"""The protocol's schema: every section's keys with their kind, and the checks that coerce a
table of TOML values to them (one sentence per mistake, with the nearest valid key)."""

from __future__ import annotations

import datetime as dt
import difflib
import re
from dataclasses import dataclass, fields
from typing import Any

from towtank.errors import ProtocolError
from towtank.ingest.values import finite_number, shown
from towtank.runtime.safefile import MAX_TABLE_BYTES, check_table_size  # noqa: F401 - here too

CANONICAL_CHANNELS = ("time", "speed", "accel", "drag", "lift")
#: A captive run's channels (docs/formats.md, "Captive manoeuvring tests"): the balance's
#: body-axis forces fx, fy [N] and yaw moment mz [N m], the PMM's sway [m] and yaw [deg]; read
#: only for the runs the sheet marks as captive tests.
CAPTIVE_CHANNELS = ("fx", "fy", "mz", "sway", "yaw")


@dataclass(frozen=True)
class Processing:
    """Signal-processing knobs; every one has a default a lab can live with."""

    cutoff_hz: float = 4.0
    filter_order: int = 4
    zero_window_s: float = 2.0
    trim_s: float | None = None
    min_steady_s: float = 0.5
    min_accel_s: float = 0.3
    steady_tolerance: float = 0.01
    nominal_tolerance: float = 0.05
    fit_sample_hz: float | None = None
    max_nan_gap_s: float = 0.05
    max_bad_row_fraction: float = 0.01
    despike: bool = True
    damping_alpha_max_deg: float = 30.0
    laminar_re: float = 2.0e5
    jobs: int | None = None
    zero_at: str = "before_motion"
    drift: str = "linear"
    drift_settle_s: float = 1.0
    speed_source: str = "measured"
    speed_tolerance: float = 0.005

    @property
    def trim(self) -> float:
        """Time cut from each end of a phase window [s]: default 1.5 filter time constants."""
        return self.trim_s if self.trim_s is not None else 1.5 / self.cutoff_hz


@dataclass(frozen=True)
class ReportOptions:
    date: str | None = None
    pdf: bool = True
    figures: bool = True


@dataclass(frozen=True)
class WatchOptions:
    """``[watch]``: the timings of ``towtank watch`` (docs/formats.md, "towtank watch").

    settle_s [s]: a run file the writer may still hold (its closing cannot be seen, e.g. on a
    network share) counts as complete once it has not changed for this long.
    never_stops_s [s]: a file still changing after this long is reported once.
    pdf_interval_s [s]: the PDF and figures are redrawn at most this often (and at the end).
    """

    settle_s: float = 1.0
    never_stops_s: float = 600.0
    pdf_interval_s: float = 60.0


# --------------------------------------------------------------------------------------------
# Schema: key -> (kind, required). kinds: str, float, int, bool, path, floats, table
NUM = "float"
SCHEMA: dict[str, dict[str, tuple[str, bool]]] = {
    "campaign": {
        "name": ("str", True),
        "run_sheet": ("path", True),
        "data_dir": ("path", True),
        "output_dir": ("path", False),
        "reference": ("str", False),
        "test_date": ("date", False),
    },
    "water": {
        "type": ("str", False),
        "temperature_C": (NUM, True),
        "salinity_g_kg": (NUM, False),
        "pressure_Pa": (NUM, False),
        "relative_humidity_pct": (NUM, False),
    },
    "model": {
        "name": ("str", False),
        "length_m": (NUM, True),
        "diameter_m": (NUM, False),
        "mass_kg": (NUM, True),
        "frontal_area_m2": (NUM, False),
        "lateral_area_m2": (NUM, False),
        "wetted_area_m2": (NUM, False),
        "volume_m3": (NUM, False),
        "scale": (NUM, False),
        "depth_m": (NUM, False),
        "mass_uncertainty_kg": (NUM, False),
        "length_uncertainty_m": (NUM, False),
        "diameter_uncertainty_m": (NUM, False),
        "myring": ("table", False),
        "izz_kg_m2": (NUM, False),
        "iyy_kg_m2": (NUM, False),
        "xg_m": (NUM, False),
        "balance_x_m": (NUM, False),
        "draught_m": (NUM, False),
    },
    "model.myring": {
        "a": (NUM, True),
        "b": (NUM, True),
        "c": (NUM, True),
        "n": (NUM, True),
        "theta_deg": (NUM, True),
        "d": (NUM, True),
        "a_offset": (NUM, False),
        "c_offset": (NUM, False),
    },
    "fin": {
        "chord_m": (NUM, True),
        "span_m": (NUM, True),
        "section": ("str", False),
        "mounting": ("str", False),
        "oswald_e": (NUM, False),
        "x_m": (NUM, False),
        "linear_max_deg": (NUM, False),
    },
    "prototype": {
        "length_m": (NUM, False),
        "speeds_m_s": ("floats", True),
        "delta_cf": (NUM, False),
        "water": ("table", False),
    },
    "prototype.water": {
        "type": ("str", False),
        "temperature_C": (NUM, True),
        "salinity_g_kg": (NUM, False),
        "pressure_Pa": (NUM, False),
        "relative_humidity_pct": (NUM, False),
    },
    "channels": {name: ("table", False) for name in CANONICAL_CHANNELS + CAPTIVE_CHANNELS},
    "channel": {
        "column": ("str", False),
        "columns": ("strs", False),
        "gain": (NUM, False),
        "offset": (NUM, False),
        "unit": ("str", False),
    },
    "tare": {
        "source": ("str", False),
        "table": ("path", False),
        "columns": ("table", False),
    },
    "balance": {
        "inputs": ("strs", True),
        "outputs": ("strs", True),
        "matrix": ("matrix", True),
    },
    "processing": {
        f.name: ({"int": "int", "bool": "bool", "str": "str"}.get(str(f.type).split(" ")[0], NUM),
                 False)
        for f in fields(Processing)
    },  # annotations are strings here: "float", "int | None", "bool", ...
    "report": {
        "date": ("date", False),
        "pdf": ("bool", False),
        "figures": ("bool", False),
    },
    "watch": {
        "settle_s": (NUM, False),
        "never_stops_s": (NUM, False),
        "pdf_interval_s": (NUM, False),
    },
    "captive": {
        "moment_ref": ("str", False),
        "means": ("path", False),
        "means_prime": ("bool", False),
        "means_columns": ("table", False),
        "roll_deg": (NUM, False),
        "min_cycles": ("int", False),
        "amplitude_tolerance": (NUM, False),
    },
    "read": {
        "format": ("str", False),
        "delimiter": ("str", False),
        "decimal": ("str", False),
        "skip_rows": ("int", False),
        "group": ("str", False),
        "sample_rate_hz": (NUM, False),
        "segment": ("int", False),
    },
}
TOP_LEVEL = ("campaign", "water", "model", "fin", "prototype", "channels", "processing", "report",
             "watch", "read", "vehicle", "balance", "tare", "speed_log",
             "zeros", "sheet", "captive")

_KIND_WORDS = {
    "str": "a text string",
    "date": "a date (2024-05-17, written bare or as text)",
    "path": "a path (text)",
    "float": "a number",
    "int": "a whole number",
    "bool": "true or false",
    "floats": "a list of numbers",
    "strs": "a list of text strings",
    "matrix": "a list of rows, each a list of numbers",
    "table": "a table",
}


def suggest(key: str, valid: list[str] | tuple[str, ...]) -> str:
    near = difflib.get_close_matches(key, list(valid), n=1, cutoff=0.5)
    if not near:
        near = difflib.get_close_matches(key.lower(), [v.lower() for v in valid], n=1, cutoff=0.4)
        near = [v for v in valid if v.lower() in near]
    if near:
        return f"; did you mean '{near[0]}'?"
    return f"; valid keys are: {', '.join(valid)}"


def _date_text(value: Any, bad: ProtocolError, where: str, src: str) -> str:
    """A date given as a TOML date (``2024-05-17``) or as text, as text; a text that looks
    like an ISO date (YYYY-MM-DD) must be one that exists."""
    if isinstance(value, dt.datetime):
        return value.date().isoformat()
    if isinstance(value, dt.date):
        return value.isoformat()
    if not isinstance(value, str) or not value.strip():
        raise bad
    if re.fullmatch(r"\s*\d{4}-\d{1,2}-\d{1,2}\s*", value):
        try:
            dt.datetime.strptime(value.strip(), "%Y-%m-%d")
        except ValueError:
            raise ProtocolError(f"{src}: {where} = {value!r} is not a date that exists.") from None
    return value


#: Largest magnitude of a number in the protocol: every key is a quantity in SI units, none of
#: which comes near it in a towing tank; a larger one is a mistake that would only overflow.
MAX_MAGNITUDE = 1e12


def coerce(value: Any, kind: str, where: str, src: str) -> Any:
    bad = ProtocolError(
        f"{src}: {where} must be {_KIND_WORDS[kind]}, but it is {shown(value)}."
    )
    if kind in ("str", "path"):
        if not isinstance(value, str) or not value.strip():
            raise bad
        if kind == "path" and ("\x00" in value or any(len(part) > 255
                                                      for part in value.split("/"))):
            raise ProtocolError(f"{src}: {where} is not a usable path ({value[:60]!r}...).")
        return value
    if kind == "date":
        return _date_text(value, bad, where, src)
    if kind == "float":
        number = finite_number(value)
        if number is None:
            raise bad
        return number
    if kind == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            raise bad
        return value
    if kind == "bool":
        if not isinstance(value, bool):
            raise bad
        return value
    if kind == "floats":
        if not isinstance(value, list) or not value:
            raise bad
        numbers = [finite_number(v) for v in value]
        if None in numbers:
            held = shown(value[numbers.index(None)])
            raise ProtocolError(f"{src}: {where} must be {_KIND_WORDS[kind]}, but it holds "
                                f"{held}.")
        return tuple(v for v in numbers if v is not None)
    if kind == "table":
        if not isinstance(value, dict):
            raise bad
        return value
    if kind == "strs":
        if not isinstance(value, list) or not value or not all(
                isinstance(v, str) and v.strip() for v in value):
            raise bad
        return tuple(value)
    if kind == "matrix":
        if not isinstance(value, list) or not value:
            raise bad
        return tuple(coerce(row, "floats", where, src) for row in value)
    raise AssertionError(kind)


def check_magnitudes(data: Any, src: str, path: tuple[str, ...] = ()) -> None:
    """A ProtocolError naming the first number of a parsed protocol (tables, lists, lists of
    tables) beyond :data:`MAX_MAGNITUDE`. Run after the keys' own checks, which say more: it
    catches what would only overflow further on."""
    if isinstance(data, dict):
        for key, value in data.items():
            check_magnitudes(value, src, (*path, str(key)))
    elif isinstance(data, list):
        for value in data:  # a list's numbers are its key's
            check_magnitudes(value, src, path)
    elif isinstance(data, int | float) and not isinstance(data, bool) \
            and abs(data) > MAX_MAGNITUDE:
        raise ProtocolError(f"{src}: '{path[-1]}' in [{'.'.join(path[:-1])}] is {shown(data)}, "
                            f"beyond the {MAX_MAGNITUDE:g} in magnitude any quantity of a "
                            "protocol (in SI units) stays within.")


def check_keys(data: Any, keys: list[str] | tuple[str, ...], label: str, src: str) -> None:
    """``[label]`` must be a table whose keys are all among ``keys``: else a ProtocolError
    naming the unknown key and the nearest valid one."""
    if not isinstance(data, dict):
        raise ProtocolError(f"{src}: [{label}] must be a table of keys, but it is {data!r}.")
    for key in data:
        if key not in keys:
            raise ProtocolError(f"{src}: unknown key '{key}' in [{label}]{suggest(key, keys)}")


def checked_section(data: Any, schema_name: str, label: str, src: str) -> dict[str, Any]:
    """Validate one table against SCHEMA[schema_name]; return the coerced values."""
    spec = SCHEMA[schema_name]
    check_keys(data, list(spec), label, src)
    out: dict[str, Any] = {}
    for key, value in data.items():
        kind, _ = spec[key]
        out[key] = coerce(value, kind, f"'{key}' in [{label}]", src)
    for key, (_kind, required) in spec.items():
        if required and key not in out:
            raise ProtocolError(f"{src}: [{label}] is missing the required key '{key}'.")
    return out


#: [processing] keys that must be > 0, and the closed ranges of the others.
PROCESSING_POSITIVE = (
    "cutoff_hz", "filter_order", "zero_window_s", "min_steady_s", "min_accel_s",
    "steady_tolerance", "nominal_tolerance", "fit_sample_hz", "damping_alpha_max_deg",
    "laminar_re", "jobs",
)
PROCESSING_RANGES = {
    "cutoff_hz": (0.05, 100000.0),  # below 0.05 Hz a run of tens of seconds is filtered away
    "filter_order": (1, 10),  # a Butterworth of a higher order rings and is ill-conditioned
    "jobs": (1, 4096),
    "trim_s": (0.0, 60.0),
    "max_nan_gap_s": (0.0, 60.0),
    "max_bad_row_fraction": (0.0, 0.5),
    "steady_tolerance": (0.0, 0.5),
    "nominal_tolerance": (0.0, 1.0),
    "damping_alpha_max_deg": (0.0, 90.0),
    "drift_settle_s": (0.0, 60.0),
    "speed_tolerance": (0.0, 0.5),
}
#: [processing] keys that take one of a few words.
PROCESSING_CHOICES = {
    "zero_at": ("before_motion", "file_start"),
    "speed_source": ("measured", "nominal"),
    "drift": ("linear", "none"),
}


def check_positive(values: dict[str, Any], keys: tuple[str, ...], label: str, src: str) -> None:
    for key in keys:
        if key in values and values[key] is not None and values[key] <= 0:
            raise ProtocolError(
                f"{src}: '{key}' in [{label}] must be positive, but it is {values[key]}."
            )
