"""Protocol loader: the campaign's TOML file (FORMATS.md §1), validated.

Every key is checked against a schema: an unknown or misspelt key is an error that names it and
suggests the nearest valid key, a missing required key or a value of the wrong type likewise, and
paths are resolved relative to the protocol file. Nothing downstream ever sees an unvalidated
value. All errors are :class:`~towtank.errors.ProtocolError` with one sentence for the user.
"""

from __future__ import annotations

import difflib
import math
import re
import tomllib
from collections.abc import Iterable
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from towtank.errors import ProtocolError

CANONICAL_CHANNELS = ("time", "speed", "accel", "drag", "lift")
#: Largest |ΔC_F| accepted: five times the ITTC-78 roughness allowance of a full-size hull
#: (about 4e-4); anything larger is a unit or typing mistake.
MAX_DELTA_CF = 0.002
#: Largest mismatch between [prototype] length_m and [model] length_m × scale [-].
LENGTH_SCALE_TOLERANCE = 0.01
WATER_TYPES = ("fresh", "sea")
FIN_MOUNTINGS = ("free", "wall")


@dataclass(frozen=True)
class ChannelMap:
    """How a canonical channel is found in a run file: value = gain·(raw − offset)."""

    column: str
    gain: float = 1.0
    offset: float = 0.0


@dataclass(frozen=True)
class Campaign:
    name: str
    run_sheet: Path
    data_dir: Path
    output_dir: Path
    reference: str = "remus"
    test_date: str | None = None


@dataclass(frozen=True)
class Water:
    type: str = "fresh"
    temperature_C: float = 15.0
    salinity_g_kg: float | None = None


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

    @property
    def frontal_area(self) -> float:
        """Frontal area A [m²]: given, or π D²/4."""
        if self.frontal_area_m2 is not None:
            return self.frontal_area_m2
        assert self.diameter_m is not None
        return math.pi * self.diameter_m**2 / 4.0

    @property
    def lateral_area(self) -> float:
        """Projected side area for transverse tows [m²]: given, or L·D."""
        if self.lateral_area_m2 is not None:
            return self.lateral_area_m2
        assert self.diameter_m is not None
        return self.length_m * self.diameter_m


@dataclass(frozen=True)
class Fin:
    chord_m: float
    span_m: float
    section: str = "NACA0015"
    mounting: str = "free"
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

    @property
    def name(self) -> str:
        return self.campaign.name


# --------------------------------------------------------------------------------------------
# Schema: key -> (kind, required). kinds: str, float, int, bool, path, floats, table
_NUM = "float"
SCHEMA: dict[str, dict[str, tuple[str, bool]]] = {
    "campaign": {
        "name": ("str", True),
        "run_sheet": ("path", True),
        "data_dir": ("path", True),
        "output_dir": ("path", False),
        "reference": ("str", False),
        "test_date": ("str", False),
    },
    "water": {
        "type": ("str", False),
        "temperature_C": (_NUM, True),
        "salinity_g_kg": (_NUM, False),
    },
    "model": {
        "name": ("str", False),
        "length_m": (_NUM, True),
        "diameter_m": (_NUM, False),
        "mass_kg": (_NUM, True),
        "frontal_area_m2": (_NUM, False),
        "lateral_area_m2": (_NUM, False),
        "wetted_area_m2": (_NUM, False),
        "volume_m3": (_NUM, False),
        "scale": (_NUM, False),
        "depth_m": (_NUM, False),
        "mass_uncertainty_kg": (_NUM, False),
        "length_uncertainty_m": (_NUM, False),
        "diameter_uncertainty_m": (_NUM, False),
        "myring": ("table", False),
    },
    "model.myring": {
        "a": (_NUM, True),
        "b": (_NUM, True),
        "c": (_NUM, True),
        "n": (_NUM, True),
        "theta_deg": (_NUM, True),
        "d": (_NUM, True),
        "a_offset": (_NUM, False),
        "c_offset": (_NUM, False),
    },
    "fin": {
        "chord_m": (_NUM, True),
        "span_m": (_NUM, True),
        "section": ("str", False),
        "mounting": ("str", False),
        "oswald_e": (_NUM, False),
        "x_m": (_NUM, False),
        "linear_max_deg": (_NUM, False),
    },
    "prototype": {
        "length_m": (_NUM, False),
        "speeds_m_s": ("floats", True),
        "delta_cf": (_NUM, False),
        "water": ("table", False),
    },
    "prototype.water": {
        "type": ("str", False),
        "temperature_C": (_NUM, True),
        "salinity_g_kg": (_NUM, False),
    },
    "channels": {name: ("table", False) for name in CANONICAL_CHANNELS},
    "channel": {
        "column": ("str", True),
        "gain": (_NUM, False),
        "offset": (_NUM, False),
    },
    "processing": {
        f.name: ({"int": "int", "bool": "bool", "str": "str"}.get(str(f.type).split(" ")[0], _NUM),
                 False)
        for f in fields(Processing)
    },  # annotations are strings here: "float", "int | None", "bool", ...
    "report": {
        "date": ("str", False),
        "pdf": ("bool", False),
        "figures": ("bool", False),
    },
}
TOP_LEVEL = ("campaign", "water", "model", "fin", "prototype", "channels", "processing", "report")

