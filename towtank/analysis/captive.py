"""The joint fit of the captive derivatives (FORMATS section 8; ITTC 7.5-02-06-02).

One weighted least-squares fit per equation (Y and N; Z and M for vertical-plane runs) over
every run's components at once (:class:`towtank.reduce.captive.CaptiveRun` rows: a static
run's steady mean, a PMM run's cycle-averaged mean and first harmonics), so the nonlinear
regressors' harmonics are columns of the same design matrix as the linear ones and a linear
derivative is never read off a first harmonic that still holds v|v| or r|r|. The unit of
information is a run's component, never a sample.

Weights: 1/var of each row's load less its regressors times the derivatives, the variance
from the row's covariance of load and regressors over the run's cycles or blocks and the
zero's (the effective-variance method: the motion channels' noise is in the regressors), by a
few passes of weighted least squares. A variance estimated from a few cycles is on average
dof/(dof - 2) times too small (:func:`variance_inflation`): each row's own factor enters the
derivatives' covariance (:func:`row_covariance`), each derivative's interval takes the
Welch-Satterthwaite dof of its rows, and the chi^2 test of model error takes the heavy tail of
such weights (:func:`chi2_p_value`); the reduced chi^2 widens the intervals when it exceeds 1
(model error widens an interval, never narrows it; it is a warning when that test rejects the
model at :data:`CHI2_P`). Rows without a standard error (a
lab's table of means) are fitted on the prime scale (each row over 1/2 rho L^2 U^2, L^3 for
moments) with the residual-based covariance and Student's t on n - p degrees of
freedom.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
import pandas as pd

from towtank.analysis.hull import COEFFICIENT_COLUMNS, COEFFICIENT_EXTRA_COLUMNS
from towtank.reduce.captive import (
    COMPONENTS,
    COV_NAMES,
    CYCLE_COLUMNS,
    PERIOD_COLUMNS,
    PMM_TESTS,
    REGRESSORS,
    ROW_COLUMNS,
    STATIC_BLOCKS,
    VERTICAL_REGRESSORS,
    CaptiveRun,
    Inertia,
    arm_kinematics,
    body_kinematics,
    moment_point,
)
from towtank.reduce.captive import regressors as make_regressors
from towtank.stats.intervals import welch_satterthwaite
from towtank.stats.quantiles import t_quantile

#: Each regressor's power k of L in its prime (value / (1/2 rho L^k)) for the force and the
#: moment equation.
PRIME_POWER = {
    "uv": (2, 3), "v|v|": (2, 3), "ur": (3, 4), "r|r|": (4, 5), "vdot": (3, 4),
    "rdot": (4, 5), "uudr": (2, 3), "uu": (2, 3),
}
#: Units of the derivatives by regressor for the force and the moment equation.
UNITS = {
    "uv": ("kg/m", "kg"), "v|v|": ("kg/m", "kg"), "ur": ("kg/rad", "kg*m/rad"),
    "r|r|": ("kg*m/rad^2", "kg*m^2/rad^2"), "vdot": ("kg", "kg*m"),
    "rdot": ("kg*m/rad", "kg*m^2/rad"), "uudr": ("kg/m/rad", "kg/rad"), "uu": ("kg/m", "kg"),
}
#: The vertical regressor = this sign times the horizontal one of the rig, times s =
#: sign(roll_deg) where marked 0 -> -s, 1 -> +s, None -> 1 (w = -s v, q = s r).
_VERTICAL_SIGN = {"uv": -1, "v|v|": -1, "ur": 1, "r|r|": 1, "vdot": -1, "rdot": 1,
                  "uudr": None, "uu": None}
TEST_NAMES = {"drift": "static drift", "rudder": "rudder", "arm": "rotating arm",
              "sway": "pure sway", "yaw": "pure yaw", "yaw_drift": "yaw with drift"}
#: Agreement across PMM runs: "differ" below this p value of the chi^2 homogeneity test.
AGREEMENT_P = 0.01
#: The derivatives whose agreement over omega' and amplitude is tested (acceleration and
#: velocity derivatives a PMM run measures).
AGREEMENT_REGRESSORS = ("vdot", "rdot", "uv", "ur")
PMM_COLUMNS = ("run", "test", "frequency_hz", "amplitude_m", "omega_prime", "cycles_used",
               "fy_in", "fy_quad", "mz_in", "mz_quad", "fy_in_se", "fy_quad_se", "mz_in_se",
               "mz_quad_se")
BY_RUN_COLUMNS = ("run", "test", "omega_prime", "amplitude_m", "symbol", "value", "std_error")


def plane_names(plane: str) -> tuple[tuple[str, str], tuple[str, ...]]:
    """The equations' letters and the regressor names of ``plane``."""
    if plane == "vertical":
        return ("Z", "M"), VERTICAL_REGRESSORS
    return ("Y", "N"), REGRESSORS


