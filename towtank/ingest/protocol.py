"""Protocol loader: the campaign's TOML file (docs/formats.md §1), validated.

Every key is checked against a schema: an unknown or misspelt key is an error that names it and
suggests the nearest valid key, a missing required key or a value of the wrong type likewise, and
paths are resolved relative to the protocol file. Nothing downstream ever sees an unvalidated
value. All errors are :class:`~towtank.errors.ProtocolError` with one sentence for the user.

The protocol's types are in :mod:`towtank.ingest.protocol_types` and the parsers of the lab
sections in :mod:`towtank.ingest.sections` (both importable from here too); this module reads the
file and checks the campaign, water, model, fin, prototype, channels and processing sections.
:func:`with_output_dir` checks an output folder for a protocol
(:mod:`towtank.runtime.outfolder`).
"""

from __future__ import annotations

import dataclasses
import math
import re
import sys
import tomllib
import warnings as _warnings
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

from towtank.errors import ProtocolError
from towtank.ingest.protocol_types import (  # noqa: F401 - the types, importable from here too
    Balance,
    Campaign,
    Captive,
    ChannelMap,
    Fin,
    Model,
    Myring,
    Protocol,
    Prototype,
    SpeedLog,
    TareSource,
    Water,
    ZeroFile,
    channel_map,
)
from towtank.ingest.readers import ReadOptions, known_units
from towtank.ingest.schema import (  # noqa: F401 - SCHEMA, TOP_LEVEL: public here too
    CANONICAL_CHANNELS,
    NUM,
    PROCESSING_CHOICES,
    PROCESSING_POSITIVE,
    PROCESSING_RANGES,
    SCHEMA,
    TOP_LEVEL,
    Processing,
    ReportOptions,
    WatchOptions,
    check_keys,
    check_magnitudes,
    check_positive,
    checked_section,
    suggest,
)
from towtank.ingest.sections import (  # noqa: F401 - MASS_RATIO_RANGE: public here too
    MASS_RATIO_RANGE,
    captive_model_missing,
    check_mass,
    parse_balance,
    parse_captive,
    parse_read_options,
    parse_speed_log,
    parse_tare,
    parse_zero_file,
)
from towtank.ingest.sheetlayout import SheetOptions, parse_sheet_options  # noqa: F401
from towtank.ingest.vehicle_protocol import parse_vehicle
from towtank.reference import geometry
from towtank.reference.air import (
    AIR_PRESSURE_RANGE_PA,
    AIR_TEMPERATURE_RANGE_C,
    DEFAULT_RELATIVE_HUMIDITY_PCT,
    STANDARD_PRESSURE_PA,
)
from towtank.reference.sets import BUILTIN_REFERENCES, read_reference_csv
from towtank.reference.water import temperature_problem
from towtank.runtime import outfolder
from towtank.runtime.outfolder import OUTPUT_NAMES  # noqa: F401 - public here too
from towtank.runtime.pathcheck import (
    FILE,
    FOLDER,
    MISSING,
    OTHER,
    is_regular_file,
    path_kind,
    resolved,
)

#: Largest |ΔC_F| accepted: five times the ITTC-78 roughness allowance of a full-size hull
#: (about 4e-4); anything larger is a unit or typing mistake.
MAX_DELTA_CF = 0.002

#: Fastest prototype speed taken in [prototype] speeds_m_s [m/s] (a torpedo runs at 25-35).
MAX_PROTOTYPE_SPEED = 100.0

#: Largest mismatch between [prototype] length_m and [model] length_m × scale [-].
LENGTH_SCALE_TOLERANCE = 0.01
#: The media of [water] type: fresh or sea water (ITTC 7.5-02-01-03), or air (a wind tunnel or
#: any rig in air; CIPM-2007 density, Sutherland viscosity: towtank.reference.air).
WATER_TYPES = ("fresh", "sea", "air")
#: Keys of [water] that only air takes.
AIR_KEYS = ("pressure_Pa", "relative_humidity_pct")
FIN_MOUNTINGS = ("free", "wall")


#: The salinity a protocol gives must stay below it [g/kg]: a kilogram of sea water holds less
#: than a kilogram of salt (sea water is 35 g/kg; from 42 g/kg on the properties are
#: extrapolated, with a warning).
SALT_PER_KG_LIMIT = 1000.0


