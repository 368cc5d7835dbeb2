"""Sting tare (report §4: "test the rod without the model and subtract"; docs/method.md,
"Sting tare").

Runs with config = sting measure the mounting alone. Per tare group and per force channel,
F_tare(U, a) = t2·U|U| + t1·U + m_t·a is fitted by least squares over the sting runs' steady and
constant-acceleration samples, and subtracted sample by sample from the model runs of that
group. A model run whose speeds lie outside the tare runs' speed range is flagged.

The fit's covariance is clustered by run (:func:`towtank.stats.intervals.cr2_covariance`): the
samples of one sting run share its zero and noise, and an error of the tare is common to every
model run of the group, so it is propagated into their coefficients (an error of m_t goes
one-for-one into X_udot) and must not be understated. Treating the samples as independent
understates the standard error of m_t by a factor of about 1.8 on a synthetic day.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from towtank.stats.intervals import cr2_covariance
from towtank.stats.quantiles import t95

TARE_TERMS = ("t2", "t1", "m_t")


def tare_design(speed: np.ndarray, accel: np.ndarray) -> np.ndarray:
    """Regressors of the tare model, columns [U|U|, U, a].

    Parameters
    ----------
    speed : ndarray
        Carriage speed U [m/s].
    accel : ndarray
        Carriage acceleration a [m/s²].
    """
    speed = np.asarray(speed, dtype=float)
    return np.column_stack([speed * np.abs(speed), speed, np.asarray(accel, dtype=float)])


def tare_force(coef: np.ndarray, speed: np.ndarray, accel: np.ndarray) -> np.ndarray:
    """F_tare = t2·U|U| + t1·U + m_t·a [N].

    Parameters
    ----------
    coef : ndarray
        (t2 [N s²/m²], t1 [N s/m], m_t [kg]).
    speed : ndarray
        U [m/s].
    accel : ndarray
        a [m/s²].
    """
    return tare_design(speed, accel) @ np.asarray(coef, dtype=float)


@dataclass(frozen=True)
class TareFit:
    """Tare of one force channel of one tare group."""

    coef: np.ndarray  # t2 [N s²/m²], t1 [N s/m], m_t [kg]
    cov: np.ndarray  # covariance of coef
    residual_std: float  # [N]
    n_samples: int
    dof: float = math.inf  # degrees of freedom of cov (Student's t)

    def __call__(self, speed: np.ndarray, accel: np.ndarray) -> np.ndarray:
        return tare_force(self.coef, speed, accel)

    @property
    def std_errors(self) -> np.ndarray:
        """Standard errors of t2, t1, m_t [N s²/m², N s/m, kg]."""
        return np.sqrt(np.clip(np.diag(self.cov), 0.0, None))

    @property
    def interval_dof(self) -> float:
        """Degrees of freedom of the coefficients' intervals: ``dof``, or ∞ (a normal
        interval) when it is not a positive number [-]."""
        return self.dof if math.isfinite(self.dof) and self.dof > 0 else math.inf

    def std_error(self, speed: np.ndarray, accel: np.ndarray) -> np.ndarray:
        """Standard error of the fitted tare at (U, a) [N]."""
        x = tare_design(speed, accel)
        return np.sqrt(np.einsum("ij,jk,ik->i", x, self.cov, x))


@dataclass(frozen=True)
class TareModel:
    """The tare of one group: a fit per force channel and the range it was fitted over."""

    group: str
    runs: tuple[int, ...]
    drag: TareFit
    lift: TareFit | None
    speed_range: tuple[float, float]  # steady speeds of the tare runs [m/s]
    accel_range: tuple[float, float]  # accelerations covered [m/s²]

    def covers(self, speed: float, *, rel: float = 0.05, abs_tol: float = 0.02) -> bool:
        """Is a model-run speed inside the tare runs' range (with a small margin)?"""
        lo, hi = self.speed_range
        return lo - max(rel * lo, abs_tol) <= speed <= hi + max(rel * hi, abs_tol)


def fit_channel(
    speed: np.ndarray,
    accel: np.ndarray,
    force: np.ndarray,
    groups: np.ndarray | None = None,
) -> TareFit:
    """Least-squares fit of F = t2·U|U| + t1·U + m_t·a.

    Parameters
    ----------
    speed : ndarray
        U [m/s] of the samples.
    accel : ndarray
        a [m/s²] of the samples.
    force : ndarray
        Zeroed, filtered force of the sting runs [N].
    groups : ndarray, optional
        Sting run of each sample. With four or more runs the covariance is clustered by run
        (CR2, t with runs − 1 degrees of freedom; :func:`towtank.stats.intervals.cr2_covariance`);
        otherwise, or without groups, it assumes independent samples (n − p degrees of
        freedom), which understates it.
    """
    x = tare_design(speed, accel)
    y = np.asarray(force, dtype=float)
    ok = np.isfinite(y) & np.isfinite(x).all(axis=1)
    x, y = x[ok], y[ok]
    g = None if groups is None else np.asarray(groups)[ok]
    # a tare group without accelerated samples cannot resolve m_t: fit t2, t1 only
    active = np.array([True, True, np.ptp(x[:, 2]) > 1e-3 if len(x) else False])
    coef = np.zeros(3)
    cov = np.zeros((3, 3))
    xa = x[:, active]
    beta, *_ = np.linalg.lstsq(xa, y, rcond=None)
    resid = y - xa @ beta
    dof: float = max(len(y) - int(active.sum()), 1)
    s2 = float(resid @ resid) / dof
    if g is not None and np.unique(g).size >= 4:
        cov_a, dof = cr2_covariance(xa, resid, g)
    else:
        cov_a = s2 * np.linalg.pinv(xa.T @ xa)
    coef[active] = beta
    cov[np.ix_(active, active)] = cov_a
    return TareFit(coef=coef, cov=cov, residual_std=float(np.sqrt(s2)), n_samples=int(len(y)),
                   dof=float(dof))


