"""The form factor's trend over Reynolds number: is one 1 + k an honest average?

The per-speed form factors of :func:`towtank.analysis.similarity.form_factor` are regressed on
Re by ordinary least squares; the slope's Student-t interval and p-value say whether 1 + k
changes with Re over the tested range (a Reynolds dependence, e.g. laminar flow over part of the
model at the lowest speeds), which the report then names (docs/method.md, "Similarity and
scaling").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike


@dataclass(frozen=True)
class FormFactorTrend:
    """Straight-line trend of the per-speed form factor against Reynolds number.

    Attributes
    ----------
    slope : float
        d(1 + k)/dRe of the least-squares line [-] (per unit Re); NaN with fewer than 3 speeds
    ci_low, ci_high : float
        Its interval at ``confidence`` (Student's t with ``dof``) [-]
    dof : int
        Residual degrees of freedom, number of tested speeds − 2
    p_value : float
        Two-sided p-value of the slope against 0 [-]
    significant : bool
        Whether the interval excludes 0: 1 + k changes with Re beyond its scatter
    confidence : float
        Confidence level of the interval [-]
    first, last : tuple of float
        (Re, 1 + k) of the lowest and of the highest tested speed [-]
    """

    slope: float
    ci_low: float
    ci_high: float
    dof: int
    p_value: float
    significant: bool
    confidence: float
    first: tuple[float, float]
    last: tuple[float, float]


def form_factor_trend(
    reynolds: ArrayLike, one_plus_k: ArrayLike, confidence: float = 0.95
) -> FormFactorTrend:
    """Test whether the form factor changes with Reynolds number.

    Ordinary least squares of ``(1 + k)_i = b0 + b1 Re_i`` over the tested speeds (one point
    per speed, as :func:`form_factor` averages them); the slope's interval is
    ``b1 ± t(confidence, n - 2) s / sqrt(sum (Re_i - mean Re)^2)`` with ``s^2`` the residual
    variance over ``n - 2`` degrees of freedom. A slope whose interval excludes 0 is a trend:
    the ITTC form factor is assumed independent of Re (ITTC 7.5-02-02-01), so a trend means
    Reynolds dependence (laminar flow over part of the model at the lowest speeds, or a
    turbulence stimulator's own drag), and the mean 1 + k is an average over it.

    Parameters
    ----------
    reynolds : array_like
        Reynolds number of each tested speed [-]
    one_plus_k : array_like
        Form factor ``1 + k`` at each tested speed [-]
    confidence : float, default 0.95
        Confidence level of the slope's interval [-]

    Returns
    -------
    FormFactorTrend
        With NaN slope and ``significant`` False for fewer than three speeds.

    Raises
    ------
    ValueError
        The arrays differ in length, or ``confidence`` is not in (0, 1).
    """
    # loaded on use: scipy.stats loads while the workers reduce the runs (pipeline preload)
    from scipy import stats

    x = np.atleast_1d(np.asarray(reynolds, dtype=float)).ravel()
    y = np.atleast_1d(np.asarray(one_plus_k, dtype=float)).ravel()
    if x.shape != y.shape:
        raise ValueError(f"reynolds and one_plus_k differ in length ({x.size} and {y.size}).")
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must lie in (0, 1), not {confidence}.")
    keep = np.isfinite(x) & np.isfinite(y)
    x, y = x[keep], y[keep]
    order = np.argsort(x, kind="stable")
    x, y = x[order], y[order]
    n = int(x.size)
    ends = ((float(x[0]), float(y[0])), (float(x[-1]), float(y[-1]))) if n else (
        (math.nan, math.nan), (math.nan, math.nan))
    sxx = float(np.sum((x - x.mean()) ** 2)) if n else 0.0
    if n < 3 or sxx <= 0.0:
        return FormFactorTrend(math.nan, math.nan, math.nan, max(n - 2, 0), math.nan, False,
                               confidence, *ends)
    slope = float(np.sum((x - x.mean()) * (y - y.mean())) / sxx)
    resid = y - (y.mean() + slope * (x - x.mean()))
    dof = n - 2
    se = math.sqrt(float(np.sum(resid**2)) / dof / sxx)
    half = float(stats.t.ppf(0.5 + confidence / 2.0, dof)) * se
    if se > 0.0:
        p_value = float(2.0 * stats.t.sf(abs(slope) / se, dof))
    else:
        p_value = 0.0 if slope != 0.0 else 1.0
    lo, hi = slope - half, slope + half
    return FormFactorTrend(slope, lo, hi, dof, p_value, bool(lo > 0.0 or hi < 0.0),
                           confidence, *ends)


def form_factor_trend_statement(trend: FormFactorTrend, one_plus_k: float) -> str:
    """One or two sentences on the form factor's trend with Reynolds number, for the report.

    Parameters
    ----------
    trend : FormFactorTrend
        From :func:`form_factor_trend`
    one_plus_k : float
        The single form factor used (the mean over the tested speeds) [-]

    Returns
    -------
    str
        Empty when fewer than three speeds allow no test.
    """
    if not math.isfinite(trend.slope):
        return ""
    per = 1e5
    ci = (f"slope {trend.slope * per:+.3g} per 10⁵ of Re [{trend.ci_low * per:+.3g}, "
          f"{trend.ci_high * per:+.3g}] ({100 * trend.confidence:g} %)")
    (re0, k0), (re1, k1) = trend.first, trend.last
    if not trend.significant:
        return (f"1 + k shows no significant trend with Re ({ci}, including 0): its spread "
                f"over the tested speeds is scatter; the mean {one_plus_k:.3f} is used.")
    if trend.slope > 0:
        head, why = "rises", "e.g. laminar flow over part of the model at the lowest speeds"
    else:
        head, why = "falls", "e.g. a turbulence stimulator's own drag at the lowest speeds"
    change = 100.0 * (k1 / one_plus_k - 1.0)
    return (f"1 + k {head} with Re from {k0:.3f} (Re = {re0:.3g}) to {k1:.3f} "
            f"({re1:.3g}), {ci}: Reynolds dependence, {why}; a single form factor is an "
            f"average. Used: the mean {one_plus_k:.3f}; the value at the highest tested Re, "
            f"{k1:.3f}, would make (1 + k)·C_F {abs(change):.1f}\u00a0% "
            f"{'larger' if change > 0 else 'smaller'}.")