def _water(values: dict[str, Any], label: str, src: str) -> Water:
    wtype = values.get("type", "fresh")
    if wtype not in WATER_TYPES:
        raise ProtocolError(
            f"{src}: 'type' in [{label}] must be one of {', '.join(WATER_TYPES)}, "
            f"but it is {wtype!r}{suggest(wtype, WATER_TYPES)}"
        )
    if wtype == "air":
        return _air(values, label, src)
    for key in AIR_KEYS:
        if key in values:
            raise ProtocolError(
                f"{src}: [{label}] gives {key} for {wtype} water, but only air takes it "
                "(set type = \"air\" for a rig in air, or remove the key)."
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
    if salinity is not None and salinity >= SALT_PER_KG_LIMIT:
        raise ProtocolError(
            f"{src}: 'salinity_g_kg' in [{label}] is {salinity:g}, but a salinity is grams of "
            f"salt in a kilogram of sea water, below {SALT_PER_KG_LIMIT:g}: was it given in "
            "mg/kg or ppm?"
        )
    problem = temperature_problem(values["temperature_C"])
    if problem is not None:
        raise ProtocolError(f"{src}: 'temperature_C' in [{label}]: {problem}.")
    return Water(type=wtype, temperature_C=values["temperature_C"], salinity_g_kg=salinity)


def _air(values: dict[str, Any], label: str, src: str) -> Water:
    """``[water] type = "air"``: temperature, absolute pressure and relative humidity checked."""
    if "salinity_g_kg" in values:
        raise ProtocolError(
            f"{src}: [{label}] gives salinity_g_kg for air; remove it (air has none)."
        )
    t = values["temperature_C"]
    problem = temperature_problem(t, AIR_TEMPERATURE_RANGE_C, "of air in a test rig")
    if problem is not None:
        raise ProtocolError(f"{src}: 'temperature_C' in [{label}]: {problem}.")
    pressure = values.get("pressure_Pa", STANDARD_PRESSURE_PA)
    lo, hi = AIR_PRESSURE_RANGE_PA
    if not (math.isfinite(pressure) and lo <= pressure <= hi):
        hint = ""
        if math.isfinite(pressure) and 0 < pressure < lo:
            # the unit that puts it nearest the standard atmosphere
            u, k = min((("hPa or mbar", 100.0), ("kPa", 1000.0), ("bar", 1.0e5)),
                       key=lambda uk: abs(math.log(pressure * uk[1] / STANDARD_PRESSURE_PA)))
            hint = f" (was it in {u}: {pressure * k:g} Pa?)"
        raise ProtocolError(
            f"{src}: 'pressure_Pa' in [{label}] is the absolute air pressure in Pa, "
            f"{lo:g}–{hi:g}, but it is {pressure:g}{hint}."
        )
    rh = values.get("relative_humidity_pct", DEFAULT_RELATIVE_HUMIDITY_PCT)
    if not (math.isfinite(rh) and 0.0 <= rh <= 100.0):
        raise ProtocolError(
            f"{src}: 'relative_humidity_pct' in [{label}] is a relative humidity in per cent, "
            f"0–100, but it is {rh:g}."
        )
    return Water(type="air", temperature_C=t, pressure_Pa=float(pressure),
                 relative_humidity_pct=float(rh))


#: The note of a day in air: which of towtank's water-only checks are skipped and why.
AIR_NOTE = (
    "[water] type = \"air\": the forces are normalised with the air's density (CIPM-2007) and "
    "viscosity (Sutherland); the water-only checks are skipped: [model] mass_kg against the "
    "displaced mass (a model in air is not ballasted near neutral buoyancy), the added mass "
    "against ρV (in air it is below the weighing's uncertainty) and Froude similarity and "
    "depth (no free surface)."
)


def _air_notes(water: Water, model: Model | None, prototype_water_given: bool) -> list[str]:
    """The day's notes for a rig in air (none in water)."""
    if not water.is_air:
        return []
    out = [AIR_NOTE]
    if model is not None and model.depth_m is not None:
        out.append("[model] depth_m is ignored in air: there is no free surface to be deep "
                   "below.")
    if not prototype_water_given:
        out.append("[prototype.water] is not given: the prototype is taken in sea water at "
                   "15 °C (the default); give [prototype.water] type = \"air\" for a "
                   "prototype in air.")
    return out


def slugify(text: str) -> str:
    """A file-system-safe folder name from a campaign name."""
    slug = re.sub(r"[^A-Za-z0-9]+", "_", text).strip("_").lower()
    return slug or "campaign"


#: [model] areas given with a diameter, against the body of revolution of that length L and
#: diameter D [m]: (key, what it is compared with, its value from L and D, the range of
#: ratios a hull has, the units a ratio far outside suggests). Wetted area against the
#: cylinder's side πDL (a Myring hull about 0.75–0.9 of it, a double cone 0.5, a hull with
#: fins and appendages up to about 1.2); frontal area against πD²/4 (fins add a little);
#: lateral area against L·D (0.7–0.9 for a Myring profile). A volume in other units is
#: caught with the mass (:func:`towtank.ingest.sections.check_mass`).
AREA_CHECKS: tuple[tuple[str, str, Callable[[float, float], float], tuple[float, float],
                         str], ...] = (
    ("wetted_area_m2", "π·D·L", lambda L, D: math.pi * D * L, (0.3, 1.5), "cm² or mm²"),
    ("frontal_area_m2", "π·D²/4", lambda L, D: math.pi * D * D / 4.0, (0.5, 3.0),
     "cm² or mm²"),
    ("lateral_area_m2", "L·D", lambda L, D: L * D, (0.3, 1.5), "cm² or mm²"),
)


def _area_warnings(model: Model) -> list[str]:
    """One sentence per [model] area that no hull of its length and diameter has
    (:data:`AREA_CHECKS`): a unit slip (cm² for m²) that would scale the drag coefficients or
    the form factor by a power of ten. Nothing without a diameter (a ship)."""
    L, D = model.length_m, model.diameter_m
    if not D or not 0.05 <= L <= 20.0 or not 0.005 <= D <= 3.0:
        return []  # a length or diameter in other units: their own warnings name it
    out = []
    for key, against, size, (lo, hi), units in AREA_CHECKS:
        value = getattr(model, key)
        if value is None or key in model.myring_computed:
            continue
        ratio = value / size(L, D)
        if not lo <= ratio <= hi:
            out.append(f"[model] {key} = {value:g} m² is {ratio:.3g} times {against} = "
                       f"{size(L, D):.3g} m² of a body {L:g} m long and {D:g} m across, "
                       f"where a hull has {lo:g}–{hi:g} times it: was it given in {units}?")
    return out


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
        out += _area_warnings(model)
    if fin is not None:
        check(fin.chord_m, 0.005, 5.0, "[fin] chord_m", "was it given in mm or cm?")
        check(fin.span_m, 0.005, 10.0, "[fin] span_m", "was it given in mm or cm?")
    check(water.temperature_C, 0.0, 40.0, "[water] temperature_C", "was it given in K or °F?")
    for label, w in (("water", water), ("prototype.water", prototype.water if prototype else None)):
        if w is None or not w.is_air:
            continue
        rh = w.relative_humidity_pct
        if rh is not None and 0.0 < rh <= 1.0:
            out.append(f"[{label}] relative_humidity_pct = {rh:g} is in per cent: was it given "
                       f"as a fraction ({rh * 100:g} %)?")
        check(w.pressure_Pa, 60.0e3, 110.0e3, f"[{label}] pressure_Pa",
              "there the CIPM-2007 air density is extrapolated (was it the absolute pressure "
              "in Pa?)")
    if prototype is not None:
        pw = prototype.water
        check(pw.temperature_C, 0.0, 40.0, "[prototype.water] temperature_C",
              "was it given in K or °F?" if pw.is_air else
              "there the ITTC water properties, and so the prototype's Re and drag, are "
              "extrapolated (was it given in K or °F?)")
        if pw.type == "sea":
            check(pw.salinity_g_kg, 0.0, 42.0, "[prototype.water] salinity_g_kg",
                  "there the sea-water properties are extrapolated (was it given in ‰ × 10?)")
    return out


def load_protocol(
    path: str | Path, *, check_paths: bool = True, require_runs: bool = True
) -> Protocol:
    """Read and validate a protocol file.

    Parameters
    ----------
    path : str or Path
        The protocol (TOML) file.
    check_paths : bool
        Check that the run sheet and the data folder exist.
    require_runs : bool
        False for a protocol read by ``towtank predict``: [campaign] may leave out the run
        sheet and the data folder (and its name: the file's stem).

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
    except RecursionError:
        raise ProtocolError(f"{src}: its tables or lists are nested too deeply to be a "
                            "protocol.") from None
    except ValueError:  # Python's bound on the digits of an integer it converts from text
        raise ProtocolError(f"{src}: {_long_integer_key(text)} is an integer of more than "
                            f"{sys.get_int_max_str_digits()} digits, not a number a protocol "
                            "can hold.") from None

    for key in data:
        if key not in TOP_LEVEL:
            raise ProtocolError(f"{src}: unknown section [{key}]{suggest(key, TOP_LEVEL)}")
    if not require_runs:  # towtank predict: the vehicle and the water are enough
        camp = data.setdefault("campaign", {})
        if isinstance(camp, dict):
            camp.setdefault("name", path.stem)
            for key in ("run_sheet", "data_dir"):
                if key not in camp:
                    camp[key], check_paths = ".", False
    _means_for_runs(data)
    for required in ("campaign", "water"):
        if required not in data:
            raise ProtocolError(f"{src}: the required section [{required}] is missing.")

    try:
        protocol = _build(path, src, data, check_paths)
    except (OSError, ValueError) as exc:  # an unusable path on this file system
        raise ProtocolError(f"{src}: a path in the protocol cannot be used ({exc}).") from None
    except ArithmeticError:  # an overflow from a number far too large: name it
        check_magnitudes(data, src)
        raise
    # [vehicle]'s numbers are checked against the vehicle they describe by the vehicle stage
    check_magnitudes({k: v for k, v in data.items() if k != "vehicle"}, src)
    return protocol


#: Marks a [campaign] whose run_sheet and data_dir stand for the [captive] means table.
_MEANS_ONLY = "__means_only__"


def _means_for_runs(data: dict[str, Any]) -> None:
    """A protocol with ``[captive] means`` may leave out [campaign] run_sheet and data_dir
    (both left out): they are set to the table (see :class:`Campaign` ``sheet_given``)."""
    camp, captive = data.get("campaign"), data.get("captive")
    if not (isinstance(camp, dict) and isinstance(captive, dict) and
            isinstance(captive.get("means"), str)):
        return
    if "run_sheet" not in camp and "data_dir" not in camp:
        camp["run_sheet"] = camp["data_dir"] = captive["means"]
        camp[_MEANS_ONLY] = True


def _long_integer_key(text: str) -> str:
    """The key (``'mass_kg'``) holding the first integer of more digits than Python converts
    from text, in a protocol's text; ``a value`` when it cannot be told."""
    digits = re.search(rf"[0-9_]{{{max(sys.get_int_max_str_digits(), 1) + 1},}}", text)
    keys = re.findall(r"([A-Za-z0-9_-]+)[\"']?\s*=", text[: digits.start()]) if digits else []
    return f"'{keys[-1]}'" if keys else "a value"


def _build(path: Path, src: str, data: dict[str, Any], check_paths: bool) -> Protocol:
    """The validated protocol from parsed TOML (see :func:`load_protocol`)."""
    base = path.resolve().parent
    campaign = _campaign(data["campaign"], base, src, check_paths)
    water = _water(checked_section(data["water"], "water", "water", src), "water", src)

    model = _model(data["model"], src, water, captive="captive" in data) \
        if "model" in data else None
    fin = _fin(data["fin"], src) if "fin" in data else None

    vehicle = None
    if "vehicle" in data and water.is_air:
        raise ProtocolError(
            f"{src}: [vehicle] predicts an underwater vehicle, but [water] type is \"air\"; "
            "remove [vehicle] or set [water] type to fresh or sea."
        )
    if "vehicle" in data:
        vehicle = parse_vehicle(data["vehicle"], base, src,
                                model.myring if model is not None else None, check_paths)
    if model is None and fin is None and vehicle is None:
        raise ProtocolError(f"{src}: the protocol needs a [model] or a [fin] section.")

    captive = parse_captive(data["captive"], base, src, check_paths) \
        if "captive" in data else None
    if captive is not None and captive.means is not None:
        missing = captive_model_missing(model, captive, ())
        if model is None:
            raise ProtocolError(f"{src}: [captive] means needs a [model] section (its length "
                                "and the origin the table's moments are about).")
        if missing:
            raise ProtocolError(
                f"{src}: [captive] means needs {' and '.join(missing)} in [model]"
                + (" (the x from the origin O of the point the table's yaw moments are about; "
                   "0 when they are about O)." if missing == ["balance_x_m"] else "."))
    prototype = _prototype(data["prototype"], model, src) if "prototype" in data else None
    channels = _channels(data["channels"], src) if "channels" in data else {}
    balance = parse_balance(data["balance"], channels, src) if "balance" in data else None

    processing = _processing(data.get("processing", {}), src)
    report = ReportOptions(**checked_section(data.get("report", {}), "report", "report", src))
    read = parse_read_options(checked_section(data.get("read", {}), "read", "read", src), src)
    if processing.speed_source == "nominal" and ("speed_log" in data or "speed" in channels):
        given = "[speed_log]" if "speed_log" in data else "[channels] speed"
        raise ProtocolError(
            f"{src}: [processing] speed_source = \"nominal\" takes each run's speed from the "
            f"run sheet, but {given} gives a measured one: keep one of the two.")

    warnings = _unit_warnings(model, fin, water, prototype) + _air_notes(
        water, model, "water" in data.get("prototype", {}) if prototype else True)
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
        read=read,
        vehicle=vehicle,
        balance=balance,
        tare=parse_tare(data.get("tare", {}), base, src, check_paths),
        speed_log=parse_speed_log(data.get("speed_log"), src),
        zeros=parse_zero_file(data.get("zeros"), src),
        sheet=parse_sheet_options(data.get("sheet"), src),
        watch=_watch(data.get("watch", {}), src),
        captive=captive,
    )


