"""Is the balance drift between the still windows a drift, or a wake still on the balance?

docs/method.md "A run": the zero is interpolated linearly between the still window before the
carriage moves and the one after it stops, once the balance has settled. A linear drift of a
few mN is common and is removed; a "drift" of the size of the signal is a wake or ringing still
on the balance after the stop, never a drift to subtract. :func:`drift_verdict` tells them apart
from the run's own filtered force:

- the drift (post-window zero − pre-window zero) against the run's steady force (the larger
  of its steady drag and lift): above :data:`DRIFT_WARN_FRACTION` of it, and above
  :data:`DRIFT_FLOOR_N`, the engineer is warned, naming the drift;
- whether the balance is still moving in the post-run window: the means of the window's two
  halves differ by more than a straight drift explains (:data:`SETTLE_SIGMAS` times the
  filtered noise, at least :data:`SETTLE_FRACTION` of the steady force). Unsettled with a
  drift above :data:`DRIFT_REJECT_FRACTION` of the steady force, the run is rejected ("the
  balance had not settled after the stop"); unsettled with a smaller drift, it is a warning.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from towtank.errors import RunError

#: A drift above this fraction of the run's steady force is a warning naming it [-].
DRIFT_WARN_FRACTION = 0.10
#: A drift above this fraction of the steady force, with the balance still moving after the
#: stop, rejects the run [-].
DRIFT_REJECT_FRACTION = 0.25
#: The post-run window counts as still moving when its two halves' means differ, beyond the
#: straight drift, by more than this many standard deviations of the filtered force's noise...
SETTLE_SIGMAS = 4.0
#: ... and by more than this fraction of the run's steady force [-].
SETTLE_FRACTION = 0.005
#: Forces below this are treated as this when taking fractions of the steady force [N].
FORCE_FLOOR_N = 0.005
#: A drift below this is never worth a warning: a few mN over a run are common [N].
DRIFT_FLOOR_N = 0.01


@dataclass(frozen=True)
class DriftVerdict:
    """The drift of one force channel between its still windows."""

    drift: float  # post − pre zero [N]
    fraction: float  # |drift| / |steady force| [-]
    unsettled: float  # change across the post window beyond the straight drift [N]
    settled: bool
    warning: str | None
    reject: str | None


def _trend_residual_std(x: np.ndarray) -> float:
    """Standard deviation of ``x`` about its least-squares line (the noise) [unit of x]."""
    if x.size < 4:
        return 0.0
    k = np.arange(x.size, dtype=float)
    coef = np.polyfit(k, x, 1)
    return float(np.std(x - np.polyval(coef, k)))


def drift_verdict(
    t: np.ndarray,
    force_f: np.ndarray,
    pre: tuple[int, int] | None,
    post: tuple[int, int],
    steady_force: float,
    channel: str = "drag",
    level: float | None = None,
) -> DriftVerdict:
    """Judge the drift of a filtered, not yet zeroed force between two still windows.

    Parameters
    ----------
    t : ndarray
        Time [s].
    force_f : ndarray
        Low-pass filtered force, zero not removed [N].
    pre, post : tuple of int
        Index windows [i0, i1) of the still windows before and after the run; ``pre`` None for
        a run that starts in motion with ``level`` given (its zero then holds at the file's
        start, and the noise is measured on the post window).
    steady_force : float
        The run's steady force with the pre-run zero removed, the larger of its drag and lift
        [N].
    channel : str
        The channel's name, for the sentences.
    level : float, optional
        The pre-run zero measured apart (a zeros file) [N], in place of the pre window's mean.

    Returns
    -------
    DriftVerdict
    """
    b = force_f[post[0] : post[1]]
    a = b if pre is None else force_f[pre[0] : pre[1]]
    if pre is None and level is None:
        raise ValueError("drift_verdict needs the pre-run window or a level")
    z0 = float(np.mean(a)) if level is None else float(level)
    z1 = float(np.mean(b))
    drift = z1 - z0
    t0 = float(t[0]) if pre is None else float(np.mean(t[pre[0] : pre[1]]))
    t1 = float(np.mean(t[post[0] : post[1]]))
    rate = drift / (t1 - t0) if t1 > t0 else 0.0
    half = b.size // 2
    tb = t[post[0] : post[1]]
    change = float(np.mean(b[half:]) - np.mean(b[:half])) if half >= 2 else 0.0
    expected = rate * float(np.mean(tb[half:]) - np.mean(tb[:half])) if half >= 2 else 0.0
    unsettled = abs(change - expected)
    scale = max(abs(steady_force), FORCE_FLOOR_N)
    noise = _trend_residual_std(a)
    settled = unsettled <= max(SETTLE_SIGMAS * noise, SETTLE_FRACTION * scale)
    fraction = abs(drift) / scale
    warning = reject = None
    what = (f"the {channel} zero moved by {1000 * drift:+.1f} mN between the still windows "
            f"before and after the run ({100 * fraction:.0f} % of the run's steady force "
            f"{abs(steady_force):.4g} N)")
    big = abs(drift) > DRIFT_FLOOR_N
    if not settled and big and fraction > DRIFT_REJECT_FRACTION:
        reject = (f"the balance had not settled after the stop: {what}, and the {channel} is "
                  f"still changing by {1000 * unsettled:.1f} mN across the post-run window "
                  "(a wake or ringing, not a drift to subtract; raise [processing] "
                  "drift_settle_s, or set drift = \"none\")")
    elif not settled and big:
        warning = (f"the {channel} is still changing by {1000 * unsettled:.1f} mN across the "
                   f"post-run still window ({what}): the balance may not have settled after "
                   "the stop (see [processing] drift_settle_s)")
    elif big and fraction > DRIFT_WARN_FRACTION:
        warning = f"{what}: a large balance drift, removed linearly; check the balance"
    return DriftVerdict(drift, fraction, unsettled, settled, warning, reject)


def check_drift(t: np.ndarray, force: np.ndarray, pre: tuple[int, int] | None,
                 post: tuple[int, int], steady_force: float, name: str, level: float | None,
                 notes: list[str], warnings: list[str]) -> None:
    """The drift check of one force channel (:func:`drift_verdict`): a reject raises RunError,
    a warning is added to the run's ``notes`` and ``warnings``."""
    verdict = drift_verdict(t, force, pre, post, steady_force, name, level=level)
    if verdict.reject is not None:
        raise RunError(verdict.reject)
    if verdict.warning is not None:
        notes.append(verdict.warning)
        warnings.append(verdict.warning)