_KIND_WORDS = {
    "str": "a text string",
    "path": "a path (text)",
    "float": "a number",
    "int": "a whole number",
    "bool": "true or false",
    "floats": "a list of numbers",
    "table": "a table",
}


def _suggest(key: str, valid: list[str] | tuple[str, ...]) -> str:
    near = difflib.get_close_matches(key, list(valid), n=1, cutoff=0.5)
    if not near:
        near = difflib.get_close_matches(key.lower(), [v.lower() for v in valid], n=1, cutoff=0.4)
        near = [v for v in valid if v.lower() in near]
    if near:
        return f"; did you mean '{near[0]}'?"
    return f"; valid keys are: {', '.join(valid)}"


def _coerce(value: Any, kind: str, where: str, src: str) -> Any:
    bad = ProtocolError(
        f"{src}: {where} must be {_KIND_WORDS[kind]}, but it is {value!r}."
    )
    if kind in ("str", "path"):
        if not isinstance(value, str) or not value.strip():
            raise bad
        if kind == "path" and ("\x00" in value or any(len(part) > 255
                                                      for part in value.split("/"))):
            raise ProtocolError(f"{src}: {where} is not a usable path ({value[:60]!r}...).")
        return value
    if kind == "float":
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise bad
        if not math.isfinite(value):
            raise bad
        return float(value)
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
        out = []
        for v in value:
            if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
                raise bad
            out.append(float(v))
        return tuple(out)
    if kind == "table":
        if not isinstance(value, dict):
            raise bad
        return value
    raise AssertionError(kind)


def _section(data: Any, schema_name: str, label: str, src: str) -> dict[str, Any]:
    """Validate one table against SCHEMA[schema_name]; return the coerced values."""
    if not isinstance(data, dict):
        raise ProtocolError(f"{src}: [{label}] must be a table of keys, but it is {data!r}.")
    spec = SCHEMA[schema_name]
    out: dict[str, Any] = {}
    for key, value in data.items():
        if key not in spec:
            raise ProtocolError(
                f"{src}: unknown key '{key}' in [{label}]{_suggest(key, list(spec))}"
            )
        kind, _ = spec[key]
        out[key] = _coerce(value, kind, f"'{key}' in [{label}]", src)
    for key, (_kind, required) in spec.items():
        if required and key not in out:
            raise ProtocolError(f"{src}: [{label}] is missing the required key '{key}'.")
    return out


#: [processing] keys that must be > 0, and the closed ranges of the others.
_PROCESSING_POSITIVE = (
    "cutoff_hz", "filter_order", "zero_window_s", "min_steady_s", "min_accel_s",
    "steady_tolerance", "nominal_tolerance", "fit_sample_hz", "damping_alpha_max_deg",
    "laminar_re", "jobs",
)
_PROCESSING_RANGES = {
    "trim_s": (0.0, 60.0),
    "max_nan_gap_s": (0.0, 60.0),
    "max_bad_row_fraction": (0.0, 0.5),
    "steady_tolerance": (0.0, 0.5),
    "nominal_tolerance": (0.0, 1.0),
    "damping_alpha_max_deg": (0.0, 90.0),
    "drift_settle_s": (0.0, 60.0),
}
#: [processing] keys that take one of a few words.
_PROCESSING_CHOICES = {
    "zero_at": ("before_motion", "file_start"),
    "drift": ("linear", "none"),
}


