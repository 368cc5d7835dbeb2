"""A glider's steady glides and steady spirals, with the control positions that hold them
(``towtank steady``, steady.csv; docs/method.md, "Steady glide and steady spiral").

A steady motion keeps the body-axis velocities ``nu = (u, v, w, p, q, r)`` constant while the
glider turns at a constant rate ``Omega`` about the vertical, at constant pitch theta and roll
phi. With ``phi_dot = theta_dot = 0`` and ``psi_dot = Omega`` the body rates are
``(p, q, r) = Omega (-sin theta, sin phi cos theta, cos phi cos theta)`` (Fossen 2011,
eq. 2.41 inverted), and the equations of motion at rest,
``tau_hydro(nu) - C_RB(nu) nu - C_A(nu) nu - g(eta) = 0`` (six equations; Fossen 2011,
eq. 7.190; the steady-spiral equations of Zhang et al. 2013, "Spiraling motion of underwater
gliders: modeling, analysis, and experimental results", Ocean Eng. 60, 1-13, eqs. 10-11),
fix the six unknowns ``u, v, w, Omega`` and the control positions that hold the asked pitch
and roll: the moving mass's travel ``dx`` and the roll mass's angle ``gamma``
(:mod:`towtank.vehicle.glider_controls`, eqs. G3-G4). scipy's ``root`` (MINPACK hybrd)
solves them from the wings-level glide, the roll stepped up to the asked one by continuation.

Wings level (phi = 0) the problem is the steady glide of Graver (2005, ch. 3): v = Omega = 0,
gamma = 0, the surge and heave balances fix u and w (the existing
:func:`towtank.vehicle.glider.steady_glide`) and the pitch balance the travel.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pandas as pd
from scipy.optimize import brentq, minimize_scalar, root

from towtank.reference.constants import STANDARD_GRAVITY
from towtank.vehicle.fossen import coriolis_rigid_body, restoring_matrix
from towtank.vehicle.glider import steady_glide
from towtank.vehicle.glider_controls import ballast_model, cg_with_controls, net_buoyancy
from towtank.vehicle.model import coriolis_added_mass
from towtank.vehicle.simulate import Dynamics, restoring_terms

__all__ = ["STEADY_COLUMNS", "body_rates", "equilibrium_residual", "steady_state",
           "solve_state", "steady_table", "roll_reach", "ROLL_STEP_DEG", "TOLERANCE"]

STEADY_COLUMNS = ("ballast_cc", "net_buoyancy_N", "pitch_deg", "roll_deg", "speed_m_s", "u_m_s",
                  "v_m_s", "w_m_s", "angle_of_attack_deg", "sideslip_deg", "glide_angle_deg",
                  "depth_rate_m_s", "turn_radius_m", "turn_period_s", "moving_mass_travel_mm",
                  "roll_mass_angle_deg", "converged", "note")
#: Largest step of the roll continuation [deg].
ROLL_STEP_DEG = 2.0
#: Largest force and moment left at a converged state, as a fraction of the weight [N] and of
#: the weight times the length [N m] [-].
TOLERANCE = 1e-9


def body_rates(omega_rad_s: float, phi_rad: float, theta_rad: float) -> np.ndarray:
    """Body rates p, q, r [rad/s] of a turn at ``omega_rad_s`` [rad/s] about the vertical at
    constant roll ``phi_rad`` and pitch ``theta_rad`` [rad] (module docstring)."""
    return omega_rad_s * np.array([-math.sin(theta_rad), math.sin(phi_rad) * math.cos(theta_rad),
                                   math.cos(phi_rad) * math.cos(theta_rad)])


def equilibrium_residual(dyn: Dynamics, nu: np.ndarray, phi_rad: float, theta_rad: float,
                         rg: np.ndarray) -> np.ndarray:
    """The force and moment [N, N m] left by the equations of motion at velocities ``nu``,
    roll and pitch [rad], centre of gravity ``rg`` [m] (where the glider's moving mass puts
    it; ``dyn``'s own is left as it is): ``M nu_dot``."""
    rg = np.asarray(rg, dtype=float)
    g_rows = restoring_matrix(dyn.weight_n, dyn.buoyancy, rg, dyn.rb).tolist()
    return (dyn.hydro(nu, 0.0, 0.0) - coriolis_rigid_body(dyn.mass, rg, dyn.io, nu)
            - coriolis_added_mass(dyn.ma, nu)
            - np.array(restoring_terms(g_rows, phi_rad, theta_rad)))


def _scales(dyn: Dynamics, model: dict[str, Any]) -> np.ndarray:
    length = float(model.get("length_m", 1.0))
    w = dyn.weight_n
    return np.array([w, w, w, w * length, w * length, w * length])


def _solve_glide(model: dict[str, Any], dyn: Dynamics, theta: float
                 ) -> tuple[np.ndarray, bool, str]:
    """u, w, travel of the wings-level glide."""
    net = dyn.buoyancy - dyn.weight_n
    glide = steady_glide(model, net, math.degrees(theta))
    mp = float(model["glider"]["moving_mass_kg"])
    if not glide["converged"]:
        way = ("heavy, it glides forward only nose down" if net < 0 else
               "light, it glides forward only nose up" if net > 0 else
               "neutrally buoyant, it does not glide")
        return np.zeros(3), False, f"no forward steady glide: the glider is {way}"
    u, w = glide["u_m_s"], glide["w_m_s"]
    scale = _scales(dyn, model)

    def resid(x: np.ndarray) -> np.ndarray:
        nu = np.array([x[0], 0.0, x[1], 0.0, 0.0, 0.0])
        tau = equilibrium_residual(dyn, nu, 0.0, theta, cg_with_controls(model, x[2], 0.0))
        return tau[[0, 2, 4]] / scale[[0, 2, 4]]

    dx0 = -glide["trim_moment_Nm"] / (mp * STANDARD_GRAVITY * math.cos(theta)) if mp > 0 else 0.0
    sol = root(resid, np.array([u, w, dx0]), method="hybr", tol=1e-14)
    ok = bool(np.max(np.abs(resid(sol.x))) < TOLERANCE and sol.x[0] > 0)
    return sol.x, ok, "" if ok else "the pitch balance has no solution"


def _solve_spiral(model: dict[str, Any], dyn: Dynamics, theta: float, phi_target: float,
                  start: np.ndarray) -> tuple[np.ndarray, bool, str]:
    """u, v, w, Omega, travel, gamma of the steady spiral at roll ``phi_target`` [rad], by
    continuation from ``start`` (at roll 0 or a smaller roll) in steps of ROLL_STEP_DEG."""
    scale = _scales(dyn, model)

    def resid(x: np.ndarray, phi: float) -> np.ndarray:
        nu = np.concatenate((x[:3], body_rates(x[3], phi, theta)))
        tau = equilibrium_residual(dyn, nu, phi, theta, cg_with_controls(model, x[4], x[5]))
        return tau / scale

    x = np.asarray(start, dtype=float)
    phi0 = float(start[6]) if len(start) > 6 else 0.0
    x = x[:6]
    steps = max(1, int(math.ceil(abs(math.degrees(phi_target - phi0)) / ROLL_STEP_DEG)))
    for k in range(1, steps + 1):
        phi = phi0 + (phi_target - phi0) * k / steps
        sol = root(resid, x, args=(phi,), method="hybr", tol=1e-14)
        if not np.all(np.isfinite(sol.x)) or np.max(np.abs(resid(sol.x, phi))) > 1e-6:
            return x, False, (f"no steady spiral found beyond {math.degrees(phi):.3g} deg of "
                              "roll (continuation from the glide failed)")
        x = sol.x
    ok = bool(np.max(np.abs(resid(x, phi_target))) < TOLERANCE and x[0] > 0)
    return x, ok, "" if ok else "the spiral's balance was not met to the tolerance"


def _spiral_at_gamma(model: dict[str, Any], dyn: Dynamics, theta: float, gamma: float,
                     guess: np.ndarray) -> np.ndarray | None:
    """u, v, w, Omega, travel and the roll phi [rad] of the steady spiral with the roll mass
    held at ``gamma`` [rad] (the roll now an unknown), from ``guess``; None when not met."""
    scale = _scales(dyn, model)

    def resid(y: np.ndarray) -> np.ndarray:
        nu = np.concatenate((y[:3], body_rates(y[3], y[5], theta)))
        return equilibrium_residual(dyn, nu, y[5], theta,
                                    cg_with_controls(model, y[4], gamma)) / scale

    sol = root(resid, guess, method="hybr", tol=1e-14)
    ok = np.all(np.isfinite(sol.x)) and np.max(np.abs(resid(sol.x))) < 1e-6
    return sol.x if ok else None


def roll_reach(model: dict[str, Any], dyn: Dynamics, theta: float, start: np.ndarray,
               sign: float = 1.0) -> tuple[float, float]:
    """The largest steady roll [deg] the roll mass holds at pitch ``theta`` [rad] and the
    roll-mass angle [deg] that gives it.

    The roll mass's heeling moment ``m_r g R cos(theta) sin(gamma - phi)`` peaks when the mass
    lies level across the glider (gamma = phi + 90 deg): turned further it rolls the glider
    less. The spiral is followed in the roll mass's angle gamma (the roll an unknown) from
    ``start`` (u, v, w, Omega, travel, gamma, phi of a converged glide or spiral) towards the
    side of ``sign`` (+1 starboard down) in steps of :data:`ROLL_STEP_DEG` until the roll
    falls, and the peak refined between the last steps (bounded Brent search of the roll over
    gamma).
    """
    y = np.array([*start[:5], start[6]])
    gamma = float(start[5])
    best = (abs(float(start[6])), gamma, y)
    step = sign * math.radians(ROLL_STEP_DEG)
    while abs(gamma + step) <= math.pi:
        nxt = _spiral_at_gamma(model, dyn, theta, gamma + step, y)
        if nxt is None:
            break
        gamma, y = gamma + step, nxt
        if abs(y[5]) < best[0]:
            break
        best = (abs(float(y[5])), gamma, y)
    g0, y0 = best[1], best[2]

    def minus_roll(g: float) -> float:
        sol = _spiral_at_gamma(model, dyn, theta, g, y0)
        return math.inf if sol is None else -abs(float(sol[5]))

    lo, hi = sorted((g0 - step, min(abs(g0 + step), math.pi) * sign))
    res = minimize_scalar(minus_roll, bounds=(lo, hi), method="bounded",
                          options={"xatol": 1e-6})
    if math.isfinite(res.fun) and -res.fun > best[0]:
        return math.degrees(-res.fun), math.degrees(abs(res.x))
    return math.degrees(best[0]), math.degrees(abs(g0))


def _beyond_reach(roll_deg: float, reach: tuple[float, float]) -> str:
    """The note of a roll the roll mass cannot hold."""
    side = "starboard" if roll_deg > 0 else "port"
    return (f"a roll of {roll_deg:g} deg is beyond the roll mass's reach: it holds at most "
            f"{reach[0]:.3g} deg to {side}, turned to {reach[1]:.4g} deg (its moment peaks with "
            "the mass level across the glider; turned further it rolls the glider less)")


def pitch_reach(model: dict[str, Any], dyn: Dynamics, theta: float, limit_m: float
                ) -> float | None:
    """The pitch [deg] nearest ``theta`` [rad] (towards level) at which the wings-level glide
    needs the moving mass at ``limit_m`` [m], the end of its travel that ``theta`` is beyond:
    the travel along the glides from ``theta`` towards level in 1 deg steps until it is back
    inside, then the root of travel - limit between the last two steps (Brent). None when no
    glide towards level holds the mass inside its travel."""
    def excess(th: float) -> float:
        g, ok, _ = _solve_glide(model, dyn, th)
        return float(g[2]) - limit_m if ok else math.nan

    far, f_far = theta, excess(theta)
    towards = -math.copysign(math.radians(1.0), theta)
    for k in range(1, int(abs(math.degrees(theta))) + 1):
        near = theta + k * towards
        f_near = excess(near)
        if not math.isfinite(f_near):
            return None
        if math.copysign(1.0, f_near) != math.copysign(1.0, f_far):
            return math.degrees(brentq(excess, near, far, xtol=1e-9))
        far, f_far = near, f_near
    return None


def _row(model: dict[str, Any], ballast_cc: float, pitch_deg: float, roll_deg: float,
         x: np.ndarray | None, note: str, reach_deg: float | None = None) -> dict[str, Any]:
    nan = float("nan")
    base = {"ballast_cc": float(ballast_cc), "net_buoyancy_N": net_buoyancy(model, ballast_cc),
            "pitch_deg": float(pitch_deg), "roll_deg": float(roll_deg)}
    if x is None:
        return {**base, **{c: nan for c in STEADY_COLUMNS[4:16]}, "converged": False,
                "note": note}
    u, v, w, omega, travel, gamma = (float(a) for a in x)
    theta, phi = math.radians(pitch_deg), math.radians(roll_deg)
    speed = math.sqrt(u * u + v * v + w * w)
    zdot = (-u * math.sin(theta) + v * math.cos(theta) * math.sin(phi)
            + w * math.cos(theta) * math.cos(phi))
    horizontal = math.sqrt(max(speed * speed - zdot * zdot, 0.0))
    turning = omega != 0.0 and roll_deg != 0.0
    glider = model["glider"]
    notes = [note] if note else []
    lo, hi = glider["moving_mass_travel_mm"]
    if not lo <= travel * 1e3 <= hi:
        notes.append(f"the moving mass would need {travel * 1e3:.4g} mm of travel, outside its "
                     f"range {lo:g} to {hi:g} mm" + ("" if reach_deg is None else
                     f": the steepest pitch it holds in a straight glide at {ballast_cc:g} cc "
                     f"is {reach_deg:.3g} deg"))
    return {**base, "speed_m_s": speed, "u_m_s": u, "v_m_s": v, "w_m_s": w,
            "angle_of_attack_deg": math.degrees(math.atan2(w, u)),
            "sideslip_deg": math.degrees(math.asin(v / speed)) if speed else nan,
            "glide_angle_deg": math.degrees(math.asin(-zdot / speed)) if speed else nan,
            "depth_rate_m_s": zdot,
            "turn_radius_m": horizontal / abs(omega) if turning else nan,
            "turn_period_s": 2.0 * math.pi / abs(omega) if turning else nan,
            "moving_mass_travel_mm": travel * 1e3,
            "roll_mass_angle_deg": math.degrees(gamma), "converged": True,
            "note": "; ".join(notes)}


def steady_state(model: dict[str, Any], ballast_cc: float, pitch_deg: float,
                 roll_deg: float = 0.0) -> dict[str, Any]:
    """One row of steady.csv: the steady glide (``roll_deg`` 0) or spiral of the glider with
    ``ballast_cc`` [cc] pumped, at pitch ``pitch_deg`` [deg, nose up positive] and roll
    ``roll_deg`` [deg, starboard down positive]; columns :data:`STEADY_COLUMNS`."""
    return steady_table(model, [ballast_cc], [pitch_deg], [roll_deg]).iloc[0].to_dict()


def solve_state(model: dict[str, Any], ballast_cc: float, pitch_deg: float,
                roll_deg: float = 0.0) -> tuple[np.ndarray | None, dict[str, Any], str]:
    """The solution vector (u, v, w [m/s], Omega [rad/s], travel [m], gamma [rad]), the model
    with that ballast and the note (None and the reason when there is none)."""
    mdl = ballast_model(model, ballast_cc)
    dyn = Dynamics(mdl)
    theta = math.radians(pitch_deg)
    g, ok, note = _solve_glide(mdl, dyn, theta)
    if not ok:
        return None, mdl, note
    x = np.array([g[0], 0.0, g[1], 0.0, g[2], 0.0])
    if roll_deg == 0.0:
        return x, mdl, ""
    glider = mdl["glider"]
    if not glider.get("roll_mass_kg"):
        return None, mdl, "the glider has no roll mass (roll_mass_kg in [vehicle.glider])"
    x, ok, note = _solve_spiral(mdl, dyn, theta, math.radians(roll_deg), x)
    return (x if ok else None), mdl, note


def steady_table(model: dict[str, Any], ballasts_cc: list[float], pitches_deg: list[float],
                 rolls_deg: list[float] | None = None) -> pd.DataFrame:
    """steady.csv: :func:`steady_state` for every ballast, pitch and roll (the glide of each
    ballast and pitch first, then its spirals, each continued from the last smaller roll of the
    same sign)."""
    rolls = [0.0] if not rolls_deg else [float(r) for r in rolls_deg]
    rows = []
    for b in ballasts_cc:
        mdl = ballast_model(model, b)
        dyn = Dynamics(mdl)
        for p in pitches_deg:
            theta = math.radians(p)
            g, ok, note = _solve_glide(mdl, dyn, theta)
            glide = np.array([g[0], 0.0, g[1], 0.0, g[2], 0.0, 0.0]) if ok else None
            lo_mm, hi_mm = mdl["glider"]["moving_mass_travel_mm"]
            reach_deg = (pitch_reach(mdl, dyn, theta, (hi_mm if g[2] * 1e3 > hi_mm else lo_mm)
                                     * 1e-3)
                         if ok and not lo_mm <= g[2] * 1e3 <= hi_mm else None)
            done: dict[float, dict[str, Any]] = {}
            for sign in (1.0, -1.0):
                start = glide
                reach: tuple[float, float] | None = None
                last = glide
                for r in sorted({r for r in rolls if r * sign > 0}, key=abs):
                    if start is None and reach is not None and abs(r) > reach[0]:
                        done[r] = _row(model, b, p, r, None, _beyond_reach(r, reach))
                        continue
                    if start is None:
                        why = note if glide is None else "no steady spiral at a smaller roll"
                        done[r] = _row(model, b, p, r, None, why)
                        continue
                    if not mdl["glider"].get("roll_mass_kg"):
                        done[r] = _row(model, b, p, r, None, "the glider has no roll mass "
                                       "(roll_mass_kg in [vehicle.glider])")
                        continue
                    x, ok_s, note_s = _solve_spiral(mdl, dyn, theta, math.radians(r), start)
                    if not ok_s:
                        if reach is None and last is not None:
                            reach = roll_reach(mdl, dyn, theta, last, sign)
                        if reach is not None and abs(r) > reach[0]:
                            note_s = _beyond_reach(r, reach)
                    done[r] = _row(model, b, p, r, x if ok_s else None, note_s)
                    start = np.append(x, math.radians(r)) if ok_s else None
                    last = start if ok_s else last
            for r in rolls:
                if r == 0.0:
                    rows.append(_row(model, b, p, 0.0, glide[:6] if glide is not None else None,
                                     note, reach_deg))
                else:
                    rows.append(done[r])
    return pd.DataFrame(rows, columns=list(STEADY_COLUMNS))