def symbol(eq: str, k: int, plane: str) -> str:
    """The symbol of regressor ``k`` (index in :data:`REGRESSORS`) in equation ``eq``."""
    return f"{eq}_{plane_names(plane)[1][k]}"


@dataclass(frozen=True)
class CaptiveEstimate:
    """One fitted derivative [SI]: value, standard error, degrees of freedom, 95 % interval,
    the tests its rows came from and how many runs carry it."""

    symbol: str
    value: float
    std_error: float
    dof: float
    ci_low: float
    ci_high: float
    unit: str
    prime: float
    prime_lt: float
    scale: float
    scale_lt: float
    method: str
    n_runs: int


@dataclass(frozen=True)
class CaptiveFit:
    """The captive derivatives of a day (:func:`fit_captive`).

    ``notes``: what the report shows beside the derivatives (the PMM runs' agreement over
    omega'); ``warnings``: what the day's warnings carry (runs that differ over omega',
    derivatives the runs do not determine, a fit widened by its reduced chi^2).
    """

    plane: str
    rho: float
    length_m: float
    draught_m: float | None
    estimates: dict[str, CaptiveEstimate]
    runs: tuple[CaptiveRun, ...]
    notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()
    by_run: pd.DataFrame = field(default_factory=lambda: pd.DataFrame(
        columns=list(BY_RUN_COLUMNS)))
    chi2_reduced: dict[str, float] = field(default_factory=dict)
    #: per equation ("Y", "N"; "Z", "M"), the covariance of its derivatives [SI], indexed by
    #: symbol both ways (what a prediction's band is drawn from)
    cov: dict[str, pd.DataFrame] = field(default_factory=dict)
    #: x [m] from O of the point P the moments and derivatives refer to (0: O; the balance
    #: point with ``[captive] moment_ref = "balance"``, :func:`towtank.reduce.captive.reference_x`)
    ref_x_m: float = 0.0

    def moment_point(self) -> str:
        """Where the moments are taken, in words (:func:`towtank.reduce.captive.moment_point`)."""
        return moment_point(self.ref_x_m)

    def table(self) -> pd.DataFrame:
        """coefficients.csv rows: the hull table's columns (NaN where not applicable) and
        ``prime_LT``."""
        rows = []
        for e in self.estimates.values():
            half = (e.ci_high - e.ci_low) / 2.0
            rows.append({
                "symbol": e.symbol, "value": e.value, "unit": e.unit, "prime": e.prime,
                "ci_low": e.ci_low, "ci_high": e.ci_high, "method": e.method,
                "reference_prime": math.nan, "diff_pct": math.nan,
                "prototype_value": math.nan, "std_error": e.std_error,
                "prime_ci_low": (e.value - half) / e.scale,
                "prime_ci_high": (e.value + half) / e.scale, "n_runs": e.n_runs,
                "alt_value": math.nan, "alt_method": "", "agreement": "",
                "u_regression": e.std_error, "u_tare": math.nan, "u_mass": math.nan,
                "dof": e.dof, "prime_LT": e.prime_lt,
            })
        return pd.DataFrame(rows, columns=[*COEFFICIENT_COLUMNS, *COEFFICIENT_EXTRA_COLUMNS,
                                           "prime_LT"])

    def pmm_table(self) -> pd.DataFrame:
        """pmm.csv: one row per PMM run, the first harmonics of Y and N about O."""
        rows = []
        for r in self.runs:
            if r.test not in PMM_TESTS:
                continue
            rr = r.rows.set_index("component")
            rows.append({
                "run": r.run, "test": r.test, "frequency_hz": r.frequency_hz,
                "amplitude_m": r.amplitude_m, "omega_prime": r.omega_prime(self.length_m),
                "cycles_used": r.cycles_used,
                "fy_in": rr.at["sin", "Y"], "fy_quad": rr.at["cos", "Y"],
                "mz_in": rr.at["sin", "N"], "mz_quad": rr.at["cos", "N"],
                "fy_in_se": rr.at["sin", "Y_se"], "fy_quad_se": rr.at["cos", "Y_se"],
                "mz_in_se": rr.at["sin", "N_se"], "mz_quad_se": rr.at["cos", "N_se"],
            })
        return pd.DataFrame(rows, columns=list(PMM_COLUMNS))


