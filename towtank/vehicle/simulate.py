"""6-DOF manoeuvre simulation of a Fossen-form model (model.json; docs/method.md).

``M nu_dot = tau_hydro(nu, delta) + tau_thrust - C_RB(nu) nu - C_A(nu) nu - g(eta)`` with
``eta_dot = J(eta) nu`` (Fossen 2011, eqs. 2.40, 3.56, 4.6, 6.43, 7.190), integrated by
:func:`scipy.integrate.solve_ivp` (RK45, tolerances rtol 1e-8, atol 1e-9, and a largest step).
Every coefficient ``F_<product>`` of the model that is not an added mass adds
``F * product`` to the force F, where the product reads the subscript: ``u`` a velocity,
``|u|`` its magnitude, ``dr``/``ds`` the rudder/stern-plane angle [rad] (``Y_uudr`` gives
``Y_uudr u u delta_r``, ``N_r|r|`` gives ``N_r|r| r |r|``). The propulsion (none for a glide)
balances the axial drag ``X_u|u|`` at the commanded speed on a straight course:
``propeller="thrust"`` keeps that thrust constant; ``propeller="rps"`` keeps the rate n of the
model's B-series propeller constant at its self-propulsion point, the surge force
``(1 - t) rho n^2 D^4 K_T(J)`` with ``J = u (1 - w) / (n D)`` (:mod:`towtank.vehicle.powering`),
rising as the vehicle slows.

Manoeuvres (metrics.csv ``metric, value, unit``):

- turning: rudder step at t = 0; advance and transfer at 90 deg of heading change, tactical
  diameter at 180 deg, steady turn radius: the least-squares circle of the plan track over the
  last fifth of the run;
- zigzag: rudder +-delta switched when the heading passes -+delta (the classic delta/delta test,
  the first execute to positive heading); first and second overshoot angles, period;
- dive: stern-plane step; steady pitch and depth rate; with ``dive_angle_deg`` the stern plane
  holds that pitch (nose down) by :func:`pitch_command`; time to the angle and overshoot;
- spiral: rudder and stern-plane steps; turn radius, pitch and depth change per turn;
- glide: no thrust, net buoyancy and stern plane; steady glide angle, speed, depth rate;
- sine: a sinusoidal rudder ``delta_r = A sin(2 pi t / T)`` (the identification manoeuvre of
  the REMUS Kalman-filter study, docs/method.md "Identification"); amplitudes of heading and
  yaw rate over the last half of the run;
- schedule: the rudder and stern plane follow a table of (t_s, rudder_deg, sternplane_deg),
  linearly interpolated (:func:`read_schedule`); the same amplitudes.

Steady metrics only when the last fifth of the run is steady (:mod:`towtank.vehicle.steady`),
else NaN and a note (metrics.csv ``note``).

One simulation takes at most :data:`towtank.vehicle.schema.MAX_STEPS` integration steps over
all its legs, and stops at once when the state or the forces stop being finite: whatever the
model, it ends (a ValueError with one sentence) instead of hanging.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

from towtank.vehicle import steady as sd
from towtank.vehicle.fossen import (
    DOF,
    VELOCITIES,
    added_mass_matrix,
    coriolis_added_mass,
    coriolis_rigid_body,
    quadratic_form,
    restoring_matrix,
    rigid_body_mass_matrix,
)
from towtank.vehicle.glider_controls import cg_with_controls, roll_mass_angle_for_static_roll_deg
from towtank.vehicle.powering import (
    kt_polynomial,
    propeller_from,
    propeller_thrust,
    self_propulsion_rps,
)
from towtank.vehicle.schema import MAX_STEPS, default_duration
from towtank.vehicle.wings import Wings

__all__ = ["MANOEUVRES", "PROPULSION", "Dynamics", "restoring_terms", "simulate", "propulsion",
           "default_duration",
           "manoeuvre_metrics",
           "sample_models", "pitch_command", "trim_state", "trim_warning", "TRIM_PITCH_DEG",
           "TRIM_DEPTH_RATE_M_S", "PITCH_KP", "PITCH_KD", "FIN_LIMIT_DEG"]

#: Proportional gain of the dive's pitch law, stern plane per pitch error [rad/rad].
PITCH_KP = 10.0
#: Derivative gain of the dive's pitch law, stern plane per pitch rate [rad/(rad/s)] = [s].
PITCH_KD = 3.0
#: Stern-plane (and rudder) limit of a model without ``fin_limit_deg`` [deg].
FIN_LIMIT_DEG = 20.0
#: The band of the commanded angle the dive's time to angle is measured to [-].
DIVE_ANGLE_BAND = 0.1

#: Largest steady pitch with zero controls of a model in trim [deg] (docs/formats.md §6).
TRIM_PITCH_DEG = 2.0
#: Largest steady depth rate with zero controls of a model in trim [m/s].
TRIM_DEPTH_RATE_M_S = 0.05

#: simulate's propulsion: a constant thrust, or the model's propeller at a constant rate.
PROPULSION = ("thrust", "rps")
MANOEUVRES = ("turning", "zigzag", "dive", "spiral", "glide", "sine", "schedule")
_TOKEN = re.compile(r"\|[uvwpqr]\||dr|ds|[uvwpqr]")
COLUMNS = ("t_s", "x_m", "y_m", "z_m", "phi_deg", "theta_deg", "psi_deg", "u_m_s", "v_m_s",
           "w_m_s", "p_deg_s", "q_deg_s", "r_deg_s", "rudder_deg", "sternplane_deg")


def _terms(coefficients: dict[str, float]) -> list[tuple[int, float, list[tuple[str, int]]]]:
    out = []
    for sym, val in coefficients.items():
        head, _, sub = sym.partition("_")
        if sub.endswith("dot") or float(val) == 0.0:
            continue
        tokens = _TOKEN.findall(sub)
        if "".join(tokens) != sub:
            raise ValueError(f"the coefficient symbol {sym!r} cannot be read as a product of "
                             "u, v, w, p, q, r, |.|, dr, ds.")
        spec = []
        for tok in tokens:
            if tok in ("dr", "ds"):
                spec.append((tok, 0))
            elif tok.startswith("|"):
                spec.append(("abs", VELOCITIES.index(tok[1])))
            else:
                spec.append(("vel", VELOCITIES.index(tok)))
        out.append((DOF.index(head), float(val), spec))
    return out


def _factors_of(vel: list[float], dr: float, ds: float) -> list[float]:
    """The factors the terms multiply: u, v, w, p, q, r, their absolute values, dr, ds."""
    return [*vel, *(abs(x) for x in vel), dr, ds]


def _factor_index(kind: str, i: int) -> int:
    """Index into :func:`_factors_of` of a term's factor (its kind and velocity index as
    :func:`_terms` gives them)."""
    return {"vel": i, "abs": 6 + i, "dr": 12, "ds": 13}[kind]


def restoring_terms(g_rows: list[list[float]], phi: float, theta: float) -> list[float]:
    """g(eta) [N, N m]: the rows of :func:`~towtank.vehicle.fossen.restoring_matrix`
    (``g_rows``, as Python floats) times [sin theta, cos theta sin phi, cos theta cos phi] for
    the roll ``phi`` and pitch ``theta`` [rad], their non-zero products only, in Python floats
    (the same arithmetic as numpy's, less overhead) (Fossen 2011, eq. 4.6)."""
    g = g_rows
    sth, cth, sph, cph = math.sin(theta), math.cos(theta), math.sin(phi), math.cos(phi)
    return [
        g[0][0] * sth,
        g[1][1] * cth * sph,
        g[2][2] * cth * cph,
        g[3][2] * cth * cph + g[3][1] * cth * sph,
        g[4][0] * sth + g[4][2] * cth * cph,
        g[5][1] * cth * sph + g[5][0] * sth,
    ]


@dataclass
class Dynamics:
    """The model's matrices and terms, ready for the right-hand side."""

    model: dict[str, Any]
    weight: float | None = None  # overrides the model's weight [N] (glide: B - net buoyancy)
    mass: float = field(init=False)
    m_total: np.ndarray = field(init=False)
    m_inv: np.ndarray = field(init=False)
    ma: np.ndarray = field(init=False)
    terms: list = field(init=False)
    wings: Any = field(init=False)  # a glider's wings (towtank.vehicle.wings) or None
    factors: list = field(init=False)  # the terms as (dof, value, indices into _factors_of)
    coriolis_form: np.ndarray = field(init=False)  # C_RB(nu) nu + C_A(nu) nu, quadratic_form
    g_rows: list = field(init=False)  # g(eta)'s matrix G (restoring_matrix) as Python floats

    def __post_init__(self) -> None:
        mdl = self.model
        self.weight_n = float(mdl["weight_N"] if self.weight is None else self.weight)
        self.mass = float(mdl["mass_kg"])
        self.buoyancy = float(mdl["buoyancy_N"])
        self.rg = np.asarray(mdl["cg_m"], dtype=float)
        self.rb = np.asarray(mdl["cb_m"], dtype=float)
        self.io = np.diag(np.asarray(mdl["inertia_kg_m2"], dtype=float))
        self.g_rows = restoring_matrix(self.weight_n, self.buoyancy, self.rg, self.rb).tolist()
        m_rb = rigid_body_mass_matrix(self.mass, self.rg, self.io)
        self.ma = added_mass_matrix(mdl["coefficients"])
        self.m_total = m_rb + self.ma
        self.m_inv = np.linalg.inv(self.m_total)
        self.terms = _terms(mdl["coefficients"])
        self.factors = [(dof, val, tuple(_factor_index(kind, i) for kind, i in spec))
                        for dof, val, spec in self.terms]
        self.x_uu = float(mdl["coefficients"].get("X_u|u|", 0.0))
        self.coriolis_form = quadratic_form(
            lambda nu: self.coriolis_rb(nu) + coriolis_added_mass(self.ma, nu))
        glider = mdl.get("glider")
        if isinstance(glider, dict) and "wing_area_m2" in glider:
            self.wings = Wings(glider, float(mdl.get("rho_kg_m3", 1025.0)))
        else:
            self.wings = None

    def hydro(self, nu: np.ndarray, dr: float, ds: float) -> np.ndarray:
        out = np.array(self._hydro_terms(np.asarray(nu, dtype=float)[:6].tolist(), dr, ds))
        if self.wings is not None:
            out += self.wings.force(nu)
        return out

    def _hydro_terms(self, vel: list[float], dr: float, ds: float) -> list[float]:
        # the products in Python floats, term by term in the order of the terms: the same
        # IEEE operations as on numpy scalars, without their overhead
        values = _factors_of(vel, dr, ds)
        tau = [0.0] * 6
        for dof, val, indices in self.factors:
            prod = val
            for i in indices:
                prod *= values[i]
            tau[dof] += prod
        return tau

    def coriolis_rb(self, nu: np.ndarray) -> np.ndarray:
        return coriolis_rigid_body(self.mass, self.rg, self.io, nu)

    def restoring(self, phi: float, theta: float) -> np.ndarray:
        return np.array(self._restoring_terms(phi, theta))

    def _restoring_terms(self, phi: float, theta: float) -> list[float]:
        return restoring_terms(self.g_rows, phi, theta)

    def rhs(self, state: np.ndarray, dr: float, ds: float, thrust: float) -> np.ndarray:
        phi, theta, psi = state[3:6].tolist()
        nu = state[6:]
        vel = nu.tolist()
        hydro = self._hydro_terms(vel, dr, ds)
        hydro[0] += thrust
        tau = np.array([f - g for f, g in zip(hydro, self._restoring_terms(phi, theta),
                                               strict=True)])
        if self.wings is not None:
            tau += self.wings.force(nu)
        tau -= np.outer(nu, nu).ravel() @ self.coriolis_form  # C_RB(nu) nu + C_A(nu) nu
        nu_dot = self.m_inv @ tau
        u, v, w, p, q, r = vel
        cph, sph, cth, sth = math.cos(phi), math.sin(phi), math.cos(theta), math.sin(theta)
        cps, sps = math.cos(psi), math.sin(psi)
        # position: R(phi, theta, psi) (u, v, w); attitude: T(phi, theta) (p, q, r) (Fossen
        # 2011, eqs. 2.18 and 2.29), row by row
        eta_dot = [
            cps * cth * u + (-sps * cph + cps * sth * sph) * v + (sps * sph + cps * cph * sth) * w,
            sps * cth * u + (cps * cph + sph * sth * sps) * v + (-cps * sph + sth * sps * cph) * w,
            -sth * u + cth * sph * v + cth * cph * w,
            p + sph * sth / cth * q + cph * sth / cth * r,
            cph * q - sph * r,
            sph / cth * q + cph / cth * r,
        ]
        return np.concatenate((eta_dot, nu_dot))


def simulate(
    model: dict[str, Any],
    manoeuvre: str,
    speed_m_s: float,
    rudder_deg: float = 0.0,
    sternplane_deg: float = 0.0,
    net_buoyancy_n: float | None = None,
    duration_s: float | None = None,
    max_step_s: float | None = None,
    max_steps: int | None = None,
    dive_angle_deg: float | None = None,
    roll_deg: float | None = None,
    initial_state: np.ndarray | None = None,
    period_s: float | None = None,
    schedule: pd.DataFrame | None = None,
    sample_hz: float | None = None,
    propeller: str = "thrust",
) -> pd.DataFrame:
    """Simulate one manoeuvre; the time series of manoeuvre.csv (columns :data:`COLUMNS`).

    Parameters
    ----------
    model : dict
        model.json (:func:`towtank.vehicle.model.read_model`)
    manoeuvre : {"turning", "zigzag", "dive", "spiral", "glide"}
    speed_m_s : float
        Initial (and, with thrust, commanded) speed [m/s]
    rudder_deg, sternplane_deg : float
        Control angles [deg] (zigzag: rudder_deg is both the rudder and the check angle)
    net_buoyancy_n : float, optional
        Buoyancy minus weight [N]; replaces the model's weight (weight = B - this)
    duration_s : float, optional
        Simulated time [s]; default enough for the manoeuvre (40 vehicle lengths of travel,
        a glide 200 lengths)
    max_step_s : float, optional
        Largest integration step [s]; default duration/2000
    max_steps : int, optional
        Most integration steps [-]; default :data:`towtank.vehicle.schema.MAX_STEPS`. The
        simulation stops (ValueError) when it has taken them, or as soon as it has taken a
        tenth of them and, at its pace so far, would need more: a model too stiff for its
        duration never hangs
    dive_angle_deg : float, optional
        dive: the pitch to hold, nose down positive [deg]; the stern plane then follows
        :func:`pitch_command` (``sternplane_deg`` unused)
    roll_deg : float, optional
        glide: roll the glider by its roll mass, turned to the angle that gives this roll at
        rest (:func:`towtank.vehicle.glider_controls.roll_mass_angle_for_static_roll_deg`,
        eq. G6) [deg, starboard down positive]; needs the model's ``glider`` roll mass
    initial_state : numpy.ndarray, optional
        The 12 states at t = 0 (x, y, z [m], phi, theta, psi [rad], u, v, w [m/s], p, q, r
        [rad/s]); default at rest in attitude, moving at ``speed_m_s`` along x
    period_s : float, optional
        sine: the rudder's period T [s] (``rudder_deg`` its amplitude A); default 10 s
    schedule : DataFrame, optional
        schedule: columns ``t_s`` [s], ``rudder_deg``, ``sternplane_deg`` [deg]
        (:func:`read_schedule`), interpolated linearly, held before and after
    sample_hz : float, optional
        Write the time series at this rate [Hz] (the integrator's dense output; a zigzag
        interpolated linearly) instead of at the integrator's steps
    propeller : {"thrust", "rps"}
        The propulsion of a powered manoeuvre: "thrust" a constant thrust, the axial drag at
        ``speed_m_s``; "rps" the model's ``propeller`` at the constant rate of its
        self-propulsion point at ``speed_m_s`` (:func:`propulsion`). The time series'
        ``attrs`` keep ``propeller`` and, with "rps", ``propeller_rps`` [1/s]
    """
    if manoeuvre not in MANOEUVRES:
        raise ValueError(f"the manoeuvre must be one of {', '.join(MANOEUVRES)}, not "
                         f"{manoeuvre!r}.")
    if not (math.isfinite(speed_m_s) and speed_m_s > 0):
        raise ValueError(f"the speed must be > 0 m/s, not {speed_m_s}.")
    if manoeuvre == "glide" and roll_deg:  # the roll mass turned (#26)
        gamma = math.radians(roll_mass_angle_for_static_roll_deg(model, roll_deg))
        model = dict(model, cg_m=cg_with_controls(model, 0.0, gamma).tolist())
    weight = None if net_buoyancy_n is None else float(model["buoyancy_N"]) - net_buoyancy_n
    dyn = Dynamics(model, weight)
    if duration_s is None:
        duration_s = default_duration(model, manoeuvre, speed_m_s)
    if not (math.isfinite(duration_s) and duration_s > 0):
        raise ValueError(f"the simulated time must be > 0 s, not {duration_s}.")
    h = max_step_s if max_step_s is not None else duration_s / 2000.0
    budget = _Budget(duration_s, MAX_STEPS if max_steps is None else max_steps)
    push, rps = propulsion(model, dyn, 0.0 if manoeuvre == "glide" else speed_m_s, propeller)
    dr = math.radians(rudder_deg) if manoeuvre in ("turning", "spiral", "zigzag",
                                                   "glide") else 0.0
    ds = math.radians(sternplane_deg) if manoeuvre in ("dive", "spiral", "glide", "sine") else 0.0
    rudder_at = _rudder_law(manoeuvre, rudder_deg, period_s, schedule, dr)
    if manoeuvre == "schedule":
        tab = schedule if schedule is not None else pd.DataFrame(
            {"t_s": [0.0], "rudder_deg": [0.0], "sternplane_deg": [0.0]})
        st_t, st_v = tab["t_s"].to_numpy(float), np.radians(tab["sternplane_deg"].to_numpy(float))
    state0 = np.zeros(12)
    state0[6] = speed_m_s
    if initial_state is not None:
        state0 = np.asarray(initial_state, dtype=float).copy()
    closed = manoeuvre == "dive" and dive_angle_deg is not None
    if manoeuvre == "dive" and dive_angle_deg is not None:  # closed
        limit = math.radians(float(model.get("fin_limit_deg", FIN_LIMIT_DEG)))
        sigma = 1.0 if float(model["coefficients"].get("M_uuds", -1.0)) <= 0 else -1.0
        theta_cmd = -math.radians(dive_angle_deg)

        def stern(y: np.ndarray) -> float:
            return pitch_command(y[4], y[10], theta_cmd, PITCH_KP, PITCH_KD, limit, sigma)
    elif manoeuvre == "schedule":
        def stern_at(t: float) -> float:
            return float(np.interp(t, st_t, st_v))
    else:
        def stern(y: np.ndarray) -> float:
            return ds
    t_eval = None
    if sample_hz is not None:
        t_eval = np.arange(0.0, duration_s * (1 + 1e-12), 1.0 / sample_hz)
    if manoeuvre == "schedule":
        sol = budget.solve(lambda t, y: dyn.rhs(y, rudder_at(t), stern_at(t), push(y[6])),
                           (0.0, duration_s), state0, method="RK45", rtol=1e-8, atol=1e-9,
                           max_step=h, t_eval=t_eval)
        _check(sol)
        times, states = sol.t, sol.y.T
        rudder = np.array([rudder_at(t) for t in times])
        sterns = np.array([stern_at(t) for t in times])
    elif manoeuvre != "zigzag":
        sol = budget.solve(lambda t, y: dyn.rhs(y, rudder_at(t), stern(y), push(y[6])),
                           (0.0, duration_s), state0, method="RK45", rtol=1e-8, atol=1e-9,
                           max_step=h, dense_output=False, t_eval=t_eval)
        _check(sol)
        times, states = sol.t, sol.y.T
        rudder = np.array([rudder_at(t) for t in times])
    else:
        # first execute towards positive heading: the sign of N_uudr decides the rudder's
        sigma = 1.0 if model["coefficients"].get("N_uudr", -1.0) > 0 else -1.0
        check = abs(dr)
        command = sigma * abs(dr)
        t0, y0 = 0.0, state0
        t_parts, y_parts, r_parts = [], [], []
        target = 1.0
        while t0 < duration_s:
            def event(t, y, target=target):  # noqa: ANN001
                return y[5] - target * check
            # solve_ivp reads these two attributes of an event function
            vars(event).update(terminal=True, direction=target)
            sol = budget.solve(lambda t, y, c=command: dyn.rhs(y, c, ds, push(y[6])),
                               (t0, duration_s), y0, method="RK45", rtol=1e-8, atol=1e-9,
                               max_step=h, events=event)
            _check(sol)
            t_parts.append(sol.t)
            y_parts.append(sol.y.T)
            r_parts.append(np.full(len(sol.t), command))
            if sol.status != 1:
                break
            t0, y0 = float(sol.t[-1]), sol.y[:, -1]
            command, target = -command, -target
        times = np.concatenate(t_parts)
        states = np.concatenate(y_parts)
        rudder = np.concatenate(r_parts)
        if t_eval is not None:  # the switches repeat a time: the later sample is kept
            keep = np.r_[np.diff(times) > 0, True]
            times, states, rudder = times[keep], states[keep], rudder[keep]
            states = np.column_stack([np.interp(t_eval, times, c) for c in states.T])
            rudder = np.array([rudder[min(np.searchsorted(times, t, "right") - 1,
                                          len(times) - 1)] for t in t_eval])
            times = t_eval
    out = pd.DataFrame({
        "t_s": times, "x_m": states[:, 0], "y_m": states[:, 1], "z_m": states[:, 2],
        "phi_deg": np.degrees(states[:, 3]), "theta_deg": np.degrees(states[:, 4]),
        "psi_deg": np.degrees(states[:, 5]), "u_m_s": states[:, 6], "v_m_s": states[:, 7],
        "w_m_s": states[:, 8], "p_deg_s": np.degrees(states[:, 9]),
        "q_deg_s": np.degrees(states[:, 10]), "r_deg_s": np.degrees(states[:, 11]),
        "rudder_deg": np.degrees(rudder),
        "sternplane_deg": (np.degrees(sterns) if manoeuvre == "schedule" else
                           np.degrees([stern(y) for y in states]) if closed else np.degrees(ds)),
    })
    out.attrs["manoeuvre"] = manoeuvre
    out.attrs["propeller"] = propeller
    if rps is not None:
        out.attrs["propeller_rps"] = rps
    if closed and dive_angle_deg is not None:
        out.attrs["dive_angle_deg"] = float(dive_angle_deg)
    out.attrs["check_deg"] = abs(rudder_deg)
    if manoeuvre == "glide" and (roll_deg or rudder_deg):
        out.attrs["turning"] = True  # metrics: turn radius and period (#26)
    return out


def propulsion(model: dict[str, Any], dyn: Dynamics, speed_m_s: float,
               propeller: str = "thrust") -> tuple[Any, float | None]:
    """The surge force of the propulsion [N] as a function of the surge speed u [m/s], and the
    propeller's rate n [1/s] (None for a constant thrust).

    Both balance the axial drag ``R = -X_u|u| U|U|`` at ``speed_m_s`` U (0: no propulsion).
    "thrust": the force R whatever u. "rps": n is the self-propulsion point of the model's
    ``propeller`` block at U, ``T (1 - t) = R`` with ``V_A = U (1 - w)``
    (:func:`towtank.vehicle.powering.self_propulsion_rps`), and the force is
    ``(1 - t) rho n^2 D^4 K_T(J)``, ``J = u (1 - w) / (n D)`` (Oosterveld & van Oossanen 1975;
    docs/method.md "Propeller at constant rps").

    Raises
    ------
    ValueError
        An unknown ``propeller``; "rps" without the model's ``propeller`` block, or with a
        propeller that cannot deliver R.
    """
    if propeller not in PROPULSION:
        raise ValueError(f"the propulsion must be one of {', '.join(PROPULSION)}, not "
                         f"{propeller!r}.")
    drag = -dyn.x_uu * speed_m_s * abs(speed_m_s)
    if propeller == "thrust" or drag == 0.0:
        return (lambda u: drag), None
    block = model.get("propeller")
    if not isinstance(block, dict):
        raise ValueError("a propeller at constant rps needs the model's 'propeller' block "
                         "(the protocol's [vehicle.propeller]: diameter_m, pitch_ratio, "
                         "blade_area_ratio, blades); add it and run predict again.")
    prop = propeller_from(block)
    rho = float(model.get("rho_kg_m3", 1025.0))
    n = self_propulsion_rps(drag, speed_m_s, prop, rho)
    kt = kt_polynomial(prop)
    share = 1.0 - prop.thrust_deduction
    return (lambda u: share * propeller_thrust(u, n, prop, rho, kt)), n


def _rudder_law(manoeuvre: str, rudder_deg: float, period_s: float | None,
                schedule: pd.DataFrame | None, dr: float) -> Any:
    """The rudder angle [rad] as a function of time [s] of the open-loop manoeuvres."""
    if manoeuvre == "sine":
        amp = math.radians(rudder_deg)
        omega = 2.0 * math.pi / (10.0 if period_s is None else float(period_s))
        return lambda t: amp * math.sin(omega * t)
    if manoeuvre == "schedule" and schedule is not None:
        t_s = schedule["t_s"].to_numpy(float)
        val = np.radians(schedule["rudder_deg"].to_numpy(float))
        return lambda t: float(np.interp(t, t_s, val))
    return lambda t: dr


#: Columns of a control schedule (``simulate --schedule``).
SCHEDULE_COLUMNS = ("t_s", "rudder_deg", "sternplane_deg")


def read_schedule(path: Any, limit_deg: float = 45.0) -> pd.DataFrame:
    """A control schedule: CSV with ``t_s`` [s], ``rudder_deg``, ``sternplane_deg`` [deg].

    The times must be finite and increase, the angles finite and within ``limit_deg`` [deg];
    a missing angle column is 0.

    Raises
    ------
    ValueError
        One sentence naming the file and the problem.
    """
    name = Path(path).name
    try:
        tab = pd.read_csv(path)
    except (OSError, ValueError, UnicodeDecodeError) as exc:
        raise ValueError(f"{name}: cannot be read as a CSV schedule ({exc}).") from None
    tab.columns = [str(c).strip() for c in tab.columns]
    if "t_s" not in tab.columns or not ({"rudder_deg", "sternplane_deg"} & set(tab.columns)):
        raise ValueError(f"{name}: a schedule needs the columns t_s and rudder_deg and/or "
                         f"sternplane_deg, not {', '.join(map(str, tab.columns)) or 'none'}.")
    out = pd.DataFrame({c: pd.to_numeric(tab[c], errors="coerce") if c in tab.columns
                        else 0.0 for c in SCHEDULE_COLUMNS})
    if len(out) == 0:
        raise ValueError(f"{name}: the schedule has no rows.")
    bad = ~np.isfinite(out.to_numpy(float)).all(axis=1)
    if bad.any():
        raise ValueError(f"{name}: row {int(np.nonzero(bad)[0][0]) + 2} of the schedule holds a "
                         "value that is not a finite number.")
    if (np.diff(out["t_s"].to_numpy()) <= 0).any():
        raise ValueError(f"{name}: the schedule's t_s must increase from row to row.")
    big = out[["rudder_deg", "sternplane_deg"]].abs().to_numpy().max()
    if big > limit_deg:
        raise ValueError(f"{name}: the schedule's angles must lie within ±{limit_deg:g} deg, "
                         f"not {big:g}.")
    return out


def pitch_command(theta_rad: float, q_rad_s: float, theta_cmd_rad: float, kp: float,
                  kd: float, limit_rad: float, sigma: float = 1.0) -> float:
    """Stern-plane angle of the dive's pitch law [rad] (docs/method.md, "Dive to an angle").

    ``delta_s = sigma (Kp (theta - theta_cmd) + Kd q)``, saturated at +-``limit_rad``: a PD
    law on the pitch error (a PID pitch autopilot without its integral term, Fossen 2011,
    ch. 12). SNAME/Prestero signs: theta positive nose up, M_uuds < 0 (a positive stern
    plane pitches the nose down), sigma = +1; a model with M_uuds > 0 takes sigma = -1.

    Parameters
    ----------
    theta_rad : float
        Pitch [rad]
    q_rad_s : float
        Pitch rate [rad/s]
    theta_cmd_rad : float
        Commanded pitch [rad] (a dive of A deg: -A)
    kp : float
        Proportional gain [rad/rad]
    kd : float
        Derivative gain [s]
    limit_rad : float
        Stern-plane limit [rad]
    sigma : float
        +1 or -1, the sign above [-]
    """
    delta = sigma * (kp * (theta_rad - theta_cmd_rad) + kd * q_rad_s)
    return float(min(max(delta, -limit_rad), limit_rad))


def trim_state(model: dict[str, Any], speed_m_s: float,
               net_buoyancy_n: float | None = None) -> dict[str, float]:
    """The steady straight run the model settles at with zero controls (docs/method.md,
    "Trim check").

    The thrust T = -X_u|u| U|U| of ``simulate`` at ``speed_m_s`` U [m/s]; roll, sway and the
    angular rates zero; the surge, heave and pitch equations of motion at rest
    (``u_dot = w_dot = q_dot = 0``: the static balance of thrust, hydrodynamic forces,
    weight and buoyancy, Fossen 2011 eqs. 4.6 and 7.190) are solved for the speeds u, w
    [m/s] and the pitch theta [rad], from u = U, w = 0, theta = 0. The depth rate is
    ``z_dot = -u sin(theta) + w cos(theta)`` [m/s] (Fossen 2011 eq. 2.40, phi = 0).

    Parameters
    ----------
    model : dict
        model.json
    speed_m_s : float
        Commanded speed [m/s]
    net_buoyancy_n : float, optional
        Buoyancy minus weight [N], replacing the model's weight (as ``simulate``)

    Returns
    -------
    dict
        ``pitch_deg`` [deg], ``depth_rate_m_s`` [m/s, positive down], ``u_m_s``, ``w_m_s``
        [m/s], ``converged`` (False: no steady straight run found; the others NaN)
    """
    weight = None if net_buoyancy_n is None else float(model["buoyancy_N"]) - net_buoyancy_n
    dyn = Dynamics(model, weight)
    thrust = -dyn.x_uu * speed_m_s * abs(speed_m_s)

    def balance(x: np.ndarray) -> np.ndarray:
        state = np.zeros(12)
        state[4], state[6], state[8] = x[2], x[0], x[1]
        return dyn.rhs(state, 0.0, 0.0, thrust)[[6, 8, 10]]

    with np.errstate(all="ignore"):
        x, _, ier, _ = fsolve(balance, np.array([speed_m_s, 0.0, 0.0]), full_output=True,
                              xtol=1e-12)
        resid = np.abs(balance(x))
    ok = (ier == 1 and bool(np.all(np.isfinite(x))) and float(resid.max()) < 1e-6
          and abs(x[2]) < math.pi / 2)
    if not ok:
        nan = float("nan")
        return {"pitch_deg": nan, "depth_rate_m_s": nan, "u_m_s": nan, "w_m_s": nan,
                "converged": False}
    u, w, theta = (float(v) for v in x)
    return {"pitch_deg": math.degrees(theta),
            "depth_rate_m_s": -u * math.sin(theta) + w * math.cos(theta),
            "u_m_s": u, "w_m_s": w, "converged": True}


def trim_warning(model: dict[str, Any], speed_m_s: float,
                 net_buoyancy_n: float | None = None) -> str | None:
    """One sentence when the model is out of trim (:func:`trim_state`: steady pitch beyond
    :data:`TRIM_PITCH_DEG` [deg] or depth rate beyond :data:`TRIM_DEPTH_RATE_M_S` [m/s] with
    zero controls at ``speed_m_s`` [m/s]), else None."""
    st = trim_state(model, speed_m_s, net_buoyancy_n)
    check = "check weight_N, buoyancy_N, cg_m and cb_m (or --net-buoyancy-N)"
    if not st["converged"]:
        return (f"the model has no steady straight run with zero controls at {speed_m_s:g} m/s "
                f"(the balance of surge, heave and pitch has no solution); {check}.")
    if abs(st["pitch_deg"]) > TRIM_PITCH_DEG or abs(st["depth_rate_m_s"]) > TRIM_DEPTH_RATE_M_S:
        way = "down" if st["depth_rate_m_s"] > 0 else "up"
        return (f"the model is out of trim: with zero controls at {speed_m_s:g} m/s it settles "
                f"at a pitch of {st['pitch_deg']:+.1f} deg and goes {way} at "
                f"{abs(st['depth_rate_m_s']):.3g} m/s (in trim: within +-{TRIM_PITCH_DEG:g} deg "
                f"and +-{TRIM_DEPTH_RATE_M_S:g} m/s); {check}.")
    return None


class _Stop(Exception):
    """Raised inside the right-hand side to end an integration that cannot be finished."""


class _Budget:
    """The integration steps one simulation may take (``max_steps``) across its calls of
    :func:`scipy.integrate.solve_ivp` (a zigzag makes one per rudder switch).

    RK45 evaluates the right-hand side 6 times per step; the budget counts evaluations. It
    stops the integration (one sentence, ValueError) when the steps are spent; when a tenth
    of them is spent and, at the pace so far, the rest of the simulated time would need more;
    and at once when the state or its derivative is not finite (a NaN in the model makes the
    step size NaN, on which RK45 would retry for ever).
    """

    def __init__(self, duration_s: float, max_steps: int):
        self.duration = float(duration_s)
        self.max_steps = int(max_steps)
        self.evaluations = 0

    def solve(self, fun: Any, t_span: tuple[float, float], y0: np.ndarray,
              **kwargs: Any) -> Any:
        def guarded(t: float, y: np.ndarray) -> np.ndarray:
            self.evaluations += 1
            steps = self.evaluations // 6
            if steps > self.max_steps:
                raise _Stop(self._sentence(t, f"took the {self.max_steps} integration steps "
                                              "a simulation may take"))
            if steps >= self.max_steps // 10 and self.evaluations % 600 == 0 and t > 0:
                pace = steps * self.duration / t
                if pace > self.max_steps:
                    raise _Stop(self._sentence(t, f"would need about {pace:.3g} integration "
                                                  f"steps at its pace, more than the "
                                                  f"{self.max_steps} a simulation may take"))
            if not np.isfinite(y).all():
                raise _Stop(_diverged(t, "the state is no longer finite"))
            out = fun(t, y)
            if not np.isfinite(out).all():
                raise _Stop(_diverged(t, "the forces are no longer finite"))
            return out

        try:
            with np.errstate(all="ignore"):
                return solve_ivp(guarded, t_span, y0, **kwargs)
        except _Stop as exc:
            raise ValueError(str(exc)) from None
        except (OverflowError, ZeroDivisionError) as exc:  # Python floats out of range
            raise ValueError(_diverged(None, f"{type(exc).__name__}: {exc}")) from None

    def _sentence(self, t: float, what: str) -> str:
        return (f"the simulation stopped at t = {t:.3g} s of {self.duration:.6g} s: it {what}; "
                "the model's motion is too fast for that time (stiff: forces out of proportion "
                "to the masses), check the coefficients' magnitudes or give a shorter "
                "--duration-s.")


def _diverged(t: float | None, why: str) -> str:
    at = "" if t is None else f" at t = {t:.3g} s"
    return (f"the simulation stopped{at} ({why}): the model's motion diverges; check the "
            "signs and magnitudes of its damping terms.")


def _check(sol: Any) -> None:
    """A failed integration (a model whose motion diverges) is one sentence, not a crash."""
    if sol.status == -1 or not np.all(np.isfinite(sol.y)):
        t = float(sol.t[-1]) if len(sol.t) else 0.0
        raise ValueError(_diverged(t, sol.message))


def _at_heading(ts: pd.DataFrame, change_deg: float) -> pd.Series | None:
    dpsi = np.abs(ts["psi_deg"].to_numpy() - ts["psi_deg"].iloc[0])
    idx = np.nonzero(dpsi >= change_deg)[0]
    if len(idx) == 0 or idx[0] == 0:
        return None
    i = idx[0]
    f = (change_deg - dpsi[i - 1]) / (dpsi[i] - dpsi[i - 1])
    return ts.iloc[i - 1] + f * (ts.iloc[i] - ts.iloc[i - 1])


def _rates(ts: pd.DataFrame) -> dict[str, np.ndarray]:
    """The quantities the steady metrics average, sample by sample."""
    t = ts["t_s"].to_numpy()
    grad = (lambda c: np.gradient(ts[c].to_numpy(), t)) if len(t) > 1 else (
        lambda c: np.zeros(len(t)))
    xr, yr, zr = grad("x_m"), grad("y_m"), grad("z_m")
    return {
        "t": t, "speed_m_s": sd.speed_magnitude(ts["u_m_s"].to_numpy(), ts["v_m_s"].to_numpy(),
                                                ts["w_m_s"].to_numpy()),
        "horizontal_speed_m_s": np.hypot(xr, yr), "xr": xr, "depth_rate_m_s": zr,
        "yaw_rate_deg_s": grad("psi_deg"), "pitch_deg": ts["theta_deg"].to_numpy(),
        "drift_deg": np.degrees(np.arctan2(ts["v_m_s"], ts["u_m_s"])).to_numpy(),
        "angle_of_attack_deg": np.degrees(np.arctan2(ts["w_m_s"], ts["u_m_s"])).to_numpy(),
    }


def manoeuvre_metrics(ts: pd.DataFrame) -> pd.DataFrame:
    """metrics.csv of a simulated manoeuvre: metric, value, unit, note.

    Steady metrics are means over the last fifth of the run, given only when that part is
    steady (:mod:`towtank.vehicle.steady`; NaN and a note otherwise); angles wrapped to
    +-180 deg. The turn radius is the least-squares circle through the plan track (x, y) of
    that part (:func:`towtank.vehicle.steady.circle_fit`).
    """
    kind = ts.attrs.get("manoeuvre", "turning")
    rows: list[tuple[str, float, str, str]] = []
    nan = float("nan")
    with np.errstate(all="ignore"):  # a zigzag repeats the switching times
        q = _rates(ts)
    last = sd.steady_mask(q["t"])
    loop = sd.looped(q["pitch_deg"], ts["u_m_s"].to_numpy())

    def check(*names: str) -> str:
        if loop:
            return loop
        for name in names:
            note = sd.steadiness(q[name][last], name)
            if note:
                return f"{sd.LABELS[name]} {note}"
        return ""

    def steady(metric: str, name: str, unit: str, *needs: str, angle: bool = False) -> None:
        note = check(name, *needs)
        value = float(np.mean(q[name][last])) if not note else nan
        rows.append((metric, float(sd.wrap_deg(value)) if angle and not note else value, unit,
                     note))

    def turn(needs: tuple[str, ...]) -> tuple[str, float]:
        """The steady turn's radius row (Kasa's circle of the plan track's steady part); its
        note (why not steady or not turning, else "") and mean yaw rate [deg/s]."""
        note = check(*needs)
        yaw = float(np.mean(q["yaw_rate_deg_s"][last]))
        if not note and abs(yaw) < sd.MIN_YAW_RATE_DEG_S:
            note = f"not turning: the yaw rate is below {sd.MIN_YAW_RATE_DEG_S:g} deg/s"
        radius = nan if note else sd.circle_fit(ts["x_m"].to_numpy()[last],
                                                ts["y_m"].to_numpy()[last])[2]
        rows.append(("steady_turn_radius_m", radius, "m", note))
        return note, yaw

    if kind in ("turning", "spiral"):
        needs = ("yaw_rate_deg_s", "speed_m_s") + (("depth_rate_m_s",) if kind == "spiral"
                                                    else ())
        note, yaw = turn(needs)
        at90, at180 = _at_heading(ts, 90.0), _at_heading(ts, 180.0)
        rows.append(("advance_m", float(at90["x_m"] - ts["x_m"].iloc[0]) if at90 is not None
                     else nan, "m", "" if at90 is not None else "no 90 deg of heading change"))
        rows.append(("transfer_m", float(abs(at90["y_m"])) if at90 is not None else nan, "m",
                     "" if at90 is not None else "no 90 deg of heading change"))
        rows.append(("tactical_diameter_m", float(abs(at180["y_m"])) if at180 is not None
                     else nan, "m", "" if at180 is not None else "no 180 deg of heading change"))
        steady("steady_speed_m_s", "speed_m_s", "m/s")
        beside = next(i for i, r in enumerate(rows) if r[0] == "steady_turn_radius_m") + 1
        rows.insert(beside, _speed_loss(rows[-1], float(q["speed_m_s"][0]),
                                        ts.attrs.get("propeller_rps")))
        steady("steady_yaw_rate_deg_s", "yaw_rate_deg_s", "deg/s")
        steady("steady_drift_angle_deg", "drift_deg", "deg", angle=True)
        if kind == "spiral":
            steady("steady_pitch_deg", "pitch_deg", "deg", angle=True)
            steady("depth_rate_m_s", "depth_rate_m_s", "m/s")
            note = check("depth_rate_m_s", *needs)
            per_turn = nan if note else float(np.mean(q["depth_rate_m_s"][last]) * 360.0
                                              / abs(yaw))
            rows.append(("depth_change_per_turn_m", per_turn, "m", note))
    elif kind == "zigzag":
        check_deg = float(ts.attrs.get("check_deg", 20.0))
        switch = np.nonzero(np.diff(ts["rudder_deg"].to_numpy()) != 0)[0] + 1
        psi = ts["psi_deg"].to_numpy()
        t = ts["t_s"].to_numpy()
        for k in range(2):
            if len(switch) > k + 1:
                seg = psi[switch[k]:switch[k + 1]]
                over = (seg.max() - check_deg) if k % 2 == 0 else (-seg.min() - check_deg)
                rows.append((f"overshoot_{k + 1}_deg", float(over), "deg", ""))
        if len(switch) >= 3:
            rows.append(("period_s", float(t[switch[2]] - t[switch[0]]), "s", ""))
        if len(switch) >= 1:
            rows.append(("time_to_first_execute_s", float(t[switch[0]]), "s", ""))
    elif kind in ("sine", "schedule"):
        half = q["t"] >= 0.5 * q["t"][-1]
        for metric, col, unit in (("rudder_amplitude_deg", "rudder_deg", "deg"),
                                  ("heading_amplitude_deg", "psi_deg", "deg"),
                                  ("yaw_rate_amplitude_deg_s", "r_deg_s", "deg/s"),
                                  ("pitch_amplitude_deg", "theta_deg", "deg")):
            vals = ts[col].to_numpy()[half]
            rows.append((metric, 0.5 * float(np.ptp(vals)) if len(vals) else nan, unit,
                         "half the peak-to-peak over the last half of the run"))
    else:  # dive, glide
        steady("steady_pitch_deg", "pitch_deg", "deg", angle=True)
        steady("depth_rate_m_s", "depth_rate_m_s", "m/s")
        steady("speed_m_s", "speed_m_s", "m/s")
        note = check("depth_rate_m_s", "speed_m_s")
        ahead = q["horizontal_speed_m_s" if ts.attrs.get("turning") else "xr"][last]
        glide = nan if note else float(np.degrees(np.arctan2(
            np.mean(-q["depth_rate_m_s"][last]), np.mean(ahead))))
        rows.append(("glide_angle_deg", glide, "deg", note))
        steady("angle_of_attack_deg", "angle_of_attack_deg", "deg", angle=True)
        rows.append(("depth_change_m", float(ts["z_m"].iloc[-1] - ts["z_m"].iloc[0]), "m", ""))
        if "dive_angle_deg" in ts.attrs:
            rows += _dive_angle_rows(ts, float(ts.attrs["dive_angle_deg"]))
        if ts.attrs.get("turning"):  # a glide rolled or with rudder: a spiral (#26)
            note, yaw = turn(("yaw_rate_deg_s", "speed_m_s", "depth_rate_m_s"))
            rows.append(("turn_period_s", nan if note else 360.0 / abs(yaw), "s", note))
            steady("steady_yaw_rate_deg_s", "yaw_rate_deg_s", "deg/s")
    if ts.attrs.get("propeller_rps") is not None:
        rows.append(("propeller_rps", float(ts.attrs["propeller_rps"]), "1/s",
                     "constant (--propeller rps): the self-propulsion point at the start speed"))
    return pd.DataFrame(rows, columns=["metric", "value", "unit", "note"])


def _speed_loss(steady_speed: tuple[str, float, str, str], start_m_s: float,
                rps: float | None = None) -> tuple[str, float, str, str]:
    """metrics.csv's ``speed_loss_percent``: the steady turn's speed below the speed at the
    start [%], under the propulsion that held the start speed on a straight course (a constant
    thrust, or the propeller at a constant ``rps`` [1/s])."""
    _, value, _, note = steady_speed
    if not note and not start_m_s > 0.0:
        note = f"no speed at the start ({start_m_s:.3g} m/s) to lose speed from"
    loss = float("nan") if note else 100.0 * (1.0 - value / start_m_s)
    how = ("under constant thrust" if rps is None
           else f"with the propeller at a constant {rps:.4g} rps")
    return ("speed_loss_percent", loss, "%",
            note or f"of the {start_m_s:.3g} m/s at the start, {how}")


def _dive_angle_rows(ts: pd.DataFrame, angle_deg: float) -> list[tuple[str, float, str, str]]:
    """The dive to an angle: commanded angle, time to reach it within
    :data:`DIVE_ANGLE_BAND` of it [s], overshoot beyond it [deg] (dive angle = -pitch)."""
    dive = -ts["theta_deg"].to_numpy()
    t = ts["t_s"].to_numpy()
    sign = 1.0 if angle_deg >= 0 else -1.0
    reached = np.nonzero(sign * dive >= (1.0 - DIVE_ANGLE_BAND) * abs(angle_deg))[0]
    rows = [("dive_angle_deg", angle_deg, "deg", "commanded: pitch held at -this")]
    if len(reached) == 0:
        why = f"never within {DIVE_ANGLE_BAND:.0%} of the commanded angle"
        return rows + [("time_to_dive_angle_s", float("nan"), "s", why),
                       ("dive_angle_overshoot_deg", float("nan"), "deg", why)]
    i = reached[0]
    if i > 0:  # interpolated to the crossing
        target = sign * (1.0 - DIVE_ANGLE_BAND) * abs(angle_deg)
        f = (target - sign * dive[i - 1]) / (sign * dive[i] - sign * dive[i - 1])
        t_reach = float(t[i - 1] + f * (t[i] - t[i - 1]))
    else:
        t_reach = float(t[0])
    over = max(0.0, float(np.max(sign * dive)) - abs(angle_deg))
    return rows + [("time_to_dive_angle_s", t_reach, "s", ""),
                   ("dive_angle_overshoot_deg", over, "deg", "")]


def sample_models(model: dict[str, Any], n: int, seed: int = 1) -> list[dict[str, Any]]:
    """``n`` copies of the model with the measured coefficients drawn from their covariance.

    Raises
    ------
    ValueError
        The model has no covariance of measured coefficients.
    """
    cov = model.get("covariance") or {}
    symbols = list(cov.get("symbols") or [])
    if not symbols:
        raise ValueError("the model has no covariance of measured coefficients; --samples "
                         "needs a model written by 'towtank process' with measured values.")
    matrix = np.asarray(cov["matrix"], dtype=float)
    mean = np.array([model["coefficients"].get(s, 0.0) for s in symbols])
    rng = np.random.default_rng(seed)
    draws = rng.multivariate_normal(mean, matrix, size=n, method="eigh")
    out = []
    for row in draws:
        m = dict(model)
        m["coefficients"] = dict(model["coefficients"]) | dict(zip(symbols, map(float, row),
                                                                   strict=True))
        out.append(m)
    return out