def _campaign(data: Any, base: Path, src: str, check_paths: bool) -> Campaign:
    """``[campaign]``: paths resolved, the reference and (with ``check_paths``) the sheet and
    data folder checked."""
    means_only = bool(data.pop(_MEANS_ONLY, False)) if isinstance(data, dict) else False
    camp = checked_section(data, "campaign", "campaign", src)

    output_dir = (
        base / camp["output_dir"]
        if "output_dir" in camp
        else Path.cwd() / "reports" / slugify(camp["name"])
    )
    reference = camp.get("reference", "remus")
    if reference not in BUILTIN_REFERENCES:
        ref_path = base / reference
        if check_paths and not is_regular_file(ref_path):
            raise ProtocolError(
                f"{src}: the reference '{reference}' in [campaign] is neither a built-in "
                f"set ({', '.join(BUILTIN_REFERENCES)}) nor an existing CSV file ({ref_path})."
            )
        reference = str(ref_path)
        if check_paths:
            read_reference_csv(ref_path)  # a bad reference stops here, before any work
    campaign = Campaign(
        name=camp["name"],
        run_sheet=_resolved(base, camp["run_sheet"], "run_sheet", src),
        data_dir=_resolved(base, camp["data_dir"], "data_dir", src),
        output_dir=_resolved(base, output_dir, "output_dir", src),
        reference=reference,
        test_date=camp.get("test_date"),
        sheet_given=not means_only,
    )
    if check_paths and campaign.sheet_given:  # [captive] means is checked with [captive]
        kind = path_kind(campaign.run_sheet)
        if kind != FILE:
            what = {FOLDER: "is a folder", OTHER: "is not a regular file (a pipe or a device)",
                    MISSING: "does not exist"}.get(kind, f"cannot be opened ({kind})")
            raise ProtocolError(
                f"{src}: the run sheet '{camp['run_sheet']}' in [campaign] {what} "
                f"({campaign.run_sheet})."
            )
        if campaign.run_sheet.suffix.lower() not in (".csv", ".xlsx"):
            raise ProtocolError(
                f"{src}: the run sheet '{camp['run_sheet']}' must be a .csv or .xlsx file."
            )
        kind = path_kind(campaign.data_dir)
        if kind != FOLDER:
            what = {FILE: "is a file, not a folder", OTHER: "is not a folder",
                    MISSING: "does not exist"}.get(kind, f"cannot be opened ({kind})")
            raise ProtocolError(
                f"{src}: the data folder '{camp['data_dir']}' in [campaign] {what} "
                f"({campaign.data_dir})."
            )
    return campaign