def mapped_rows(run: CaptiveRun, roll_deg: float = 90.0) -> pd.DataFrame:
    """The run's component rows in its plane's names: a vertical run's rig Y, N and
    regressors turned into Z = -s Y, M = s N and w = -s v, q = s r (s = sign(roll_deg))."""
    rows = run.rows
    if run.plane != "vertical":
        return rows
    s = math.copysign(1.0, roll_deg)
    out = pd.DataFrame({"component": rows["component"]})
    for q, new, sign in (("X", "X", 1.0), ("Y", "Z", -s), ("N", "M", s)):
        out[new] = sign * rows[q]
        out[f"{new}_se"] = rows[f"{q}_se"]
    for k, kv in zip(REGRESSORS, VERTICAL_REGRESSORS, strict=True):
        k_sign = _VERTICAL_SIGN[k]
        out[kv] = rows[k] * (1.0 if k_sign is None else k_sign * s)
    return out


def mapped_cov(run: CaptiveRun, roll_deg: float = 90.0) -> np.ndarray:
    """The run's component covariances (:attr:`CaptiveRun.cov`, of
    :data:`towtank.reduce.captive.COV_NAMES`) in its plane's signs (:func:`mapped_rows`);
    NaN where the run has none."""
    n = len(COV_NAMES)
    if run.cov is None:
        return np.full((len(run.rows), n, n), np.nan)
    if run.plane != "vertical":
        return np.asarray(run.cov, dtype=float)
    s = math.copysign(1.0, roll_deg)
    signs = (_VERTICAL_SIGN[k] for k in REGRESSORS)
    d = np.array([-s, s, *(1.0 if k is None else k * s for k in signs)])
    return np.asarray(run.cov, dtype=float) * np.outer(d, d)


def _effective_weights(cov: np.ndarray, eq: int, keep: list[int], coef: np.ndarray
                       ) -> np.ndarray:
    """1 / var(y_i - x_i b) of each row from its covariance ``cov`` (rows, 10, 10): the
    equation's load (``eq`` 0 force, 1 moment) and the kept regressors with the
    coefficients ``coef`` (the regressors' scatter enters with the derivatives' weights)."""
    a = np.zeros(cov.shape[1])
    a[eq] = 1.0
    a[[2 + k for k in keep]] = -np.asarray(coef, dtype=float)
    return 1.0 / np.einsum("i,nij,j->n", a, cov, a)


def _design(runs: Sequence[CaptiveRun], plane: str, roll_deg: float
            ) -> tuple[pd.DataFrame, np.ndarray, np.ndarray]:
    """All rows of the runs (with run, test, speed), the run index of each row."""
    frames = []
    for i, r in enumerate(runs):
        m = mapped_rows(r, roll_deg).copy()
        m["run_index"] = i
        m["speed"] = r.speed
        frames.append(m)
    rows = pd.concat(frames, ignore_index=True)
    regs = plane_names(plane)[1]
    return rows, rows[list(regs)].to_numpy(dtype=float), rows["run_index"].to_numpy()


#: A regressor whose largest component, made non-dimensional (:func:`_excited`), is below
#: this fraction of the largest regressor's is not excited by the runs (measurement noise of
#: the motion, not a test of it).
EXCITED_FRACTION = 1e-3


def _excited(X: np.ndarray, speed: np.ndarray, length_m: float) -> np.ndarray:
    """Columns that carry information (see :data:`EXCITED_FRACTION`).

    Each regressor is compared as its term enters the force's prime: x·L^(k-2)/U² (k its
    :data:`PRIME_POWER`; u v/U², r|r|·L²/U², v'·L/U², ...), so that the test does not depend
    on the model's size or speed (in SI, r|r| [rad²/s²] beside u² [m²/s²] would count as
    noise on a long model whose r' is large). ``speed`` U [m/s] of each row, ``length_m``
    L [m]."""
    powers = np.array([PRIME_POWER[name][0] for name in REGRESSORS], dtype=float)
    if math.isfinite(length_m) and length_m > 0:
        with np.errstate(divide="ignore", invalid="ignore"):
            X = (X * length_m ** (powers - 2.0)[None, :]
                 / (np.asarray(speed, dtype=float) ** 2)[:, None])
    size = np.where(np.isfinite(X), np.abs(X), 0.0)
    scale = np.max(size, axis=0) if size.size else np.zeros(X.shape[1])
    return scale > EXCITED_FRACTION * (float(np.max(scale)) if scale.size else 1.0)


