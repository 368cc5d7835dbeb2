"""Hull coefficients: added mass and quadratic damping with 95 % intervals (SUT-2 report §2).

Added mass (report eqs. 7–8; docs/method.md "Added mass"). At constant acceleration a and speed U
the balance drag is D = (m − X_udot)·a + R(U). The primary estimate is the joint regression
D = k2·U|U| + k1·U + M·a over all steady and constant-acceleration samples of the α = 0 runs
(α = 90° for Y_vdot), X_udot = m − M. Its interval combines the regression's standard error
(clustered by run with the small-sample CR2 correction, :mod:`towtank.stats.intervals`), the tare's
(clustered likewise) and the stated uncertainty of the weighed mass, with Student's t at the
Welch–Satterthwaite degrees of freedom. The report's own method, a quadratic D_a(U) per
acceleration level minus the steady quadratic D_s(U) averaged over their common speed range,
is the second estimate, reported beside it (in the method text too) with a check of their
agreement.

Damping (report eqs. 13–15; docs/method.md "Damping from C_D(α)"). C_D = R/(½ρAU²) per steady hull
run with |α| ≤ 30°; C_D(α) = a·α² + b·α + c (α in rad) by OLS (statsmodels); then
X_u|u| = −½ρA·c, X_uv = X_uw = −½ρA·b, X_v|v| = X_w|w| = −½ρA·(a − c/2), Y_uv = Z_uw = −½ρA·c,
and Y_v|v| = Z_w|w| = −½ρ·A_lat·C_D,90 from the transverse steady runs' R = K·U|U|. The frontal
and lateral areas cancel in these dimensional values (the fits are of R/U²): the stated
uncertainty of the length (``length_uncertainty_m``) enters the prime values only, through
½ρL³ and ½ρL², and that of the diameter (``diameter_uncertainty_m``) enters no coefficient at
all (A = πD²/4 and A_lat = L·D cancel; the primes use L alone), so it is recorded in
provenance.json only.

A coefficient the day's runs cannot support is omitted with a sentence saying which runs are
missing; nothing is ever extrapolated into a value.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field, fields, replace
from typing import Any, Literal

import numpy as np
import pandas as pd

from towtank.ingest.protocol import read_reference_csv
from towtank.reduce.run import PHASE_ACCEL, PHASE_STEADY, RunReduction
from towtank.reduce.tare import TareModel, tare_design
from towtank.reference.sets import BUILTIN_REFERENCES, builtin_reference
from towtank.stats.intervals import bm_dof, cr2_covariance, welch_satterthwaite
from towtank.stats.quantiles import ALPHA, interval, normal_quantile, t95

SYMBOLS = (
    "X_udot", "Y_vdot", "Z_wdot", "X_u|u|", "X_uv", "X_uw", "X_v|v|", "X_w|w|",
    "Y_uv", "Z_uw", "Y_v|v|", "Z_w|w|",
)
KIND = {s: ("added_mass" if s.endswith("dot") else "damping") for s in SYMBOLS}
UNIT = {s: ("kg" if KIND[s] == "added_mass" else "kg/m") for s in SYMBOLS}
MIRROR = {"Z_wdot": "Y_vdot", "X_uw": "X_uv", "X_w|w|": "X_v|v|", "Z_uw": "Y_uv",
          "Z_w|w|": "Y_v|v|"}


def mirrored(symbols: Iterable[str]) -> dict[str, str]:
    """The coefficients among ``symbols`` that repeat another's estimate on an axisymmetric
    hull (:data:`MIRROR`), each with the symbol it repeats (also among ``symbols``)."""
    have = set(symbols)
    return {t: s for t, s in MIRROR.items() if t in have and s in have}
ANGLE_TOL_DEG = 0.5


@dataclass(frozen=True, repr=False)
class Agreement:
    """The verdict of two estimates of one added mass: do they agree, by how much, within what.

    A typed verdict: ``agrees`` (|difference| ≤ tolerance), ``difference`` [kg] (second
    estimate minus the primary) and ``tolerance`` [kg] (:func:`agreement`). ``str()`` gives its
    sentence, "agree: difference … kg within … kg" or "DISAGREE: difference … kg exceeds …
    kg", the agreement column of coefficients.csv; nothing parses the sentence back.
    """

    agrees: bool
    difference: float  # [kg]
    tolerance: float  # [kg]

    @property
    def verdict(self) -> Literal["agree", "DISAGREE"]:
        """"agree" or "DISAGREE"."""
        return "agree" if self.agrees else "DISAGREE"

    @property
    def detail(self) -> str:
        """"difference … kg within/exceeds … kg"."""
        word = "within" if self.agrees else "exceeds"
        return f"difference {self.difference:+.2g} kg {word} {self.tolerance:.2g} kg"

    def __str__(self) -> str:
        return f"{self.verdict}: {self.detail}"

    def __repr__(self) -> str:
        return f"Agreement({self.verdict}, difference={self.difference:+.3g} kg, " \
               f"tolerance={self.tolerance:.3g} kg)"


@dataclass(frozen=True)
class Estimate:
    """One coefficient: model-scale SI value, its uncertainty budget, d.o.f. and 95 % interval.

    ``conf_int(alpha)`` gives the interval at any level from the same budget:
    value ∓ t₁₋α/₂(ν)·u_c, ν the Welch–Satterthwaite degrees of freedom ``dof`` (GUM G.4.1).
    """

    symbol: str
    value: float
    std_error: float
    ci_low: float
    ci_high: float
    method: str
    n_runs: int
    alt_value: float = math.nan
    alt_method: str = ""
    agreement: Agreement | None = None
    # the uncertainty budget, u_c² = u_regression² + u_tare² + u_mass² (GUM eq. 10), in the
    # value's unit, and the degrees of freedom of the interval's t (Welch–Satterthwaite)
    u_regression: float = math.nan
    u_tare: float = math.nan
    u_mass: float = math.nan
    dof: float = math.nan

    def conf_int(self, alpha: float = 0.05) -> tuple[float, float]:
        """(lower, upper): the two-sided interval of level 1 − ``alpha`` [the value's unit].

        With ``alpha`` = 0.05 (to within rounding) these are ``ci_low`` and ``ci_high``.
        """
        if math.isclose(alpha, ALPHA, rel_tol=1e-9) or not math.isfinite(self.std_error):
            return self.ci_low, self.ci_high
        return interval(self.value, self.std_error, self.dof, alpha)

    def __repr__(self) -> str:
        return (f"Estimate({self.symbol} = {self.value:.5g} ± {self.std_error:.2g}, "
                f"95 % [{self.ci_low:.5g}, {self.ci_high:.5g}], dof={self.dof:.3g})")


@dataclass
class CurveLevel:
    """One acceleration level of the curve difference (report eqs. 7–8)."""

    accel: float  # mean acceleration of the level [m/s²]
    delta_drag: float  # mean ΔD = D_a(U) − D_s(U) over the common speed range [N]
    M: float  # m − X = ΔD / a [kg]
    value: float  # X [kg]
    speed_range: tuple[float, float]  # [m/s]
    n: int  # samples
    quadratic: list[float]  # p2 [N s²/m²], p1 [N s/m], p0 [N] of D_a(U)

    def __getitem__(self, key: str) -> Any:  # the mapping access of the former dict
        return getattr(self, key)


@dataclass
class CurveDifference:
    """The report's curve-difference estimate of an added mass and its levels.

    ``value`` [kg] is None when the runs cannot give it; ``spread`` [kg] is the standard
    deviation of the per-level values; ``steady_quadratic`` (q2 [N s²/m²], q1 [N s/m]) the
    steady D_s(U). Item access (``cd["value"]``) is kept for scripts written against the
    former dict.
    """

    value: float | None = None
    spread: float = 0.0
    levels: list[CurveLevel] = field(default_factory=list)
    steady_quadratic: list[float] | None = None

    def __getitem__(self, key: str) -> Any:
        return getattr(self, key)

    def __setitem__(self, key: str, value: Any) -> None:
        if key not in {f.name for f in fields(self)}:
            raise KeyError(key)
        setattr(self, key, value)

    def get(self, key: str, default: Any = None) -> Any:
        return getattr(self, key, default)


@dataclass
class AddedMassFit:
    """Joint regression D = k2·U|U| + k1·U + M·a and its by-products."""

    symbol: str
    mass: float  # [kg]
    M: float  # m − X_udot [kg]
    M_se: float  # regression and tare combined [kg]
    k2: float  # [N s²/m²]
    k1: float  # [N s/m]
    dof: float  # effective degrees of freedom of the interval (Welch–Satterthwaite)
    runs: list[int]
    accel_levels: list[float]
    residual_by_run: dict[int, float]
    estimate: Estimate
    curve_difference: CurveDifference = field(default_factory=CurveDifference)
    regression_se: float = math.nan  # the regression's alone (CR2, clustered by run) [kg]
    regression_dof: float = math.nan  # Bell–McCaffrey (clustered), samples − 3 otherwise
    tare_se: float = math.nan  # the subtracted tare's [kg]


@dataclass
class ClusteredOLS:
    """OLS estimates with a covariance clustered by run (or iid with too few runs)."""

    params: np.ndarray
    cov: np.ndarray
    dof: float  # degrees of freedom of Student's t for intervals from cov
    resid: np.ndarray
    fittedvalues: np.ndarray
    clustered: bool

    @property
    def bse(self) -> np.ndarray:
        """Standard errors of the estimates."""
        return np.sqrt(np.maximum(np.diag(self.cov), 0.0))


@dataclass
class DampingFit:
    """C_D(α) quadratic fit and the transverse C_D,90."""

    params: np.ndarray  # a, b, c  (C_D = a α² + b α + c, α in rad)
    cov: np.ndarray
    dof: int
    rho: float
    area: float
    runs: pd.DataFrame  # run, angle_deg, alpha_rad, speed, cd, fitted, resid, student, cooks
    outliers: list[int]
    cd90: float = math.nan
    cd90_se: float = math.nan
    transverse_runs: pd.DataFrame | None = None


@dataclass
class HullFit:
    """All hull coefficients of the day, with their diagnostics and messages."""

    estimates: dict[str, Estimate]
    rho: float
    length: float
    mass: float
    added_mass: dict[str, AddedMassFit]
    damping: DampingFit | None
    repeats: pd.DataFrame
    messages: list[str]
    lift_slope: tuple[float, float, float] | None = None  # dCL/dα [1/rad], ci low, ci high

    def table(self) -> pd.DataFrame:
        """The estimates in the order of docs/formats.md (without prime/reference columns)."""
        rows = [vars(self.estimates[s]) for s in SYMBOLS if s in self.estimates]
        return pd.DataFrame(rows)


# ------------------------------------------------------------------------------ selection
def select_runs(runs: pd.DataFrame, angle_deg: float, *, config: str = "hull") -> pd.DataFrame:
    """The usable runs of ``config`` at ``angle_deg`` (± 0.5°)."""
    ok = (runs["status"] == "ok") & (runs["config"] == config)
    return runs[ok & (np.abs(runs["angle_deg"] - angle_deg) <= ANGLE_TOL_DEG)]


def pooled_samples(
    reductions: dict[int, RunReduction], run_ids: list[int]
) -> dict[str, np.ndarray]:
    """Fit samples (tare removed) of several runs, with a 'run' column."""
    parts = [reductions[r].samples for r in run_ids]
    out = {k: np.concatenate([p[k] for p in parts]) for k in ("phase", "U", "a", "drag")}
    out["run"] = np.concatenate(
        [np.full(p["U"].size, r, dtype=int) for r, p in zip(run_ids, parts, strict=True)]
    )
    return out


def accel_levels(reductions: dict[int, RunReduction], run_ids: list[int], *,
                 rel_tol: float = 0.1) -> list[float]:
    """Distinct constant-acceleration levels [m/s²] among the runs (clustered within 10 %)."""
    vals = sorted(reductions[r].accel_mean for r in run_ids
                  if math.isfinite(reductions[r].accel_mean))
    levels: list[list[float]] = []
    for v in vals:
        if levels and abs(v - np.mean(levels[-1])) <= rel_tol * abs(np.mean(levels[-1])):
            levels[-1].append(v)
        else:
            levels.append([v])
    return [float(np.mean(g)) for g in levels]


# ---------------------------------------------------------------------- tare uncertainty
def tare_covariance(
    A: np.ndarray,
    tare_rows: np.ndarray,
    groups: np.ndarray,
    tares: dict[str, TareModel] | None,
) -> np.ndarray:
    """Covariance that the subtracted tare adds to an estimate β = A·y.

    Each y_i had F_tare = T_i·t_g removed, with t_g the tare coefficients of its group (common
    to all runs of the group, so their error never shows in the residual scatter). Then
    cov(β) gains Σ_g (A T_g) Σ_g (A T_g)ᵀ, Σ_g the tare fit's covariance (GUM, JCGM 100:2008,
    §5.2: correlated input quantities).

    Parameters
    ----------
    A : ndarray (p, n)
        Linear map from the n observations to the p estimates.
    tare_rows : ndarray (n, 3)
        Tare regressors [U|U|, U, a] of each observation, divided by whatever the
        observation was divided by (e.g. ½ρAU² for C_D).
    groups : ndarray (n,)
        Tare group of each observation.
    tares : dict
        Tare models by group; None adds nothing.
    """
    p = A.shape[0]
    out = np.zeros((p, p))
    if not tares:
        return out
    groups = np.asarray(groups).astype(str)
    for g in np.unique(groups):
        if g not in tares:
            continue
        tg = np.where((groups == g)[:, None], tare_rows, 0.0)
        b = A @ tg
        out += b @ tares[g].drag.cov @ b.T
    return out


# ----------------------------------------------------------------------------- added mass
def joint_regression(
    speed: np.ndarray, accel: np.ndarray, drag: np.ndarray, groups: np.ndarray
) -> ClusteredOLS:
    """OLS of D = k2·U|U| + k1·U + M·a with standard errors clustered by run.

    The samples of one run share its zero, drift correction and filtered noise, so their errors
    are correlated, and a day has few runs per angle (4 to 10). The covariance is therefore the
    Bell–McCaffrey bias-reduced cluster-robust one (CR2) (:func:`towtank.stats.intervals.
    cr2_covariance`; Bell & McCaffrey 2002, Imbens & Kolesár 2016, Cameron & Miller 2015 §VI)
    with Student's t at the Bell–McCaffrey degrees of freedom of M
    (:func:`towtank.stats.intervals.bm_dof`), which fall below G − 1 (G the number of runs)
    when a few accelerated runs hold M's leverage, e.g. with two acceleration levels. The
    usual CR1 correction (statsmodels' ``cov_type="cluster"``) is biased low with so few
    clusters, most where a few accelerated runs carry the leverage on M. With fewer than four
    runs no clustered covariance can be estimated and the samples are taken as independent
    (n − 3 degrees of freedom), which understates the interval.

    Parameters
    ----------
    speed : ndarray
        Sample speeds U [m/s].
    accel : ndarray
        Sample accelerations a [m/s²].
    drag : ndarray
        Tare-corrected balance drag D [N].
    groups : ndarray
        Run number of each sample (the clusters).

    Returns
    -------
    ClusteredOLS
        params (k2 [N s²/m²], k1 [N s/m], M [kg]), their covariance and its degrees of freedom.
    """
    # loaded on use: statsmodels loads while the workers reduce the runs
    from statsmodels.regression.linear_model import OLS

    x = np.column_stack([speed * np.abs(speed), speed, accel])
    res = OLS(drag, x).fit()
    resid = np.asarray(res.resid)
    if len(np.unique(groups)) >= 4:
        cov, _ = cr2_covariance(x, resid, groups)
        dof = bm_dof(x, groups, np.array([0.0, 0.0, 1.0]))  # the added mass's: M
        clustered = True
    else:
        cov, dof, clustered = np.asarray(res.cov_params()), res.df_resid, False
    return ClusteredOLS(params=np.asarray(res.params), cov=cov, dof=float(dof), resid=resid,
                        fittedvalues=np.asarray(res.fittedvalues), clustered=clustered)


def fit_added_mass(
    symbol: str,
    reductions: dict[int, RunReduction],
    run_ids: list[int],
    mass: float,
    mass_sd: float,
    tares: dict[str, TareModel] | None = None,
) -> AddedMassFit:
    """Added mass from the runs at one angle (α = 0 for X_udot, 90° for Y_vdot).

    X = m − M, M from :func:`joint_regression`. Its standard uncertainty combines three
    independent parts, u_c² = u_reg² + u_tare² + u_m² (GUM, JCGM 100:2008, eq. 10): the
    regression's (CR2, clustered by run, Bell–McCaffrey degrees of freedom), the subtracted
    tare's (its
    m_t goes one-for-one into X; its covariance is clustered by sting run likewise in
    :func:`towtank.reduce.tare.fit_channel` and propagated by :func:`tare_covariance`, one component
    per tare group with that fit's degrees of freedom) and the weighed mass's (``mass_sd``, a
    stated value: infinite degrees of freedom). The 95 % interval is X ± t₀.₉₇₅(ν_eff)·u_c with
    ν_eff from the Welch–Satterthwaite formula (GUM G.4.1). The second estimate, the report's
    curve difference (:func:`curve_difference`), is set beside it in ``alt_value`` and at the
    end of the method text, with the agreement of the two (:func:`agreement`).

    Parameters
    ----------
    symbol : str
        "X_udot" or "Y_vdot".
    reductions : dict
        Tare-corrected run reductions.
    run_ids : list of int
        The usable runs at that angle.
    mass : float
        Weighed mass of the model (everything downstream of the balance but the sting) [kg].
    mass_sd : float
        Standard uncertainty of the weighed mass [kg].
    tares : dict, optional
        The tare models subtracted, whose uncertainty (m_t above all) is propagated.
    """
    s = pooled_samples(reductions, run_ids)
    res = joint_regression(s["U"], s["a"], s["drag"], s["run"])
    k2, k1, M = (float(v) for v in res.params)
    x = tare_design(s["U"], s["a"])
    group_of = {r: reductions[r].tare_group for r in run_ids}
    groups = np.array([group_of[int(r)] for r in s["run"]])
    pinv = np.linalg.pinv(x)
    # one variance component per tare group, each with its own degrees of freedom
    tare_parts = [
        (float(tare_covariance(pinv, x, groups, {g: tares[g]})[2, 2]), tares[g].drag.dof)
        for g in sorted(set(groups.tolist())) if tares and g in tares
    ]
    reg_var = float(res.cov[2, 2])
    tare_var = sum(v for v, _ in tare_parts)
    M_se = math.sqrt(reg_var + tare_var)
    value = mass - M
    u_c = math.hypot(M_se, mass_sd)
    dof = welch_satterthwaite(
        [reg_var, *(v for v, _ in tare_parts), mass_sd**2],
        [res.dof, *(nu for _, nu in tare_parts), math.inf],
    )
    half = t95(dof) * u_c if u_c > 0 else 0.0
    by_run = {int(r): float(np.mean(res.resid[s["run"] == r])) for r in run_ids}
    errors = ("clustered by run" if res.clustered
              else f"samples as independent: only {len(run_ids)} runs")
    method = ("joint regression D = k2·U|U| + k1·U + (m − " + symbol + ")·a over steady and "
              f"constant-acceleration samples of {len(run_ids)} runs (report eqs. 7–8; "
              f"errors {errors})")
    cd = curve_difference(reductions, run_ids, mass)
    alt, alt_method, verdict = math.nan, "", None
    if cd.value is not None and math.isfinite(float(cd.value)):
        alt = float(cd.value)
        alt_method = ("curve difference (report eqs. 7–8: per-acceleration quadratic minus "
                      "steady quadratic)")
        verdict = agreement(value, alt, M_se, float(cd.spread))
        method += (f"; second estimate (curve difference, report eqs. 7–8) {alt:.5g} kg: "
                   f"{verdict.verdict} ({verdict.detail})")
    est = Estimate(
        symbol=symbol, value=value, std_error=u_c, ci_low=value - half, ci_high=value + half,
        method=method, n_runs=len(run_ids), alt_value=alt, alt_method=alt_method,
        agreement=verdict, u_regression=math.sqrt(reg_var), u_tare=math.sqrt(tare_var),
        u_mass=float(mass_sd), dof=float(dof),
    )
    return AddedMassFit(
        symbol=symbol, mass=mass, M=M, M_se=M_se, k2=k2, k1=k1, dof=dof, runs=list(run_ids),
        accel_levels=accel_levels(reductions, run_ids), residual_by_run=by_run, estimate=est,
        curve_difference=cd, regression_se=math.sqrt(reg_var), regression_dof=res.dof,
        tare_se=math.sqrt(tare_var),
    )


def agreement(primary: float, second: float, se: float, spread: float) -> Agreement:
    """Do the joint regression and the curve difference agree? A sentence saying so.

    They agree when |second − primary| ≤ 2·√(se² + spread²), se the joint regression's
    standard error (regression and tare, without the mass, which both share) and spread the
    standard deviation of the curve-difference values between acceleration levels [kg].

    Parameters
    ----------
    primary, second : float
        The two estimates [kg].
    se : float
        Standard error of the primary estimate, mass excluded [kg].
    spread : float
        Standard deviation of the per-level curve-difference values [kg].

    Returns
    -------
    Agreement
        ``.agrees``, ``.difference`` [kg], ``.tolerance`` [kg]; it reads as "agree: difference
        … kg within … kg" or "DISAGREE: difference … kg exceeds … kg".
    """
    tol = 2.0 * math.hypot(se, spread)
    diff = second - primary
    return Agreement(bool(abs(diff) <= max(tol, 1e-12)), float(diff), float(tol))


def curve_difference(
    reductions: dict[int, RunReduction], run_ids: list[int], mass: float
) -> CurveDifference:
    """The report's method: ΔD = D_a(U) − D_s(U) averaged over the common speed range.

    Per acceleration level a quadratic D_a(U) = p2·U² + p1·U + p0 through that level's
    constant-acceleration samples, and D_s(U) = q2·U|U| + q1·U through the steady samples;
    M_a = mean ΔD / a over the common speed range; X = m − M_a, averaged over the levels.
    """
    s = pooled_samples(reductions, run_ids)
    st = s["phase"] == PHASE_STEADY
    acc = s["phase"] == PHASE_ACCEL
    if st.sum() < 3 or acc.sum() < 3:
        return CurveDifference()
    us, ds = s["U"][st], s["drag"][st]
    q, *_ = np.linalg.lstsq(np.column_stack([us * np.abs(us), us]), ds, rcond=None)
    levels = accel_levels(reductions, run_ids)
    out_levels: list[CurveLevel] = []
    for level in levels:
        sel = acc & (np.abs(s["a"] - level) <= 0.15 * abs(level))
        if sel.sum() < 4:
            continue
        ua, da = s["U"][sel], s["drag"][sel]
        lo, hi = max(ua.min(), us.min()), min(ua.max(), us.max())
        if not hi > lo:
            lo, hi = ua.min(), ua.max()  # steady curve through the origin covers [0, max]
            lo = max(lo, 0.0)
        p = np.polyfit(ua, da, 2)
        grid = np.linspace(lo, hi, 50)
        dd = np.polyval(p, grid) - (q[0] * grid * np.abs(grid) + q[1] * grid)
        a_mean = float(np.mean(s["a"][sel]))
        M_a = float(np.mean(dd)) / a_mean
        out_levels.append(CurveLevel(accel=a_mean, delta_drag=float(np.mean(dd)), M=M_a,
                                     value=mass - M_a, speed_range=(float(lo), float(hi)),
                                     n=int(sel.sum()), quadratic=p.tolist()))
    if not out_levels:
        return CurveDifference()
    vals = np.array([lv.value for lv in out_levels])
    return CurveDifference(
        value=float(np.mean(vals)),
        spread=float(np.std(vals, ddof=1)) if vals.size > 1 else 0.0,
        levels=out_levels,
        steady_quadratic=q.tolist(),
    )


# -------------------------------------------------------------------------------- damping
def fit_cd_alpha(alpha_rad: np.ndarray, cd: np.ndarray):
    """OLS of C_D(α) = a·α² + b·α + c (report eq. 13); statsmodels results."""
    # loaded on use: statsmodels loads while the workers reduce the runs
    from statsmodels.regression.linear_model import OLS

    x = np.column_stack([alpha_rad**2, alpha_rad, np.ones_like(alpha_rad)])
    return OLS(cd, x).fit()


def _lin(symbol: str, g: np.ndarray, params: np.ndarray, cov: np.ndarray, dof: float,
         method: str, n: int, tare_cov: np.ndarray | None = None,
         tare_dof: float = math.inf) -> Estimate:
    """g·params with its 95 % interval: the regression's covariance ``cov`` (``dof``) plus the
    subtracted tare's ``tare_cov`` (``tare_dof``), t at the Welch–Satterthwaite d.o.f."""
    value = float(g @ params)
    var_reg = max(float(g @ cov @ g), 0.0)
    var_tare = max(float(g @ tare_cov @ g), 0.0) if tare_cov is not None else 0.0
    se = math.sqrt(var_reg + var_tare)
    nu = welch_satterthwaite([var_reg, var_tare], [dof, tare_dof])
    half = t95(nu) * se if se > 0 else 0.0  # an exact fit: a zero-width interval, not nan
    return Estimate(symbol, value, se, value - half, value + half, method, n,
                    u_regression=math.sqrt(var_reg), u_tare=math.sqrt(var_tare), u_mass=0.0,
                    dof=float(nu))


def _tare_dof(sel: pd.DataFrame, reductions: dict[int, RunReduction] | None,
              tares: dict[str, TareModel] | None) -> float:
    """Degrees of freedom of the tares subtracted from the runs ``sel`` (the smallest)."""
    if not reductions or not tares:
        return math.inf
    groups = {reductions[int(r)].tare_group for r in sel["run"] if int(r) in reductions}
    dofs = [tares[g].drag.dof for g in groups if g in tares]
    return float(min(dofs)) if dofs else math.inf


def _influence(x: np.ndarray, resid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Externally studentized residuals and Cook's distances of an OLS fit, in closed form.

    With leverages h = diag(X (X'X)^-1 X'), p regressors and n samples: the leave-one-out
    variance s_(i)^2 = (SSE - e_i^2 / (1 - h_i)) / (n - p - 1) (Belsley, Kuh & Welsch 1980,
    eq. 2.8), t_i = e_i / (s_(i) sqrt(1 - h_i)), and D_i = e_i^2 h_i / (p s^2 (1 - h_i)^2).
    The same values as statsmodels' OLSInfluence, without its n refits (O(n), not O(n^2)).
    """
    n, p = x.shape
    q, _ = np.linalg.qr(x)
    h = np.einsum("ij,ij->i", q, q)
    sse = float(resid @ resid)
    s2 = sse / (n - p)
    with np.errstate(divide="ignore", invalid="ignore"):
        s2_i = (sse - resid**2 / (1.0 - h)) / (n - p - 1)
        student = resid / np.sqrt(s2_i * (1.0 - h))
        cooks = resid**2 * h / (p * s2 * (1.0 - h) ** 2)
    return student, cooks


def fit_damping(
    runs: pd.DataFrame,
    rho: float,
    area: float,
    alpha_max_deg: float,
    reductions: dict[int, RunReduction] | None = None,
    tares: dict[str, TareModel] | None = None,
) -> tuple[DampingFit | None, dict[str, Estimate], list[str]]:
    """C_D(α) damping terms from the steady hull runs with |α| ≤ ``alpha_max_deg``.

    Parameters
    ----------
    runs : DataFrame
        runs.csv rows (status ok) with angle_deg, speed_mean, drag_mean, rho.
    rho : float
        Water density for the dimensional values [kg/m³].
    area : float
        Frontal area A [m²] (C_D reference).
    alpha_max_deg : float
        Largest |α| used [deg].
    reductions, tares : dict, optional
        Run reductions and tare models, to propagate the tare's uncertainty.
    """
    msgs: list[str] = []
    est: dict[str, Estimate] = {}
    hull = runs[(runs["status"] == "ok") & (runs["config"] == "hull")]
    sel = hull[np.abs(hull["angle_deg"]) <= alpha_max_deg + 1e-9]
    sel = sel[sel["speed_mean"] > 0]
    if sel.empty:
        msgs.append("X_u|u|, X_uv, X_v|v| and Y_uv need steady hull runs at |α| ≤ "
                    f"{alpha_max_deg:g}°; the day has none.")
        return None, est, msgs
    alpha = np.radians(sel["angle_deg"].to_numpy(float))
    cd = sel["cd"].to_numpy(float)
    q = 0.5 * rho * area
    angles = sorted(set(np.round(sel["angle_deg"].to_numpy(float), 1)))
    n = len(sel)
    method = f"C_D(α) quadratic OLS over {n} steady runs at α = " + ", ".join(
        f"{a:g}" for a in angles) + "° (report eqs. 13–15)"
    if len(angles) >= 3 and n >= 4:
        res = fit_cd_alpha(alpha, cd)
        params, cov, dof = np.asarray(res.params), np.asarray(res.cov_params()), int(res.df_resid)
        x = np.column_stack([alpha**2, alpha, np.ones_like(alpha)])
        cov_tare = _run_tare_cov(np.linalg.pinv(x), sel, reductions, tares, q)
        tare_dof = _tare_dof(sel, reductions, tares)
        student, cooks = _influence(x, np.asarray(res.resid))
        table = pd.DataFrame({
            "run": sel["run"].to_numpy(int), "angle_deg": sel["angle_deg"].to_numpy(float),
            "alpha_rad": alpha, "speed": sel["speed_mean"].to_numpy(float), "cd": cd,
            "fitted": res.fittedvalues, "resid": res.resid, "student": student,
            "cooks": cooks,
        })
        # with n - p - 1 < 1 no run can be left out of the variance (t_i is NaN) and Cook's
        # distance is fixed by the angles alone: no run is judged
        flag = ((np.abs(student) > 3.0) | (cooks > max(4.0 / n, 0.5))
                if n - x.shape[1] - 1 >= 1 else np.zeros(n, dtype=bool))
        outl = table.loc[flag, "run"]
        fit = DampingFit(params=params, cov=cov + cov_tare, dof=dof, rho=rho, area=area,
                         runs=table, outliers=[int(r) for r in outl])
        for sym, g in (("X_u|u|", [0, 0, -q]), ("X_uv", [0, -q, 0]),
                       ("X_v|v|", [-q, 0, q / 2]), ("Y_uv", [0, 0, -q])):
            est[sym] = _lin(sym, np.array(g), params, cov, dof, method, n,
                            tare_cov=cov_tare, tare_dof=tare_dof)
        return fit, est, msgs
    zero = sel[np.abs(sel["angle_deg"]) <= ANGLE_TOL_DEG]
    msgs.append(
        "X_uv and X_v|v| need steady hull runs at three or more angles up to "
        f"{alpha_max_deg:g}°; the day has {len(angles)} ("
        + ", ".join(f"{a:g}°" for a in angles) + ")."
    )
    if len(zero) >= 2:
        c = zero["cd"].to_numpy(float)
        mean, se = float(np.mean(c)), float(np.std(c, ddof=1) / math.sqrt(len(c)))
        avg = np.full((1, len(c)), 1.0 / len(c))
        se = math.sqrt(se**2 + float(_run_tare_cov(avg, zero, reductions, tares, q)[0, 0]))
        params = np.array([0.0, 0.0, mean])
        cov = np.diag([0.0, 0.0, se**2])
        m2 = f"mean C_D of {len(zero)} steady runs at α = 0 (report eq. 13, c only)"
        est["X_u|u|"] = _lin("X_u|u|", np.array([0, 0, -q]), params, cov, len(c) - 1, m2,
                             len(c))
        est["Y_uv"] = _lin("Y_uv", np.array([0, 0, -q]), params, cov, len(c) - 1, m2, len(c))
    else:
        msgs.append("X_u|u| and Y_uv need two or more steady hull runs at α = 0.")
    return None, est, msgs


def _run_tare_cov(
    A: np.ndarray,
    sel: pd.DataFrame,
    reductions: dict[int, RunReduction] | None,
    tares: dict[str, TareModel] | None,
    q_area: float,
) -> np.ndarray:
    """Tare covariance of a fit over per-run steady means (divided by q_area·U² when C_D)."""
    if not reductions or not tares:
        return np.zeros((A.shape[0], A.shape[0]))
    ids = [int(r) for r in sel["run"]]
    rows = np.array([reductions[r].steady_regressors for r in ids], dtype=float)
    u = sel["speed_mean"].to_numpy(float)
    denom = q_area * u * u if q_area else np.ones_like(u)
    groups = np.array([reductions[r].tare_group for r in ids])
    return tare_covariance(A, rows / denom[:, None], groups, tares)


#: The note of a day with transverse tows and no lateral area ([model] without
#: lateral_area_m2 and diameter_m, such as a ship given by its frontal area).
LATERAL_AREA_UNKNOWN = (
    "[model] gives neither lateral_area_m2 nor diameter_m, so the lateral area is unknown: "
    "C_D,90 and the runs' cd_lateral are not computed (Y_v|v| is, as it does not depend on "
    "the area); give lateral_area_m2 for them."
)


def fit_transverse(
    runs: pd.DataFrame,
    rho: float,
    lateral_area: float,
    reductions: dict[int, RunReduction] | None = None,
    tares: dict[str, TareModel] | None = None,
) -> tuple[Estimate | None, float, float, pd.DataFrame | None, list[str]]:
    """Y_v|v| = −½ρ·A_lat·C_D,90 from the transverse steady runs: OLS of R = K·U|U|.

    ``lateral_area`` [m²] NaN (not known): Y_v|v| all the same, C_D,90 NaN, no run table and
    the note :data:`LATERAL_AREA_UNKNOWN`."""
    # loaded on use: statsmodels loads while the workers reduce the runs
    from statsmodels.regression.linear_model import OLS

    tr = select_runs(runs, 90.0)
    tr = tr[tr["speed_mean"] > 0]
    if len(tr) < 2:
        return None, math.nan, math.nan, None, [
            "Y_v|v| and Z_w|w| need two or more steady transverse (α = 90°) hull runs; "
            f"the day has {len(tr)}."
        ]
    u = tr["speed_mean"].to_numpy(float)
    r = tr["drag_mean"].to_numpy(float)
    # Y_v|v| does not depend on A_lat: without it the fit runs on 1 m² and C_D,90 is unknown
    known_area = math.isfinite(lateral_area) and lateral_area > 0
    lateral_area = lateral_area if known_area else 1.0
    # each run at its own water density: R/(½ρ_run·A_lat) = C_D,90·U|U|
    y = r / (0.5 * tr["rho"].to_numpy(float) * lateral_area)
    uu = (u * np.abs(u))[:, None]
    res = OLS(y, uu).fit()
    cd90, cd90_se, dof = float(res.params[0]), float(res.bse[0]), int(res.df_resid)
    q_run = 0.5 * tr["rho"].to_numpy(float) * lateral_area
    tare_var = float(_run_tare_cov(np.linalg.pinv(uu) / q_run[None, :], tr, reductions, tares,
                                   0.0)[0, 0])
    reg_var = cd90_se**2
    cd90_se = math.sqrt(reg_var + tare_var)
    q90 = 0.5 * rho * lateral_area
    value, se = -q90 * cd90, q90 * cd90_se
    nu = welch_satterthwaite([reg_var, tare_var], [dof, _tare_dof(tr, reductions, tares)])
    tq = t95(nu)
    est = Estimate(
        "Y_v|v|", value, se, value - tq * se, value + tq * se,
        f"transverse tow R = ½ρA_lat·C_D,90·U|U| by OLS over {len(tr)} steady runs at α = 90° "
        "(report eq. 15)", len(tr),
        u_regression=q90 * math.sqrt(reg_var), u_tare=q90 * math.sqrt(tare_var), u_mass=0.0,
        dof=float(nu),
    )
    # residual of each run's drag [N]: R − ½ρ_run·A_lat·C_D,90·U|U|
    if not known_area:
        return est, math.nan, math.nan, None, [LATERAL_AREA_UNKNOWN]
    table = pd.DataFrame({"run": tr["run"].to_numpy(int), "speed": u, "drag": r,
                          "cd90": y / (u * u), "resid": np.asarray(res.resid) * q_run})
    return est, cd90, cd90_se, table, []


def repeat_spread(runs: pd.DataFrame) -> pd.DataFrame:
    """Spread of C_D between repeats: runs at the same angle and speed (within 3 %).

    C_D is each run's coefficient on the area its test uses (runs.csv ``cd_ref``: the lateral
    area at α = 90°, else the frontal area); ``cd`` when the table has no ``cd_ref``.
    """
    hull = runs[(runs["status"] == "ok") & (runs["config"] == "hull")]
    cd = hull["cd"].to_numpy(float)
    if "cd_ref" in hull:
        ref = hull["cd_ref"].to_numpy(float)
        cd = np.where(np.isnan(ref), cd, ref)
    angle = np.round(hull["angle_deg"].to_numpy(float), 1)
    speed = hull["speed_mean"].to_numpy(float)
    run, drag = hull["run"].to_numpy(), hull["drag_mean"].to_numpy(float)
    # by angle (a run without one in none), then by speed within an angle
    order = [i for i in np.lexsort((speed, angle)) if not np.isnan(angle[i])]
    rows = []
    cluster: list[dict[str, Any]] = []
    for i in order:
        r = {"run": run[i], "speed_mean": speed[i], "cd": cd[i], "drag_mean": drag[i]}
        if cluster and (angle[i] != cluster[0]["angle"] or abs(
                r["speed_mean"] - cluster[0]["speed_mean"]) > 0.03 * max(
                cluster[0]["speed_mean"], 1e-9)):
            rows.append(_spread_row(cluster[0]["angle"], cluster))
            cluster = []
        cluster.append(r | {"angle": angle[i]})
    if cluster:
        rows.append(_spread_row(cluster[0]["angle"], cluster))
    df = pd.DataFrame(rows)
    return df[df["n"] > 1].reset_index(drop=True) if not df.empty else df


def _spread_row(angle: float, cluster: list[dict[str, Any]]) -> dict[str, object]:
    cds = np.array([c["cd"] for c in cluster], dtype=float)
    drags = np.array([c["drag_mean"] for c in cluster], dtype=float)
    return {
        "angle_deg": float(angle),
        "speed": float(np.mean([c["speed_mean"] for c in cluster])),
        "n": len(cluster),
        "runs": " ".join(str(r) for r in sorted(int(c["run"]) for c in cluster)),
        "cd_mean": float(np.mean(cds)),
        "cd_std": float(np.std(cds, ddof=1)) if len(cds) > 1 else math.nan,
        "drag_std": float(np.std(drags, ddof=1)) if len(drags) > 1 else math.nan,
    }


# ------------------------------------------------------------------------------- the table
def fit_hull(
    runs: pd.DataFrame,
    reductions: dict[int, RunReduction],
    *,
    mass: float,
    mass_sd: float,
    length: float,
    frontal_area: float,
    lateral_area: float,
    alpha_max_deg: float = 30.0,
    tares: dict[str, TareModel] | None = None,
    rho: float | None = None,
) -> HullFit:
    """Every hull coefficient the day supports (model scale, SI, SNAME signs).

    Parameters
    ----------
    runs : DataFrame
        runs.csv rows.
    reductions : dict
        Tare-corrected run reductions (for the sample-level added-mass regressions).
    mass : float
        Weighed model mass [kg].
    mass_sd : float
        Its standard uncertainty [kg].
    length : float
        Model length L [m] (for the prime values).
    frontal_area : float
        Frontal area A [m²].
    lateral_area : float
        Projected side area A_lat [m²].
    alpha_max_deg : float
        Largest |α| of the C_D(α) fit [deg].
    tares : dict, optional
        Tare models by group: their uncertainty is propagated into every interval.
    rho : float, optional
        Reference water density of the dimensional damping values and the primes [kg/m³]:
        the day's nominal water ([water] of the protocol). Each run's C_D is normalised with its
        own water; the coefficients are C_D's made dimensional at this one density, so that
        normalising and rescaling never use different waters. Default: the mean of the hull
        runs' densities.
    """
    messages: list[str] = []
    hull_ok = runs[(runs["status"] == "ok") & (runs["config"] == "hull")]
    if rho is None:
        rho = float(hull_ok["rho"].mean()) if len(hull_ok) else math.nan
    estimates: dict[str, Estimate] = {}
    added: dict[str, AddedMassFit] = {}
    for symbol, angle in (("X_udot", 0.0), ("Y_vdot", 90.0)):
        sel = select_runs(runs, angle)
        # a run without a measured speed (speed_source = "nominal") has no acceleration
        ids = [int(r) for r in sel["run"] if int(r) in reductions
               and reductions[int(r)].speed_source == "measured"]
        levels = accel_levels(reductions, ids)
        if len(levels) < 2:
            found = ", ".join(f"{lv:.2f}" for lv in levels) or "none"
            who, it = ((f"{symbol} and Z_wdot need", "they are") if symbol == "Y_vdot"
                       else (f"{symbol} needs", "it is"))
            messages.append(
                f"{who} accelerated hull runs at α = {angle:g}° at two or more "
                f"accelerations; the day has {len(levels)} (m/s²: {found}), so {it} omitted."
            )
            continue
        if len(levels) == 2:
            messages.append(
                f"{symbol} rests on two acceleration levels at α = {angle:g}° "
                f"({levels[0]:.2f} and {levels[1]:.2f} m/s²): with two, its 95 % interval held "
                "the truth on only about 90 % of towtank's synthetic days (docs/method.md); "
                "tow a third acceleration to trust it fully."
            )
        fit = fit_added_mass(symbol, reductions, ids, mass, mass_sd, tares)
        added[symbol] = fit
        estimates[symbol] = fit.estimate
    damping, est_d, msgs = fit_damping(runs, rho, frontal_area, alpha_max_deg, reductions,
                                       tares)
    estimates.update(est_d)
    messages += msgs
    yvv, cd90, cd90_se, ttable, msgs = fit_transverse(runs, rho, lateral_area, reductions,
                                                      tares)
    messages += msgs
    if yvv is not None:
        estimates["Y_v|v|"] = yvv
        if damping is not None:
            damping.cd90, damping.cd90_se, damping.transverse_runs = cd90, cd90_se, ttable
    for target, source in MIRROR.items():
        if source in estimates:
            e = estimates[source]
            estimates[target] = replace(e, symbol=target,
                                        method=f"same as {source} (axisymmetric hull)")
    lift_slope = None
    small = hull_ok[np.abs(hull_ok["angle_deg"]) <= alpha_max_deg]
    if small["cl"].notna().sum() >= 3 and small["angle_deg"].nunique() >= 2:
        # loaded on use: statsmodels loads while the workers reduce the runs
        from statsmodels.regression.linear_model import OLS

        a = np.radians(small["angle_deg"].to_numpy(float))
        res = OLS(small["cl"].to_numpy(float), a[:, None]).fit()
        lo, hi = res.conf_int()[0]
        lift_slope = (float(res.params[0]), float(lo), float(hi))
    return HullFit(
        estimates=estimates, rho=rho, length=length, mass=mass, added_mass=added,
        damping=damping, repeats=repeat_spread(runs), messages=messages, lift_slope=lift_slope,
    )


def hull_warnings(hull: HullFit) -> list[str]:
    """The day's sentences about a hull fit's verdicts (its ``messages`` aside): two added-mass
    estimates that disagree (:func:`agreement`) and the C_D(α) fit's flagged runs
    (|studentized residual| > 3 or Cook's distance > max(4/n, 0.5))."""
    out: list[str] = []
    for sym, am in hull.added_mass.items():
        verdict = am.estimate.agreement
        if verdict is not None and not verdict.agrees:
            out.append(
                f"{sym}: the curve-difference estimate {am.estimate.alt_value:.4g} kg and the "
                f"joint regression {am.estimate.value:.4g} kg disagree ({verdict.detail})."
            )
    if hull.damping is not None and hull.damping.outliers:
        dm = hull.damping
        t = dm.runs.set_index("run")
        flagged = ", ".join(
            f"{r} (studentized residual {t.loc[r, 'student']:+.3g}, Cook's distance "
            f"{t.loc[r, 'cooks']:.2g})" for r in dm.outliers)
        one = len(dm.outliers) == 1
        out.append(
            f"C_D(α) fit: {'run' if one else 'runs'} {flagged} "
            f"{'is' if one else 'are'} flagged as {'an outlier' if one else 'outliers'} "
            f"(|studentized residual| > 3 or Cook's distance > {max(4.0 / len(t), 0.5):.2g}); "
            f"{'it is' if one else 'they are'} still in the fit: check "
            f"{'it' if one else 'them'} before trusting X_u|u|, X_uv, X_v|v| and Y_uv."
        )
    return out


def load_reference(reference: str) -> dict[str, float]:
    """Reference prime values by symbol: a built-in set ('remus', 'remus-prestero2001') or a
    CSV (symbol, prime)."""
    if reference in BUILTIN_REFERENCES:
        return builtin_reference(reference)
    return read_reference_csv(reference)


COEFFICIENT_COLUMNS = [
    "symbol", "value", "unit", "prime", "ci_low", "ci_high", "method", "reference_prime",
    "diff_pct", "prototype_value",
]
#: Extension columns of coefficients.csv after the docs/formats.md §5 ones (docs/formats.md).
COEFFICIENT_EXTRA_COLUMNS = [
    "std_error", "prime_ci_low", "prime_ci_high", "n_runs", "alt_value", "alt_method",
    "agreement", "u_regression", "u_tare", "u_mass", "dof",
]


def coefficients_table(
    hull: HullFit, reference: dict[str, float], length_sd: float = 0.0
) -> pd.DataFrame:
    """coefficients.csv (docs/formats.md §5) without prototype values, plus extension columns.

    prime = value/(½ρL³) for added mass and value/(½ρL²) for damping (k = 3 or 2 below);
    diff_pct = (prime − reference)/|reference|·100, empty where the reference is zero or
    missing. A symmetric twin (Z_wdot, X_uw, X_w|w|, Z_uw, Z_w|w|) the reference lacks takes its
    source's reference (Y_vdot, X_uv, X_v|v|, Y_uv, Y_v|v|), as its value does.

    The prime's standard uncertainty adds the length's in quadrature,
    u(prime) = √((u(value)/(½ρL^k))² + (prime·k·u(L)/L)²), and its 95 % interval uses the
    coverage factor of the value's interval, (ci_high − ci_low)/(2·std_error). The value itself
    is independent of L, and of the diameter, whose areas cancel in every coefficient
    (module docstring).

    Parameters
    ----------
    hull : HullFit
        The day's hull fit.
    reference : dict
        Reference prime values by symbol (:func:`load_reference`).
    length_sd : float, default 0
        Standard uncertainty of the model length L [m].
    """
    rows = []
    for s in SYMBOLS:
        if s not in hull.estimates:
            continue
        e = hull.estimates[s]
        k = 3 if KIND[s] == "added_mass" else 2
        scale = 0.5 * hull.rho * hull.length**k
        prime = e.value / scale
        ref = float(reference.get(s, reference.get(MIRROR.get(s, s), math.nan)))
        diff = (prime - ref) / abs(ref) * 100.0 if math.isfinite(ref) and ref != 0 else math.nan
        rel_len = k * length_sd / hull.length
        prime_se = math.hypot(e.std_error / scale, abs(prime) * rel_len)
        half = (e.ci_high - e.ci_low) / 2.0
        factor = half / e.std_error if e.std_error > 0 else normal_quantile()
        rows.append({
            "symbol": s, "value": e.value, "unit": UNIT[s], "prime": prime,
            "ci_low": e.ci_low, "ci_high": e.ci_high, "method": e.method,
            "reference_prime": ref, "diff_pct": diff, "prototype_value": math.nan,
            "std_error": e.std_error, "prime_ci_low": prime - factor * prime_se,
            "prime_ci_high": prime + factor * prime_se, "n_runs": e.n_runs,
            "alt_value": e.alt_value, "alt_method": e.alt_method,
            "agreement": str(e.agreement or ""),
            "u_regression": e.u_regression, "u_tare": e.u_tare, "u_mass": e.u_mass,
            "dof": e.dof,
        })
    return pd.DataFrame(rows, columns=COEFFICIENT_COLUMNS + COEFFICIENT_EXTRA_COLUMNS)
