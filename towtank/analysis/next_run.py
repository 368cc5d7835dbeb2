"""Which run next: the remaining runs ranked by how much they narrow the widest interval.

From the current hull fits (:mod:`towtank.analysis.hull`), each candidate condition (a row of
the run sheet still to be towed, or a suggested condition not on it) is given the information
it would add to the regression models it enters, and the expected 95 % half-widths after it
are predicted (docs/method.md "Which run next"):

* the C_D(α) quadratic (report eq. 13) over the steady hull runs with |α| ≤ α_max: one design
  row [α², α, 1] per run (α in rad);
* the joint added-mass regression D = k2·U|U| + k1·U + M·a (report eqs. 7–8) over the
  samples of the α = 0 (X_udot) or α = 90° (Y_vdot) runs: the run's design rows built from
  its nominal profile (a ramp at the nominal acceleration up to the nominal speed, then the
  plateau), with the sample spacing, the trimming of the ramp and the plateau's length of the
  day's runs at that angle;
* the transverse tow R = ½ρA_lat·C_D,90·U|U| (report eq. 15): one row [U|U|] per run.

For a coefficient ℓ'β of a model with design X now and rows X_c added, the regression variance
is expected to become u_reg² · ℓ'(X'X + X_c'X_c)⁻¹ℓ / ℓ'(X'X)⁻¹ℓ · E s²_new / E s²_now: the
information of the run under the fit's residual variance, Cov_new = (Cov⁻¹ + I_run)⁻¹ with
I_run = X_c'X_c/σ², times the change of the residual variance the refit will report. For the two
fits over runs (C_D(α), transverse) that change is expected from a model of each run's residual
variance, v(U) = θ₀ + θ₁·U⁻⁴ for C_D (a force error of fixed size divided by ½ρAU²: a run at
0.8 m/s scatters three times more than one at 2 m/s) and θ₀ + θ₁·U⁴ for the transverse tow,
fitted to the current residuals; E s² = Σ v_i(1 − h_i)/(n − p). For the clustered added-mass
regression the clustered-to-naive variance ratio of the current fit is carried over (it cancels
in the expression) and its Bell–McCaffrey degrees of freedom are recomputed on the augmented
design. The tare's and the weighed mass's parts of each uncertainty budget are kept as they
are.

Pure functions, no I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from scipy.optimize import nnls

from towtank.analysis.hull import ANGLE_TOL_DEG, MIRROR, SYMBOLS, Estimate, HullFit
from towtank.reduce.run import PHASE_ACCEL, PHASE_STEADY, RunReduction
from towtank.stats.intervals import bm_dof
from towtank.stats.quantiles import ALPHA, t_quantile

#: Columns of :func:`rank_next_runs`' frame, in order.
COLUMNS = ["rank", "run", "description", "angle_deg", "speed_m_s", "accel_m_s2", "target",
           "half_width_now", "half_width_after", "relative_now", "relative_after"]

#: The coefficients that are ranked: the table's symbols without their axisymmetric twins.
RANKED = tuple(s for s in SYMBOLS if s not in MIRROR)

#: Symbols of the C_D(α) quadratic, with ℓ over (a, b, c): X_u|u| = Y_uv ∝ c, X_uv ∝ b,
#: X_v|v| ∝ a − c/2 (report eqs. 13–15; hull.fit_damping).
CD_ALPHA_ELL = {"X_u|u|": (0.0, 0.0, 1.0), "Y_uv": (0.0, 0.0, 1.0), "X_uv": (0.0, 1.0, 0.0),
                "X_v|v|": (1.0, 0.0, -0.5)}

_SPEED_MATCH = 0.03  # a condition repeats a sheet row within 3 % in speed [-]
_ACCEL_MATCH = 0.10  # ... and within 10 % in acceleration (accelerated tows) [-]


@dataclass(frozen=True)
class Condition:
    """One run to rank: a sheet row still to tow (``run``) or a suggestion (``run`` None).

    Attributes: ``config`` ("hull", "sting", "fin"), ``angle_deg`` [deg], ``speed`` nominal
    [m/s], ``accel`` nominal [m/s²], ``test`` ("steady" or "accel").
    """

    run: int | None
    config: str
    angle_deg: float
    speed: float
    accel: float
    test: str = "steady"

    def description(self) -> str:
        """"run 23: α 20°, 1.0 m/s, steady" or "new: α 25°, 1.2 m/s, accel 0.5 m/s²"."""
        head = f"run {self.run}" if self.run is not None else "new"
        cfg = "" if self.config == "hull" else f"{self.config}, "
        kind = (f"accel {_num(self.accel)} m/s²" if self.test == "accel" else "steady")
        return f"{head}: {cfg}α {self.angle_deg:g}°, {_num(self.speed)} m/s, {kind}"


def _num(x: float) -> str:
    """A speed or acceleration as a lab writes it: 1.0, 1.25, 0.15."""
    text = f"{x:.2f}"
    return text[:-1] if text.endswith("0") else text


@dataclass
class Profile:
    """The sample layout of the day's runs at one angle (for design rows of a nominal run).

    ``dt`` [s] the fit samples' spacing, ``n_steady`` the plateau's samples, ``trim_start`` and
    ``trim_end`` [s] the time cut from each end of the constant-acceleration ramp.
    """

    dt: float
    n_steady: int
    trim_start: float
    trim_end: float


@dataclass
class Model:
    """One regression of the hull stage: its design now and the coefficients it gives.

    ``kind`` is "cd_alpha", "mean0" (C_D at α = 0 alone), "transverse" or "joint";
    ``design`` (n, p) its rows now; ``ell`` {symbol: ℓ (p,)}; ``reg_dof`` the regression's
    degrees of freedom; for "joint": ``groups`` (the run of each row), ``angle`` [deg] and
    ``profile``.
    """

    kind: str
    design: np.ndarray
    ell: dict[str, np.ndarray]
    reg_dof: float
    groups: np.ndarray | None = None
    angle: float = 0.0
    profile: Profile | None = None
    alpha_max_deg: float = 30.0
    speeds: np.ndarray | None = None  # of the rows now [m/s] (the residual variance's model)
    theta: np.ndarray | None = None  # the residual variance's model, see variance_basis


# ------------------------------------------------------------------------------ design rows
def cd_alpha_rows(angle_deg: float) -> np.ndarray:
    """The C_D(α) fit's design row [α², α, 1] of a steady run at ``angle_deg`` [deg] (α in rad)."""
    a = math.radians(angle_deg)
    return np.array([[a * a, a, 1.0]])