def _positive(values: dict[str, Any], keys: tuple[str, ...], label: str, src: str) -> None:
    for key in keys:
        if key in values and values[key] is not None and values[key] <= 0:
            raise ProtocolError(
                f"{src}: '{key}' in [{label}] must be positive, but it is {values[key]}."
            )


def _water(values: dict[str, Any], label: str, src: str) -> Water:
    wtype = values.get("type", "fresh")
    if wtype not in WATER_TYPES:
        raise ProtocolError(
            f"{src}: 'type' in [{label}] must be one of {', '.join(WATER_TYPES)}, "
            f"but it is {wtype!r}{_suggest(wtype, WATER_TYPES)}"
        )
    salinity = values.get("salinity_g_kg")
    if salinity is not None and wtype == "fresh" and salinity != 0:
        raise ProtocolError(
            f"{src}: [{label}] gives salinity_g_kg = {salinity:g} for fresh water; "
            "set type = \"sea\" for saline water."
        )
    if salinity is not None and salinity < 0:
        raise ProtocolError(
            f"{src}: 'salinity_g_kg' in [{label}] must not be negative, but it is {salinity:g}."
        )
    return Water(type=wtype, temperature_C=values["temperature_C"], salinity_g_kg=salinity)


def slugify(text: str) -> str:
    """A file-system-safe folder name from a campaign name."""
    slug = re.sub(r"[^A-Za-z0-9]+", "_", text).strip("_").lower()
    return slug or "campaign"


def _unit_warnings(
    model: Model | None, fin: Fin | None, water: Water, prototype: Prototype | None = None
) -> list[str]:
    """Order-of-magnitude checks: a value that is plausible only in other units.

    The water temperatures (tank and prototype) are checked against 0–40 °C and a sea water's
    salinity against 0–42 g/kg, the ranges of the water properties (ITTC 7.5-02-01-03): outside
    them the density and viscosity are extrapolated.
    """
    out: list[str] = []

    def check(value: float | None, lo: float, hi: float, what: str, hint: str) -> None:
        if value is not None and not lo <= value <= hi:
            out.append(f"{what} = {value:g} is outside the usual {lo:g}–{hi:g}; {hint}")

    if model is not None:
        check(model.length_m, 0.05, 20.0, "[model] length_m", "was it given in mm or cm?")
        check(model.diameter_m, 0.005, 3.0, "[model] diameter_m", "was it given in mm or cm?")
        check(model.mass_kg, 0.01, 5000.0, "[model] mass_kg", "was it given in g?")
        if model.diameter_m and model.length_m / model.diameter_m > 40:
            out.append(
                f"[model] length/diameter = {model.length_m / model.diameter_m:.0f} is unusually "
                "large; check the units of length_m and diameter_m."
            )
    if fin is not None:
        check(fin.chord_m, 0.005, 5.0, "[fin] chord_m", "was it given in mm or cm?")
        check(fin.span_m, 0.005, 10.0, "[fin] span_m", "was it given in mm or cm?")
    check(water.temperature_C, 0.0, 40.0, "[water] temperature_C", "was it given in K or °F?")
    if prototype is not None:
        pw = prototype.water
        check(pw.temperature_C, 0.0, 40.0, "[prototype.water] temperature_C",
              "there the ITTC water properties, and so the prototype's Re and drag, are "
              "extrapolated (was it given in K or °F?)")
        if pw.type == "sea":
            check(pw.salinity_g_kg, 0.0, 42.0, "[prototype.water] salinity_g_kg",
                  "there the sea-water properties are extrapolated (was it given in ‰ × 10?)")
    return out


def load_protocol(path: str | Path, *, check_paths: bool = True) -> Protocol:
    """Read and validate a protocol file.

    Parameters
    ----------
    path : str or Path
        The protocol (TOML) file.
    check_paths : bool
        Check that the run sheet and the data folder exist.

    Returns
    -------
    Protocol

    Raises
    ------
    ProtocolError
        With one sentence naming the file, the key and what is wrong.
    """
    path = Path(path)
    src = path.name
    try:
        text = path.read_text(encoding="utf-8-sig")  # a BOM from a Windows editor is fine
    except FileNotFoundError:
        raise ProtocolError(f"{path}: the protocol file does not exist.") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ProtocolError(f"{path}: the protocol file cannot be read ({exc}).") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ProtocolError(f"{src}: not valid TOML ({exc}).") from None

    for key in data:
        if key not in TOP_LEVEL:
            raise ProtocolError(f"{src}: unknown section [{key}]{_suggest(key, TOP_LEVEL)}")
    for required in ("campaign", "water"):
        if required not in data:
            raise ProtocolError(f"{src}: the required section [{required}] is missing.")

    try:
        return _build(path, src, data, check_paths)
    except (OSError, ValueError) as exc:  # an unusable path on this file system
        raise ProtocolError(f"{src}: a path in the protocol cannot be used ({exc}).") from None