def _resolved(base: Path, given: str | Path, key: str, src: str) -> Path:
    """The path ``given`` for ``key`` in [campaign] (relative to ``base``), absolute with its
    links resolved; a ProtocolError when it cannot be (a symlink loop, a name too long)."""
    out = resolved(base / given)
    if isinstance(out, str):
        raise ProtocolError(f"{src}: the {key} '{given}' in [campaign] cannot be opened ({out}).")
    return out


#: [model] keys that are positions along x from the origin O [m]: any sign, within the length.
SIGNED_MODEL_KEYS = ("xg_m", "balance_x_m")


def _model(data: Any, src: str, water: Water | None = None, *, captive: bool = False
           ) -> Model:
    """``[model]`` checked, its Myring geometry filled in and its mass checked. A model of a
    protocol with ``[captive]`` (``captive``) may leave out its diameter and frontal area."""
    m = checked_section(data, "model", "model", src)
    check_positive(
        m,
        tuple(k for k, (kind, _) in SCHEMA["model"].items()
              if kind == NUM and k not in SIGNED_MODEL_KEYS),
        "model",
        src,
    )
    for key in SIGNED_MODEL_KEYS:
        if key in m and not abs(m[key]) < m["length_m"]:
            raise ProtocolError(
                f"{src}: '{key}' in [model] is {m[key]:g} m from the origin, but the model is "
                f"{m['length_m']:g} m long: was it given in mm or cm?")
    myring = None
    if "myring" in m:
        my = checked_section(m.pop("myring"), "model.myring", "model.myring", src)
        check_positive(my, ("a", "b", "c", "n", "d"), "model.myring", src)
        myring = Myring(**my)
    if "diameter_m" not in m and "frontal_area_m2" not in m and myring is None and not captive:
        raise ProtocolError(
            f"{src}: [model] needs 'diameter_m' (or 'frontal_area_m2') for the frontal area."
        )
    model = Model(**{"diameter_m": None, **m}, myring=myring)
    if myring is not None:
        model = _with_myring_geometry(model, src)
    if water is None or not water.is_air:  # in air the displaced mass bounds nothing
        check_mass(model, src)
    return model