def transverse_rows(speed: float) -> np.ndarray:
    """The transverse fit's design row [U|U|] of a run at ``speed`` U [m/s]."""
    return np.array([[speed * abs(speed)]])


def profile_rows(speed: float, accel: float, profile: Profile) -> np.ndarray:
    """Design rows [U|U|, U, a] of the joint regression for a nominal run.

    The ramp at ``accel`` a [m/s²] up to ``speed`` U [m/s] gives samples every ``dt`` between
    t = trim_start and U/a − trim_end (U = a·t), the plateau ``n_steady`` samples at U with
    a = 0 (report eqs. 7–8 evaluated on the nominal profile).
    """
    rows = [np.tile([speed * abs(speed), speed, 0.0], (max(profile.n_steady, 0), 1))]
    if accel > 0 and speed > 0 and profile.dt > 0:
        t = np.arange(profile.trim_start, speed / accel - profile.trim_end, profile.dt)
        u = accel * t
        rows.append(np.column_stack([u * np.abs(u), u, np.full(u.size, accel)]))
    return np.vstack(rows)


def day_profile(reductions: dict[int, RunReduction], run_ids: list[int]) -> Profile | None:
    """The sample layout of ``run_ids`` (medians over the runs): spacing, plateau samples, the
    ramp's trimming at each end [s]. None when the runs have no samples."""
    dts, ns, starts, ends = [], [], [], []
    for r in run_ids:
        red = reductions.get(r)
        if red is None or not red.samples or red.samples["U"].size < 2:
            continue
        s = red.samples
        t = np.sort(s["t"])
        dts.append(float(np.median(np.diff(t))))
        st, acc = s["phase"] == PHASE_STEADY, s["phase"] == PHASE_ACCEL
        ns.append(int(st.sum()))
        a = float(np.mean(s["a"][acc])) if acc.any() else math.nan
        if acc.any() and a > 0 and st.any():
            starts.append(float(np.min(s["U"][acc])) / a)
            ends.append((float(np.mean(s["U"][st])) - float(np.max(s["U"][acc]))) / a)
    if not dts:
        return None
    return Profile(dt=float(np.median(dts)), n_steady=int(np.median(ns)),
                   trim_start=float(np.median(starts)) if starts else 0.0,
                   trim_end=float(np.median(ends)) if ends else 0.0)