def _build(path: Path, src: str, data: dict[str, Any], check_paths: bool) -> Protocol:
    """The validated protocol from parsed TOML (see :func:`load_protocol`)."""
    base = path.resolve().parent
    camp = _section(data["campaign"], "campaign", "campaign", src)
    water = _water(_section(data["water"], "water", "water", src), "water", src)

    output_dir = (
        base / camp["output_dir"]
        if "output_dir" in camp
        else Path.cwd() / "reports" / slugify(camp["name"])
    )
    reference = camp.get("reference", "remus")
    if reference != "remus":
        ref_path = base / reference
        if check_paths and not ref_path.is_file():
            raise ProtocolError(
                f"{src}: the reference '{reference}' in [campaign] is neither the built-in "
                f"set 'remus' nor an existing CSV file ({ref_path})."
            )
        reference = str(ref_path)
        if check_paths:
            read_reference_csv(ref_path)  # a bad reference stops here, before any work
    campaign = Campaign(
        name=camp["name"],
        run_sheet=(base / camp["run_sheet"]).resolve(),
        data_dir=(base / camp["data_dir"]).resolve(),
        output_dir=output_dir.resolve(),
        reference=reference,
        test_date=camp.get("test_date"),
    )
    if check_paths:
        if not campaign.run_sheet.is_file():
            raise ProtocolError(
                f"{src}: the run sheet '{camp['run_sheet']}' in [campaign] does not exist "
                f"({campaign.run_sheet})."
            )
        if campaign.run_sheet.suffix.lower() not in (".csv", ".xlsx"):
            raise ProtocolError(
                f"{src}: the run sheet '{camp['run_sheet']}' must be a .csv or .xlsx file."
            )
        if not campaign.data_dir.is_dir():
            raise ProtocolError(
                f"{src}: the data folder '{camp['data_dir']}' in [campaign] does not exist "
                f"({campaign.data_dir})."
            )

    model = None
    if "model" in data:
        m = _section(data["model"], "model", "model", src)
        _positive(
            m,
            tuple(k for k, (kind, _) in SCHEMA["model"].items() if kind == _NUM and k != "depth_m"),
            "model",
            src,
        )
        myring = None
        if "myring" in m:
            my = _section(m.pop("myring"), "model.myring", "model.myring", src)
            _positive(my, ("a", "b", "c", "n", "d"), "model.myring", src)
            myring = Myring(**my)
        if "diameter_m" not in m and "frontal_area_m2" not in m and myring is None:
            raise ProtocolError(
                f"{src}: [model] needs 'diameter_m' (or 'frontal_area_m2') for the frontal area."
            )
        model = Model(**m, myring=myring)
        if myring is not None:
            model = _with_myring_geometry(model, src)
        _check_mass(model, src)

    fin = None
    if "fin" in data:
        f = _section(data["fin"], "fin", "fin", src)
        _positive(f, ("chord_m", "span_m", "oswald_e", "linear_max_deg"), "fin", src)
        if f.get("linear_max_deg", 0.0) > 90.0:
            raise ProtocolError(
                f"{src}: 'linear_max_deg' in [fin] is the largest angle of attack of the "
                f"linear range, 0–90°, but it is {f['linear_max_deg']}."
            )
        mounting = f.get("mounting", "free")
        if mounting not in FIN_MOUNTINGS:
            raise ProtocolError(
                f"{src}: 'mounting' in [fin] must be one of {', '.join(FIN_MOUNTINGS)}, "
                f"but it is {mounting!r}{_suggest(mounting, FIN_MOUNTINGS)}"
            )
        section = f.get("section", "NACA0015")
        if section.replace(" ", "").upper() != "NACA0015":
            raise ProtocolError(
                f"{src}: [fin] section {section!r} has no shipped section data; "
                "only NACA0015 (Sandia, SAND80-2114) is available."
            )
        fin = Fin(**f)

    if model is None and fin is None:
        raise ProtocolError(f"{src}: the protocol needs a [model] or a [fin] section.")

    prototype = None
    if "prototype" in data:
        p = _section(data["prototype"], "prototype", "prototype", src)
        if "length_m" in p:
            length_p = p["length_m"]
        elif model is not None and model.scale is not None:
            length_p = model.length_m * model.scale
        else:
            raise ProtocolError(
                f"{src}: [prototype] needs 'length_m', or [model] needs 'scale' to derive it."
            )
        if model is not None and model.scale is not None and "length_m" in p:
            expected = model.length_m * model.scale
            if abs(length_p - expected) > LENGTH_SCALE_TOLERANCE * expected:
                raise ProtocolError(
                    f"{src}: [prototype] length_m = {length_p:g} m does not match [model] "
                    f"length_m × scale = {model.length_m:g} × {model.scale:g} = {expected:.4g} m "
                    f"(they must agree within {LENGTH_SCALE_TOLERANCE:.0%}); correct one of them "
                    "or leave [prototype] length_m out."
                )
        if any(s <= 0 for s in p["speeds_m_s"]):
            raise ProtocolError(f"{src}: 'speeds_m_s' in [prototype] must all be positive.")
        delta_cf = p.get("delta_cf", 0.0)
        if abs(delta_cf) > MAX_DELTA_CF:
            raise ProtocolError(
                f"{src}: 'delta_cf' in [prototype] is {delta_cf:g}, but a roughness allowance "
                f"ΔC_F lies within ±{MAX_DELTA_CF:g} (the ITTC value for a full-size hull is "
                "about 0.0004)."
            )
        pw = (
            _water(_section(p["water"], "prototype.water", "prototype.water", src),
                   "prototype.water", src)
            if "water" in p
            else Water(type="sea", temperature_C=15.0)
        )
        prototype = Prototype(
            length_m=length_p,
            speeds_m_s=p["speeds_m_s"],
            water=pw,
            delta_cf=delta_cf,
        )

    channels: dict[str, ChannelMap] = {}
    if "channels" in data:
        ch = _section(data["channels"], "channels", "channels", src)
        for name, spec in ch.items():
            c = _section(spec, "channel", f"channels.{name}", src)
            if c.get("gain", 1.0) == 0:
                raise ProtocolError(f"{src}: 'gain' in [channels.{name}] must not be zero.")
            channels[name] = ChannelMap(**c)

    proc_values = _section(data.get("processing", {}), "processing", "processing", src)
    _positive(proc_values, _PROCESSING_POSITIVE, "processing", src)
    for key, (low, high) in _PROCESSING_RANGES.items():
        value = proc_values.get(key)
        if value is not None and not low <= value <= high:
            raise ProtocolError(
                f"{src}: '{key}' in [processing] must lie in {low:g}–{high:g}, but it is {value}."
            )
    for key, choices in _PROCESSING_CHOICES.items():
        value = proc_values.get(key)
        if value is not None and value not in choices:
            raise ProtocolError(
                f"{src}: '{key}' in [processing] must be one of {', '.join(choices)}, but it is "
                f"{value!r}{_suggest(value, choices)}"
            )
    processing = Processing(**proc_values)
    report = ReportOptions(**_section(data.get("report", {}), "report", "report", src))

    warnings = _unit_warnings(model, fin, water, prototype)
    return Protocol(
        path=path.resolve(),
        campaign=campaign,
        water=water,
        model=model,
        fin=fin,
        prototype=prototype,
        channels=channels,
        processing=processing,
        report=report,
        warnings=tuple(warnings),
    )


