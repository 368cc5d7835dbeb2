"""Robust order statistics on sample arrays, shared by the reading checks and the phases.

Order statistics rather than interpolated percentiles: one ``np.partition`` each, no sorting,
which matters when every run of a campaign asks for a dozen of them. The thresholds they feed
are fractions of peaks and multiples of noise levels, for which the interpolation between two
neighbouring samples is immaterial.
"""

from __future__ import annotations

import numpy as np

#: 1/Φ⁻¹(0.75): a normal distribution's standard deviation over its median absolute deviation.
MAD_TO_SD = 1.4826
#: Φ⁻¹(0.95): the 90th percentile of |x − median| of a normal distribution, in standard deviations.
Q90_ABS_TO_SD = 1.6449


#: Values a robust statistic of a channel is taken from (see :func:`blocks`): the standard error
#: of a MAD from 2048 normal values is about 2.5 %, far below what the thresholds need.
STAT_SAMPLES = 2048


def blocks(x: np.ndarray, size: int = STAT_SAMPLES, n_blocks: int = 8) -> np.ndarray:
    """At most ``size`` values of ``x`` for a statistic: contiguous blocks spread over it.

    Blocks rather than every k-th value, so that a periodic disturbance (mains hum) is seen at
    all its phases.
    """
    if x.size <= size:
        return x
    block = size // n_blocks
    starts = np.arange(n_blocks) * (x.size - block) // (n_blocks - 1)
    return x[(starts[:, None] + np.arange(block)[None, :]).ravel()]


def quantiles(x: np.ndarray, qs: tuple[float, ...]) -> np.ndarray:
    """Order statistics of ``x`` at fractions ``qs`` (one partition, no interpolation).

    The value of rank ⌊q·n⌋ (0-based, at most n − 1) for each q; ``x`` must not be empty.
    """
    k = [min(x.size - 1, int(q * x.size)) for q in qs]
    return np.partition(x, k)[k]


def quantile(x: np.ndarray, q: float) -> float:
    """One order statistic of ``x`` (see :func:`quantiles`)."""
    return float(quantiles(x, (q,))[0])


def spread_sample(x: np.ndarray, size: int = 2 * STAT_SAMPLES) -> np.ndarray:
    """At most about ``size`` values of ``x``, every k-th: for a quantile of a smooth signal.

    Unlike :func:`blocks`, every stretch of the signal longer than k samples is represented, so
    a short plateau still sets a high percentile; for a low-passed signal (k well below the
    filter's time constant in samples) the quantiles are those of all the samples.
    """
    step = max(1, x.size // size)
    return x[::step]


def robust_scale(r: np.ndarray, floor: float, *, centred: bool = False) -> float:
    """A standard deviation of ``r`` that ignores outliers and survives quantised values.

    1.4826·MAD collapses when most values are tied (a quantised channel: half the residuals are
    exactly 0), so the 90th percentile of |r − median|/1.645 is taken too, and the larger wins;
    never below ``floor`` [unit of r]. ``centred`` says that ``r`` scatters about 0 by
    construction (second differences, residuals), so that |r| replaces |r − median| and one
    order statistic is saved.
    """
    if r.size == 0:
        return floor
    c = np.abs(r) if centred else np.abs(r - quantile(r, 0.5))
    q50, q90 = quantiles(c, (0.5, 0.9))
    return float(max(MAD_TO_SD * q50, q90 / Q90_ABS_TO_SD, floor))