# -------------------------------------------------------------------------------- the models
def hull_models(fit: HullFit, reductions: dict[int, RunReduction] | None = None,
                alpha_max_deg: float = 30.0) -> list[Model]:
    """The regression models of a hull fit, with their design rows now.

    The added-mass regressions need the run ``reductions`` (their samples); without them those
    coefficients are not predicted (they keep their half-widths).
    """
    models: list[Model] = []
    dm = fit.damping
    if dm is not None and dm.runs is not None and len(dm.runs) >= 1:
        a = dm.runs["alpha_rad"].to_numpy(float)
        x = np.column_stack([a * a, a, np.ones_like(a)])
        speeds = dm.runs["speed"].to_numpy(float)
        models.append(Model("cd_alpha", x, {s: np.array(v) for s, v in CD_ALPHA_ELL.items()},
                            float(dm.dof), alpha_max_deg=alpha_max_deg, speeds=speeds,
                            theta=variance_model("cd_alpha", x, speeds,
                                                 dm.runs["resid"].to_numpy(float))))
    elif "X_u|u|" in fit.estimates:  # fewer than three angles: the mean C_D at α = 0
        n = max(int(fit.estimates["X_u|u|"].n_runs), 1)
        one = np.array([1.0])
        models.append(Model("mean0", np.ones((n, 1)), {"X_u|u|": one, "Y_uv": one},
                            float(n - 1), alpha_max_deg=alpha_max_deg))
    tr = dm.transverse_runs if dm is not None else None
    if tr is not None and len(tr) >= 1:
        u = tr["speed"].to_numpy(float)
        x = (u * np.abs(u))[:, None]
        models.append(Model("transverse", x, {"Y_v|v|": np.array([1.0])}, float(len(u) - 1),
                            speeds=u, theta=variance_model("transverse", x, u,
                                                           tr["resid"].to_numpy(float))))
    for sym, angle in (("X_udot", 0.0), ("Y_vdot", 90.0)):
        am = fit.added_mass.get(sym)
        if am is None or not reductions or any(r not in reductions for r in am.runs):
            continue
        parts = [reductions[r].samples for r in am.runs]
        u = np.concatenate([p["U"] for p in parts])
        acc = np.concatenate([p["a"] for p in parts])
        groups = np.concatenate([np.full(p["U"].size, r) for r, p in zip(am.runs, parts,
                                                                          strict=True)])
        models.append(Model("joint", np.column_stack([u * np.abs(u), u, acc]),
                            {sym: np.array([0.0, 0.0, 1.0])}, float(am.regression_dof),
                            groups=groups, angle=angle,
                            profile=day_profile(reductions, list(am.runs))))
    return models