#: [model] mass_kg against the displaced mass ρV (ρ ≈ 1000 kg/m³): outside this range of
#: ratios it is in other units (grams give ~1000, tonnes ~0.001); a solid steel body is ~8.
MASS_RATIO_RANGE = (0.05, 20.0)


def _check_mass(model: Model, src: str) -> None:
    """Stop on a weighed mass that no body of this size can have (a unit slip)."""
    from towtank.reference.geometry import displaced_volume

    if not 0.05 <= model.length_m <= 20.0 or not 0.005 <= (model.diameter_m or 0.05) <= 3.0:
        return  # a length or diameter in other units: the unit warnings name it
    volume = displaced_volume(model.length_m, model.diameter_m, model.volume_m3)
    if volume is None:
        return
    disp = 1000.0 * volume
    ratio = model.mass_kg / disp
    lo, hi = MASS_RATIO_RANGE
    if not lo <= ratio <= hi:
        unit = "grams" if ratio > hi else "tonnes, or the geometry in other units"
        raise ProtocolError(
            f"{src}: [model] mass_kg = {model.mass_kg:g} is {ratio:.3g} times the mass of the "
            f"water the hull displaces (about {disp:.3g} kg for its "
            f"{'given' if model.volume_m3 else 'estimated'} volume {volume:.3g} m³); a towed "
            f"model weighs {lo:g}–{hi:g} times that: was it given in {unit}?"
        )


