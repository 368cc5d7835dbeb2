"""Signal conditioning: zero, drift, zero-phase low-pass filter, acceleration from speed.

docs/method.md "A run": the force channels' zero is their mean over the still window before the
carriage moves; where the file also ends at rest the zero is interpolated linearly in time
between the pre- and post-run windows (balance drift). One zero-phase low-pass filter is applied
identically to speed and forces, and acceleration is taken from the filtered speed: filtering
force and speed differently biases the added mass, because the two smear the jerk transitions
differently.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np


@lru_cache(maxsize=64)
def butter_sos(cutoff_hz: float, fs: float, order: int = 4) -> np.ndarray:
    """Second-order sections of a Butterworth low-pass.

    Parameters
    ----------
    cutoff_hz : float
        -3 dB frequency of the single pass [Hz]; the forward-backward pass is -6 dB there.
    fs : float
        Sample rate [Hz].
    order : int
        Filter order of one pass (the zero-phase filter has twice this order).
    """
    # loaded on use: scipy.signal only to design a filter
    from scipy.signal import butter

    nyq = 0.5 * fs
    wn = min(cutoff_hz / nyq, 0.99)
    return butter(order, wn, btype="low", output="sos")


def lowpass(x: np.ndarray, fs: float, cutoff_hz: float, order: int = 4) -> np.ndarray:
    """Zero-phase Butterworth low-pass (forward-backward, ``scipy.signal.sosfiltfilt``).

    Parameters
    ----------
    x : ndarray
        Signal(s), time along axis 0 [any unit]. Several channels as columns are filtered
        identically in one call.
    fs : float
        Sample rate [Hz].
    cutoff_hz : float
        Cut-off frequency [Hz].
    order : int
        Order of one pass.

    Returns
    -------
    ndarray
        Filtered signal(s), same shape, no phase lag (Gustafsson 1996, IEEE Trans. Signal
        Process. 44(4), "Determining the initial states in forward-backward filtering").

    """
    # loaded on use: scipy.signal only when the fast filter cannot be used (another
    # dtype), never in a reduction worker
    from scipy.signal import sosfiltfilt

    sos = butter_sos(float(cutoff_hz), float(fs), int(order))
    # pad by an even (mirror) extension over two periods of the cut-off: the still windows at
    # the file's ends hold the zero and the drift, and an odd extension about the last sample
    # (scipy's default) shifts the padding's level by twice that sample's hum or noise, which
    # the filter then smears back into the window (0.7 mN of drift from 0.05 N of hum)
    padlen = min(x.shape[0] - 1, max(3 * (2 * sos.shape[0] + 1), int(2.0 * fs / cutoff_hz)))
    return sosfiltfilt(sos, x, axis=0, padtype="even", padlen=padlen)


def still_level(x: np.ndarray, fs: float | None = None, taper_s: float | None = None) -> float:
    """The level of a force recorded at rest (a zeros file): its mean weighted by a window with
    cosine tapers at its ends (Tukey's window; Hann's when the tapers meet).

    Parameters
    ----------
    x : ndarray
        Force at rest [N], evenly sampled; missing samples (NaN) are interpolated first.
    fs : float, optional
        Sample rate [Hz].
    taper_s : float, optional
        Duration of each taper [s], at most half the record; the run's trim (1.5 / cutoff_hz)
        in towtank. Without ``fs`` or ``taper_s`` the tapers meet (the Hann window).

    Returns
    -------
    float
        F_zero = Σ w_k·x_k / Σ w_k [N], w_k = sin²(π(k + 1)/(2(m + 1))) for the first m
        samples, mirrored for the last m, 1 between them, m = taper_s·fs (Harris 1978, Proc.
        IEEE 66(1), "On the use of windows for harmonic analysis with the discrete Fourier
        transform": the Tukey and Hann windows).

    Notes
    -----
    The plain mean of a record that is not a whole number of periods of a disturbance long
    keeps part of a period: 0.05 N of 50 Hz mains hum moves the mean of a 1.5 s zeros file by
    up to 0.2 mN. The tapered mean is an FIR low-pass read at the record's centre with no
    start-up at the record's ends: with 0.375 s tapers, 50–150 Hz hum is rejected to 0.0002 mN
    over 1.5 s (0.001 mN over 0.5 s), and white noise gives 1.10 times the plain mean's
    standard deviation (the full Hann window: 1.22; the run's Butterworth low-pass averaged
    clear of the record's ends: 1.45, and up to 0.004 mN of hum). A constant or a straight
    drift gives its plain mean.
    """
    x = np.asarray(x, dtype=float)
    ok = np.isfinite(x)
    if not ok.all():
        idx = np.arange(x.size)
        x = np.interp(idx, idx[ok], x[ok])
    n = x.size
    m = n // 2
    if fs is not None and taper_s is not None and fs > 0:
        m = min(m, max(0, int(round(taper_s * fs))))
    w = np.ones(n)
    if m > 0:
        ramp = np.sin(0.5 * np.pi * np.arange(1, m + 1) / (m + 1)) ** 2
        w[:m] = ramp
        w[n - m:] = ramp[::-1]
    return float(np.dot(w, x) / np.sum(w))


def derivative(x: np.ndarray, fs: float) -> np.ndarray:
    """Time derivative by central differences (one-sided at the ends).

    Parameters
    ----------
    x : ndarray
        Signal sampled at a constant rate, time along axis 0 (e.g. speed [m/s]).
    fs : float
        Sample rate [Hz].

    Returns
    -------
    ndarray
        dx/dt in [unit of x per s] (e.g. acceleration [m/s²]).
    """
    return np.gradient(x, 1.0 / fs, axis=0)


def zero_line(
    t: np.ndarray,
    force: np.ndarray,
    pre: tuple[int, int] | None,
    post: tuple[int, int] | None,
    level: float | None = None,
) -> tuple[np.ndarray, float, float]:
    """The balance zero along the run: constant, or linear between still windows.

    Parameters
    ----------
    t : ndarray
        Time [s].
    force : ndarray
        Raw force channel [N].
    pre : tuple of int or None
        Index range [i0, i1) of the still window before the carriage moves; None for a run
        that starts in motion (then ``level`` is required and holds at the file's start).
    post : tuple of int or None
        Index range of the still window after the carriage stops, if the file ends at rest.
    level : float, optional
        The zero measured apart (a zeros file) [N]: it replaces the pre-window mean.

    Returns
    -------
    zero : ndarray
        Zero at every sample [N]: the pre-window mean, or the straight line through the pre-
        and post-window means at their mid-times (docs/method.md: zero and drift).
    zero_pre : float
        Pre-run zero [N].
    drift : float
        Post-run minus pre-run zero [N] (0 without a post window).
    """
    if level is not None:
        z0 = float(level)
    elif pre is not None:
        z0 = float(np.mean(force[pre[0] : pre[1]]))
    else:
        raise ValueError("zero_line needs the pre-run window or a level")
    if post is None or post[1] - post[0] < 2:
        return np.full(t.shape, z0), z0, 0.0
    z1 = float(np.mean(force[post[0] : post[1]]))
    t0 = float(t[0]) if pre is None else float(np.mean(t[pre[0] : pre[1]]))
    t1 = float(np.mean(t[post[0] : post[1]]))
    slope = (z1 - z0) / (t1 - t0) if t1 > t0 else 0.0
    return z0 + slope * (t - t0), z0, z1 - z0


def decimate_indices(i0: int, i1: int, fs: float, rate_hz: float) -> np.ndarray:
    """Indices in [i0, i1) spaced 1/rate_hz apart, centred in the window."""
    step = max(1, int(round(fs / rate_hz)))
    n = (i1 - i0 - 1) // step + 1 if i1 > i0 else 0
    if n <= 0:
        return np.array([], dtype=int)
    start = i0 + ((i1 - i0 - 1) - (n - 1) * step) // 2
    return start + step * np.arange(n)
