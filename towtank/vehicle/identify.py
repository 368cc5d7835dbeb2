"""Coefficients from a manoeuvre record: augmented-state Kalman filter and smoother, checked by
output-error least squares (``towtank identify``; docs/method.md "Identification").

State-space form. The state of the 6-DOF model of :mod:`towtank.vehicle.simulate`
``s = [x, y, z, phi, theta, psi, u, v, w, p, q, r]`` is augmented with the unknown
coefficients ``beta`` as random-walk states (the REMUS identification study's ``x* = [x, y, u,
v, r, psi, beta]``)::

    s_{k+1} = f(s_k, beta_k, delta(t)) + w_s,     beta_{k+1} = beta_k + w_beta,
    z_k = H s_k + v_k,                             v_k ~ N(0, R)

f is the simulator's right-hand side (Fossen 2011 eqs. 2.40, 7.190, 6.43) integrated from
sample to sample by the classical 4th-order Runge-Kutta scheme (at most :data:`MAX_STEP_S` per
step, the controls linear between samples); H picks the measured states. The filter is
filterpy's unscented Kalman filter (Wan & van der Merwe 2000; scaled sigma points, van der
Merwe 2004) or its extended one (Jacobian of f by finite differences), followed by the
Rauch-Tung-Striebel smoother (Rauch, Tung & Striebel 1965; unscented form Särkkä 2008):
``G_k = D_{k+1} (P^-_{k+1})^{-1}``, ``m^s_k = m_k + G_k (m^s_{k+1} - m^-_{k+1})``,
``P^s_k = P_k + G_k (P^s_{k+1} - P^-_{k+1}) G_k^T`` with ``D`` the cross-covariance of
``s_k`` and ``s^-_{k+1}`` (EKF: ``D = P_k F_k^T``).

Cross-check: output-error least squares (:func:`scipy.optimize.least_squares`) of the
simulated against the measured states with white noise, weighted by each one's noise sd
re-estimated from the residuals (relaxation; Maine & Iliff 1986, Jategaonkar 2015, ch. 4);
the covariance the Newey-West sandwich ``M^+ S M^+``, ``M = J^T R^-1 J``, at least ``M^+``
(:func:`least_squares_fit`).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from typing import Any, NamedTuple

import numpy as np
import pandas as pd
from filterpy.kalman import ExtendedKalmanFilter, MerweScaledSigmaPoints
from filterpy.kalman import UnscentedKalmanFilter as UKF
from scipy.optimize import least_squares
from statsmodels.stats.sandwich_covariance import S_hac_simple

from towtank.vehicle.adequacy import adequacy_table, noise_dof
from towtank.vehicle.fossen import (
    DOF,
    SYMBOL_RE,
    VELOCITIES,
    added_mass_matrix,
    coriolis_added_mass,
    coriolis_rigid_body,
    quadratic_form,
    restoring_matrix,
    rigid_body_mass_matrix,
)
from towtank.vehicle.identify_log import (
    MAX_GAP_S,
    MIN_ROWS,
    STATE_COLUMNS,
    ManoeuvreLog,
    exact_states,
    noise_entry,
    noise_floor,
    noise_free_states,
    noise_sd,
)
from towtank.vehicle.predict import coefficient_unit

__all__ = ["record_speed", "simulate_fitted", "with_coefficients", "HOLDOUT_FRACTION",
           "MAX_STEP_S", "MAX_SUBSTEPS", "METHODS", "IDENTIFIABLE_RATIO", "BatchModel",
           "IdentifyFit", "Progress", "identify", "rts_smooth", "coefficient_unit",
           "least_squares_fit", "kalman_fit"]

#: Largest Runge-Kutta step of the process model [s].
MAX_STEP_S = 0.05
#: Most Runge-Kutta steps from one sample to the next: the longest step of the time a record
#: may have (:data:`towtank.vehicle.identify_log.MAX_GAP_S`) in steps of :data:`MAX_STEP_S`.
MAX_SUBSTEPS = math.ceil(MAX_GAP_S / MAX_STEP_S)
METHODS = ("ukf", "ekf", "ls")
#: A coefficient is identifiable when its standard deviation after the record is below this
#: fraction of its prior standard deviation (the record removed >= 99.75 % of the variance;
#: with the default prior, 3 max(|model value|, 1), an sd below 15 % of the model's value).
IDENTIFIABLE_RATIO = 0.05
#: Process noise of the states, per sqrt(second) [m, rad, m/s, rad/s per sqrt(s)]: chosen so
#: that the filter's 95 % intervals cover (docs/method.md, "Coverage"; a tenth of it made them
#: 40 % too narrow, three times it 30 % too wide, ten times it biased the estimates).
PROCESS_SD = np.array([1e-3, 1e-3, 1e-3, 1e-4, 1e-4, 1e-4, 1e-3, 1e-3, 1e-3, 1e-4, 1e-4, 1e-4])
#: Prior sd of the speed the thrust balances, a state of the filter when u is measured [m/s].
THRUST_SPEED_SD = 0.05
#: Passes of the filter: each starts from the previous estimates with a prior of
#: PASS_PRIOR times their standard deviations (at most the first prior), until the estimates
#: move by less than PASS_TOL of a standard deviation. The first pass from a far start (zero)
#: updates the coefficients while their prior is wide and the motion it predicts is far from
#: the record; what those early updates lock in is a bias of several standard deviations that
#: the later passes, linearised near the answer, remove (docs/method.md).
MAX_PASSES = 4
PASS_PRIOR = 10.0
PASS_TOL = 0.2
#: Fractions of the record least squares alone fits one after the other from zero starts.
LS_WINDOWS = (0.1, 0.25, 0.5, 1.0)
#: Most evaluations of the residuals (each a simulation along the record) of one least-squares
#: fit.
LS_MAX_NFEV = 60
#: Most refits of least squares with the noise covariance re-estimated from its residuals
#: (relaxation), and the relative change of a state's noise sd that calls for one [-].
LS_RELAX = 2
LS_RELAX_TOL = 0.1
#: Fraction of the record held out (its end) for the adequacy test of the model simulated
#: along it, its coefficients fitted to the rest (docs/method.md, "Model adequacy").
HOLDOUT_FRACTION = 0.25
#: Rows of the record between two calls of the progress callback of :func:`identify`.
PROGRESS_ROWS = 100

#: ``progress(stage, done, total)``: what :func:`identify` has done of its current stage.
Progress = Callable[[str, int, int], None]
#: Spread of the sigma points (van der Merwe 2004) [-].
ALPHA = 0.1
#: In the filter's process model an estimated diagonal added-mass derivative (X_udot, Y_vdot,
#: Z_wdot, K_pdot, M_qdot, N_rdot: minus an added mass, <= 0 for a body in a fluid; Newman
#: 1977, sec. 4.13) is taken at most DOT_BOUND times the rest of that diagonal entry of the
#: mass matrix M_RB + M_A: the sigma points of a wide prior (from zero, N_rdot +- 0.4 * 14
#: kg m^2 for REMUS, I_zz = 3.45 kg m^2) otherwise reach a singular mass matrix and the
#: predicted motion blows up; the filter's estimate is projected onto the bound after each
#: update (Simon 2010) (docs/method.md, "Robustness from zero starts") [-].
DOT_BOUND = 0.5


class RowCoefficients(NamedTuple):
    """What :meth:`BatchModel.rhs_with` needs of N coefficient sets, computed once for the
    Runge-Kutta steps that share them (:meth:`BatchModel.coefficients`)."""

    est: np.ndarray
    """The estimated terms' coefficients (N, k_terms)."""
    drag: np.ndarray | float
    """The thrust's balance of the axial drag, -X_u|u| u0 |u0| [N] per row."""
    added: np.ndarray | None
    """The estimated added masses (N, k_dot); None when none is estimated."""
    minv: np.ndarray | None
    """The inverse mass matrix of each row (N, 6, 6) [1/kg, 1/(kg m²)]; None when no added
    mass is estimated (the model's own inverse is used)."""