def _with_myring_geometry(model: Model, src: str) -> Model:
    """Fill the areas and volume the protocol leaves out from the Myring description."""
    from dataclasses import replace

    from towtank.reference import geometry

    my = model.myring
    assert my is not None
    try:
        g = geometry.myring_geometry(
            my.a, my.b, my.c, my.n, my.theta_deg, my.d, a_offset=my.a_offset, c_offset=my.c_offset
        )
    except ValueError as exc:
        raise ProtocolError(f"{src}: [model.myring] does not describe a hull ({exc}).") from None
    if abs(g.length - model.length_m) > 0.01 * model.length_m:
        raise ProtocolError(
            f"{src}: [model.myring] gives a length of {g.length:.4f} m but length_m is "
            f"{model.length_m:.4f} m."
        )
    computed = [
        name for name, given in (
            ("frontal area", model.frontal_area_m2), ("lateral area", model.lateral_area_m2),
            ("wetted area", model.wetted_area_m2), ("volume", model.volume_m3),
        ) if given is None
    ]
    given = [n for n in ("frontal area", "lateral area", "wetted area", "volume")
             if n not in computed]
    source = (
        (", ".join(computed) + " computed from the protocol's Myring description"
         if computed else "")
        + ("; " if computed and given else "")
        + (", ".join(given) + " as given in the protocol" if given else "")
    )
    return replace(
        model,
        diameter_m=model.diameter_m if model.diameter_m is not None else my.d,
        frontal_area_m2=model.frontal_area_m2 or g.frontal_area,
        lateral_area_m2=model.lateral_area_m2 or g.lateral_area,
        wetted_area_m2=model.wetted_area_m2 or g.wetted_area,
        volume_m3=model.volume_m3 or g.volume,
        geometry_source=source,
        myring_computed=tuple(
            key for key in ("frontal_area_m2", "lateral_area_m2", "wetted_area_m2", "volume_m3")
            if getattr(model, key) is None
        ),
    )


def model_geometry(model: Model, scale: float | None = None) -> list[dict[str, Any]]:
    """The hull geometry the day used, each quantity with where it came from.

    Rows, in order: frontal area ``A`` (given, Myring, or ``pi D^2 / 4``), lateral area ``A_lat``
    (given, Myring, or ``L D``), wetted area ``S_m`` and volume ``V`` (given, Myring, or not
    known), and, when ``scale`` is given and ``S_m`` known, the prototype's wetted area
    ``S_p = lambda^2 S_m`` of the ITTC-57 extrapolation.

    Parameters
    ----------
    model : Model
        The validated [model] section.
    scale : float, optional
        Scale ratio ``lambda = L_p / L_m`` [-]

    Returns
    -------
    list of dict
        ``quantity``, ``symbol``, ``value`` (None when not known), ``unit``, ``source``.
    """
    myring = "computed from the [model.myring] Myring description"

    def origin(key: str, default: str) -> str:
        if key in model.myring_computed:
            return myring
        if getattr(model, key) is not None:
            return f"given in the protocol ({key})"
        return default

    rows = [
        ("frontal area", "A", model.frontal_area, "m²",
         origin("frontal_area_m2", "π D²/4 from diameter_m")),
        ("lateral area", "A_lat", model.lateral_area, "m²",
         origin("lateral_area_m2", "L·D from length_m and diameter_m (default)")),
        ("wetted area", "S_m", model.wetted_area_m2, "m²",
         origin("wetted_area_m2", "not known (no wetted_area_m2, no Myring description)")),
        ("volume", "V", model.volume_m3, "m³",
         origin("volume_m3", "not known (no volume_m3, no Myring description)")),
    ]
    if scale is not None and model.wetted_area_m2 is not None:
        rows.append(("prototype wetted area", "S_p", model.wetted_area_m2 * scale**2, "m²",
                     f"λ²·S_m with λ = {scale:g}"))
    return [
        {"quantity": q, "symbol": sym, "value": v, "unit": u, "source": src}
        for q, sym, v, u, src in rows
    ]