def variance_basis(kind: str, speeds: np.ndarray) -> np.ndarray:
    """Regressors of a run's residual variance v(U) = θ₀ + θ₁·f(U) [response unit²].

    C_D(α): f = U⁻⁴, a force error of fixed size divided by ½ρAU² (the low-speed runs'
    C_D scatter more) on top of a run-to-run floor θ₀; transverse tow (R/(½ρA_lat) against
    U|U|): f = U⁴, a relative error on top of the force's fixed one.
    """
    u = np.maximum(np.abs(np.asarray(speeds, dtype=float)), 1e-6)
    f = u**-4 if kind == "cd_alpha" else u**4
    return np.column_stack([np.ones_like(u), f])


def leverages(design: np.ndarray) -> np.ndarray:
    """h_i = diag(X (X'X)⁺ X') of the rows of ``design``."""
    with np.errstate(all="ignore"):
        return np.einsum("ij,ij->i", design @ np.linalg.pinv(design.T @ design), design)


def variance_model(kind: str, design: np.ndarray, speeds: np.ndarray,
                   resid: np.ndarray) -> np.ndarray | None:
    """θ ≥ 0 of v(U) = θ₀ + θ₁·f(U) (:func:`variance_basis`) fitted to the current fit's
    residuals by non-negative least squares of e_i²/(1 − h_i) on the basis (E e_i² = (1 − h_i)
    v_i for independent errors). None with too few runs (fewer than two residual degrees of
    freedom) or a fit that fails: the runs are then taken as equally precise."""

    n, p = design.shape
    if n - p < 2 or resid.size != n:
        return None
    h = np.clip(leverages(design), 0.0, 0.99)
    target = resid**2 / (1.0 - h)
    basis = variance_basis(kind, speeds)
    scale = np.maximum(np.max(np.abs(basis), axis=0), 1e-300)
    try:
        theta, _ = nnls(basis / scale, target)
    except (ValueError, RuntimeError):
        return None
    theta = theta / scale
    return theta if np.all(np.isfinite(theta)) and float(np.sum(theta)) > 0 else None


def expected_s2(design: np.ndarray, v: np.ndarray) -> float:
    """E s² = Σ v_i (1 − h_i)/(n − p): the OLS residual variance expected with independent
    errors of variances v_i [response unit²] (E SSE = tr((I − H)Σ)); nan without freedom."""
    n, p = design.shape
    if n - p <= 0:
        return math.nan
    return float(np.sum(v * (1.0 - leverages(design)))) / (n - p)


def s2_ratio(model: Model, added: np.ndarray, speed: float) -> float:
    """The factor the expected residual variance s² of an OLS over runs changes by when a run
    at ``speed`` [m/s] adds the rows ``added``: E s²_new / E s²_now; 1 for equally precise
    runs or a fit without a variance model."""
    if model.theta is None or model.speeds is None or added.shape[0] == 0:
        return 1.0
    v_now = variance_basis(model.kind, model.speeds) @ model.theta
    v_add = variance_basis(model.kind, np.full(added.shape[0], speed)) @ model.theta
    now = expected_s2(model.design, v_now)
    new = expected_s2(np.vstack([model.design, added]), np.concatenate([v_now, v_add]))
    ratio = new / now if now > 0 else math.nan
    return ratio if math.isfinite(ratio) and ratio > 0 else 1.0


def candidate_rows(model: Model, cond: Condition) -> np.ndarray:
    """The design rows ``cond`` adds to ``model`` (none when it does not enter it)."""
    p = model.design.shape[1]
    none = np.zeros((0, p))
    if cond.config != "hull" or not cond.speed > 0:
        return none
    if model.kind == "cd_alpha":
        ok = abs(cond.angle_deg) <= model.alpha_max_deg + 1e-9
        return cd_alpha_rows(cond.angle_deg) if ok else none
    if model.kind == "mean0":
        return np.ones((1, 1)) if abs(cond.angle_deg) <= ANGLE_TOL_DEG else none
    if model.kind == "transverse":
        return transverse_rows(cond.speed) if abs(cond.angle_deg - 90.0) <= ANGLE_TOL_DEG \
            else none
    if model.kind == "joint" and model.profile is not None \
            and abs(cond.angle_deg - model.angle) <= ANGLE_TOL_DEG:
        return profile_rows(cond.speed, cond.accel, model.profile)
    return none