class BatchModel:
    """The simulator's dynamics for many states and coefficient sets at once.

    The same equations as :class:`towtank.vehicle.simulate.Dynamics` (the tests compare the
    two), with the estimated coefficients ``beta`` (N, k) taken per row: each hydrodynamic
    term is ``coefficient * product`` (simulate's module docstring), and an estimated added
    mass enters ``M_A = M_A0 + sum_j beta_j B_j`` (linear in the ``..dot`` coefficients).
    The thrust balances the axial drag ``X_u|u|`` at the record's first speed (as simulate's).
    """

    def __init__(self, model: dict[str, Any], estimate: list[str], speed_m_s: float,
                 weight: float | None = None) -> None:
        coef = {k: float(v) for k, v in (model.get("coefficients") or {}).items()}
        self.estimate = list(estimate)
        base = dict(coef)
        for s in estimate:
            base[s] = 0.0
        self.mass = float(model["mass_kg"])
        self.weight = float(model["weight_N"] if weight is None else weight)
        self.buoyancy = float(model["buoyancy_N"])
        self.rg = np.asarray(model["cg_m"], dtype=float)
        self.rb = np.asarray(model["cb_m"], dtype=float)
        self.io = np.diag(np.asarray(model["inertia_kg_m2"], dtype=float))
        m_rb = rigid_body_mass_matrix(self.mass, self.rg, self.io)
        self.ma0 = added_mass_matrix(base)
        self.mb = []  # d M_A / d beta_j
        self.dot_index = []
        for j, s in enumerate(estimate):
            if s.endswith("dot"):
                self.mb.append(added_mass_matrix(base | {s: 1.0}) - self.ma0)
                self.dot_index.append(j)
        self.m_rb = m_rb
        self.mb_stack = np.array(self.mb).reshape(len(self.mb), 6, 6)
        # C_RB(nu) nu + C_A(nu) nu, quadratic in nu and linear in M_A: its coefficients of
        # nu_a nu_b with M_A0, then those of each estimated added-mass derivative's d M_A
        self.coriolis = np.concatenate(
            [quadratic_form(lambda nu: coriolis_rigid_body(self.mass, self.rg, self.io, nu)
                            + coriolis_added_mass(self.ma0, nu))]
            + [quadratic_form(partial(coriolis_added_mass, mb)) for mb in self.mb], axis=1)
        # g(eta) = g_mat @ [sin(theta), cos(theta) sin(phi), cos(theta) cos(phi)]
        self.g_mat = restoring_matrix(self.weight, self.buoyancy, self.rg, self.rb)
        self.minv0 = np.linalg.inv(m_rb + self.ma0)
        # upper bound of each estimated coefficient in the filter's process model: a diagonal
        # added-mass derivative (X_udot ... N_rdot) at most half the diagonal of M_RB + M_A0,
        # so that the total inertia of its degree of freedom stays >= half the known one
        self.upper = np.full(len(estimate), np.inf)
        for j, s in enumerate(estimate):
            if s.endswith("dot") and DOF.index(s[0]) == VELOCITIES.index(s[2]):
                i = DOF.index(s[0])
                self.upper[j] = DOT_BOUND * (m_rb[i, i] + self.ma0[i, i])
        # fixed terms: product index table over ext = [nu, |nu|, dr, ds, 1]
        fixed = [(s, v) for s, v in base.items() if not s.split("_", 1)[1].endswith("dot")
                 and v != 0.0]
        self.fixed_idx, self.fixed_c = self._table(fixed)
        est = [(s, 1.0) for s in estimate if not s.endswith("dot")]
        self.est_cols = [j for j, s in enumerate(estimate) if not s.endswith("dot")]
        self.est_idx, self.est_e = self._table(est)
        # both tables padded to one width, the fixed terms first
        width = max(self.fixed_idx.shape[1], self.est_idx.shape[1])
        self.n_fixed = len(self.fixed_idx)
        self.all_idx = np.concatenate([np.pad(tab, ((0, 0), (0, width - tab.shape[1])),
                                              constant_values=14)
                                       for tab in (self.fixed_idx, self.est_idx)])
        self.x_uu = coef.get("X_u|u|", 0.0)
        self.x_uu_j = estimate.index("X_u|u|") if "X_u|u|" in estimate else None
        self.u0: Any = float(speed_m_s)  # [m/s], or one per row of the states

    @staticmethod
    def _table(terms: list[tuple[str, float]]) -> tuple[np.ndarray, np.ndarray]:
        rows, coefs = [], []
        for sym, val in terms:
            head, _, sub = sym.partition("_")
            idx = []
            for tok in re.findall(r"\|[uvwpqr]\||dr|ds|[uvwpqr]", sub):
                idx.append(12 if tok == "dr" else 13 if tok == "ds" else
                           6 + VELOCITIES.index(tok[1]) if tok.startswith("|")
                           else VELOCITIES.index(tok))
            rows.append(idx)
            c = np.zeros(6)
            c[DOF.index(head)] = val
            coefs.append(c)
        width = max((len(r) for r in rows), default=1)
        table = np.array([r + [14] * (width - len(r)) for r in rows], dtype=int).reshape(
            len(rows), width)
        return table, np.array(coefs).reshape(len(rows), 6)

    def coefficients(self, beta: np.ndarray) -> RowCoefficients:
        """What :meth:`rhs` needs of the coefficients ``beta`` (N, k), computed once for the
        steps that share them: the estimated terms' coefficients, the axial drag ``X_u|u|``,
        the estimated added masses and the inverse mass matrix of each row (N, 6, 6), None
        when no added mass is estimated."""
        x_uu = self.x_uu if self.x_uu_j is None else beta[:, self.x_uu_j]
        est, drag = beta[:, self.est_cols], -x_uu * self.u0 * np.abs(self.u0)
        if not self.dot_index:
            return RowCoefficients(est, drag, None, None)
        bd = beta[:, self.dot_index]
        ma = self.ma0 + np.einsum("nj,jab->nab", bd, self.mb_stack)
        return RowCoefficients(est, drag, bd, np.linalg.inv(self.m_rb + ma))

    def rhs(self, s: np.ndarray, beta: np.ndarray, dr: float, ds: float) -> np.ndarray:
        """ds/dt (N, 12) of the states ``s`` (N, 12) with the coefficients ``beta`` (N, k),
        rudder ``dr`` and stern plane ``ds`` [rad]."""
        return self.rhs_with(s, self.coefficients(beta), dr, ds)

    def rhs_with(self, s: np.ndarray, pre: RowCoefficients, dr: float, ds: float) -> np.ndarray:
        """:meth:`rhs` with the coefficients given by :meth:`coefficients`."""
        n = s.shape[0]
        nu = s[:, 6:]
        ext = np.empty((n, 15))
        ext[:, :6] = nu
        np.abs(nu, out=ext[:, 6:12])
        ext[:, 12] = dr
        ext[:, 13] = ds
        ext[:, 14] = 1.0
        # every term's product of velocities and controls in one gather: the fixed terms',
        # then the estimated ones'
        prod = ext[:, self.all_idx].prod(axis=2)
        tau = prod[:, :self.n_fixed] @ self.fixed_c
        if len(self.est_cols):
            tau += (prod[:, self.n_fixed:] * pre.est) @ self.est_e
        tau[:, 0] += pre.drag
        # C(nu) nu from the products nu_a nu_b, its M_A part with each row's added masses
        quad = (nu[:, :, None] * nu[:, None, :]).reshape(n, 36) @ self.coriolis
        rest = quad[:, :6]
        if pre.added is not None:
            rest = rest + np.einsum("nj,njk->nk", pre.added, quad[:, 6:].reshape(n, -1, 6))
        sn, cs = np.sin(s[:, 3:6].T), np.cos(s[:, 3:6].T)
        sph, sth, sps = sn
        cph, cth, cps = cs
        # g(eta): linear in sin(theta), cos(theta) sin(phi), cos(theta) cos(phi)
        g = np.array([sth, cth * sph, cth * cph]).T @ self.g_mat.T
        total = tau - rest - g
        if pre.minv is None:
            nu_dot = total @ self.minv0.T
        else:
            nu_dot = np.einsum("nab,nb->na", pre.minv, total)
        u, v, w_, p, q, r = nu.T
        # eta_dot = J(eta) nu (Fossen eq. 2.40), R = R_z(psi) R_y(theta) R_x(phi) applied in turn
        v_x, w_x = cph * v - sph * w_, sph * v + cph * w_
        u_y = cth * u + sth * w_x
        out = np.empty((n, 12))
        out[:, 0] = cps * u_y - sps * v_x
        out[:, 1] = sps * u_y + cps * v_x
        out[:, 2] = cth * w_x - sth * u
        turn = sph * q + cph * r
        out[:, 3] = p + turn * sth / cth
        out[:, 4] = cph * q - sph * r
        out[:, 5] = turn / cth
        out[:, 6:] = nu_dot
        return out

    def step(self, aug: np.ndarray, dt: float, c0: tuple[float, float],
             c1: tuple[float, float], pre: RowCoefficients | None = None) -> np.ndarray:
        """The augmented states (N, 12 + k) after ``dt`` [s]: RK4 in steps of at most
        :data:`MAX_STEP_S`, the controls [rad] linear from ``c0`` to ``c1``; ``pre``: the
        coefficients' :meth:`coefficients` when already computed.

        Raises
        ------
        ValueError
            ``dt`` not finite, or longer than :data:`MAX_SUBSTEPS` steps (one sentence).
        """
        s, beta = aug[:, :12], aug[:, 12:]
        nsub = max(1, math.ceil(dt / MAX_STEP_S - 1e-9)) if math.isfinite(dt) else 0
        if not 0 < nsub <= MAX_SUBSTEPS:
            raise ValueError(f"a time step of {dt:g} s would take more than the {MAX_SUBSTEPS} "
                             f"Runge-Kutta steps of {MAX_STEP_S:g} s identify takes from one "
                             f"sample to the next (at most {MAX_GAP_S:g} s between samples).")
        if pre is None:
            pre = self.coefficients(beta)
        h = dt / nsub
        for i in range(nsub):
            def ctl(f: float) -> tuple[float, float]:
                return (c0[0] + f * (c1[0] - c0[0]), c0[1] + f * (c1[1] - c0[1]))
            fa, fb, fc = i / nsub, (i + 0.5) / nsub, (i + 1) / nsub
            k1 = self.rhs_with(s, pre, *ctl(fa))
            k2 = self.rhs_with(s + 0.5 * h * k1, pre, *ctl(fb))
            k3 = self.rhs_with(s + 0.5 * h * k2, pre, *ctl(fb))
            k4 = self.rhs_with(s + h * k3, pre, *ctl(fc))
            s = s + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        return np.concatenate((s, beta), axis=1)

    def run(self, s0: np.ndarray, beta: np.ndarray, log: ManoeuvreLog) -> np.ndarray:
        """Simulate from ``s0`` (N, 12) with ``beta`` (N, k) along the record's times and
        controls: states (n_samples, N, 12)."""
        aug = np.concatenate((s0, beta), axis=1)
        out = np.empty((len(log.t), s0.shape[0], 12))
        out[0] = s0
        with np.errstate(all="ignore"):
            pre = self.coefficients(beta)
            for k in range(1, len(log.t)):
                aug = self.step(aug, float(log.t[k] - log.t[k - 1]),
                                (log.rudder[k - 1], log.sternplane[k - 1]),
                                (log.rudder[k], log.sternplane[k]), pre)
                out[k] = aug[:, :12]
        return out


