"""The ``[vehicle.glider]`` section's keys and their checks (docs/formats.md §6): ballast range
and position, moving mass and its travel, roll mass and its radius, wings. The conversions of
these controls into buoyancy, centre of gravity, pitch and roll are in
:mod:`towtank.vehicle.glider_controls`; this module only reads and checks what the user wrote.
"""

from __future__ import annotations

from typing import Any

from towtank.errors import ProtocolError
from towtank.ingest.values import finite_number

__all__ = ["GLIDER_KEYS", "glider_problems", "parse_glider"]

#: key -> (kind, required, low, high, what); "pair" = [min, max], "triple" = [x, y, z].
GLIDER_KEYS: dict[str, tuple[str, bool, float, float, str]] = {
    "ballast_cc": ("pair", True, -1e6, 1e6,
                   "the ballast's range of pumped volume from neutral [cc], [min, max]"),
    "ballast_x_m": ("float", False, -100.0, 100.0,
                    "the ballast tank's position from the reference point [m]"),
    "moving_mass_kg": ("float", True, 0.0, 1e5, "the moving (pitch) mass [kg]"),
    "moving_mass_travel_mm": ("pair", True, -1e5, 1e5,
                              "the moving mass's travel from neutral [mm], [min, max]"),
    "moving_mass_neutral_m": ("triple", False, -100.0, 100.0,
                              "the moving mass's neutral position [x, y, z] [m]"),
    "roll_mass_kg": ("float", False, 0.0, 1e5, "the roll mass [kg]"),
    "roll_mass_radius_m": ("float", False, 0.0, 100.0,
                           "the roll mass's distance from the x axis [m]"),
    "wing_area_m2": ("float", False, 0.0, 1e4, "the area of both wings [m^2]"),
    "wing_span_m": ("float", False, 0.0, 1e3, "the wings' span, tip to tip [m]"),
    "wing_sweep_deg": ("float", False, -1.0, 60.0, "the wings' quarter-chord sweep [deg]"),
    "wing_x_m": ("float", False, -100.0, 100.0,
                 "the wings' aerodynamic centre from the reference point [m]"),
    "wing_cd0": ("float", False, -1.0, 1.0, "the wings' zero-lift drag coefficient [-]"),
}
_WING = ("wing_area_m2", "wing_span_m", "wing_x_m")


def glider_problems(raw: Any, label: str, mass_kg: float | None = None) -> list[str]:
    """The problems of a ``[vehicle.glider]`` table or a model.json ``glider`` block, one
    sentence each naming the key (``label`` names the table; ``mass_kg`` [kg], when known,
    bounds the moving and roll masses)."""
    if not isinstance(raw, dict):
        return [f"{label} must be a table of keys, not {raw!r}."]
    problems = []
    for key in raw:
        if key not in GLIDER_KEYS:
            problems.append(f"unknown key '{key}' in {label} (known: {', '.join(GLIDER_KEYS)}).")
    for key, (kind, required, low, high, what) in GLIDER_KEYS.items():
        if key not in raw:
            if required:
                problems.append(f"{label} is missing the required key '{key}' ({what}).")
            continue
        value = raw[key]
        size = {"pair": 2, "triple": 3}.get(kind)
        if size is None:
            v = finite_number(value)
            if v is None or not low < v <= high:
                problems.append(f"'{key}' in {label} must be a number above {low:g} and at most "
                                f"{high:g} ({what}), not {value!r}.")
            continue
        vals = [finite_number(x) for x in value] if isinstance(value, list) else []
        if len(vals) != size or any(x is None or not low <= x <= high for x in vals):
            problems.append(f"'{key}' in {label} must be {size} finite numbers ({what}), "
                            f"not {value!r}.")
        elif kind == "pair" and not vals[0] < vals[1]:  # type: ignore[operator]
            problems.append(f"'{key}' in {label} must be [min, max] with min < max ({what}), "
                            f"not {value!r}.")
    if ("roll_mass_kg" in raw) != ("roll_mass_radius_m" in raw):
        problems.append(f"{label} gives one of 'roll_mass_kg' and 'roll_mass_radius_m'; a roll "
                        "mass needs both.")
    given = [k for k in _WING if k in raw]
    if given and len(given) != len(_WING):
        problems.append(f"{label}: wings need all of {', '.join(_WING)} (given: "
                        f"{', '.join(given)}).")
    if mass_kg is not None and not problems:
        moving = float(raw["moving_mass_kg"]) + float(raw.get("roll_mass_kg", 0.0))
        if moving >= mass_kg:
            problems.append(f"{label}: the moving and roll masses ({moving:g} kg) must be less "
                            f"than the glider's mass ({mass_kg:g} kg).")
    if not problems and "wing_area_m2" in raw:
        ar = float(raw["wing_span_m"]) ** 2 / float(raw["wing_area_m2"])
        if not 0.5 <= ar <= 50.0:
            problems.append(f"{label}: the wings' aspect ratio span^2/area is {ar:.3g}; it must "
                            "be from 0.5 to 50 (check wing_span_m and wing_area_m2).")
    return problems


def parse_glider(raw: Any, src: str) -> dict[str, Any]:
    """The checked ``[vehicle.glider]`` (floats and lists of floats).

    Raises
    ------
    ProtocolError
        Its first problem (:func:`glider_problems`) in one sentence naming the key.
    """
    problems = glider_problems(raw, "[vehicle.glider]")
    if problems:
        raise ProtocolError(f"{src}: {problems[0]}")
    return {k: ([float(x) for x in v] if isinstance(v, list) else float(v))
            for k, v in raw.items()}
