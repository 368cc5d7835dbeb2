"""The protocol's ``[vehicle]`` section and its ``[[vehicle.fins]]`` (docs/formats.md).

The body a prediction and a manoeuvring model are for: its hull (Myring, DARPA SUBOFF, Series 58
or a radius table), mass properties and fin pairs. Validated like the rest of the protocol: an
unknown key, a wrong type or an impossible value is a :class:`~towtank.errors.ProtocolError`
with one sentence naming the key.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from towtank.errors import ProtocolError
from towtank.ingest import design_inputs  # powering and pressure hull (#21)
from towtank.ingest.glider_inputs import parse_glider
from towtank.ingest.schema import SCHEMA, coerce, suggest
from towtank.reference.constants import STANDARD_GRAVITY
from towtank.reference.series58 import SERIES58_PARENT, check_series58
from towtank.runtime.pathcheck import is_regular_file, resolved

HULLS = ("myring", "suboff", "series58", "table")
FIN_PLANES = ("rudder", "sternplane")

VEHICLE_SCHEMA: dict[str, tuple[str, bool]] = {
    "name": ("str", False),
    "hull": ("str", True),
    "hull_table": ("path", False),
    "myring": ("table", False),
    "series58": ("table", False),
    "length_m": ("float", False),
    "scale": ("float", False),
    "mass_kg": ("float", False),
    "weight_N": ("float", False),
    "buoyancy_N": ("float", False),
    "volume_m3": ("float", False),
    "cg_m": ("floats", False),
    "cb_m": ("floats", False),
    "inertia_kg_m2": ("floats", False),
    "speed_m_s": ("float", False),
    "origin_m": ("float", False),
    "added_mass": ("str", False),  # "towtank" | "prestero" (towtank.vehicle.predict)
    "damping": ("str", False),  # "towtank" | "prestero" (towtank.vehicle.predict)
    "fin_lift": ("str", False),  # "towtank" | "prestero" (towtank.vehicle.predict)
    "fin_limit_deg": ("float", False),
}
#: ``[vehicle.series58]``: length and largest diameter [m], Gertler's (1950) parameters [-]
#: (default: :data:`towtank.reference.series58.SERIES58_PARENT`).
SERIES58_SCHEMA: dict[str, tuple[str, bool]] = {
    "length_m": ("float", True),
    "diameter_m": ("float", True),
    "m": ("float", False),
    "r0": ("float", False),
    "r1": ("float", False),
    "cp": ("float", False),
}
FIN_SCHEMA: dict[str, tuple[str, bool]] = {
    "plane": ("str", True),
    "x_m": ("float", True),
    "span_m": ("float", True),
    "chord_m": ("float", True),
    "section": ("str", False),
    "taper": ("float", False),
    "x_drag_m": ("float", False),
}


@dataclass(frozen=True)
class VehicleFin:
    """One ``[[vehicle.fins]]`` entry: a pair of fins (both sides of the hull) [m]."""

    plane: str
    x_m: float
    span_m: float
    chord_m: float
    section: str = "NACA0012"
    taper: float = 1.0
    x_drag_m: float | None = None  # centre of the fins' cross-flow drag, default x_m


@dataclass(frozen=True)
class Vehicle:
    """The validated ``[vehicle]`` section.

    ``myring`` holds the Myring parameters (a, b, c, n, theta_deg, d, a_offset, c_offset) of
    ``[vehicle.myring]``, else of ``[model.myring]``; ``series58`` the length, diameter and
    Gertler parameters of ``[vehicle.series58]`` (the defaults filled in); ``scale``
    multiplies every length of the hull (a prototype described by its model's hull);
    ``origin_m`` is the reference point aft of the nose tip, None for the centre of buoyancy.
    The mass properties are used as given; None means not given
    (:func:`towtank.vehicle.model.mass_properties` then computes it from the hull and says so
    in model.json ``sources``): ``mass_kg`` [kg] (else ``weight_N``/g,
    else neutrally buoyant), ``weight_N`` [N] (else mass g), ``buoyancy_N`` [N] (else
    rho g ``volume_m3``, else rho g times the hull's volume), ``cb_m`` [m] (else the hull's
    centre of buoyancy), ``cg_m`` [m] (else the centre of buoyancy).
    """

    hull: str
    name: str = "vehicle"
    hull_table: Path | None = None
    myring: dict[str, float] | None = None
    series58: dict[str, float] | None = None
    length_m: float | None = None
    scale: float = 1.0
    mass_kg: float | None = None
    weight_N: float | None = None  # noqa: N815 (the key's name)
    buoyancy_N: float | None = None  # noqa: N815
    volume_m3: float | None = None
    cg_m: tuple[float, float, float] | None = None
    cb_m: tuple[float, float, float] | None = None
    inertia_kg_m2: tuple[float, float, float] | None = None
    speed_m_s: float = 1.5
    origin_m: float | None = None
    fin_limit_deg: float | None = None
    fins: tuple[VehicleFin, ...] = ()
    added_mass: str = "towtank"
    damping: str = "towtank"
    fin_lift: str = "towtank"
    propeller: dict[str, Any] | None = None  # [vehicle.propeller] (towtank.ingest.design_inputs)
    pressure_hull: dict[str, Any] | None = None  # [vehicle.pressure_hull]
    glider: dict[str, Any] | None = None  # [vehicle.glider] (towtank.vehicle.glider_controls)
    assumed: dict[str, str] | None = None  # [vehicle.assumed]: {input: why it is a guess}


def _check(values: dict[str, Any], spec: dict[str, tuple[str, bool]], label: str,
           src: str) -> dict[str, Any]:
    if not isinstance(values, dict):
        raise ProtocolError(f"{src}: [{label}] must be a table of keys, but it is {values!r}.")
    out: dict[str, Any] = {}
    for key, value in values.items():
        if key not in spec:
            raise ProtocolError(
                f"{src}: unknown key '{key}' in [{label}]{suggest(key, list(spec))}")
        out[key] = coerce(value, spec[key][0], f"'{key}' in [{label}]", src)
    for key, (_, required) in spec.items():
        if required and key not in out:
            raise ProtocolError(f"{src}: [{label}] is missing the required key '{key}'.")
    return out


def _triple(values: dict[str, Any], key: str, src: str) -> None:
    if key in values and len(values[key]) != 3:
        raise ProtocolError(
            f"{src}: '{key}' in [vehicle] must be three numbers [x, y, z], not "
            f"{len(values[key])}.")


#: Largest relative difference between a given ``weight_N`` and ``mass_kg`` g [-] (as in
#: model.json, :data:`towtank.vehicle.schema.WEIGHT_TOLERANCE`).
WEIGHT_TOLERANCE = 0.01


def _check_weight(v: dict[str, Any], src: str) -> None:
    """Both ``mass_kg`` [kg] and ``weight_N`` [N] given: W = m g within 1 %."""
    if "mass_kg" in v and "weight_N" in v:
        mg = v["mass_kg"] * STANDARD_GRAVITY
        if math.isfinite(mg) and abs(v["weight_N"] - mg) > WEIGHT_TOLERANCE * mg:
            raise ProtocolError(f"{src}: 'weight_N' = {v['weight_N']:g} N in [vehicle] must be "
                                f"mass_kg x g ({mg:.6g} N) within 1 %; give one of them.")


def parse_vehicle(data: Any, base: Path, src: str, model_myring: Any = None,
                  check_paths: bool = True) -> Vehicle:
    """The validated ``[vehicle]`` section.

    Parameters
    ----------
    data : dict
        The parsed TOML table ``[vehicle]`` (with its ``fins`` array of tables)
    base : Path
        Folder of the protocol (``hull_table`` is relative to it)
    src : str
        The protocol's file name, for the messages
    model_myring : object, optional
        The ``[model.myring]`` description, used when ``hull = "myring"`` has none of its own
    check_paths : bool
        Check that the hull table exists

    Raises
    ------
    ProtocolError
        One sentence naming the key and what is wrong.
    """
    if not isinstance(data, dict):
        raise ProtocolError(f"{src}: [vehicle] must be a table of keys, but it is {data!r}.")
    data = dict(data)
    fins_raw = data.pop("fins", [])
    design = {k: getattr(design_inputs, f"parse_{k}")(data.pop(k), src)
              for k in ("propeller", "pressure_hull") if k in data}
    if "glider" in data:  # ballast, moving mass, roll mass, wings (#26)
        design["glider"] = parse_glider(data.pop("glider"), src)
    if "assumed" in data:
        design["assumed"] = _assumed(data.pop("assumed"), src, design.get("glider"))
    v = _check(data, VEHICLE_SCHEMA, "vehicle", src)
    if v["hull"] == "drdc":
        raise ProtocolError(
            f"{src}: towtank has no 'drdc' hull (the DRDC standard submarine's bow and stern "
            "equations could not be found, docs/method.md \"Hull families\"), so give the body "
            "as a radius table: hull = \"table\" with hull_table = a CSV of the columns x_m, r_m "
            "from nose to tail (the other hulls are myring, suboff, series58).")
    if v["hull"] not in HULLS:
            raise ProtocolError(f"{src}: 'hull' in [vehicle] must be one of {', '.join(HULLS)}, "
                            f"but it is {v['hull']!r}{suggest(v['hull'], HULLS)}")
    for key in ("length_m", "scale", "mass_kg", "speed_m_s", "weight_N", "buoyancy_N",
                "volume_m3"):
        if key in v and not v[key] > 0:
            raise ProtocolError(f"{src}: '{key}' in [vehicle] must be positive, but it is "
                                f"{v[key]}.")
    if "fin_limit_deg" in v and not 0 < v["fin_limit_deg"] <= 45:
        raise ProtocolError(f"{src}: 'fin_limit_deg' in [vehicle] must be more than 0 and at "
                            f"most 45 deg, but it is {v['fin_limit_deg']}.")
    if "buoyancy_N" in v and "volume_m3" in v:
        raise ProtocolError(f"{src}: [vehicle] gives both 'buoyancy_N' and 'volume_m3'; give "
                            "one of them (the buoyancy is rho g V).")
    _check_weight(v, src)
    for key in ("cg_m", "cb_m", "inertia_kg_m2"):
        _triple(v, key, src)
    if "inertia_kg_m2" in v and min(v["inertia_kg_m2"]) <= 0:
        raise ProtocolError(f"{src}: 'inertia_kg_m2' in [vehicle] must be three positive "
                            "moments of inertia [Ixx, Iyy, Izz].")
    myring = None
    if "myring" in v:
            myring = _check(v.pop("myring"), {k: s for k, s in SCHEMA["model.myring"].items()},
                        "vehicle.myring", src)
    elif model_myring is not None:
        myring = {k: float(getattr(model_myring, k)) for k in
                  ("a", "b", "c", "n", "theta_deg", "d", "a_offset", "c_offset")}
    if v["hull"] == "myring" and myring is None:
        raise ProtocolError(f"{src}: [vehicle] hull = \"myring\" needs a [vehicle.myring] or "
                            "[model.myring] description.")
    series58 = _series58(v.pop("series58", None), v["hull"], src)
    table: Path | None = None
    if v["hull"] == "table":
        if "hull_table" not in v:
            raise ProtocolError(f"{src}: [vehicle] hull = \"table\" needs 'hull_table', a CSV "
                                "with the columns x_m, r_m.")
        given = base / v.pop("hull_table")
        found = resolved(given)
        if isinstance(found, str):
            raise ProtocolError(f"{src}: the hull table in [vehicle] cannot be opened ({found}: "
                                f"{given}).")
        table = found
        if check_paths and not is_regular_file(table):
            raise ProtocolError(f"{src}: the hull table in [vehicle] does not exist ({table}).")
    else:
        v.pop("hull_table", None)
    if not isinstance(fins_raw, list):
        raise ProtocolError(f"{src}: [[vehicle.fins]] must be an array of tables (one "
                            "[[vehicle.fins]] header per fin pair).")
    fins = []
    for i, f in enumerate(fins_raw, start=1):
        label = f"vehicle.fins #{i}"
        fv = _check(f, FIN_SCHEMA, label, src)
        if fv["plane"] not in FIN_PLANES:
            raise ProtocolError(f"{src}: 'plane' in [{label}] must be one of "
                                f"{', '.join(FIN_PLANES)}, but it is {fv['plane']!r}.")
        for key in ("span_m", "chord_m", "taper"):
            if key in fv and not (math.isfinite(fv[key]) and fv[key] > 0):
                raise ProtocolError(f"{src}: '{key}' in [{label}] must be positive, but it is "
                                    f"{fv[key]}.")
        fins.append(VehicleFin(**fv))
    return Vehicle(**v, hull_table=table, myring=myring, series58=series58, fins=tuple(fins),
                   **design)


def _assumed(raw: Any, src: str, glider: dict[str, Any] | None) -> dict[str, str]:
    """``[vehicle.assumed]``: {input: why}, the inputs the protocol guessed (a [vehicle] key,
    ``fins`` or ``glider.KEY``), each with its reason as text."""
    if not isinstance(raw, dict):
        raise ProtocolError(f"{src}: [vehicle.assumed] must be a table of input = \"why it is "
                            f"assumed\", but it is {raw!r}.")
    known = [*VEHICLE_SCHEMA, "fins", *(f"glider.{k}" for k in (glider or {}))]
    for key, why in raw.items():
        if key not in known:
            raise ProtocolError(f"{src}: [vehicle.assumed] names '{key}', which is not an input "
                                f"of [vehicle]{suggest(key, known)}")
        if not isinstance(why, str) or not why.strip():
            raise ProtocolError(f"{src}: '{key}' in [vehicle.assumed] must say, as text, why it "
                                f"is assumed, not {why!r}.")
    return {k: str(v).strip() for k, v in raw.items()}


def _series58(raw: Any, hull: str, src: str) -> dict[str, float] | None:
    """``[vehicle.series58]`` checked: the keys, and a polynomial that is a body.

    Raises
    ------
    ProtocolError
        hull = "series58" without the section, an unknown or missing key, or parameters
        that give no body of revolution (:func:`towtank.reference.series58.check_series58`).
    """
    if raw is None:
        if hull == "series58":
            raise ProtocolError(f"{src}: [vehicle] hull = \"series58\" needs a [vehicle.series58] "
                                "section with length_m and diameter_m (and optionally m, r0, r1, "
                                "cp).")
        return None

    values = {**SERIES58_PARENT, **_check(raw, SERIES58_SCHEMA, "vehicle.series58", src)}
    try:
        check_series58(**values)
    except ValueError as exc:
        raise ProtocolError(f"{src}: [vehicle.series58]: {exc}") from None
    return {k: float(val) for k, val in values.items()}