def variance_ratio(design: np.ndarray, added: np.ndarray, ell: np.ndarray) -> float:
    """ℓ'(X'X + X_c'X_c)⁻¹ℓ / ℓ'(X'X)⁻¹ℓ: the factor on ℓ'β̂'s regression variance when the
    rows X_c are added, at the same residual variance σ² (Cov = σ²(X'X)⁻¹, so
    Cov_new = (Cov⁻¹ + X_c'X_c/σ²)⁻¹). 1 when nothing is added or the fit is degenerate."""
    if added.shape[0] == 0:
        return 1.0
    with np.errstate(all="ignore"):
        xtx = design.T @ design
        before = float(ell @ np.linalg.pinv(xtx) @ ell)
        after = float(ell @ np.linalg.pinv(xtx + added.T @ added) @ ell)
    if not (math.isfinite(before) and math.isfinite(after)) or before <= 0.0:
        return 1.0
    return min(max(after / before, 0.0), 1.0)  # information never widens it


def regression_dof_after(model: Model, added: np.ndarray) -> float:
    """Degrees of freedom of the model's regression with the rows ``added`` (one more run).

    OLS over runs: one more; the clustered joint regression: the Bell–McCaffrey degrees of
    freedom of M over the augmented design (four runs or more), samples − 3 otherwise.
    """
    if added.shape[0] == 0:
        return model.reg_dof
    if model.kind != "joint" or model.groups is None:
        return model.reg_dof + added.shape[0]
    x = np.vstack([model.design, added])
    new_group = int(np.max(model.groups)) + 1 if model.groups.size else 0
    groups = np.concatenate([model.groups, np.full(added.shape[0], new_group)])
    if len(np.unique(groups)) < 4:
        return float(x.shape[0] - x.shape[1])
    try:
        return float(bm_dof(x, groups, model.ell[next(iter(model.ell))]))
    except (np.linalg.LinAlgError, ValueError):
        return model.reg_dof + 1.0


def half_width(est: Estimate, ratio: float = 1.0, reg_dof_new: float | None = None,
               reg_dof: float = math.inf, alpha: float = ALPHA) -> float:
    """The half-width t₁₋α/₂(ν)·u_c [the coefficient's unit] of ``est`` with its regression
    variance multiplied by ``ratio``.

    u_c² = u_reg² + u_tare² + u_mass² (GUM eq. 10) with u_reg² scaled; ν by Welch–Satterthwaite
    (GUM G.4.1), the other parts' share Σ u_i⁴/ν_i taken from the estimate's own ν:
    u_c⁴/ν − u_reg⁴/ν_reg (``reg_dof``), the regression's ν becoming ``reg_dof_new``.

    Parameters
    ----------
    est : Estimate
        The coefficient now.
    ratio : float
        Factor on its regression variance [-].
    reg_dof_new, reg_dof : float
        The regression's degrees of freedom after and now [-].
    alpha : float
        Significance level [-].
    """
    uc2 = est.std_error**2
    reg2 = est.u_regression**2 if math.isfinite(est.u_regression) else 0.0
    if ratio == 1.0 and reg_dof_new in (None, reg_dof):
        return t_quantile(est.dof, alpha) * est.std_error if est.std_error > 0 else 0.0
    rest = max(uc2 - reg2, 0.0)
    share = 0.0
    if math.isfinite(est.dof) and est.dof > 0:
        share = uc2 * uc2 / est.dof - (reg2 * reg2 / reg_dof if reg_dof > 0 else 0.0)
    share = max(share, 0.0) if math.isfinite(share) else 0.0
    reg2_new = reg2 * ratio
    uc2_new = rest + reg2_new
    if uc2_new <= 0.0:
        return 0.0
    nu_reg = reg_dof_new if reg_dof_new is not None else reg_dof
    denom = (reg2_new * reg2_new / nu_reg if nu_reg > 0 else math.inf) + share
    nu = uc2_new * uc2_new / denom if denom > 0 else math.inf
    return t_quantile(nu, alpha) * math.sqrt(uc2_new)