def _independent(X: np.ndarray, cols: list[int]) -> tuple[list[int], list[int]]:
    """``cols`` split into those that raise the rank in order and those that do not."""
    keep: list[int] = []
    dropped: list[int] = []
    norm = X / np.maximum(np.max(np.abs(X), axis=0), 1e-300)
    for c in cols:
        trial = keep + [c]
        if np.linalg.matrix_rank(norm[:, trial], tol=1e-8 * math.sqrt(X.shape[0])) == len(
                trial):
            keep = trial
        else:
            dropped.append(c)
    return keep, dropped


def _and(names: Sequence[str]) -> str:
    return ", ".join(names)


#: What a regressor needs of the runs to be excited (for the sentence of those that are not).
_NEEDS = {"ur": "yaw-rate runs (rotating arm, PMM yaw)",
          "r|r|": "yaw-rate runs (rotating arm, PMM yaw)", "vdot": "PMM runs",
          "rdot": "PMM runs", "uudr": "rudder runs", "uv": "drift runs (static, PMM sway)",
          "v|v|": "drift runs (static, PMM sway)", "uu": "runs"}


def not_excited_sentence(runs: Sequence[CaptiveRun], terms: Sequence[tuple[str, str, str]]
                         ) -> str:
    """One sentence naming the derivatives (``terms``: force and moment letters, regressor
    name) the runs do not determine and the runs that would."""
    names = _and([f"{f}_{k}, {m}_{k}" for f, m, k in terms])
    horizontal = dict(zip(VERTICAL_REGRESSORS, REGRESSORS, strict=True))
    needs = dict.fromkeys(_NEEDS[horizontal.get(k, k)] for _, _, k in terms)
    tests = ", ".join(sorted({TEST_NAMES[r.test] for r in runs}))
    return (f"{names}: not determined (left out): no {' and no '.join(needs)} excite them "
            f"(the captive runs: {tests})")


#: Significance of the reduced chi^2 above which the fit is said to have model error.
CHI2_P = 0.01


def variance_inflation(dof: np.ndarray | float) -> np.ndarray:
    """E[(e/s)^2] of a residual e over a standard error s estimated on ``dof`` degrees of
    freedom (Student's t variance dof / (dof - 2), taken at 3 dof below 3): the factor by
    which weights 1/s^2 from a few cycles or blocks inflate the chi^2 of a fit that is
    right, and deflate its covariance."""
    d = np.maximum(np.asarray(dof, dtype=float), 3.0)
    return d / (d - 2.0)


@dataclass(frozen=True)
class RowCovariance:
    """The derivatives' covariance of a weighted fit whose weights are estimated
    (:func:`row_covariance`): ``cov`` [SI^2], ``parts`` (derivatives, rows) each row's share
    of each derivative's variance, ``leverage`` the rows' leverages h_i, ``expected_chi2``
    the weighted residuals' sum of squares a right fit gives on average."""

    cov: np.ndarray
    parts: np.ndarray
    leverage: np.ndarray
    expected_chi2: float


def row_covariance(X: np.ndarray, w: np.ndarray, inflation: np.ndarray) -> RowCovariance:
    """Covariance of the weighted least-squares coefficients b = (X'WX)^-1 X'W y when each
    row's weight ``w`` is one over a variance estimated with few degrees of freedom, so
    that the row's true variance is on average ``inflation`` / w
    (:func:`variance_inflation`): cov = C diag(inflation / w) C', C = (X'WX)^-1 X'W. A
    derivative carried by PMM rows (5 cycles) is so widened by their factor 2 and one
    carried by static rows (8 blocks) by 1.4. The expected chi^2 is
    sum inflation_i (1 - h_i), h_i the rows' leverages."""
    w = np.asarray(w, dtype=float)
    inflation = np.asarray(inflation, dtype=float)
    a_inv = np.linalg.pinv(X.T @ (X * w[:, None]))
    c = a_inv @ X.T * w[None, :]
    parts = c**2 * (inflation / w)[None, :]
    leverage = w * np.einsum("ij,jk,ik->i", X, a_inv, X)
    return RowCovariance(cov=(c * (inflation / w)[None, :]) @ c.T, parts=parts,
                         leverage=leverage,
                         expected_chi2=float(np.sum(inflation * (1.0 - leverage))))


