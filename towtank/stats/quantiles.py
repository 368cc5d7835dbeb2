"""Coverage factors of two-sided intervals: the one home of the normal and Student's t quantiles.

A two-sided interval of level 1 − α around an estimate x with standard uncertainty u is
x ± k·u, k = t₁₋α/₂(ν) for ν degrees of freedom (GUM, JCGM 100:2008, G.3.2), and
k = z₁₋α/₂, the standard normal quantile, for ν = ∞ (a stated uncertainty).
"""

from __future__ import annotations

import math

#: The default significance level of every interval: 95 % intervals [-].
ALPHA = 0.05


def _check_alpha(alpha: float) -> float:
    if not 0.0 < alpha < 1.0:
        raise ValueError(f"alpha must lie strictly between 0 and 1, not {alpha!r}")
    return float(alpha)


def normal_quantile(alpha: float = ALPHA) -> float:
    """z₁₋α/₂: the standard normal quantile of a two-sided interval of level 1 − ``alpha``.

    Parameters
    ----------
    alpha : float, default 0.05
        Significance level [-]; 0.05 gives z = 1.95996...

    Returns
    -------
    float
        The coverage factor [-].
    """
    # loaded on use: scipy.stats only when an interval is
    # computed; modules that `towtank inspect` loads import this one
    from scipy.stats import norm

    return float(norm.ppf(1.0 - _check_alpha(alpha) / 2.0))


def t_quantile(dof: float, alpha: float = ALPHA) -> float:
    """t₁₋α/₂(ν): Student's t coverage factor of a two-sided interval of level 1 − ``alpha``.

    Parameters
    ----------
    dof : float
        Degrees of freedom ν [-]; ∞ gives the normal quantile, ν ≤ 0 or NaN (no freedom left)
        an infinite factor.
    alpha : float, default 0.05
        Significance level [-].

    Returns
    -------
    float
        The coverage factor [-] (GUM G.3.2).
    """
    # loaded on use: scipy.stats, as above
    from scipy.stats import t

    a = _check_alpha(alpha)
    if not dof > 0:  # NaN too
        return math.inf
    if math.isinf(dof):
        return normal_quantile(a)
    return float(t.ppf(1.0 - a / 2.0, dof))


def t95(dof: float) -> float:
    """t₀.₉₇₅(ν), the coverage factor of a 95 % interval (:func:`t_quantile` with α = 0.05)."""
    return t_quantile(dof, ALPHA)


def interval(value: float, std_error: float, dof: float, alpha: float = ALPHA
             ) -> tuple[float, float]:
    """(lower, upper) = value ∓ t₁₋α/₂(ν)·u; a zero-width interval where u = 0 (an exact fit).

    Parameters
    ----------
    value : float
        The estimate, in its unit.
    std_error : float
        Its standard uncertainty u, in the same unit.
    dof : float
        Degrees of freedom ν of u [-] (∞ for a normal interval).
    alpha : float, default 0.05
        Significance level [-].
    """
    half = t_quantile(dof, alpha) * std_error if std_error > 0 else 0.0
    return value - half, value + half