def predicted_half_widths(fit: HullFit, models: list[Model], cond: Condition | None,
                          alpha: float = ALPHA) -> dict[str, float]:
    """{symbol: expected half-width [its unit]} after towing ``cond`` (None: now)."""
    out: dict[str, float] = {}
    for sym in RANKED:
        est = fit.estimates.get(sym)
        if est is None:
            continue
        model = next((m for m in models if sym in m.ell), None)
        if model is None or cond is None:
            out[sym] = half_width(est, alpha=alpha)
            continue
        rows = candidate_rows(model, cond)
        ratio = variance_ratio(model.design, rows, model.ell[sym]) * s2_ratio(model, rows,
                                                                              cond.speed)
        out[sym] = half_width(est, ratio, regression_dof_after(model, rows), model.reg_dof,
                              alpha)
    return out


def relative(hw: float, value: float) -> float:
    """Relative half-width hw/|value| [-]; inf for a zero value."""
    return hw / abs(value) if value != 0 else math.inf


# --------------------------------------------------------------------------- the conditions
def _col(frame: pd.DataFrame, *names: str) -> pd.Series:
    for n in names:
        if n in frame:
            return pd.to_numeric(frame[n], errors="coerce")
    return pd.Series(np.nan, index=frame.index)


def sheet_conditions(candidates: pd.DataFrame) -> list[Condition]:
    """The sheet's rows still to tow as conditions (void rows and rows without a speed left out).

    Columns: run, config, angle_deg, ``speed_m_s`` or ``speed_nominal`` [m/s], ``accel_m_s2``
    or ``accel_nominal`` [m/s²], test, optionally status.
    """
    if candidates is None or len(candidates) == 0:
        return []
    c = candidates
    speed = _col(c, "speed_m_s", "speed_nominal")
    accel = _col(c, "accel_m_s2", "accel_nominal")
    angle = _col(c, "angle_deg")
    runs = _col(c, "run")
    out = []
    for i in range(len(c)):
        status = str(c["status"].iloc[i]) if "status" in c else "ok"
        u, a, ang, r = (float(speed.iloc[i]), float(accel.iloc[i]), float(angle.iloc[i]),
                        runs.iloc[i])
        if status == "void" or not math.isfinite(u) or not math.isfinite(ang) or pd.isna(r):
            continue
        test = str(c["test"].iloc[i]) if "test" in c else "steady"
        config = str(c["config"].iloc[i]) if "config" in c else "hull"
        out.append(Condition(int(r), config, ang, u, a if math.isfinite(a) else 0.0,
                             test if test in ("steady", "accel") else "steady"))
    return out


def _grid(lo: float, hi: float, n: int, step: float) -> list[float]:
    """n points from lo to hi rounded to ``step``, distinct."""
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return []
    vals = np.round(np.linspace(lo, hi, n) / step) * step
    return sorted({round(float(v), 6) for v in vals})