#: Draws of the chi^2 test's null distribution (:func:`chi2_p_value`) and their seed.
CHI2_DRAWS, CHI2_SEED = 5000, 35


def chi2_p_value(chi2: float, leverage: np.ndarray, dof: np.ndarray) -> float:
    """P(S >= ``chi2``) of a right fit's S = sum w_i e_i^2 when each weight is one over a
    variance estimated on ``dof``_i degrees of freedom: S ~ sum (1 - h_i) t_i^2 with t_i
    Student's on dof_i (``leverage`` h_i), heavier-tailed than chi^2 on n - p dof (the
    variance of t^2 on 4 dof is infinite); by :data:`CHI2_DRAWS` seeded draws."""
    nu = np.maximum(np.asarray(dof, dtype=float), 1.0)
    s = _t_squared_draws(tuple(nu.tolist())) @ (1.0 - np.asarray(leverage, dtype=float))
    return float((np.count_nonzero(s >= chi2) + 1) / (CHI2_DRAWS + 1))


@lru_cache(maxsize=32)
def _t_squared_draws(nu: tuple[float, ...]) -> np.ndarray:
    """The :data:`CHI2_DRAWS` x len(``nu``) seeded draws t_i^2 of :func:`chi2_p_value`, made
    once per set of degrees of freedom (the same seed gives the same draws; a day's fits and
    a study's days ask again for the same sets). Read-only."""
    rng = np.random.default_rng(CHI2_SEED)
    t2 = rng.standard_t(np.array(nu), size=(CHI2_DRAWS, len(nu))) ** 2
    t2.setflags(write=False)
    return t2


#: Passes of the effective-variance weights (each refits with the last pass's derivatives).
EFFECTIVE_VARIANCE_PASSES = 4


def _fit_weights(y: np.ndarray, X: np.ndarray, w: np.ndarray, cov: np.ndarray, eq: int,
                 keep: list[int]) -> np.ndarray:
    """The weights of the rows with the regressors' scatter in their variance: from the
    loads' weights ``w``, :data:`EFFECTIVE_VARIANCE_PASSES` passes of weighted least squares
    and :func:`_effective_weights` (the effective-variance method for errors in the
    regressors)."""
    for _ in range(EFFECTIVE_VARIANCE_PASSES):
        sw = np.sqrt(w)
        coef, *_ = np.linalg.lstsq(X * sw[:, None], y * sw, rcond=None)
        w_new = _effective_weights(cov, eq, keep, coef)
        if not np.all(np.isfinite(w_new) & (w_new > 0)):
            return w
        w = w_new
    return w


