"""A glider's internal controls: ballast volume, moving mass and roll mass
(``[vehicle.glider]``, model.json ``glider``; docs/formats.md §6, docs/method.md "Glider
controls").

A buoyancy-driven glider steers by moving its weight, not by fins (Graver 2005, *Underwater
gliders: dynamics, control and design*, Princeton PhD thesis, ch. 2-3; Zhang, Yu, Zhang &
Zhang 2013, "Spiraling motion of underwater gliders", Ocean Eng. 60, 1-13):

- the **ballast** pumps a volume ``dV`` [cc] from its neutral state; water taken in (dV < 0)
  makes the glider heavy by ``rho g |dV|`` and adds that mass at the tank's ``ballast_x_m``:
  ``B - W = (B0 - W0) + rho g dV`` (eq. G1), ``m = m0 - rho dV``, and the centre of gravity
  ``r_g = (m0 r_g0 - rho dV r_tank) / m`` (eq. G2);
- the **moving mass** ``m_p`` slides ``dx`` along x from its neutral position:
  ``r_g += m_p dx e_x / m`` (eq. G3);
- the **roll mass** ``m_r`` turns by an angle ``gamma`` about the x axis at radius ``R``, hanging
  straight down (z = +R) at gamma = 0: ``r_g += m_r R (0, sin gamma, cos gamma - 1) / m``
  (eq. G4); a positive angle moves it to starboard and rolls the glider starboard down.

At rest the glider hangs where the moments of weight and buoyancy vanish (Fossen 2011, eq. 4.6
with the velocities zero): pitch ``tan theta = -(x_g W - x_b B) / (z_g W - z_b B)`` (eq. G5) and
roll ``tan phi = (y_g W - y_b B) / (z_g W - z_b B)`` (eq. G6, at theta = 0). In motion the
hydrodynamic moments add to these; :mod:`towtank.vehicle.spiral` solves for the travel and
the roll-mass angle that hold a pitch and a roll.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from towtank.ingest.glider_inputs import (
    GLIDER_KEYS,
    glider_problems,
    model_glider_problems,
    parse_glider,
)
from towtank.reference.constants import STANDARD_GRAVITY as G

__all__ = ["GLIDER_KEYS", "glider_problems", "model_glider_problems", "parse_glider",
           "ballast_model",
           "cg_with_controls", "net_buoyancy", "static_pitch_deg", "travel_for_static_pitch_mm",
           "static_roll_deg", "roll_mass_angle_for_static_roll_deg", "G"]

def net_buoyancy(model: dict[str, Any], ballast_cc: float) -> float:
    """Buoyancy minus weight [N] with ``ballast_cc`` [cc] pumped from neutral (eq. G1)."""
    rho = float(model["rho_kg_m3"])
    return float(model["buoyancy_N"]) - float(model["weight_N"]) + rho * G * ballast_cc * 1e-6


def ballast_model(model: dict[str, Any], ballast_cc: float) -> dict[str, Any]:
    """A copy of model.json with the ballast at ``ballast_cc`` [cc]: mass, weight and centre of
    gravity of eqs. G1-G2 (the inertia kept)."""
    glider = model.get("glider") or {}
    rho = float(model["rho_kg_m3"])
    dm = -rho * ballast_cc * 1e-6  # [kg] water taken in
    m0 = float(model["mass_kg"])
    w0 = float(model["weight_N"])
    tank = np.array([float(glider.get("ballast_x_m", 0.0)), 0.0, 0.0])
    out = dict(model)
    out["mass_kg"] = m0 + dm
    out["weight_N"] = w0 + dm * G
    out["cg_m"] = ((m0 * np.asarray(model["cg_m"], dtype=float) + dm * tank) / (m0 + dm)).tolist()
    return out


def cg_with_controls(model: dict[str, Any], travel_m: float, roll_mass_rad: float) -> np.ndarray:
    """The centre of gravity [m] with the moving mass ``travel_m`` [m] from neutral and the roll
    mass at ``roll_mass_rad`` [rad] (eqs. G3-G4); ``model`` the one of :func:`ballast_model`."""
    glider = model.get("glider") or {}
    m = float(model["mass_kg"])
    mp = float(glider.get("moving_mass_kg", 0.0))
    mr = float(glider.get("roll_mass_kg", 0.0))
    radius = float(glider.get("roll_mass_radius_m", 0.0))
    shift = np.array([mp * travel_m, mr * radius * math.sin(roll_mass_rad),
                      mr * radius * (math.cos(roll_mass_rad) - 1.0)]) / m
    return np.asarray(model["cg_m"], dtype=float) + shift


def static_pitch_deg(model: dict[str, Any], travel_mm: float) -> float:
    """The pitch [deg] at rest with the moving mass ``travel_mm`` [mm] from neutral (eq. G5)."""
    rg = cg_with_controls(model, travel_mm * 1e-3, 0.0)
    rb = np.asarray(model["cb_m"], dtype=float)
    w, b = float(model["weight_N"]), float(model["buoyancy_N"])
    return math.degrees(math.atan2(-(rg[0] * w - rb[0] * b), rg[2] * w - rb[2] * b))


def travel_for_static_pitch_mm(model: dict[str, Any], pitch_deg: float) -> float:
    """The moving mass's travel [mm] that pitches the glider at rest to ``pitch_deg`` [deg]
    (eq. G5 solved for dx)."""
    glider = model["glider"]
    rg0 = np.asarray(model["cg_m"], dtype=float)
    rb = np.asarray(model["cb_m"], dtype=float)
    w, b = float(model["weight_N"]), float(model["buoyancy_N"])
    mp = float(glider["moving_mass_kg"])
    x_gw = -math.tan(math.radians(pitch_deg)) * (rg0[2] * w - rb[2] * b) + rb[0] * b
    return 1e3 * (x_gw - rg0[0] * w) * float(model["mass_kg"]) / (mp * w)


def static_roll_deg(model: dict[str, Any], roll_mass_deg: float) -> float:
    """The roll [deg] at rest, level, with the roll mass at ``roll_mass_deg`` [deg] (eq. G6)."""
    rg = cg_with_controls(model, 0.0, math.radians(roll_mass_deg))
    rb = np.asarray(model["cb_m"], dtype=float)
    w, b = float(model["weight_N"]), float(model["buoyancy_N"])
    return math.degrees(math.atan2(rg[1] * w - rb[1] * b, rg[2] * w - rb[2] * b))


def roll_mass_angle_for_static_roll_deg(model: dict[str, Any], roll_deg: float) -> float:
    """The roll-mass angle [deg] that rolls the level glider at rest to ``roll_deg`` [deg]
    (eq. G6 solved for gamma by bisection; it is monotonic up to the largest roll the mass can
    give).

    Raises
    ------
    ValueError
        The model has no roll mass, or the roll is more than it can give.
    """
    glider = model.get("glider") or {}
    if not glider.get("roll_mass_kg") or not glider.get("roll_mass_radius_m"):
        raise ValueError("the model has no roll mass (roll_mass_kg and roll_mass_radius_m in "
                         "[vehicle.glider]), so it cannot be rolled.")
    if roll_deg == 0:
        return 0.0
    sign = 1.0 if roll_deg > 0 else -1.0
    grid = np.linspace(0.0, 180.0, 721)
    rolls = np.array([sign * static_roll_deg(model, sign * g) for g in grid])
    k = int(np.argmax(rolls))
    if rolls[k] < abs(roll_deg):
        raise ValueError(f"the roll mass can roll the glider by at most {rolls[k]:.3g} deg at "
                         f"rest, not {abs(roll_deg):g} deg.")
    lo, hi = 0.0, float(grid[k])
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if sign * static_roll_deg(model, sign * mid) < abs(roll_deg):
            lo = mid
        else:
            hi = mid
    return sign * 0.5 * (lo + hi)