def suggestion_grid(known: list[Condition], alpha_max_deg: float = 30.0) -> list[Condition]:
    """Conditions in the sheet's range that no sheet row has (a small grid).

    Steady hull tows at five angles over the sheet's |α| ≤ α_max range (0.5° steps) and three
    speeds over its speed range (0.05 m/s steps); accelerated tows at α = 0 and 90° at three
    accelerations over the sheet's (0.05 m/s² steps) at the highest accelerated speed; steady
    transverse tows at three speeds over the sheet's (0.05 m/s steps).
    """
    hull = [c for c in known if c.config == "hull"]
    out: list[Condition] = []
    small = [c for c in hull if abs(c.angle_deg) <= alpha_max_deg + 1e-9
             and abs(c.angle_deg - 90.0) > ANGLE_TOL_DEG]
    if small:
        angles = [c.angle_deg for c in small]
        speeds = [c.speed for c in small]
        acc = float(np.median([c.accel for c in small if c.test == "steady"] or [0.0]))
        for ang in _grid(min(angles), max(angles), 5, 0.5):
            for u in _grid(min(speeds), max(speeds), 3, 0.05):
                out.append(Condition(None, "hull", ang, u, acc, "steady"))
    for angle in (0.0, 90.0):
        at = [c for c in hull if abs(c.angle_deg - angle) <= ANGLE_TOL_DEG]
        accel = [c for c in at if c.test == "accel" and c.accel > 0]
        if accel:
            u = max(c.speed for c in accel)
            for a in _grid(min(c.accel for c in accel), max(c.accel for c in accel), 3, 0.05):
                if a > 0:
                    out.append(Condition(None, "hull", angle, u, a, "accel"))
        steady = [c for c in at if c.test == "steady"]
        if angle == 90.0 and steady:
            acc = float(np.median([c.accel for c in steady]))
            for u in _grid(min(c.speed for c in steady), max(c.speed for c in steady), 3, 0.05):
                if u > 0:
                    out.append(Condition(None, "hull", angle, u, acc, "steady"))
    return [c for c in out if not any(_same(c, k) for k in known)]


def _same(a: Condition, b: Condition) -> bool:
    """Do two conditions repeat one another (angle ± 0.5°, speed ± 3 %, acceleration ± 10 %
    for accelerated tows)?"""
    if a.config != b.config or a.test != b.test or abs(a.angle_deg - b.angle_deg) > ANGLE_TOL_DEG:
        return False
    if abs(a.speed - b.speed) > _SPEED_MATCH * max(abs(b.speed), 1e-9):
        return False
    return a.test != "accel" or abs(a.accel - b.accel) <= _ACCEL_MATCH * max(abs(b.accel), 1e-9)


def _done_conditions(runs: pd.DataFrame | None) -> list[Condition]:
    """The towed runs (runs.csv rows) as conditions, at their nominal speed where known."""
    if runs is None or len(runs) == 0:
        return []
    frame = runs.copy()
    if "speed_nominal" in frame:
        frame["speed_m_s"] = _col(frame, "speed_nominal").fillna(_col(frame, "speed_mean"))
    else:
        frame["speed_m_s"] = _col(frame, "speed_mean")
    if "accel_nominal" not in frame:
        frame["accel_m_s2"] = _col(frame, "accel_mean")
    return sheet_conditions(frame)


# ------------------------------------------------------------------------------- the ranking
def empty_frame() -> pd.DataFrame:
    """The ranking's frame with no rows (its columns and dtypes)."""
    return pd.DataFrame({
        "rank": pd.Series(dtype="int64"), "run": pd.Series(dtype="Int64"),
        "description": pd.Series(dtype="object"),
        **{c: pd.Series(dtype="float64") for c in ("angle_deg", "speed_m_s", "accel_m_s2")},
        "target": pd.Series(dtype="object"),
        **{c: pd.Series(dtype="float64") for c in COLUMNS[7:]},
    })[COLUMNS]