def fit_captive(
    runs: Sequence[CaptiveRun], *, rho: float, length_m: float, draught_m: float | None = None,
    plane: str = "horizontal", roll_deg: float = 90.0, alpha: float = 0.05,
    ref_x_m: float = 0.0,
) -> CaptiveFit:
    """The derivatives of ``plane`` from the captive runs of that plane (see module docstring).

    Parameters
    ----------
    runs : sequence of CaptiveRun
        The day's reduced captive runs (those of the other plane are left out).
    rho : float
        Water density [kg/m^3] for the primes.
    length_m : float
        L [m].
    draught_m : float, optional
        T [m]: the primes on the L*T basis (``prime_LT``).
    plane : {"horizontal", "vertical"}
    roll_deg : float
        The model's roll on the rig for vertical runs [deg] (its sign maps the axes).
    alpha : float
        Significance of the intervals.
    ref_x_m : float
        x [m] from O of the point the runs' moments and velocities refer to (0: O); carried
        into the result for what it says about its moments.
    """
    # loaded on use: statsmodels only for the fit
    import statsmodels.api as sm

    runs = tuple(r for r in runs if r.plane == plane)
    (eq_f, eq_m), regs = plane_names(plane)
    warnings: list[str] = []
    if not runs:
        return CaptiveFit(plane, rho, length_m, draught_m, {}, (),
                          warnings=(f"no {plane} captive runs",), ref_x_m=ref_x_m)
    rows, X, run_index = _design(runs, plane, roll_deg)
    cov = np.concatenate([mapped_cov(r, roll_deg) for r in runs])
    excited = _excited(X, rows["speed"].to_numpy(dtype=float), length_m)
    absent = [k for k in range(len(regs)) if not excited[k]]
    if absent:
        warnings.append(not_excited_sentence(runs, [(eq_f, eq_m, regs[k]) for k in absent]))
    keep, dropped = _independent(X, [k for k in range(len(regs)) if excited[k]])
    if dropped:
        warnings.append(
            f"{_and([f'{eq_f}_{regs[k]}, {eq_m}_{regs[k]}' for k in dropped])}: not separable "
            "from the other terms by these runs (e.g. too few drift angles), left out")
    estimates: dict[str, CaptiveEstimate] = {}
    chi2: dict[str, float] = {}
    params: dict[str, np.ndarray] = {}
    param_cov: dict[str, pd.DataFrame] = {}
    Xk = X[:, keep]
    n, p = Xk.shape
    if n <= p:
        warnings.append(f"{n} run components for {p} derivatives: no interval can be given")
    tests = [runs[i].test for i in run_index]
    row_dof = np.array([runs[i].cycles_used - 1 if runs[i].test in PMM_TESTS
                        else STATIC_BLOCKS - 1 for i in run_index], dtype=float)
    for eq, moment in ((eq_f, False), (eq_m, True)):
        y = rows[eq].to_numpy(dtype=float)
        se = rows[f"{eq}_se"].to_numpy(dtype=float)
        with_se = bool(np.all(np.isfinite(se) & (se > 0)))
        if with_se:
            w = 1.0 / se**2
            if np.all(np.isfinite(cov)):
                w = _fit_weights(y, Xk, w, cov, int(moment), keep)
        else:
            U = rows["speed"].to_numpy(dtype=float)
            w = 1.0 / (0.5 * rho * length_m ** (3 if moment else 2) * U**2) ** 2
        res = sm.WLS(y, Xk, weights=w).fit()
        dof = float(n - p)
        if with_se and dof > 0:
            rc = row_covariance(Xk, w, variance_inflation(row_dof))
            stat = float(np.sum(w * res.resid**2))
            red = stat / rc.expected_chi2
            p_chi2 = chi2_p_value(stat, rc.leverage, row_dof)
            widen = max(1.0, red)
            cov_b = rc.cov * widen
            dofs = [welch_satterthwaite(list(v), list(row_dof)) for v in rc.parts]
            dofs = [d if red <= 1.0 else min(d, dof) for d in dofs]
        else:
            red = float(np.sum(w * res.resid**2) / dof) if dof > 0 else math.nan
            p_chi2 = math.nan
            cov_b = np.asarray(res.cov_params()) if dof > 0 else np.full((p, p), math.nan)
            dofs = [dof] * p
        chi2[eq] = red
        coef = np.asarray(res.params)
        bse = np.sqrt(np.diag(cov_b))
        params[eq] = coef
        names = [f"{eq}_{regs[k]}" for k in keep]
        param_cov[eq] = pd.DataFrame(cov_b, index=names, columns=names)
        for j, k in enumerate(keep):
            sym = f"{eq}_{regs[k]}"
            carrying = sorted({i for i in range(n) if abs(X[i, k]) > 1e-9 * np.max(np.abs(
                X[:, k]))}, key=int)
            methods = [TEST_NAMES[t] for t in TEST_NAMES if t in {tests[i] for i in carrying}]
            power = PRIME_POWER[REGRESSORS[k]][int(moment)]
            scale = 0.5 * rho * length_m**power
            scale_lt = (0.5 * rho * draught_m * length_m ** (power - 1)
                        if draught_m else math.nan)
            value, s = float(coef[j]), float(bse[j])
            tq = t_quantile(dofs[j], alpha)
            estimates[sym] = CaptiveEstimate(
                symbol=sym, value=value, std_error=s, dof=dofs[j], ci_low=value - tq * s,
                ci_high=value + tq * s, unit=UNITS[REGRESSORS[k]][int(moment)],
                prime=value / scale, prime_lt=value / scale_lt, scale=scale, scale_lt=scale_lt,
                method=" + ".join(methods), n_runs=len({int(run_index[i]) for i in carrying}))
        if p_chi2 < CHI2_P:
            warnings.append(f"{eq}: reduced chi^2 {red:.3g} of the fit on {dof:g} dof, the "
                            "intervals widened by its square root (model error beyond the "
                            "runs' scatter)")
    by_run, agree, differ = frequency_agreement(
        runs, rows, X, run_index, keep, params, plane, length_m, chi2,
        {eq: c.to_numpy() for eq, c in param_cov.items()}, cov)
    warnings += differ
    order = [f"{eq}_{regs[k]}" for k in range(len(regs)) for eq in (eq_f, eq_m)]
    estimates = {s: estimates[s] for s in order if s in estimates}
    return CaptiveFit(plane=plane, rho=rho, length_m=length_m, draught_m=draught_m,
                      estimates=estimates, runs=runs, notes=tuple(agree),
                      warnings=tuple(warnings), by_run=by_run,
                      chi2_reduced=chi2, cov=param_cov, ref_x_m=ref_x_m)


