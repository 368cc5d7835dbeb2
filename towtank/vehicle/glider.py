"""Glider steady states: steady glide speed and angle against net buoyancy and pitch.

In a steady wings-level glide (no thrust, q = 0, phi = 0) the body-axis forces balance:
``X(u, w) - (W - B) sin(theta) = 0`` and ``Z(u, w) + (W - B) cos(theta) = 0``, X and Z the
hydrodynamic terms of the model (drag, lift and stern plane; C_RB and C_A give no force when
the vehicle does not rotate). For a given pitch theta and net buoyancy B - W these two equations
fix u and w (solved by :func:`scipy.optimize.root`); the glide path angle is theta - alpha,
alpha = atan2(w, u), the speed sqrt(u^2 + w^2). The pitching moment that the hydrodynamic
terms, the Munk moment of C_A and the restoring moment leave is reported as ``trim_moment_Nm``:
what a moving mass (or the stern plane) must supply to hold that pitch (zero when the pitch is
the vehicle's own trim). The same balance is the one of the glider studies (e.g. Graver 2005,
Underwater gliders: dynamics, control and design, PhD thesis, Princeton, chapter 3), written
with the model's coefficients instead of C_L(alpha), C_D(alpha), C_M(alpha).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pandas as pd
from scipy.optimize import root

from towtank.vehicle.model import coriolis_added_mass
from towtank.vehicle.simulate import Dynamics

__all__ = ["GLIDE_COLUMNS", "steady_glide", "glide_table"]

GLIDE_COLUMNS = ("net_buoyancy_N", "pitch_deg", "speed_m_s", "u_m_s", "w_m_s",
                 "angle_of_attack_deg", "glide_angle_deg", "depth_rate_m_s", "trim_moment_Nm",
                 "converged")


def steady_glide(model: dict[str, Any], net_buoyancy_n: float, pitch_deg: float,
                 sternplane_deg: float = 0.0) -> dict[str, float]:
    """The steady glide at pitch ``pitch_deg`` [deg] with buoyancy minus weight
    ``net_buoyancy_n`` [N] (module docstring). A heavy vehicle glides forward nose down
    (pitch < 0), a light one nose up; the other combinations have no forward steady glide
    and give ``converged`` = False with NaN."""
    dyn = Dynamics(model, float(model["buoyancy_N"]) - net_buoyancy_n)
    theta = math.radians(pitch_deg)
    ds = math.radians(sternplane_deg)
    net_weight = dyn.weight_n - dyn.buoyancy

    def residual(x: np.ndarray) -> np.ndarray:
        nu = np.array([x[0], 0.0, x[1], 0.0, 0.0, 0.0])
        tau = dyn.hydro(nu, 0.0, ds) - dyn.restoring(0.0, theta)
        return np.array([tau[0], tau[2]])

    # start from a drag-only glide along the body axis
    x_uu = min(dyn.x_uu, -1e-9)
    u0 = math.sqrt(abs(net_weight * math.sin(theta)) / -x_uu) if net_weight else 0.0
    # then, if that fails (a wing beyond stall), from angles of attack up to 85 deg along
    # the glide's own side (w of the sign of the net weight's heave component)
    starts = [np.array([max(u0, 0.05), 0.0])]
    speed0 = max(u0, 0.05)
    sign = 1.0 if net_weight * math.cos(theta) >= 0 else -1.0
    starts += [speed0 * np.array([math.cos(a), sign * math.sin(a)])
               for a in np.radians(np.arange(5.0, 90.0, 10.0))]
    for x0 in starts:
        sol = root(residual, x0, method="hybr", tol=1e-12)
        u, w = sol.x
        ok = bool(sol.success and u > 0 and np.max(np.abs(residual(sol.x))) < 1e-6 * max(
            1.0, abs(net_weight)))
        if ok:
            break
    nan = float("nan")
    if not ok:
        return dict(zip(GLIDE_COLUMNS, (net_buoyancy_n, pitch_deg) + (nan,) * 7 + (False,),
                        strict=True))
    nu = np.array([u, 0.0, w, 0.0, 0.0, 0.0])
    tau = dyn.hydro(nu, 0.0, ds) - coriolis_added_mass(dyn.ma, nu) - dyn.restoring(0.0, theta)
    alpha = math.atan2(w, u)
    gamma = theta - alpha
    speed = math.hypot(u, w)
    return {"net_buoyancy_N": float(net_buoyancy_n), "pitch_deg": float(pitch_deg),
            "speed_m_s": speed, "u_m_s": float(u), "w_m_s": float(w),
            "angle_of_attack_deg": math.degrees(alpha), "glide_angle_deg": math.degrees(gamma),
            "depth_rate_m_s": -speed * math.sin(gamma), "trim_moment_Nm": float(-tau[4]),
            "converged": True}


def glide_table(model: dict[str, Any], net_buoyancies_n: list[float],
                pitches_deg: list[float]) -> pd.DataFrame:
    """:func:`steady_glide` over every pair of net buoyancy and pitch (glide_table.csv)."""
    rows = [steady_glide(model, b, p) for b in net_buoyancies_n for p in pitches_deg]
    return pd.DataFrame(rows, columns=list(GLIDE_COLUMNS))