def rank_next_runs(
    hull: Any,
    runs: pd.DataFrame | None,
    candidates: pd.DataFrame | None,
    *,
    reductions: dict[int, RunReduction] | None = None,
    top: int = 3,
    alpha: float = ALPHA,
    suggest: bool = True,
    n_suggest: int = 3,
    alpha_max_deg: float | None = None,
) -> pd.DataFrame:
    """Rank the sheet's remaining runs (and suggested conditions) by how much each would narrow
    the day's widest relative interval (docs/method.md "Which run next").

    The targeted coefficient is the one whose relative half-width t·u_c/|value| is widest now;
    each candidate's expected half-widths after it is towed are predicted from the current fits'
    design and residual variance (module docstring), and the candidates are ranked by the
    targeted coefficient's expected half-width (smallest first), ties by the other
    coefficients' relative half-widths after, widest first.

    Parameters
    ----------
    hull : HullResult or HullFit or None
        The day's hull fit so far (``day.hull``).
    runs : DataFrame or None
        runs.csv rows towed so far (run, config, angle_deg, speed_nominal [m/s],
        accel_nominal [m/s²], test): the sheet's range for the suggestions.
    candidates : DataFrame or None
        The sheet's rows still to tow: run, config, angle_deg, ``speed_nominal`` or
        ``speed_m_s`` [m/s], ``accel_nominal`` or ``accel_m_s2`` [m/s²], test (void rows are
        skipped).
    reductions : dict, optional
        The run reductions (``day.reductions``): the added-mass regressions' samples. Without
        them X_udot's and Y_vdot's half-widths are not predicted (kept as they are).
    top : int, default 3
        How many of the sheet's runs to return.
    alpha : float, default 0.05
        Significance level of the intervals [-].
    suggest : bool, default True
        Also suggest conditions not on the sheet (``run`` NA).
    n_suggest : int, default 3
        How many suggestions at most.
    alpha_max_deg : float, optional
        Largest |α| of the C_D(α) fit [deg] (the protocol's ``damping_alpha_max_deg``);
        default 30°.

    Returns
    -------
    DataFrame
        rank (1 best, counted separately for the sheet's runs and the suggestions), run
        (Int64, NA for a suggestion), description, angle_deg [deg], speed_m_s [m/s],
        accel_m_s2 [m/s²], target (the symbol), half_width_now and half_width_after [the
        target's unit], relative_now and relative_after [-]. Empty (same columns) without a
        fit, a coefficient or a candidate.
    """
    fit: HullFit | None = getattr(hull, "fit", hull)
    if fit is None or not isinstance(getattr(fit, "estimates", None), dict):
        return empty_frame()
    if alpha_max_deg is None:
        alpha_max_deg = 30.0
    try:
        models = hull_models(fit, reductions, alpha_max_deg)
        now = predicted_half_widths(fit, models, None, alpha)
    except (np.linalg.LinAlgError, ValueError, KeyError):
        return empty_frame()
    rel_now = {s: relative(hw, fit.estimates[s].value) for s, hw in now.items()
               if not math.isnan(relative(hw, fit.estimates[s].value))}
    if not rel_now:
        return empty_frame()
    target = max(rel_now, key=lambda s: rel_now[s])
    value = fit.estimates[target].value
    sheet = sheet_conditions(candidates) if candidates is not None else []
    extra = (suggestion_grid(_done_conditions(runs) + sheet, alpha_max_deg)
             if suggest and n_suggest > 0 else [])
    frames = []
    for conds, n in ((sheet, top), (extra, n_suggest)):
        rows = []
        for c in conds:
            try:
                after = predicted_half_widths(fit, models, c, alpha)
            except (np.linalg.LinAlgError, ValueError, KeyError):
                after = dict(now)
            rel_after = {s: relative(hw, fit.estimates[s].value) for s, hw in after.items()}
            others = sorted((v for s, v in rel_after.items() if s != target
                             and not math.isnan(v)), reverse=True)
            key = after[target] if not math.isnan(after[target]) else math.inf
            rows.append(((key, tuple(others)), c, after[target],
                         relative(after[target], value)))
        rows.sort(key=lambda r: r[0])
        for k, (_, c, hw, rel) in enumerate(rows[:max(n, 0)], start=1):
            frames.append({
                "rank": k, "run": c.run, "description": c.description(),
                "angle_deg": c.angle_deg, "speed_m_s": c.speed, "accel_m_s2": c.accel,
                "target": target, "half_width_now": now[target], "half_width_after": hw,
                "relative_now": rel_now[target], "relative_after": rel,
            })
    if not frames:
        return empty_frame()
    runs_col = pd.array([f.pop("run") for f in frames], dtype="Int64")
    out = pd.DataFrame(frames)
    out.insert(1, "run", runs_col)
    out["rank"] = out["rank"].astype("int64")
    return out[COLUMNS]