def frequency_agreement(
    runs: Sequence[CaptiveRun], rows: pd.DataFrame, X: np.ndarray, run_index: np.ndarray,
    keep: list[int], params: dict[str, np.ndarray], plane: str, length_m: float,
    chi2_reduced: dict[str, float] | None = None, cov: dict[str, np.ndarray] | None = None,
    row_cov: np.ndarray | None = None,
) -> tuple[pd.DataFrame, list[str], list[str]]:
    """Whether the PMM runs' derivatives agree over omega' and amplitude.

    Per PMM run and derivative of :data:`AGREEMENT_REGRESSORS`: the derivative from the
    component row where its regressor is largest, the other terms held at the joint fit,
    its standard error the row's over the regressor — from the row's covariance of the load
    and the regressors (``row_cov``, rows x 10 x 10: the motion channels' noise enters the
    load through the inertia removed and the regressors together), else the load's alone —
    (widened as the joint fit's by the square root of its reduced chi^2 where that exceeds
    1) combined with that of the other
    terms held at the joint fit (``cov``, per equation, of the kept derivatives); then a
    homogeneity test across the runs (S = sum ((d_i - d_w)/u_i)^2, d_w the weighted mean,
    its p value that of :func:`chi2_p_value` for u_i from the runs' few cycles) and one
    sentence per derivative.
    """
    (eq_f, eq_m), regs = plane_names(plane)
    records = []
    component_rows = (rows["component"] != "mean").to_numpy()
    for k in (REGRESSORS.index(name) for name in AGREEMENT_REGRESSORS):
        if k not in keep:
            continue
        j = keep.index(k)
        col_max = float(np.max(np.abs(X[:, k])))
        for i, run in enumerate(runs):
            if run.test not in PMM_TESTS:
                continue
            idx = np.flatnonzero((run_index == i) & component_rows)
            if not idx.size:
                continue
            best = idx[np.argmax(np.abs(X[idx, k]))]
            xk = X[best, k]
            if abs(xk) < 0.05 * col_max:
                continue
            for e, eq in enumerate((eq_f, eq_m)):
                b = params[eq]
                widen = math.sqrt(max(1.0, (chi2_reduced or {}).get(eq, 1.0)))
                others = float(X[best, keep] @ b) - b[j] * xk
                x_o = np.where(np.arange(len(keep)) == j, 0.0, X[best, keep])
                var_o = float(x_o @ cov[eq] @ x_o) if cov and eq in cov else 0.0
                se_row = float(rows.at[best, f"{eq}_se"])
                if row_cov is not None and np.all(np.isfinite(row_cov[best])):
                    a = np.zeros(row_cov.shape[1])
                    a[e] = 1.0
                    a[[2 + kk for kk in keep]] = -b
                    se_row = math.sqrt(max(float(a @ row_cov[best] @ a), 0.0))
                records.append({
                    "run": run.run, "test": run.test,
                    "omega_prime": run.omega_prime(length_m), "amplitude_m": run.amplitude_m,
                    "symbol": f"{eq}_{regs[k]}",
                    "value": (float(rows.at[best, eq]) - others) / xk,
                    "std_error": math.sqrt((widen * se_row) ** 2 + var_o) / abs(xk)})
    by_run = pd.DataFrame(records, columns=list(BY_RUN_COLUMNS))
    cycles_dof = {run.run: float(run.cycles_used - 1) for run in runs}
    agree: list[str] = []
    differ: list[str] = []
    for sym, g in by_run.groupby("symbol", sort=False):
        g = g[np.isfinite(g["std_error"]) & (g["std_error"] > 0)]
        if len(g) < 2:
            continue
        w = 1.0 / g["std_error"].to_numpy() ** 2
        d = g["value"].to_numpy()
        mean = float(np.sum(w * d) / np.sum(w))
        stat = float(np.sum(w * (d - mean) ** 2))
        dof = len(g) - 1
        pval = chi2_p_value(stat, w / np.sum(w), np.array([cycles_dof[r] for r in g["run"]]))
        kinds = " and ".join(dict.fromkeys(TEST_NAMES[t].replace(" ", "-") for t in g["test"]))
        head = (f"{sym} from {len(g)} {kinds} runs, omega' {g['omega_prime'].min():.2g}–"
                f"{g['omega_prime'].max():.2g}, y0 {g['amplitude_m'].min():.2f}–"
                f"{g['amplitude_m'].max():.2f} m")
        test = f"chi^2 = {stat:.3g} on {dof} dof, p = {pval:.2g}"
        if pval >= AGREEMENT_P:
            agree.append(f"{head}: agree ({test})")
        else:
            differ.append(f"{head}: differ ({test}): the derivative depends on frequency or "
                         "amplitude; the joint value is an average over the runs")
    return by_run, agree, differ