def channel_map(protocol_channels: dict[str, ChannelMap]) -> dict[str, ChannelMap]:
    """The complete mapping: protocol entries, canonical names for the rest."""
    out = {name: ChannelMap(column=name) for name in CANONICAL_CHANNELS}
    out.update(protocol_channels)
    return out


#: Every entry towtank writes into an output folder (FORMATS §5; the cache aside).
OUTPUT_NAMES = frozenset({
    "runs.csv", "coefficients.csv", "fins.csv", "fin_curves.csv", "fin_control.csv",
    "scaling.csv", "report.xlsx", "report.pdf", "figures", "provenance.json",
})


def read_reference_csv(path: str | Path) -> dict[str, float]:
    """Reference prime values of a user CSV with the columns ``symbol`` and ``prime`` [-].

    Lines starting with ``#`` are comments; column names are matched without regard to case
    or surrounding spaces; other columns are ignored.

    Raises
    ------
    ProtocolError
        The file cannot be read, lacks a column, holds no row, repeats a symbol or has a prime
        that is not a finite number (one sentence naming the file and the row).
    """
    import csv
    import math

    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise ProtocolError(f"{path}: the reference CSV cannot be read ({exc}).") from None
    lines = [(n, line) for n, line in enumerate(text.splitlines(), start=1)
             if line.strip() and not line.lstrip().startswith("#")]
    if not lines:
        raise ProtocolError(f"{path}: the reference CSV is empty (it needs the columns symbol "
                            "and prime and one row per coefficient).")
    rows = list(csv.reader([line for _, line in lines]))
    header = [h.strip().lower() for h in rows[0]]
    if "symbol" not in header or "prime" not in header:
        raise ProtocolError(
            f"{path}: a reference CSV needs the columns symbol and prime "
            f"(found {', '.join(repr(h) for h in rows[0])})."
        )
    i_sym, i_prime = header.index("symbol"), header.index("prime")
    out: dict[str, float] = {}
    for (lineno, _), row in zip(lines[1:], rows[1:], strict=True):
        cells = row + [""] * (len(header) - len(row))
        sym, raw = cells[i_sym].strip(), cells[i_prime].strip()
        try:
            value = float(raw)
        except ValueError:
            value = math.nan
        if not sym or not math.isfinite(value):
            raise ProtocolError(
                f"{path}: line {lineno} needs a symbol and a finite prime value "
                f"(found symbol {sym!r}, prime {raw!r})."
            )
        if sym in out:
            raise ProtocolError(f"{path}: line {lineno} repeats the symbol {sym!r}.")
        out[sym] = value
    if not out:
        raise ProtocolError(f"{path}: the reference CSV has a header but no coefficient rows.")
    return out


def check_output_dir(
    out_dir: str | Path, protocol: Protocol, inputs: Iterable[str | Path] = ()
) -> Path:
    """The output folder, resolved, after checking that writing there cannot touch an input.

    ``inputs`` are further input files (the run files the sheet names, wherever they lie).

    Raises
    ------
    ProtocolError
        ``out_dir`` is a file; it is, holds or lies inside the data folder; or one of the
        outputs would replace the protocol, the run sheet, the reference CSV or an input.
    """
    out = Path(out_dir).resolve()
    if out.exists() and not out.is_dir():
        raise ProtocolError(f"the output folder {out} is a file, not a folder.")
    data = protocol.campaign.data_dir.resolve()
    if out == data or data.is_relative_to(out) or out.is_relative_to(data):
        raise ProtocolError(
            f"the output folder {out} would mix the outputs with the raw run files in {data}; "
            "choose another folder with --out or [campaign] output_dir."
        )
    inputs = [protocol.path, protocol.campaign.run_sheet, *(Path(p) for p in inputs)]
    if protocol.campaign.reference != "remus":
        inputs.append(Path(protocol.campaign.reference))
    for name in sorted(OUTPUT_NAMES):
        target = out / name
        for path in inputs:
            if target == Path(path).resolve() or Path(path).resolve().is_relative_to(target):
                raise ProtocolError(
                    f"the output folder {out} would overwrite the input {path} with the "
                    f"output {name}; choose another folder with --out or [campaign] output_dir."
                )
    return out
