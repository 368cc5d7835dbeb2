"""The ``[vehicle.glider]`` section's keys and their checks (docs/formats.md §6): ballast range
and position, moving mass and its travel, roll mass and its radius, wings. The conversions of
these controls into buoyancy, centre of gravity, pitch and roll are in
:mod:`towtank.vehicle.glider_controls`; this module only reads and checks what the user wrote.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from towtank.errors import ProtocolError
from towtank.ingest.values import finite_number

__all__ = ["GLIDER_KEYS", "HullBounds", "glider_problems", "hull_bounds_of_model",
           "model_glider_problems", "parse_glider"]

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


@dataclass(frozen=True)
class HullBounds:
    """The hull that holds a glider's controls, for the plausibility checks of
    :func:`glider_problems`.

    Attributes
    ----------
    length_m : float
        Overall length [m]
    radius_m, volume_m3 : float or None
        Largest radius [m] and displaced volume [m^3], when known
    x_range_m : (float, float) or None
        Body-axis x of the tail end and of the nose [m] (x forward from the reference point);
        None: anywhere within one length of the reference point
    """

    length_m: float
    radius_m: float | None = None
    volume_m3: float | None = None
    x_range_m: tuple[float, float] | None = None

    def x_span(self) -> tuple[float, float]:
        """The x [m] a point inside the hull may take: the hull's own, else +- its length."""
        return self.x_range_m or (-self.length_m, self.length_m)


def hull_bounds_of_model(model: dict[str, Any]) -> HullBounds | None:
    """The :class:`HullBounds` of a model.json: its ``length_m`` and, from its ``hull`` block,
    ``diameter_m`` and ``volume_m3`` (None without a usable length)."""
    length = _number(model.get("length_m"))
    if length is None or length <= 0:
        return None
    hull = model.get("hull")
    hull = hull if isinstance(hull, dict) else {}
    diameter, volume = _number(hull.get("diameter_m")), _number(hull.get("volume_m3"))
    return HullBounds(length,
                      0.5 * diameter if diameter is not None and diameter > 0 else None,
                      volume if volume is not None and volume > 0 else None)


def _hull_problems(raw: dict[str, Any], label: str, hull: HullBounds) -> list[str]:
    """The keys of a checked ``[vehicle.glider]`` that put a control outside ``hull``: the
    moving mass's travel, the ballast's volume, the positions and the roll mass's radius; one
    sentence each naming the key, its value and the bound."""
    problems = []
    length = hull.length_m
    x_lo, x_hi = hull.x_span()
    where = (f"inside the hull (x from {x_lo:.4g} to {x_hi:.4g} m)" if hull.x_range_m
             else f"within the hull's length ({length:.4g} m) of the reference point")
    lo, hi = (v * 1e-3 for v in raw["moving_mass_travel_mm"])
    neutral = raw.get("moving_mass_neutral_m")
    if hi - lo > length or max(-lo, hi) > length:
        problems.append(f"'moving_mass_travel_mm' in {label} is {raw['moving_mass_travel_mm']}: "
                        f"the moving mass would travel {max(hi - lo, -lo, hi):.4g} m, more than "
                        f"the hull's length of {length:.4g} m that holds it.")
    elif neutral is not None and not x_lo <= neutral[0] + lo <= neutral[0] + hi <= x_hi:
        problems.append(f"'moving_mass_travel_mm' in {label} is {raw['moving_mass_travel_mm']}: "
                        f"from the neutral x of {neutral[0]:g} m it takes the moving mass "
                        f"outside the hull (x from {x_lo:.4g} to {x_hi:.4g} m).")
    b_lo, b_hi = raw["ballast_cc"]
    pumped = max(b_hi - b_lo, -b_lo, b_hi)
    if hull.volume_m3 is not None and pumped * 1e-6 > hull.volume_m3:
        problems.append(f"'ballast_cc' in {label} is {raw['ballast_cc']}: {pumped:.6g} cc of "
                        f"ballast, more than the hull's volume of {hull.volume_m3 * 1e6:.6g} cc.")
    points: list[tuple[str, float]] = [(k, raw[k]) for k in ("ballast_x_m", "wing_x_m")
                                       if k in raw]
    if neutral is not None:
        points.append(("moving_mass_neutral_m", neutral[0]))
    for key, x in points:
        if not x_lo <= x <= x_hi:
            problems.append(f"'{key}' in {label} is {raw[key]}: it must lie {where}.")
    radial = [("roll_mass_radius_m", raw.get("roll_mass_radius_m")),
              ("moving_mass_neutral_m",
               None if neutral is None else math.hypot(neutral[1], neutral[2]))]
    for key, r in radial:
        if hull.radius_m is not None and r is not None and r > hull.radius_m:
            problems.append(f"'{key}' in {label} is {raw[key]}: {r:.4g} m from the x axis, "
                            f"more than the hull's radius of {hull.radius_m:.4g} m.")
    return problems


def _number(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    v = float(value)
    return v if math.isfinite(v) else None


def glider_problems(raw: Any, label: str, mass_kg: float | None = None,
                    hull: HullBounds | None = None) -> list[str]:
    """The problems of a ``[vehicle.glider]`` table or a model.json ``glider`` block, one
    sentence each naming the key (``label`` names the table; ``mass_kg`` [kg], when known,
    bounds the moving and roll masses; ``hull``, when known, the travel, the ballast volume,
    the positions and the radii: :func:`_hull_problems`)."""
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
            problems.append(f"{label}: the moving and roll masses ('moving_mass_kg' "
                            f"{raw['moving_mass_kg']:g} kg plus 'roll_mass_kg' "
                            f"{raw.get('roll_mass_kg', 0.0):g} kg) must be less than the "
                            f"glider's mass ({mass_kg:g} kg).")
    if not problems and "wing_area_m2" in raw:
        ar = float(raw["wing_span_m"]) ** 2 / float(raw["wing_area_m2"])
        if not 0.5 <= ar <= 50.0:
            problems.append(f"{label}: the wings' aspect ratio span^2/area is {ar:.3g}; it must "
                            "be from 0.5 to 50 (check wing_span_m and wing_area_m2).")
    if not problems and hull is not None:
        problems += _hull_problems(raw, label, hull)
    return problems


def model_glider_problems(model: dict[str, Any], name: str) -> list[str]:
    """The problems of a checked model.json's ``glider`` block (``name`` the file's name):
    :func:`glider_problems` with the model's mass and hull (:func:`hull_bounds_of_model`)."""
    return glider_problems(model["glider"], f"{name}: 'glider'", float(model["mass_kg"]),
                           hull_bounds_of_model(model))


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