def captive_runs_from_means(
    table: pd.DataFrame, *, balance_x_m: float, mass_kg: float = 0.0, xg_m: float = 0.0,
    plane: str = "horizontal", ref_x_m: float = 0.0,
) -> list[CaptiveRun]:
    """Static :class:`CaptiveRun` objects from a lab's table of means (FORMATS section 8).

    ``table`` has the canonical columns run, drift_deg, rudder_deg, radius_m, speed [m/s],
    fx, fy [N], mz [N m about ``balance_x_m``] (a table of primes is first turned into SI by
    :func:`towtank.ingest.captive_means.captive_means`). The moment is moved to the point
    x = ``ref_x_m`` [m] from O the derivatives refer to (0: O; ``[captive] moment_ref =
    "balance"``: the balance point, :func:`towtank.reduce.captive.reference_x`), and the
    velocities taken there; the inertia is already removed except the rotating arm's
    centripetal part, added here with ``mass_kg`` [kg] and ``xg_m`` [m] from O. A row with
    a finite non-zero radius is an arm run, with a rudder angle a rudder run, else a drift
    run; standard errors are NaN (the fit then works on primes).
    """
    # no r' in a static mean: the inertia about the CG does not enter
    inertia = Inertia(mass_kg, 0.0, xg_m, balance_x_m, ref_x_m)
    out: list[CaptiveRun] = []
    for rec in table.to_dict("records"):
        U = float(rec["speed"])
        beta = math.radians(float(rec.get("drift_deg", 0.0) or 0.0))
        delta_deg = float(rec.get("rudder_deg", 0.0) or 0.0)
        radius = float(rec.get("radius_m", math.nan))
        radius = math.nan if radius == 0.0 else radius
        fx, fy, mz = (float(rec[k]) for k in ("fx", "fy", "mz"))
        arm = math.isfinite(radius)
        kin = inertia.at_ref(arm_kinematics(np.array([U]), beta, radius) if arm
                             else body_kinematics(np.array([U]), np.array([beta])))
        X, Y, N = inertia.loads(np.array([fx]), np.array([fy]), np.array([mz]), kin)
        reg = make_regressors(kin, math.radians(delta_deg))
        row = {"component": "mean", "X": float(X[0]), "Y": float(Y[0]), "N": float(N[0]),
               "X_se": math.nan, "Y_se": math.nan, "N_se": math.nan,
               **{k: float(v[0]) for k, v in reg.items()}}
        test = "arm" if arm else ("rudder" if delta_deg != 0.0 else "drift")
        out.append(CaptiveRun(
            run=int(rec.get("run", len(out) + 1)), file="", test=test, plane=plane, speed=U,
            drift_deg=math.degrees(beta), rudder_deg=delta_deg, radius_m=radius,
            frequency_hz=math.nan, amplitude_m=math.nan, cycles_used=0,
            rows=pd.DataFrame([row], columns=list(ROW_COLUMNS)),
            cycles=pd.DataFrame(columns=list(CYCLE_COLUMNS)),
            period=pd.DataFrame(columns=list(PERIOD_COLUMNS))))
    return out


__all__ = ["COMPONENTS", "CaptiveEstimate", "CaptiveFit", "captive_runs_from_means",
           "fit_captive", "frequency_agreement", "mapped_rows"]