def _fin(data: Any, src: str) -> Fin:
    """``[fin]`` checked (NACA 0015 only: the shipped section data)."""
    f = checked_section(data, "fin", "fin", src)
    check_positive(f, ("chord_m", "span_m", "oswald_e", "linear_max_deg"), "fin", src)
    if f.get("linear_max_deg", 0.0) > 90.0:
        raise ProtocolError(
            f"{src}: 'linear_max_deg' in [fin] is the largest angle of attack of the "
            f"linear range, 0–90°, but it is {f['linear_max_deg']}."
        )
    mounting = f.get("mounting", "free")
    if mounting not in FIN_MOUNTINGS:
        raise ProtocolError(
            f"{src}: 'mounting' in [fin] must be one of {', '.join(FIN_MOUNTINGS)}, "
            f"but it is {mounting!r}{suggest(mounting, FIN_MOUNTINGS)}"
        )
    section = f.get("section", "NACA0015")
    if section.replace(" ", "").upper() != "NACA0015":
        raise ProtocolError(
            f"{src}: [fin] section {section!r} has no shipped section data; "
            "only NACA0015 (Sandia, SAND80-2114) is available."
        )
    return Fin(**f)


def check_prototype_speed_range(speeds: Sequence[float], where: str) -> None:
    """Prototype speeds [m/s], each > 0 and at most :data:`MAX_PROTOTYPE_SPEED` (NaN is
    neither): those of ``[prototype] speeds_m_s`` and of ``towtank scale --speeds`` alike.

    Parameters
    ----------
    speeds : sequence of float
        The prototype speeds [m/s]
    where : str
        What gave them, the start of the sentence (``"p.toml: 'speeds_m_s' in [prototype]"``,
        ``"--speeds"``)

    Raises
    ------
    ProtocolError
        One sentence naming them and the bound; a speed over it that is one in mm/s (a
        thousandth of it lies within) is named as such.
    """
    if all(0 < s <= MAX_PROTOTYPE_SPEED for s in speeds):
        return
    slip = ("; was it given in mm/s for m/s?"
            if all(0 < s / 1000.0 <= MAX_PROTOTYPE_SPEED for s in speeds)
            and any(s > MAX_PROTOTYPE_SPEED for s in speeds) else ".")
    raise ProtocolError(
        f"{where} must all be positive prototype speeds up to {MAX_PROTOTYPE_SPEED:g} m/s, but "
        f"they are {', '.join(f'{s:g}' for s in speeds)}{slip}"
    )