def rts_smooth(xs: np.ndarray, ps: np.ndarray, x_prior: np.ndarray, p_prior: np.ndarray,
               cross: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rauch-Tung-Striebel smoother over a filter's pass (Särkkä 2008, eqs. 21-23).

    Parameters
    ----------
    xs, ps : ndarray
        Filtered means (n, d) and covariances (n, d, d)
    x_prior, p_prior : ndarray
        Predicted means and covariances of step k (index k, from step k-1; index 0 unused)
    cross : ndarray
        ``D_k``, cross-covariance of the state at k-1 and the prediction of k (n, d, d)

    Returns
    -------
    (ndarray, ndarray)
        Smoothed means and covariances.
    """
    xs_s, ps_s = xs.copy(), ps.copy()
    for k in range(len(xs) - 2, -1, -1):
        gain = np.linalg.solve(p_prior[k + 1].T, cross[k + 1].T).T
        xs_s[k] = xs[k] + gain @ (xs_s[k + 1] - x_prior[k + 1])
        ps_s[k] = ps[k] + gain @ (ps_s[k + 1] - p_prior[k + 1]) @ gain.T
        ps_s[k] = 0.5 * (ps_s[k] + ps_s[k].T)
    return xs_s, ps_s


@dataclass(frozen=True)
class IdentifyFit:
    """What :func:`identify` found (the result, :class:`towtank.results.IdentifyResult`, is
    built from it).

    Attributes
    ----------
    symbols : list of str
    start, value, sd : ndarray
        Starting values, estimates and standard deviations of the primary method
    prior_sd : ndarray
        The filter's prior standard deviation of each coefficient (also the scale of the
        identifiability verdict of least squares)
    method : str
    check : dict or None
        Least squares' ``value`` and ``sd`` when it ran as the cross-check
    history : dict
        ``t`` [s], ``mean`` and ``sd`` (n, k): the smoothed (filter) estimates over time
    measured, resimulated : DataFrame
        The record and the model with the estimates simulated along it (manoeuvre.csv columns)
    covariance : ndarray
        Covariance of the estimates (k, k)
    notes : tuple of str
    adequacy : DataFrame or None
        fit.csv: whether the record fits the model (:func:`towtank.vehicle.adequacy.
        adequacy_table`)
    residuals : dict or None
        What :attr:`adequacy` was computed from, the keyword arguments of :func:`towtank.
        vehicle.adequacy.adequacy_table`: ``innovation`` (n, 12) and ``check`` (m, 12) [-],
        ``check_test``, ``states``
    """

    symbols: list[str]
    start: np.ndarray
    value: np.ndarray
    sd: np.ndarray
    prior_sd: np.ndarray
    method: str
    covariance: np.ndarray
    check: dict[str, np.ndarray] | None = None
    history: dict[str, np.ndarray] = field(default_factory=dict)
    measured: pd.DataFrame | None = None
    resimulated: pd.DataFrame | None = None
    notes: tuple[str, ...] = ()
    adequacy: pd.DataFrame | None = None
    residuals: dict[str, Any] | None = None

    def fits(self) -> bool:
        """False when a test of :attr:`adequacy` failed (the record does not fit the
        model)."""
        return self.adequacy is None or bool(self.adequacy["passed"].all())


def _initial_state(log: ManoeuvreLog, model: dict[str, Any]) -> np.ndarray:
    s0 = np.zeros(12)
    for i in log.measured:
        col = log.z[:, i]
        fin = np.nonzero(np.isfinite(col))[0]
        s0[i] = col[fin[0]]
    if 6 not in log.measured:
        s0[6] = float(model.get("design_speed_m_s", 1.0))
    return s0


def _start_speed(log: ManoeuvreLog, s0: np.ndarray) -> float:
    """The speed the thrust balances [m/s]: the measured u at the record's start, the
    intercept of a parabola fitted to u over its first 2 s (the noise averaged out, the speed's
    early change followed), else the initial state's."""
    if 6 in log.measured:
        sel = (log.t <= log.t[0] + 2.0) & np.isfinite(log.z[:, 6])
        if sel.sum() >= 6:
            coef = np.polyfit(log.t[sel] - log.t[0], log.z[sel, 6], 2)
            return float(coef[-1])
        if sel.any():
            return float(np.mean(log.z[sel, 6]))
    return float(s0[6])


