"""Automatic phase detection from the carriage speed (report Fig. 2; docs/method.md "A run").

A run is: still water (zero window) → acceleration → speed settling → steady measurement zone →
deceleration → stop. The phases are found from the filtered speed and its derivative alone, so
they do not depend on the set values in the sheet (those only cross-check). Thresholds scale
with the run's own peak speed and acceleration, which keeps the detection robust from 0.1 m/s
transverse tows to 3 m/s; every window is trimmed away from its transitions.

All functions are vectorised over the samples (no per-sample Python loop); levels and peaks
are order statistics (:mod:`towtank.stats.robust`): the median, the 99th percentile sample.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from towtank.errors import RunError
from towtank.signal.masks import close_gaps, longest_run
from towtank.stats.robust import quantile, spread_sample

PHASE_NAMES = ("still_pre", "accel", "steady", "decel", "still_post")


@dataclass(frozen=True)
class Phases:
    """Index windows [i0, i1) of a run's phases; ``None`` where a phase is absent (``still_pre``
    only when the zero does not need it: a run that starts in motion)."""

    still_pre: tuple[int, int] | None
    accel: tuple[int, int] | None
    steady: tuple[int, int] | None  # None only when detected with steady_required=False
    decel: tuple[int, int] | None
    still_post: tuple[int, int] | None
    motion: tuple[int, int]
    speed_level: float
    accel_level: float | None

    def windows_s(self, t: np.ndarray) -> dict[str, tuple[float, float] | None]:
        """The phase windows in seconds."""
        out: dict[str, tuple[float, float] | None] = {}
        for name in PHASE_NAMES:
            w = getattr(self, name)
            out[name] = None if w is None else (float(t[w[0]]), float(t[w[1] - 1]))
        return out


def _trim(window: tuple[int, int] | None, n_trim: int, min_len: int) -> tuple[int, int] | None:
    if window is None:
        return None
    i0, i1 = window[0] + n_trim, window[1] - n_trim
    return (i0, i1) if i1 - i0 >= max(min_len, 2) else None


def detect_phases(
    t: np.ndarray,
    speed: np.ndarray,
    accel: np.ndarray,
    fs: float,
    *,
    trim_s: float = 0.375,
    min_steady_s: float = 0.5,
    min_accel_s: float = 0.3,
    min_still_s: float = 0.3,
    zero_window_s: float = 2.0,
    steady_tolerance: float = 0.01,
    steady_required: bool = True,
    zero_at: str = "before_motion",
    drift_settle_s: float = 0.0,
    still_required: bool = True,
) -> Phases:
    """Split a run into its phases from the filtered speed.

    Parameters
    ----------
    t : ndarray
        Time [s].
    speed : ndarray
        Low-pass filtered carriage speed [m/s].
    accel : ndarray
        Acceleration from the filtered speed [m/s²].
    fs : float
        Sample rate [Hz].
    trim_s : float
        Cut from each end of the acceleration and steady windows [s] (filter settling).
    min_steady_s, min_accel_s : float
        Shortest usable steady and constant-acceleration windows after trimming [s]. A run
        without a steady window is rejected; a too short acceleration window is dropped.
    min_still_s : float
        Shortest still window before the carriage moves [s]; without it there is no zero.
    zero_window_s : float
        Longest still window used for the zero (the part nearest the motion) [s].
    steady_tolerance : float
        Half-width of the plateau band as a fraction of the plateau speed [-].
    zero_at : {"before_motion", "file_start"}
        Where the zero window lies: the last ``zero_window_s`` before the carriage moves, or
        the first ``zero_window_s`` of the file (a model active in still water); either way it
        starts no earlier than ``trim_s`` after the file's start (filter start-up).
    drift_settle_s : float
        Time after the carriage stops before the post-run still window starts [s] (at least
        the trim margin), so that the balance has settled there.
    steady_required : bool, default True
        False when the steady window is set by hand in the run sheet: a run whose plateau is
        not found (too short, too unsteady) then still gets its still, acceleration and
        deceleration windows, with ``steady`` None, split at the peak speed.
    still_required : bool, default True
        False when the zero does not come from the still window before the carriage moves (a
        zeros file, or ``zero_at = "file_start"``): a run that starts in motion, or with a still
        stretch shorter than ``min_still_s``, then gets ``still_pre`` None and its phases start
        with the acceleration or the steady speed.

    Returns
    -------
    Phases

    Raises
    ------
    RunError
        The carriage never moves, there is no still window before it moves (with
        ``still_required``), or (with ``steady_required``) the speed never settles on a
        plateau.
    """
    n = speed.size
    # peaks held for a stated time, not percentiles of the file: independent of the run's length
    v_peak = sustained_peak(speed, max(3, int(0.5 * min_steady_s * fs)))
    if not v_peak > 0.02:
        v_low = -sustained_peak(-speed, max(3, int(0.5 * min_steady_s * fs)))
        if v_low < -0.02:  # it moves, but backwards: a towing carriage tows forwards
            raise RunError(
                f"the carriage speed is negative (down to {v_low:.3f} m/s): is the speed "
                "channel's sign or gain wrong (a negative gain in [channels] speed)?")
        raise RunError(f"the carriage never moves (peak speed {v_peak:.3f} m/s)")
    a_abs_peak = sustained_peak(np.abs(accel), max(3, int(0.5 * min_accel_s * fs)))
    # --- motion: where speed or acceleration rises above small fractions of their peaks
    moving = (speed > 0.03 * v_peak) | (np.abs(accel) > 0.1 * a_abs_peak)
    moving = close_gaps(moving, int(0.5 * fs))
    motion = longest_run(moving)
    assert motion is not None
    margin = int(round((trim_s + 0.1) * fs))
    pre_end = motion[0] - margin
    pre: tuple[int, int] | None
    # the zero window keeps clear of the file's start by the trim, where the filter starts up
    # (the mirrored padding turns mains hum into a transient there: up to 0.2 mN in a 2 s
    # window at the start from 0.05 N of 50 Hz hum), unless that leaves less than min_still_s
    lo = min(int(round(trim_s * fs)), max(0, pre_end - max(int(min_still_s * fs), 2)))
    if pre_end < int(min_still_s * fs):
        if still_required:
            raise RunError(
                f"there is no still window before the carriage moves (motion starts at "
                f"t = {t[motion[0]]:.2f} s): the zero cannot be found (a run that starts in "
                "motion needs its zero from a zeros file, [zeros], or zero_at = "
                "\"file_start\" with the still window after the stop)"
            )
        pre = None
    elif zero_at == "file_start":
        pre = (lo, min(pre_end, lo + max(int(zero_window_s * fs), 2)))
    else:
        pre = (max(lo, pre_end - int(zero_window_s * fs)), pre_end)
    post_start = motion[1] + max(margin, int(round(drift_settle_s * fs)))
    # the post window keeps clear of the file's end by the trim, where the filter starts up
    post = (post_start, min(n - int(round(trim_s * fs)), post_start + int(zero_window_s * fs)))
    still_post = post if post[1] - post[0] >= int(min_still_s * fs) else None

    # --- steady plateau: speed within a narrow band of the level where acceleration is ~0
    try:
        plateau, level, steady = _plateau(
            speed, accel, motion, fs, v_peak, a_abs_peak, trim_s=trim_s,
            min_steady_s=min_steady_s, steady_tolerance=steady_tolerance,
        )
    except RunError:
        if steady_required:
            raise
        peak = motion[0] + int(np.argmax(speed[motion[0] : motion[1]]))
        plateau, level, steady = (peak, peak), float(speed[peak]), None
    n_trim = int(round(trim_s * fs))

    # --- constant acceleration between motion start and plateau; deceleration after it
    noise_a = accel_noise(accel, steady if steady is not None else plateau)
    accel_w, accel_level = _constant_stretch(accel, motion[0], plateau[0], +1, fs, noise_a)
    accel_w = _trim(accel_w, n_trim, int(min_accel_s * fs))
    decel_w, _ = _constant_stretch(accel, plateau[1], motion[1], -1, fs, noise_a)
    decel_w = _trim(decel_w, n_trim, int(min_accel_s * fs))
    if accel_w is not None:
        accel_level = float(np.mean(accel[accel_w[0] : accel_w[1]]))
    else:
        accel_level = None
    return Phases(
        still_pre=pre,
        accel=accel_w,
        steady=steady,
        decel=decel_w,
        still_post=still_post,
        motion=motion,
        speed_level=level,
        accel_level=accel_level,
    )


def _plateau(
    speed: np.ndarray,
    accel: np.ndarray,
    motion: tuple[int, int],
    fs: float,
    v_peak: float,
    a_abs_peak: float,
    *,
    trim_s: float,
    min_steady_s: float,
    steady_tolerance: float,
) -> tuple[tuple[int, int], float, tuple[int, int]]:
    """(plateau, its median speed [m/s], the trimmed steady window) inside ``motion``.

    The plateau is the longest stretch within ``steady_tolerance`` of the level of the fast,
    calm samples (speed above half the peak, acceleration near zero).
    """
    seg = slice(motion[0], motion[1])
    v_seg, a_seg = speed[seg], accel[seg]
    fast = v_seg > 0.5 * v_peak
    calm = np.abs(a_seg) < max(0.05 * a_abs_peak, 0.002)
    cand = fast & calm
    if cand.sum() < 3:
        raise RunError(
            f"the carriage speed never settles on a plateau (peak {v_peak:.3f} m/s, "
            "no stretch of constant speed)"
        )
    level = quantile(v_seg[cand], 0.5)
    tol = max(steady_tolerance * level, 0.002)
    band = close_gaps(np.abs(v_seg - level) <= tol, int(0.05 * fs))
    plateau = longest_run(band)
    if plateau is None:  # the calm samples are spread over speeds far apart: no single level
        raise RunError(
            f"the carriage speed never settles on a plateau (peak {v_peak:.3f} m/s, no "
            f"stretch within {100 * steady_tolerance:g} % of one speed)"
        )
    plateau = (plateau[0] + motion[0], plateau[1] + motion[0])
    level = quantile(speed[plateau[0] : plateau[1]], 0.5)
    n_trim = int(round(trim_s * fs))
    steady = _trim(plateau, n_trim, int(min_steady_s * fs))
    if steady is None:
        dur = (plateau[1] - plateau[0]) / fs
        raise RunError(
            f"the carriage speed never settles on a plateau long enough to measure "
            f"(longest steady stretch {dur:.2f} s at {level:.3f} m/s, "
            f"{min_steady_s:g} s needed after trimming {trim_s:g} s at each end)"
        )
    return plateau, level, steady


def sustained_peak(x: np.ndarray, k: int) -> float:
    """The largest value that ``x`` reaches or exceeds on at least ``k`` samples.

    A peak held for a stated time (k samples), unlike a percentile of the whole file, does not
    depend on the length of the run: the ramps of a 1200 s run are well under 0.5 % of it.
    """
    k = int(min(max(k, 1), x.size))
    return float(np.partition(x, x.size - k)[x.size - k])


#: Half-width of the constant-acceleration band in standard deviations of the measured noise
#: of the acceleration (the derivative of the filtered speed) [-].
ACCEL_BAND_SIGMAS = 3.0


def accel_noise(accel: np.ndarray, window: tuple[int, int]) -> float:
    """Robust standard deviation of the acceleration on a window of constant speed [m/s²].

    The noise of the derivative of the filtered speed grows with the sample rate's noise and
    falls with the cut-off: measured on the run itself, it scales the band within which the
    acceleration counts as constant.
    """
    a = accel[window[0] : window[1]]
    if a.size < 5:
        return 0.0
    med = float(np.median(a))
    return 1.4826 * float(np.median(np.abs(a - med)))


def _constant_stretch(
    accel: np.ndarray, i0: int, i1: int, sign: int, fs: float, noise: float = 0.0
) -> tuple[tuple[int, int] | None, float | None]:
    """The constant-acceleration stretch of sign ``sign`` in [i0, i1).

    The band around the stretch's level is ±max(5 % of the level, 0.004 m/s²,
    :data:`ACCEL_BAND_SIGMAS` × ``noise``), at most half the level; ``noise`` is the measured
    noise of the acceleration [m/s²]: at low sample rates or with a noisy speed a fixed 5 %
    band is narrower than the noise, and the stretch is lost.
    """
    if i1 - i0 < 3:
        return None, None
    a = sign * accel[i0:i1]
    peak = quantile(spread_sample(a), 0.98)
    if not peak > 0.005:
        return None, None
    strong = close_gaps(a > 0.5 * peak, int(0.05 * fs))
    core = longest_run(strong)
    if core is None:
        return None, None
    level = quantile(a[core[0] : core[1]], 0.5)
    half = min(max(0.05 * level, 0.004, ACCEL_BAND_SIGMAS * noise), 0.5 * level)
    band = close_gaps(np.abs(a - level) <= half, int(0.05 * fs))
    w = longest_run(band)
    if w is None:
        return None, None
    return (w[0] + i0, w[1] + i0), sign * level


def manual_window(t: np.ndarray, start_s: float, end_s: float) -> tuple[int, int]:
    """Index window for a steady window given by hand in the run sheet [s]."""
    i0 = int(np.searchsorted(t, start_s, side="left"))
    i1 = int(np.searchsorted(t, end_s, side="right"))
    if i1 - i0 < 2:
        raise RunError(
            f"the manual window {start_s:g}–{end_s:g} s holds no samples "
            f"(the file spans {t[0]:.2f}–{t[-1]:.2f} s)"
        )
    return i0, i1


#: Half-width of the force plateau's band as a fraction of its level [-] (a force is noisier,
#: relative to its level, than a carriage speed).
FORCE_PLATEAU_TOLERANCE = 0.05


def force_plateau(
    force: np.ndarray,
    fs: float,
    *,
    zero: float,
    trim_s: float = 0.375,
    min_steady_s: float = 0.5,
    tolerance: float = FORCE_PLATEAU_TOLERANCE,
) -> tuple[int, int]:
    """The steady window of a run without a measured speed, from its filtered force.

    With the zero removed, x = F − F₀, the plateau is where x is flat and away from zero: the
    spread (max − min) of x over a sliding ``min_steady_s`` is within max(``tolerance``·|x̄|,
    2 s₀) of its centre x̄ (s₀ the spread of the calmest tenth of the run: the noise), and |x̄|
    exceeds max(3 s₀, 2 % of the sustained peak of |x|). The longest such stretch, trimmed by
    ``trim_s`` at each end, is the steady window. The ramps are not flat (the drag grows with
    the speed under the constant inertia force), and a flat stretch inside them is shorter
    than the plateau, which is the longest stretch of constant force in a tow.

    Parameters
    ----------
    force : ndarray
        Low-pass filtered force, zero not removed [N].
    fs : float
        Sample rate [Hz].
    zero : float
        The force's zero [N].
    trim_s, min_steady_s : float
        Cut from each end of the plateau, and the shortest usable window after it [s].
    tolerance : float
        Half-width of the band as a fraction of the plateau level [-].

    Returns
    -------
    tuple of int
        The steady window [i0, i1).

    Raises
    ------
    RunError
        The force shows no plateau long enough (give the window in the run sheet).
    """
    # loaded on use: scipy.ndimage only for this run-window search, not on import
    from scipy.ndimage import maximum_filter1d, minimum_filter1d

    x = np.asarray(force, dtype=float) - zero
    w = max(3, int(min_steady_s * fs))
    hi, lo = maximum_filter1d(x, w, mode="nearest"), minimum_filter1d(x, w, mode="nearest")
    spread, mid = hi - lo, 0.5 * (hi + lo)
    s0 = quantile(spread, 0.1)
    peak = sustained_peak(np.abs(x), max(3, w // 2))
    moving = np.abs(mid) > max(3.0 * s0, 0.02 * peak)
    flat = spread <= np.maximum(tolerance * np.abs(mid), 2.0 * s0)
    plateau = longest_run(close_gaps(flat & moving, int(0.1 * fs)))
    if plateau is None:
        raise RunError("the force never leaves its zero on a plateau, so no steady window can "
                       "be found from it: give window_start_s and window_end_s in the run sheet")
    steady = _trim(plateau, int(round(trim_s * fs)), int(min_steady_s * fs))
    if steady is None:
        level = float(np.median(x[plateau[0]:plateau[1]]))
        raise RunError(
            f"the force never settles on a plateau long enough to measure (longest flat "
            f"stretch {(plateau[1] - plateau[0]) / fs:.2f} s at {level:.4g} N, {min_steady_s:g} "
            f"s needed after trimming {trim_s:g} s at each end): give window_start_s and "
            "window_end_s in the run sheet")
    return steady