def _prototype(data: Any, model: Model | None, src: str) -> Prototype:
    """``[prototype]``: its length (given, or the model's × scale, which must agree), speeds,
    roughness allowance and water."""
    p = checked_section(data, "prototype", "prototype", src)
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
    check_prototype_speed_range(p["speeds_m_s"], f"{src}: 'speeds_m_s' in [prototype]")
    delta_cf = p.get("delta_cf", 0.0)
    if abs(delta_cf) > MAX_DELTA_CF:
        raise ProtocolError(
            f"{src}: 'delta_cf' in [prototype] is {delta_cf:g}, but a roughness allowance "
            f"ΔC_F lies within ±{MAX_DELTA_CF:g} (the ITTC value for a full-size hull is "
            "about 0.0004)."
        )
    pw = (
        _water(checked_section(p["water"], "prototype.water", "prototype.water", src),
               "prototype.water", src)
        if "water" in p
        else Water(type="sea", temperature_C=15.0)
    )
    return Prototype(
        length_m=length_p,
        speeds_m_s=p["speeds_m_s"],
        water=pw,
        delta_cf=delta_cf,
    )


def read_and_channels(data: dict[str, Any], src: str
                      ) -> tuple[ReadOptions, dict[str, ChannelMap]]:
    """The ``[read]`` and ``[channels]`` of a protocol fragment (a parsed TOML table, such as
    the block ``towtank inspect`` proposes), checked exactly as :func:`load_protocol` checks
    them (ProtocolError otherwise)."""
    check_keys(data, ["read", "channels"], "fragment", src)
    channels = _channels(data["channels"], src) if "channels" in data else {}
    read = parse_read_options(checked_section(data.get("read", {}), "read", "read", src), src)
    return read, channels