def fit_tare_group(
    group: str,
    runs: Sequence[int],
    speed: np.ndarray,
    accel: np.ndarray,
    drag: np.ndarray,
    lift: np.ndarray | None,
    steady_speeds: Sequence[float],
    sample_runs: np.ndarray | None = None,
) -> TareModel:
    """Fit the tare of one group from its sting runs' pooled samples.

    Parameters
    ----------
    group : str
        Tare group name.
    runs : sequence of int
        The sting runs pooled.
    speed, accel : ndarray
        Pooled sample speed [m/s] and acceleration [m/s²].
    drag, lift : ndarray
        Pooled zeroed, filtered forces [N]; lift may be None.
    steady_speeds : sequence of float
        Plateau speed of each sting run [m/s], for the covered range.
    sample_runs : ndarray, optional
        Run number of each pooled sample: the covariance is then clustered by run.
    """
    drag_fit = fit_channel(speed, accel, drag, sample_runs)
    lift_fit = None
    if lift is not None and np.isfinite(lift).sum() > 3:
        lift_fit = fit_channel(speed, accel, lift, sample_runs)
    acc = np.asarray(accel, dtype=float)
    return TareModel(
        group=group,
        runs=tuple(int(r) for r in runs),
        drag=drag_fit,
        lift=lift_fit,
        speed_range=(float(min(steady_speeds)), float(max(steady_speeds))),
        accel_range=(float(np.min(acc)), float(np.max(acc))) if acc.size else (0.0, 0.0),
    )


def table_tare(
    group: str,
    speeds: Sequence[float],
    drag: Sequence[float],
    lift: Sequence[float] | None = None,
) -> tuple[TareModel, float]:
    """The tare of a group from a tare table measured once (``[tare] source = "table"``).

    The table's points (U [m/s], F_tare [N]) are fitted with the sting tare's own form
    F = t2·U|U| + t1·U by least squares; a table holds no acceleration, so m_t = 0 (the
    accelerated runs then carry the mounting's mass in their added mass: weigh it into
    ``mass_kg`` or use sting runs). The table's uncertainty is not known to towtank: the fit's
    covariance is zero, and the intervals hold the regression's and the mass's parts only.

    Returns
    -------
    (TareModel, float)
        The model (speed range = the table's) and the largest departure of the table from the
        fitted form [N], which the day reports when it matters.
    """
    u = np.asarray(speeds, dtype=float)
    x = tare_design(u, np.zeros_like(u))[:, :2]

    def fit(force: Sequence[float]) -> tuple[TareFit, float]:
        y = np.asarray(force, dtype=float)
        beta, *_ = np.linalg.lstsq(x, y, rcond=None)
        resid = y - x @ beta
        coef = np.array([beta[0], beta[1], 0.0])
        return (TareFit(coef=coef, cov=np.zeros((3, 3)), residual_std=float(np.std(resid)),
                        n_samples=int(u.size), dof=math.inf), float(np.max(np.abs(resid))))

    drag_fit, departure = fit(drag)
    lift_fit = None
    if lift is not None and len(lift):
        lift_fit, dep_l = fit(lift)
        departure = max(departure, dep_l)
    model = TareModel(group=group, runs=(), drag=drag_fit, lift=lift_fit,
                      speed_range=(float(u.min()), float(u.max())), accel_range=(0.0, 0.0))
    return model, departure


#: Columns of :func:`tare_table` (tare.csv), units in docs/formats.md §5.
TARE_COLUMNS = (
    "tare_group", "channel", "runs", "t2", "t2_ci_low", "t2_ci_high", "t1", "t1_ci_low",
    "t1_ci_high", "m_t", "m_t_ci_low", "m_t_ci_high", "residual_std", "n_samples", "dof",
    "speed_min", "speed_max", "accel_min", "accel_max",
)


def tare_table(tares: dict[str, TareModel]) -> Any:
    """The tare fits of a day, one row per tare group and force channel.

    Each fit is the sting's tare force T = t2·U|U| + t1·U + m_t·a (docs/method.md, "Sting
    tare"): t2 [N s²/m²], t1 [N s/m] and m_t [kg] with their 95 % intervals (Student's t at
    the fit's degrees of freedom, its covariance clustered by sting run), the residual
    standard deviation [N], the samples and runs it was fitted on, and the steady speeds [m/s]
    and accelerations [m/s²] it covers.
    """
    # loaded on use: pandas for the tare table only: the reduction's workers never
    # load it
    import pandas as pd

    rows = []
    for group in sorted(tares):
        model = tares[group]
        for channel, fit in (("drag", model.drag), ("lift", model.lift)):
            if fit is None:
                continue
            q, se = t95(fit.interval_dof), fit.std_errors
            row: dict[str, object] = {"tare_group": group, "channel": channel,
                                      "runs": " ".join(str(r) for r in model.runs)}
            for name, value, s in zip(("t2", "t1", "m_t"), fit.coef, se, strict=True):
                row[name] = float(value)
                row[f"{name}_ci_low"] = float(value - q * s)
                row[f"{name}_ci_high"] = float(value + q * s)
            row.update(residual_std=float(fit.residual_std), n_samples=int(fit.n_samples),
                       dof=float(fit.dof), speed_min=float(model.speed_range[0]),
                       speed_max=float(model.speed_range[1]),
                       accel_min=float(model.accel_range[0]),
                       accel_max=float(model.accel_range[1]))
            rows.append(row)
    return pd.DataFrame(rows, columns=list(TARE_COLUMNS))