def record_speed(model: dict[str, Any], log: ManoeuvreLog) -> float:
    """The speed the thrust balances at the record's start [m/s] (:func:`_start_speed`; the
    model's design speed when u is not measured)."""
    return _start_speed(log, _initial_state(log, model))


def kalman_fit(model: dict[str, Any], log: ManoeuvreLog, symbols: list[str],
               start: np.ndarray, prior_sd: np.ndarray, sd: np.ndarray,
               method: str = "ukf", progress: Progress | None = None,
               stage: str = "filter") -> dict[str, Any]:
    """Augmented-state UKF or EKF (filterpy) and the RTS smoother over the record.

    Parameters
    ----------
    model : dict
        model.json
    log : ManoeuvreLog
    symbols : list of str
        The estimated coefficients
    start, prior_sd : ndarray
        Their starting values and prior standard deviations [their units]
    sd : ndarray
        Measurement noise standard deviation of each state [SI] (NaN: not measured)
    method : {"ukf", "ekf"}
    progress : callable, optional
        Called as ``progress(stage, rows done, rows)`` every :data:`PROGRESS_ROWS` rows

    Returns
    -------
    dict
        ``x`` (n, 12 + k) smoothed means, ``P`` (n, 12 + k, 12 + k) smoothed covariances,
        ``innovation`` (n, 12): each measured state's innovation divided by its predicted
        standard deviation ``sqrt(S_ii)`` [-] (NaN where not measured).

    Raises
    ------
    ValueError
        The filter diverged (one sentence).
    """
    k = len(symbols)
    thrust = 6 in log.measured  # the speed the thrust balances: one more state
    dim = 12 + k + (1 if thrust else 0)
    s0 = _initial_state(log, model)
    dyn = BatchModel(model, symbols, _start_speed(log, s0))
    p0 = np.zeros(dim)
    for i in range(12):
        p0[i] = sd[i] ** 2 if i in log.measured else 0.1 ** 2
    p0[12:12 + k] = prior_sd ** 2
    if thrust:
        p0[-1] = THRUST_SPEED_SD ** 2
    n = len(log.t)
    xs = np.zeros((n, dim))
    ps = np.zeros((n, dim, dim))
    x_prior = np.zeros((n, dim))
    p_prior = np.zeros((n, dim, dim))
    cross = np.zeros((n, dim, dim))
    innovation = np.full((n, 12), np.nan)  # each measured state's innovation / its sd [-]
    qrate = np.concatenate((PROCESS_SD ** 2, np.zeros(dim - 12)))

    def controls(j: int) -> tuple[float, float]:
        return (float(log.rudder[j]), float(log.sternplane[j]))

    x0 = np.concatenate((s0, start, [dyn.u0] if thrust else []))

    def step(aug: np.ndarray, dt: float, c0: tuple[float, float],
             c1: tuple[float, float]) -> np.ndarray:
        if thrust:
            dyn.u0 = aug[:, -1]
        # the motion is predicted with the added masses bounded to the physical side
        # (DOT_BOUND); the coefficients themselves stay random walks, unclipped
        phys = aug[:, :12 + k].copy()
        phys[:, 12:] = np.minimum(phys[:, 12:], dyn.upper)
        out = dyn.step(phys, dt, c0, c1)
        return np.concatenate((out[:, :12], aug[:, 12:]), axis=1)
    if method == "ukf":
        points = MerweScaledSigmaPoints(dim, alpha=ALPHA, beta=2.0, kappa=0.0)

        class _Batch(UKF):  # the process model over all sigma points at once
            def compute_process_sigmas(self, dt: float, fx: Any = None, **fx_args: Any) -> None:
                sig = self.points_fn.sigma_points(self.x, self.P)
                j = fx_args["k"]
                self._chi = sig
                self.sigmas_f = step(sig, dt, controls(j - 1), controls(j))
                self._chi_f = self.sigmas_f.copy()

            def cross_variance(self, x: np.ndarray, z: np.ndarray, sigmas_f: np.ndarray,
                               sigmas_h: np.ndarray) -> np.ndarray:
                # filterpy's sum of weighted outer products, as one product of matrices
                return (self.Wc[:, None] * (sigmas_f - x)).T @ (sigmas_h - z)

        f: Any = _Batch(dim_x=dim, dim_z=1, dt=0.05, hx=lambda x: x[:1], fx=lambda x, dt: x,
                        points=points, residual_z=np.subtract)  # filterpy's matrix path
    else:
        f = ExtendedKalmanFilter(dim_x=dim, dim_z=1)
    f.x = x0.copy()
    f.P = np.diag(p0)
    wc = points.Wc if method == "ukf" else np.zeros(0)
    j = 0
    try:
        with np.errstate(all="ignore"):
            for j in range(n):
                if j > 0:
                    dt = float(log.t[j] - log.t[j - 1])
                    f.Q = np.diag(qrate * dt)
                    xp, pp = f.x.copy(), f.P.copy()
                    if method == "ukf":
                        f.predict(dt=dt, k=j)
                        dx = f._chi - xp
                        df = f._chi_f - f.x
                        cross[j] = (wc[:, None] * dx).T @ df
                    else:
                        pts = np.vstack([xp, xp + np.diag(_fd_steps(xp))])
                        out = step(pts, dt, controls(j - 1), controls(j))
                        jac = ((out[1:] - out[0]) / _fd_steps(xp)[:, None]).T
                        f.F = jac
                        f.x = out[0].copy()
                        f.P = jac @ pp @ jac.T + f.Q
                        cross[j] = pp @ jac.T
                    x_prior[j], p_prior[j] = f.x.copy(), f.P.copy()
                zj = log.z[j]
                idx = [i for i in log.measured if np.isfinite(zj[i])]
                if idx:
                    r = np.diag(sd[idx] ** 2)
                    if method == "ukf":
                        f.update(zj[idx], R=r, hx=lambda x, idx=idx: x[idx])
                    else:
                        h = np.zeros((len(idx), dim))
                        h[np.arange(len(idx)), idx] = 1.0
                        f.update(zj[idx], HJacobian=lambda x, h=h: h, Hx=lambda x, h=h: h @ x, R=r)
                    if j > 0:  # the first sample has no prediction to compare with
                        innovation[j, idx] = f.y / np.sqrt(np.diag(f.S))
                f.P = 0.5 * (f.P + f.P.T)
                # the estimate projected onto the process model's domain (Simon 2010): a mean
                # beyond the bound would see a flat model and could never come back
                f.x[12:12 + k] = np.minimum(f.x[12:12 + k], dyn.upper)
                if not (np.all(np.isfinite(f.x)) and np.all(np.isfinite(f.P))):
                    raise ValueError(f"the {method.upper()} diverged at t = {log.t[j]:.3g} s (its "
                                     "state is no longer finite); try --start model, fewer "
                                     "coefficients or --method ls.")
                xs[j], ps[j] = f.x, f.P
                if progress is not None and (j + 1) % PROGRESS_ROWS == 0:
                    progress(stage, j + 1, n)
    except np.linalg.LinAlgError:
        raise ValueError(f"the {method.upper()}'s covariance stopped being positive definite at "
                         f"t = {log.t[j]:.3g} s (the filter diverged); try --start model, fewer "
                         "coefficients or --method ls.") from None
    if progress is not None:
        progress(stage, n, n)
    try:
        xs_s, ps_s = rts_smooth(xs, ps, x_prior, p_prior, cross)
    except np.linalg.LinAlgError:
        raise ValueError("the smoother met a singular predicted covariance (the filter "
                         "diverged); try --start model or --method ls.") from None
    return {"x": xs_s, "P": ps_s, "x_filtered": xs, "P_filtered": ps, "innovation": innovation}