def _channels(data: Any, src: str) -> dict[str, ChannelMap]:
    """``[channels]``: each channel's column (or summed load cells), gain and offset."""
    channels: dict[str, ChannelMap] = {}
    ch = checked_section(data, "channels", "channels", src)
    for name, spec in ch.items():
        c = checked_section(spec, "channel", f"channels.{name}", src)
        if c.get("gain", 1.0) == 0:
            raise ProtocolError(f"{src}: 'gain' in [channels.{name}] must not be zero.")
        if ("column" in c) == ("columns" in c):
            raise ProtocolError(
                f"{src}: [channels.{name}] needs either 'column' (one column) or 'columns' "
                "(load cells summed), not both nor neither."
            )
        if "columns" in c:
            c["column"] = " + ".join(c["columns"])
        c["calibrated"] = "gain" in c or "offset" in c
        if "unit" in c:
            c["unit"] = _channel_unit(name, c["unit"], "gain" in c, src)
        channels[name] = ChannelMap(**c)
    return channels


def _channel_unit(name: str, unit: str, has_gain: bool, src: str) -> str:
    """``unit`` of [channels.<name>], checked: a unit towtank converts for that channel (or, with
    a gain, any raw unit such as V); ProtocolError otherwise."""
    unit = unit.strip()
    known = known_units(name)
    if not unit or (not has_gain and known and unit.lower() not in {k.lower() for k in known}):
        raise ProtocolError(
            f"{src}: 'unit' in [channels.{name}] is {unit!r}, which towtank cannot convert for "
            f"the {name} channel; use one of {', '.join(known)} (a channel in volts needs a "
            "'gain' [SI unit per V])."
        )
    return unit


def _processing(data: Any, src: str) -> Processing:
    """``[processing]``: positive values, ranges and choices checked."""
    proc_values = checked_section(data, "processing", "processing", src)
    check_positive(proc_values, PROCESSING_POSITIVE, "processing", src)
    for key, (low, high) in PROCESSING_RANGES.items():
        value = proc_values.get(key)
        if value is not None and not low <= value <= high:
            raise ProtocolError(
                f"{src}: '{key}' in [processing] must lie in {low:g}–{high:g}, but it is {value}."
            )
    for key, choices in PROCESSING_CHOICES.items():
        value = proc_values.get(key)
        if value is not None and value not in choices:
            raise ProtocolError(
                f"{src}: '{key}' in [processing] must be one of {', '.join(choices)}, but it is "
                f"{value!r}{suggest(value, choices)}"
            )
    return Processing(**proc_values)


#: [watch] keys' closed ranges [s].
WATCH_RANGES = {"settle_s": (0.05, 3600.0), "never_stops_s": (1.0, 86400.0),
                "pdf_interval_s": (0.0, 86400.0)}


def _watch(data: Any, src: str) -> WatchOptions:
    """``[watch]``: each time [s] a finite number in its range (:data:`WATCH_RANGES`)."""
    values = checked_section(data, "watch", "watch", src)
    for key, (low, high) in WATCH_RANGES.items():
        value = values.get(key)
        if value is not None and not low <= value <= high:
            raise ProtocolError(
                f"{src}: '{key}' in [watch] must lie in {low:g}–{high:g} s, but it is {value}.")
    return WatchOptions(**values)


def _with_myring_geometry(model: Model, src: str) -> Model:
    """Fill the areas and volume the protocol leaves out from the Myring description."""
    my = model.myring
    assert my is not None
    try:
        g = geometry.myring_geometry(
            my.a, my.b, my.c, my.n, my.theta_deg, my.d, a_offset=my.a_offset, c_offset=my.c_offset
        )
    except (ValueError, ArithmeticError) as exc:  # a division by a length of 1e-300 m
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
    return dataclasses.replace(
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
        ("lateral area", "A_lat", model.lateral_area if model.diameter_m is not None
         or model.lateral_area_m2 is not None else None, "m²",
         origin("lateral_area_m2", "L·D from length_m and diameter_m (default)"
                if model.diameter_m is not None else
                "not known (no lateral_area_m2, no diameter_m)")),
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


def output_inputs(protocol: Protocol, inputs: Iterable[str | Path] = ()) -> list[Path]:
    """The files an output folder must not overwrite: the protocol, the run sheet, a reference
    CSV the protocol names, and ``inputs`` (the run files the sheet names, wherever they lie)."""
    out = [protocol.path, protocol.campaign.run_sheet, *(Path(p) for p in inputs)]
    if protocol.campaign.reference not in BUILTIN_REFERENCES:
        out.append(Path(protocol.campaign.reference))
    return out


def with_output_dir(
    protocol: Protocol, out_dir: str | Path, inputs: Iterable[str | Path] = ()
) -> tuple[Protocol, Path]:
    """The output folder checked (:func:`towtank.runtime.outfolder.check_output_dir`) for this
    protocol's inputs, and the protocol with the folder's note among its warnings.

    The protocol is frozen and is never changed: when the check put back a set of outputs that
    an interrupted run left beside a missing folder, a new protocol (``dataclasses.replace``)
    carries that sentence with the day's warnings.

    Returns
    -------
    (Protocol, Path)
        The protocol (the one given when there is nothing to say) and the resolved folder.

    Raises
    ------
    ProtocolError
        See :func:`towtank.runtime.outfolder.check_output_dir`.
    """
    folder = outfolder.check_output_dir(out_dir, protocol.campaign.data_dir,
                                        output_inputs(protocol, inputs))
    if folder.recovered and folder.recovered not in protocol.warnings:
        protocol = dataclasses.replace(protocol, warnings=(*protocol.warnings, folder.recovered))
    return protocol, folder.path


def check_output_dir(
    out_dir: str | Path, protocol: Protocol, inputs: Iterable[str | Path] = ()
) -> Path:
    """The output folder, resolved, after :func:`with_output_dir`'s checks; the protocol is
    left as it is (a frozen protocol is never changed).

    For callers that need only the folder. A sentence about outputs put back after an
    interrupted run is given as a Python warning (:class:`UserWarning`); use
    :func:`with_output_dir` to have it among the day's warnings instead.
    """
    folder = outfolder.check_output_dir(out_dir, protocol.campaign.data_dir,
                                        output_inputs(protocol, inputs))
    if folder.recovered:
        _warnings.warn(folder.recovered, UserWarning, stacklevel=2)
    return folder.path