def _fd_steps(x: np.ndarray) -> np.ndarray:
    return 1e-6 * np.maximum(np.abs(x), 1e-2)


def least_squares_fit(model: dict[str, Any], log: ManoeuvreLog, symbols: list[str],
                      start: np.ndarray, sd: np.ndarray,
                      windows: tuple[float, ...] = (1.0,),
                      progress: Progress | None = None, relax: bool = True) -> dict[str, Any]:
    """Output-error least squares of the coefficients and the initial measured states.

    Minimises ``sum_k sum_i ((y_i(t_k; beta, s0) - z_ik) / sigma_i)^2`` over the fitted
    states i, ``y`` the model simulated along the record (:meth:`BatchModel.run`), by
    :func:`scipy.optimize.least_squares` (trust-region reflective) with a finite-difference
    Jacobian computed in one batched simulation.

    The fitted states are the measured ones with white noise; a state the record carries
    without it (:func:`towtank.vehicle.identify_log.noise_free_states`: written exactly,
    derived, smoothed or interpolated) is left out, its initial value the first sample (its
    residuals are the model's own integration error, serially correlated, and with the weight
    of a noise estimate that measured the signal's curvature they would drive the fit); all
    are fitted when none has noise.

    Noise covariance (Maine & Iliff 1986; Jategaonkar 2015, sec. 4.5, the relaxation
    algorithm): ``R = diag(sigma_i^2)`` starts at ``sd`` and is re-estimated from the
    residuals, ``sigma_i^2 = mean_k r_ik^2``, the fit repeated with the new weights while an
    ``sigma_i`` moves by more than :data:`LS_RELAX_TOL` (at most :data:`LS_RELAX` times).

    Covariance of the estimates: the Newey-West sandwich (Newey & West 1987; for output error
    Morelli & Klein 1997, Klein & Morelli 2006, sec. 6.7)::

        M = J^T R^-1 J,   g_k = sum_i J_ik r_ik / sigma_i^2,
        S = sum_{|l| <= L} (1 - |l|/(L + 1)) sum_k g_k g_{k+l}^T,   C = M^+ S M^+

    (statsmodels' ``S_hac_simple``, Bartlett kernel, ``L = floor(4 (n/100)^(2/9))``), at
    least ``M^+`` on the diagonal: with white residuals of variance R, ``S = M``; residuals
    correlated along the record (a model or noise not quite white) widen it. ``M^+`` is the
    pseudo-inverse: a direction the record does not constrain gets an infinite variance.

    ``windows``: fractions of the record fitted one after the other, each from the previous
    estimates (from a far start, zero, the motion the model predicts over the whole record is
    too far from the measured one for the fit to find its way; over the first part it is
    not: the usual continuation of output-error fits). ``relax``: re-estimate R (the windows
    before the last do not).

    ``progress``, optional: called as ``progress(stage, evaluations, at most)`` after each
    evaluation (a simulation along the record), at most :data:`LS_MAX_NFEV` per fit.

    Returns
    -------
    dict
        ``value``, ``sd`` (k,), ``covariance`` (k, k), ``s0`` (12,), ``cost``,
        ``covariance_all`` (k + m, k + m): of the coefficients and the m measured initial
        states (zero rows and columns for the states left out, their initial values fixed),
        ``noise_sd`` (12,): R's sigma_i [SI] of the fitted states (NaN elsewhere),
        ``fitted``: the fitted states, ``left_out``: the noise-free ones left out.
    """
    for frac in windows[:-1]:
        n = max(int(frac * len(log.t)), 20)
        sub = ManoeuvreLog(t=log.t[:n], z=log.z[:n], rudder=log.rudder[:n],
                           sternplane=log.sternplane[:n], measured=log.measured, name=log.name)
        start = least_squares_fit(model, sub, symbols, start, sd, relax=False,
                                  progress=_staged(progress,
                                                   f"least squares, first {frac:.0%} of the "
                                                   "record"))["value"]

    k = len(symbols)
    s0 = _initial_state(log, model)
    dyn = BatchModel(model, symbols, _start_speed(log, s0))
    meas = list(log.measured)
    left_out = noise_free_states(log)
    fit = [i for i in meas if i not in left_out] or meas
    left_out = [i for i in meas if i not in fit]
    zm = log.z[:, fit]
    mask = np.isfinite(zm)
    rows, cols = np.nonzero(mask)
    scale_b = np.maximum(np.abs(start), 1.0)
    scale_s = np.array([max(sd[i] * 10, 1e-6) for i in fit])
    scale = np.concatenate((scale_b, scale_s))

    def unpack(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        th = theta * scale
        s = np.tile(s0, (theta.shape[0], 1)) if theta.ndim == 2 else s0.copy()
        if theta.ndim == 2:
            s[:, fit] = th[:, k:]
            return th[:, :k], s
        s[fit] = th[k:]
        return th[:k], s

    def residuals_many(thetas: np.ndarray) -> np.ndarray:
        beta, s = unpack(thetas)
        if 6 in fit:  # the thrust balances the drag at the fitted initial speed
            dyn.u0 = s[:, 6]
        sim = dyn.run(s, beta, log)[:, :, fit]  # (n, N, m)
        out = (sim - zm[:, None, :]).transpose(1, 0, 2)[:, mask]
        out[~np.isfinite(out)] = 1e6
        return out

    cache: dict[bytes, np.ndarray] = {}
    evaluations = [0]
    stage = "least squares" if len(windows) == 1 else "least squares, whole record"

    def raw(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        # the unweighted residuals and their forward-difference Jacobian from one batched
        # simulation: on a few rows the simulation costs about what one row does
        key = theta.tobytes()
        if key not in cache:
            hstep = 1e-6 * np.maximum(np.abs(theta), 1.0)
            pts = np.vstack([theta, theta + np.diag(hstep)])
            res = residuals_many(pts)
            cache.clear()
            cache[key] = np.vstack([res[0][None, :], ((res[1:] - res[0]) / hstep[:, None])])
            evaluations[0] += 1
            if progress is not None:
                progress(stage, min(evaluations[0], LS_MAX_NFEV), LS_MAX_NFEV)
        out = cache[key]
        return out[0], out[1:].T

    sigma = np.array([sd[i] for i in fit], dtype=float)
    floor = np.array([noise_floor(log.z[:, i]) for i in fit])
    theta = np.concatenate((start, s0[fit])) / scale
    cost = 0.0
    for _ in range(1 + (LS_RELAX if relax else 0)):
        w = 1.0 / sigma[cols]
        # a trial step far from the record can overflow the cost ½·f·f: it is infinite, and
        # least_squares rejects the step, as it should (quietly: not a user's warning)
        with np.errstate(over="ignore"):
            sol = least_squares(lambda th, w=w: raw(th)[0] * w,
                                theta, jac=lambda th, w=w: raw(th)[1] * w[:, None],
                                method="trf", x_scale="jac", max_nfev=LS_MAX_NFEV)
        theta, cost = sol.x, float(sol.cost)
        if not relax:
            break
        new = np.maximum(output_error_sd(raw(theta)[0], cols, len(fit)), floor)
        moved = np.abs(new / sigma - 1.0) > LS_RELAX_TOL
        sigma = new
        if not moved.any():
            break
    r, j = raw(theta)
    j = j / scale[None, :]
    cov = output_error_covariance(j / sigma[cols][:, None], r / sigma[cols], rows, len(log.t))
    p_all = k + len(meas)
    keep = list(range(k)) + [k + meas.index(i) for i in fit]
    cov_all = np.zeros((p_all, p_all))
    cov_all[np.ix_(keep, keep)] = cov
    beta, s_fit = unpack(theta)
    noise = np.full(12, np.nan)
    noise[fit] = sigma
    return {"value": beta, "sd": np.sqrt(np.diag(cov)[:k]), "covariance": cov[:k, :k],
            "s0": s_fit, "cost": cost, "covariance_all": cov_all, "noise_sd": noise,
            "fitted": fit, "left_out": left_out}


def output_error_sd(residuals: np.ndarray, cols: np.ndarray, m: int) -> np.ndarray:
    """Each output's residual rms ``sqrt(mean_k r_ik^2)`` [its unit]: the diagonal of the
    output-error estimate of the noise covariance R (Jategaonkar 2015, eq. 4.15).

    Parameters
    ----------
    residuals : ndarray
        (e,) the residuals of the finite measurements
    cols : ndarray
        (e,) the output of each
    m : int
        The number of outputs
    """
    count = np.maximum(np.bincount(cols, minlength=m), 1)
    return np.sqrt(np.bincount(cols, weights=residuals ** 2, minlength=m) / count)


def output_error_covariance(jw: np.ndarray, rw: np.ndarray, rows: np.ndarray,
                            n: int) -> np.ndarray:
    """Covariance of output-error estimates: the Newey-West sandwich ``M^+ S M^+``, at least
    ``M^+`` on the diagonal (:func:`least_squares_fit`).

    Parameters
    ----------
    jw : ndarray
        (e, p) the Jacobian of the residuals over their sd ``R^-1/2 J``
    rw : ndarray
        (e,) the residuals over their sd ``R^-1/2 r`` [-]
    rows : ndarray
        (e,) the sample (time) of each residual, 0 .. n - 1
    n : int
        Samples in the record

    Returns
    -------
    ndarray
        (p, p); ``inf`` on the diagonal of a parameter in a direction ``M`` does not
        constrain
    """
    _, sv, vt = np.linalg.svd(jw, full_matrices=False)
    tol = sv.max(initial=0.0) * max(jw.shape) * np.finfo(float).eps * 1e3
    ok = sv > max(tol, 1e-300)
    m_inv = (vt[ok].T / sv[ok] ** 2) @ vt[ok]
    score = np.zeros((n, jw.shape[1]))
    np.add.at(score, rows, jw * rw[:, None])
    cov = m_inv @ S_hac_simple(score) @ m_inv
    d = np.sqrt(np.maximum(np.diag(cov), np.diag(m_inv)) / np.maximum(np.diag(cov), 1e-300))
    cov = cov * np.outer(d, d)
    free = np.einsum("ij,ij->j", vt[~ok], vt[~ok]) > 1e-9
    cov[free, :] = np.inf
    cov[:, free] = np.inf
    return cov


def identify(model: dict[str, Any], log: ManoeuvreLog, estimate: list[str],
             method: str = "ukf", start: str = "model", noise: dict[str, float] | None = None,
             prior_sd: dict[str, float] | None = None, check: bool = True,
             progress: Progress | None = None, adequacy: bool = True,
             validate: ManoeuvreLog | None = None) -> IdentifyFit:
    """Identify coefficients of ``model`` from the manoeuvre record ``log``.

    Parameters
    ----------
    model : dict
        model.json (:func:`towtank.vehicle.model.read_model`)
    log : ManoeuvreLog
        :func:`towtank.vehicle.identify_log.read_log`
    estimate : list of str
        The coefficients to identify (model.json symbols); the others keep their values
    method : {"ukf", "ekf", "ls"}
        Augmented-state unscented or extended Kalman filter with the RTS smoother, or
        output-error least squares alone
    start : {"model", "zero"}
        Starting values: the model's, or zero (the REMUS study)
    noise : dict, optional
        Measurement noise standard deviation per state column [the column's unit]; default
        estimated from the record (:func:`towtank.vehicle.identify_log.noise_sd`)
    prior_sd : dict, optional
        The filter's prior standard deviation per coefficient; default
        ``3 max(|model value|, 1)`` (the study's initial P of 10-100 for values of a few units)
    check : bool
        With a filter, run least squares too as the cross-check
    progress : callable, optional
        ``progress(stage, done, total)``: the filter's passes in rows of the record, least
        squares in evaluations (:data:`LS_MAX_NFEV` at most)
    adequacy : bool
        Test whether the record fits the model (:mod:`towtank.vehicle.adequacy`): the
        result's ``adequacy`` table (fit.csv), else None
    validate : ManoeuvreLog, optional
        A second record the model with the estimates is tested against, instead of the
        held-out last :data:`HOLDOUT_FRACTION` of ``log``

    Raises
    ------
    ValueError
        A symbol the model cannot take, an unknown method, a diverging filter (one sentence).
    """
    if method not in METHODS:
        raise ValueError(f"--method must be one of {', '.join(METHODS)}, not {method!r}.")
    if start not in ("model", "zero"):
        raise ValueError(f"--start must be model or zero, not {start!r}.")
    symbols = [s.strip() for s in estimate if s.strip()]
    if not symbols:
        raise ValueError("--estimate names no coefficient.")
    bad = [s for s in symbols if not (SYMBOL_RE.match(s) or _dot(s))]
    if bad:
        raise ValueError(f"--estimate: {', '.join(bad)} {'is' if len(bad) == 1 else 'are'} not "
                         "model.json coefficient symbols (e.g. N_ur, N_rdot, N_uudr).")
    if len(set(symbols)) != len(symbols):
        raise ValueError("--estimate names a coefficient twice.")
    coef = model.get("coefficients") or {}
    model_vals = np.array([float(coef.get(s, 0.0)) for s in symbols])
    start_vals = model_vals.copy() if start == "model" else np.zeros(len(symbols))
    psd = np.array([float((prior_sd or {}).get(s, 3.0 * max(abs(v), 1.0)))
                    for s, v in zip(symbols, model_vals, strict=True)])
    sd = _noise(log, noise)
    notes = list(log.notes)
    hist: dict[str, np.ndarray] = {}
    ls = None
    s_init = None
    innovation: np.ndarray | None = None
    if method in ("ukf", "ekf"):
        x_start, prior, prev = start_vals, psd, None
        passes = 0
        for npass in range(1, MAX_PASSES + 1):
            passes = npass
            res = kalman_fit(model, log, symbols, x_start, prior, sd, method, progress,
                             f"{method.upper()} pass {npass} of at most {MAX_PASSES}")
            xk, pk = res["x"], res["P"]
            k = len(symbols)
            value = xk[0, 12:12 + k]
            cov = pk[0, 12:12 + k, 12:12 + k]
            sdv = np.sqrt(np.clip(np.diag(cov), 0.0, None))
            if prev is not None and np.all(np.abs(value - prev) <= PASS_TOL * sdv):
                break
            prev = value.copy()
            x_start, prior = value.copy(), np.minimum(psd, PASS_PRIOR * sdv)
        notes.append(f"{method.upper()} and smoother: {passes} passes over the record")
        hist = {"t": log.t, "mean": res["x_filtered"][:, 12:12 + k],
                "sd": np.sqrt(np.clip(np.einsum("nii->ni", res["P_filtered"])[:, 12:12 + k],
                                      0, None)),
                "smoothed": xk[:, 12:12 + k]}
        s_init = xk[0, :12]
        innovation = res["innovation"]  # the last pass's
        if check:
            ls = least_squares_fit(model, log, symbols, value.copy(), sd, progress=progress)
            s_init = ls["s0"]  # the initial state that fits the whole record open loop
            notes.extend(_left_out_note(ls))
    else:
        ls = least_squares_fit(model, log, symbols, start_vals, sd,
                               windows=LS_WINDOWS if start == "zero" else (1.0,),
                               progress=progress)
        value, sdv, cov = ls["value"], ls["sd"], ls["covariance"]
        s_init = ls["s0"]
        notes.extend(_left_out_note(ls))
        ls = None
    s0 = _initial_state(log, model)
    if s_init is not None:  # the estimated initial state, not the first noisy sample
        s0 = np.asarray(s_init, dtype=float)
    speed = _start_speed(log, _initial_state(log, model))
    if s_init is not None and 6 in log.measured and (ls is not None or method == "ls"):
        speed = float(s0[6])  # least squares' initial speed, which its thrust balanced
    sim = simulate_fitted(model, symbols, np.asarray(value), s0, log, speed)
    if innovation is None:  # least squares: its output-error residuals over the noise sd
        innovation = (log.z - sim) / sd
    table, inputs = None, None
    if adequacy:
        # the tests assume white measurement noise: a state written exactly, or without white
        # noise (derived, smoothed, interpolated) cannot have white innovations
        exact = sorted(set(exact_states(log, sd)) | set(noise_free_states(log)))
        if exact:
            notes.append(f"{', '.join(STATE_COLUMNS[i] for i in exact)} without white noise in "
                         "the record (exact, derived, smoothed or interpolated): left out of the "
                         "tests of the fit" + ("" if len(exact) < len(log.measured) else
                                               "; no state is left to test the fit on"))
        tested = [i for i in log.measured if i not in exact]
        inputs = _adequacy_inputs(model, log, symbols, np.asarray(value), sd, innovation,
                                  tested, validate, noise, progress)
        table = adequacy_table(**inputs)
    resim = ManoeuvreLog(t=log.t, z=sim, rudder=log.rudder, sternplane=log.sternplane,
                         measured=list(range(12)), name="resimulated")
    return IdentifyFit(symbols=symbols, start=start_vals, value=np.asarray(value),
                       sd=np.asarray(sdv), prior_sd=psd, method=method,
                       covariance=np.asarray(cov), history=hist, notes=tuple(notes),
                       check=None if ls is None else {"value": ls["value"], "sd": ls["sd"]},
                       measured=log.frame(), resimulated=resim.frame(), adequacy=table,
                       residuals=inputs)


def with_coefficients(model: dict[str, Any], symbols: list[str],
                      value: np.ndarray) -> dict[str, Any]:
    """A copy of ``model`` with the coefficients ``symbols`` set to ``value``."""
    out = dict(model)
    out["coefficients"] = dict(model.get("coefficients") or {}) | {
        s: float(v) for s, v in zip(symbols, value, strict=True)}
    return out


def simulate_fitted(model: dict[str, Any], symbols: list[str], value: np.ndarray,
                    s0: np.ndarray, log: ManoeuvreLog, speed_m_s: float) -> np.ndarray:
    """The states (n, 12) [SI] of ``model`` with ``symbols`` set to ``value``, simulated from
    ``s0`` along the record's times and controls, the thrust balancing the drag at
    ``speed_m_s`` [m/s]."""
    dyn = BatchModel(with_coefficients(model, symbols, value), [], speed_m_s)
    return dyn.run(np.asarray(s0, dtype=float)[None, :], np.zeros((1, 0)), log)[:, 0, :]


def _fit_and_run(model: dict[str, Any], fit_log: ManoeuvreLog, run_log: ManoeuvreLog,
                 symbols: list[str], value: np.ndarray, sd: np.ndarray,
                 progress: Progress | None, stage: str) -> np.ndarray:
    """Least squares over ``fit_log`` of the coefficients ``symbols`` from ``value`` (none:
    the initial measured states alone), then the fitted model along ``run_log`` (which starts
    as ``fit_log`` does): its residuals over their sd (n, 12) [-], the sd combining the
    noise ``sd`` and the prediction's own, ``g^T C g`` with ``g`` the states' sensitivity to
    the fitted coefficients and initial states (forward differences) and ``C`` their
    covariance."""
    fit = least_squares_fit(model, fit_log, symbols, value, sd,
                            progress=_staged(progress, stage))
    k, meas = len(symbols), list(fit_log.measured)
    theta = np.concatenate((fit["value"], fit["s0"][meas]))
    step = 1e-6 * np.maximum(np.abs(theta), 1.0)
    pts = np.vstack([theta, theta + np.diag(step)])
    states = np.tile(fit["s0"], (len(pts), 1))
    states[:, meas] = pts[:, k:]
    dyn = BatchModel(model, symbols, _start_speed(fit_log, fit["s0"]))
    if 6 in meas:  # the thrust balances the drag at the fitted initial speed
        dyn.u0 = states[:, 6]
    sim = dyn.run(states, pts[:, :k], run_log)  # (n, 1 + p, 12)
    sens = (sim[:, 1:, :] - sim[:, :1, :]) / step[None, :, None]
    cov = np.nan_to_num(fit["covariance_all"], nan=0.0, posinf=0.0, neginf=0.0)
    var = np.einsum("npi,pq,nqi->ni", sens, cov, sens)
    return (run_log.z - sim[:, 0, :]) / np.sqrt(sd ** 2 + var)


def _adequacy_inputs(model: dict[str, Any], log: ManoeuvreLog, symbols: list[str],
                     value: np.ndarray, sd: np.ndarray, innovation: np.ndarray,
                     tested: list[int], validate: ManoeuvreLog | None,
                     noise: dict[str, float] | None,
                     progress: Progress | None) -> dict[str, Any]:
    """The arguments of :func:`towtank.vehicle.adequacy.adequacy_table` (fit.csv): the
    innovations' tests and
    the model against the held-out last :data:`HOLDOUT_FRACTION` of the record (its
    coefficients fitted by least squares to the rest, from ``value``) or, given, against the
    record ``validate`` (its initial measured states fitted, the coefficients ``value``); of
    the states ``tested`` (those with noise)."""
    dof = _noise_dof(log, noise)
    if validate is not None:
        sd_v = _noise(validate, noise)
        resid = _fit_and_run(with_coefficients(model, symbols, value), validate, validate, [],
                             np.zeros(0), sd_v, progress, "validation record")
        both = [i for i in tested if i not in exact_states(validate, sd_v)]
        return {"innovation": innovation, "check": resid, "check_test": "validation",
                "states": both, "dof": dof, "check_dof": _noise_dof(validate, noise)}
    n = len(log.t)
    cut = int(round((1.0 - HOLDOUT_FRACTION) * n))
    if n - cut < MIN_ROWS or cut < MIN_ROWS:
        return {"innovation": innovation, "check": None, "check_test": "holdout",
                "states": tested, "dof": dof}
    first = ManoeuvreLog(t=log.t[:cut], z=log.z[:cut], rudder=log.rudder[:cut],
                         sternplane=log.sternplane[:cut], measured=log.measured, name=log.name)
    resid = _fit_and_run(model, first, log, symbols, value, sd, progress,
                         f"least squares, first {1 - HOLDOUT_FRACTION:.0%} of the record")
    return {"innovation": innovation, "check": resid[cut:], "check_test": "holdout",
            "states": tested, "dof": dof}


def _noise(log: ManoeuvreLog, noise: dict[str, float] | None) -> np.ndarray:
    """Each state's noise sd [SI]: estimated from ``log``, replaced where ``noise`` gives it
    [the column's unit]."""
    sd = noise_sd(log)
    for state, val in (noise or {}).items():
        col, given = noise_entry(state, val)
        sd[STATE_COLUMNS.index(col)] = given * (math.pi / 180.0 if col.endswith(
            ("_deg", "_deg_s")) else 1.0)
    return sd


def _noise_dof(log: ManoeuvreLog, noise: dict[str, float] | None) -> np.ndarray:
    """Degrees of freedom of each state's noise variance (:func:`_noise`) [-]: infinite where
    ``noise`` gives it (:func:`towtank.vehicle.adequacy.noise_dof`)."""
    given = np.zeros(len(STATE_COLUMNS), dtype=bool)
    for state, val in (noise or {}).items():
        given[STATE_COLUMNS.index(noise_entry(state, val)[0])] = True
    return noise_dof(np.isfinite(log.z).sum(axis=0), given)


def _left_out_note(ls: dict[str, Any]) -> list[str]:
    """The note naming the states least squares left out (no white noise in the record)."""
    if not ls["left_out"]:
        return []
    return [f"{', '.join(STATE_COLUMNS[i] for i in ls['left_out'])} without white noise in "
            "the record (written exactly, derived, smoothed or interpolated): left out of the "
            "least-squares fit, their initial values the first samples"]


def _staged(progress: Progress | None, stage: str) -> Progress | None:
    """``progress`` with its stage replaced by ``stage``."""
    if progress is None:
        return None
    return lambda _, done, total: progress(stage, done, total)


def _dot(symbol: str) -> bool:
    return (len(symbol) == 6 and symbol[0] in DOF and symbol[1] == "_"
            and symbol[2] in VELOCITIES and symbol[3:] == "dot")
