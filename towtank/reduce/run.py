"""Per-run reduction: from a run's calibrated channels to its phases, means and fit samples.

:func:`reduce_run` takes a :class:`~towtank.ingest.runfile.RawRun` and does, in this order
(docs/method.md, "A run"): filter speed and forces with one zero-phase low-pass and find the
phases from the speed; zero the filtered forces on the still window before the run (or at the
file's start) and remove the drift to the still window after it, once the balance has
settled; take acceleration from the filtered speed (or from an accel channel filtered the same
way); average over the trimmed steady window; keep decimated
samples of the steady and constant-acceleration windows for the fitters and a thumbnail of the
whole run for the report. Everything it returns is plain data that can be cached.

:func:`apply_tare` then subtracts a group's sting tare sample by sample, and
:func:`force_coefficient` makes a force coefficient C = F / (½ρU²A).

:func:`reduce_record` is the unit of work of the worker processes: one run-sheet row read
(:func:`towtank.ingest.runfile.load_run`) and reduced, any problem turned into the run's
one-sentence
rejection; :func:`crashed_record` is that sentence for a run whose worker died. This module
and what it imports never load pandas, so the workers start light.
"""

from __future__ import annotations

import math
import traceback
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from towtank.errors import RunError
from towtank.ingest.protocol import Processing, Protocol
from towtank.ingest.runfile import RawRun, file_bytes_stamped, load_run
from towtank.ingest.speedlog import run_speed_log
from towtank.ingest.zerofile import run_zero_levels, with_zero_levels
from towtank.reduce.tare import TareModel
from towtank.signal import conditioning, phases
from towtank.signal.drift import drift_verdict

#: The repair of the ingest that the engineer is told of on the terminal (the others, gaps
#: interpolated and spikes removed, are listed in runs.csv's notes and the report).
WARNED_REPAIRS = "non-numeric row(s) dropped"

PHASE_STEADY = 0
PHASE_ACCEL = 1
THUMB_HZ = 10.0


@dataclass
class RunReduction:
    """Everything the later stages need from one run (before tare)."""

    run: int
    file: str
    sha256: str
    fs: float
    n_samples: int
    duration_s: float
    windows: dict[str, tuple[float, float] | None]
    window_source: str
    speed_level: float  # plateau speed from detection [m/s]
    speed_mean: float  # steady-window mean of the filtered speed [m/s]
    speed_std: float  # [m/s]
    accel_mean: float  # constant-acceleration window mean [m/s²], NaN if none
    zero_drag: float  # [N]
    drift_drag: float  # [N]
    zero_lift: float  # [N], NaN without lift
    drift_lift: float  # [N]
    drag_mean_raw: float  # steady mean, zero and drift removed, tare still in [N]
    drag_std: float  # [N]
    lift_mean_raw: float  # [N], NaN without lift
    steady_regressors: tuple[float, float, float]  # means of U|U|, U, a over the steady window
    samples: dict[str, np.ndarray]  # phase, t, U, a, drag, lift (decimated fit samples)
    thumb: dict[str, np.ndarray]  # t, U, drag, lift of the whole run (zeroed, filtered)
    has_lift: bool
    notes: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)  # the notes the engineer must see
    # set by apply_tare
    tare_drag: float = 0.0
    tare_lift: float = 0.0
    tare_group: str = ""
    #: (size, mtime_ns, ctime_ns, inode) of the run file as its bytes were read, or None when
    #: it changed during the read: what the cache may remember with ``sha256``
    file_stamp: tuple[int, int, int, int] | None = None
    #: the whole run at its own rate (t, U, a, drag, lift: zeroed, filtered; tared once
    #: :func:`apply_tare` ran; "phase": the index into PHASE_NAMES, −1 outside every phase),
    #: only when asked for (``keep_series``), for the time-series export
    series: dict[str, np.ndarray] | None = None
    drag_mean: float = math.nan
    lift_mean: float = math.nan


#: A hand-set steady window whose speed varies by more than this many plateau bands is not
#: steady: the run is rejected rather than biasing a coefficient.
MANUAL_SPREAD_REJECT = 5.0
#: ... nor one whose mean speed is below this fraction of the run's peak speed (still water).
MANUAL_MIN_SPEED_FRACTION = 0.2


def manual_window_checks(
    t: np.ndarray,
    speed: np.ndarray,
    window: tuple[int, int],
    ph: phases.Phases,
    *,
    steady_tolerance: float,
    min_steady_s: float = 0.0,
) -> list[str]:
    """What is wrong with a steady window set by hand: sentences to warn, or a RunError.

    A hand window is trusted over the detection, but not blindly. It is rejected (RunError)
    when it is shorter than ``min_steady_s``, when its mean speed is below
    :data:`MANUAL_MIN_SPEED_FRACTION` of the run's peak (the carriage is at rest there), or
    when its speed varies by more than :data:`MANUAL_SPREAD_REJECT` plateau bands (it spans
    an acceleration or deceleration). Smaller faults are warnings: an overlap with the detected
    constant-acceleration or deceleration window (the force there holds the inertia
    (m − X_udot)·a), or a speed spread wider than the plateau band (max − min >
    2·``steady_tolerance``·mean, or 4 mm/s).

    Parameters
    ----------
    t : ndarray
        Time [s].
    speed : ndarray
        Filtered carriage speed [m/s].
    window : tuple of int
        Index window [i0, i1) of the hand-set steady window.
    ph : Phases
        The detected phases.
    steady_tolerance : float
        Half-width of the plateau band as a fraction of the speed [-].
    min_steady_s : float
        Shortest usable steady window [s].
    """
    i0, i1 = window
    span = (float(t[i0]), float(t[i1 - 1]))
    where = f"the hand-set steady window {span[0]:.2f}–{span[1]:.2f} s"
    if span[1] - span[0] < min_steady_s:
        raise RunError(f"{where} is {span[1] - span[0]:.2f} s long, shorter than the "
                       f"{min_steady_s:g} s a steady mean needs (min_steady_s)")
    u = speed[i0:i1]
    mean = float(np.mean(u))
    peak = float(np.max(speed))
    if not mean > MANUAL_MIN_SPEED_FRACTION * peak:
        raise RunError(f"{where} lies where the carriage is (nearly) still: mean speed "
                       f"{mean:.3f} m/s against a peak of {peak:.3f} m/s")
    spread = float(np.max(u) - np.min(u))
    allowed = max(2.0 * steady_tolerance * abs(mean), 0.004)
    if spread > MANUAL_SPREAD_REJECT * allowed:
        raise RunError(f"the speed varies by {spread:.3f} m/s inside {where} (mean {mean:.3f} "
                       f"m/s; a plateau varies by at most {allowed:.3f} m/s): the window is "
                       "not steady")
    out = []
    for name, label in (("accel", "acceleration"), ("decel", "deceleration")):
        w = getattr(ph, name)
        if w is not None and w[0] < i1 and i0 < w[1]:
            out.append(
                f"{where} overlaps the detected constant {label} "
                f"({t[w[0]]:.2f}–{t[w[1] - 1]:.2f} s): its mean holds inertia force"
            )
    if spread > allowed:
        out.append(
            f"the speed varies by {spread:.3f} m/s inside {where} "
            f"(mean {mean:.3f} m/s; a plateau varies by at most {allowed:.3f} m/s)"
        )
    return out


def reduce_run(
    raw: RawRun,
    processing: Processing,
    *,
    run: int,
    file: str,
    window_s: tuple[float, float] | None = None,
    speed_nominal: float = math.nan,
    accel_nominal: float = math.nan,
    keep_series: bool = False,
) -> RunReduction:
    """Reduce one run (before tare).

    The steps, each a function of this module: :func:`filter_channels` (one zero-phase
    low-pass for every channel), :func:`find_phases`, :func:`choose_steady_window` (detected
    or set by hand), :func:`zero_forces` (zero and drift from the filtered forces, with the
    drift check), :func:`check_force_signal` (a dead channel), :func:`nominal_checks`,
    :func:`fit_samples` and :func:`thumbnail`.

    Parameters
    ----------
    raw : RawRun
        Calibrated channels from :func:`towtank.ingest.runfile.load_run`.
    processing : Processing
        Filter and phase-detection settings.
    run : int
        Run number (for messages).
    file : str
        File name as in the sheet.
    window_s : tuple of float, optional
        Steady window set by hand in the run sheet [s]; replaces the detected one.
    speed_nominal : float
        Set carriage speed [m/s] (cross-check only).
    accel_nominal : float
        Set carriage acceleration [m/s²] (cross-check only).
    keep_series : bool
        Keep the whole conditioned run in ``series`` (for the export; never cached).
    """
    fs, t, p = raw.fs, raw.time, processing
    notes = list(raw.notes)
    filt, speed_f, accel_f = filter_channels(raw, p)
    ph = find_phases(t, speed_f, accel_f, fs, p, steady_required=window_s is None)
    windows = ph.windows_s(t)
    steady, window_source, manual_warnings = choose_steady_window(
        t, speed_f, ph, windows, window_s, p, notes
    )
    drag_f, lift_f, zeros, drift_warnings = zero_forces(t, filt, raw.lift is not None, ph,
                                                        steady, p, notes,
                                                        levels=raw.zero_levels)
    check_force_signal(raw, speed_f, steady, ph)
    s0, s1 = steady
    u_s = speed_f[s0:s1]
    speed_mean = float(np.mean(u_s))
    accel_mean = math.nan
    if ph.accel is not None:
        accel_mean = float(np.mean(accel_f[ph.accel[0] : ph.accel[1]]))
    nominal_warnings = nominal_checks(speed_mean, accel_mean, ph, p, notes,
                                      speed_nominal=speed_nominal, accel_nominal=accel_nominal)
    warn = (
        [n for n in raw.notes if WARNED_REPAIRS in n]  # dropped rows: said, not only noted
        + manual_warnings
        + drift_warnings
        + nominal_warnings
    )
    a_s = accel_f[s0:s1]
    return RunReduction(
        run=run,
        file=file,
        sha256=raw.sha256,
        fs=fs,
        n_samples=raw.n,
        duration_s=float(t[-1] - t[0]),
        windows=windows,
        window_source=window_source,
        speed_level=ph.speed_level,
        speed_mean=speed_mean,
        speed_std=float(np.std(u_s)),
        accel_mean=accel_mean,
        zero_drag=zeros[0],
        drift_drag=zeros[1],
        zero_lift=zeros[2],
        drift_lift=zeros[3],
        drag_mean_raw=float(np.mean(drag_f[s0:s1])),
        drag_std=float(np.std(drag_f[s0:s1])),
        lift_mean_raw=float(np.mean(lift_f[s0:s1])) if raw.lift is not None else math.nan,
        steady_regressors=(
            float(np.mean(u_s * np.abs(u_s))),
            speed_mean,
            float(np.mean(a_s)),
        ),
        samples=fit_samples(t, speed_f, accel_f, drag_f, lift_f, steady, ph, accel_mean, fs, p),
        thumb=thumbnail(t, speed_f, accel_f, drag_f, lift_f, fs),
        has_lift=raw.lift is not None,
        notes=notes,
        warnings=warn,
        series=(series_of(t, speed_f, accel_f, drag_f, lift_f, ph, steady)
                if keep_series else None),
    )


def series_of(
    t: np.ndarray, speed_f: np.ndarray, accel_f: np.ndarray, drag_f: np.ndarray,
    lift_f: np.ndarray, ph: phases.Phases, steady: tuple[int, int],
) -> dict[str, np.ndarray]:
    """The whole run at its own rate with each sample's phase: t [s], U [m/s], a [m/s²],
    drag, lift [N] (zeroed, filtered) and ``phase``, the index into
    :data:`towtank.signal.phases.PHASE_NAMES` (−1 between phases); the steady phase is the
    window used (set by hand or detected)."""
    label = np.full(t.size, -1, dtype=np.int8)
    for k, name in enumerate(phases.PHASE_NAMES):
        w = steady if name == "steady" else getattr(ph, name)
        if w is not None:
            label[w[0]:w[1]] = k
    return {"t": t.copy(), "U": speed_f.copy(), "a": accel_f.copy(), "drag": drag_f.copy(),
            "lift": lift_f.copy(), "phase": label}


def filter_channels(
    raw: RawRun, p: Processing
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One zero-phase low-pass for speed, forces (and accel): (stack, speed [m/s], a [m/s²]).

    The stack's columns are speed, drag, [lift], [accel]; acceleration is the derivative of the
    filtered speed unless the file has an accel channel (filtered the same way).
    """
    fs = raw.fs
    if p.cutoff_hz >= 0.5 * fs:
        raise RunError(
            f"the low-pass cut-off of [processing] cutoff_hz = {p.cutoff_hz:g} Hz is not below "
            f"half the file's sample rate ({fs:g} Hz / 2), so the run cannot be filtered"
        )
    forces = [raw.drag] + ([raw.lift] if raw.lift is not None else [])
    stack = np.column_stack([raw.speed] + forces + ([raw.accel] if raw.accel is not None else []))
    filt = conditioning.lowpass(stack, fs, p.cutoff_hz, p.filter_order)
    speed_f = filt[:, 0]
    accel_f = filt[:, -1] if raw.accel is not None else conditioning.derivative(speed_f, fs)
    return filt, speed_f, accel_f


def find_phases(
    t: np.ndarray, speed_f: np.ndarray, accel_f: np.ndarray, fs: float, p: Processing,
    *, steady_required: bool,
) -> phases.Phases:
    """The run's phases from the filtered speed, with the protocol's settings."""
    return phases.detect_phases(
        t,
        speed_f,
        accel_f,
        fs,
        trim_s=p.trim,
        min_steady_s=p.min_steady_s,
        min_accel_s=p.min_accel_s,
        zero_window_s=p.zero_window_s,
        steady_tolerance=p.steady_tolerance,
        steady_required=steady_required,
        zero_at=p.zero_at,
        drift_settle_s=p.drift_settle_s,
    )


def choose_steady_window(
    t: np.ndarray,
    speed_f: np.ndarray,
    ph: phases.Phases,
    windows: dict[str, tuple[float, float] | None],
    window_s: tuple[float, float] | None,
    p: Processing,
    notes: list[str],
) -> tuple[tuple[int, int], str, list[str]]:
    """(steady window, its source, warnings): the detected plateau or the sheet's hand window.

    ``windows`` and ``notes`` are updated in place for a hand window.
    """
    if window_s is None:
        assert ph.steady is not None
        return ph.steady, "detected", []
    steady = phases.manual_window(t, *window_s)
    det = windows["steady"]
    found = f"detected {det[0]:.2f}–{det[1]:.2f} s" if det else "no plateau detected"
    window_source = f"manual {window_s[0]:g}–{window_s[1]:g} s ({found})"
    notes.append(f"steady window set by hand in the sheet: {window_source}")
    windows["steady"] = (float(t[steady[0]]), float(t[steady[1] - 1]))
    manual_warnings = manual_window_checks(
        t, speed_f, steady, ph, steady_tolerance=p.steady_tolerance,
        min_steady_s=p.min_steady_s,
    )
    notes.extend(manual_warnings)
    return steady, window_source, manual_warnings


def zero_forces(
    t: np.ndarray,
    filt: np.ndarray,
    has_lift: bool,
    ph: phases.Phases,
    steady: tuple[int, int],
    p: Processing,
    notes: list[str],
    levels: dict[str, float] | None = None,
) -> tuple[np.ndarray, np.ndarray, tuple[float, float, float, float], list[str]]:
    """Zeroed filtered drag and lift, (zero_drag, drift_drag, zero_lift, drift_lift), warnings.

    The zero and the drift are taken from the FILTERED forces (docs/method.md "A run"), so that
    mains hum and vibration in the still windows do not leak into them. With [processing]
    drift = "linear" and a post-run still window, the zero is a straight line between the two
    windows, after :func:`towtank.signal.drift.drift_verdict` has judged the drift: a run whose
    balance had not settled after the stop is rejected, a large drift is a warning.
    ``levels`` (drag, lift [N] of a zeros file, ``[zeros]``) replace the pre-run window's means.
    """
    levels = levels or {}
    post = ph.still_post if p.drift == "linear" else None
    if p.drift == "linear" and ph.still_post is None:
        notes.append("the file does not end at rest: zero held constant (no drift correction)")
    elif p.drift == "none":
        notes.append("zero held constant ([processing] drift = \"none\")")
    out: list[np.ndarray] = []
    zeros: list[float] = []
    warnings: list[str] = []
    cols = [(1, "drag")] + ([(2, "lift")] if has_lift else [])
    pre = ph.still_pre
    steady_force = max(
        abs(float(np.mean(filt[steady[0] : steady[1], k])
                  - levels.get(name, np.mean(filt[pre[0] : pre[1], k]))))
        for k, name in cols
    )
    for k, name in cols:
        force = filt[:, k]
        if post is not None and post[1] - post[0] >= 2:
            verdict = drift_verdict(t, force, pre, post, steady_force, name,
                                    level=levels.get(name))
            if verdict.reject is not None:
                raise RunError(verdict.reject)
            if verdict.warning is not None:
                notes.append(verdict.warning)
                warnings.append(verdict.warning)
        zero, z, drift = conditioning.zero_line(t, force, pre, post, level=levels.get(name))
        out.append(force - zero)
        zeros += [z, drift]
    if not has_lift:
        out.append(np.full(t.shape, np.nan))
        zeros += [math.nan, math.nan]
    return out[0], out[1], (zeros[0], zeros[1], zeros[2], zeros[3]), warnings


def nominal_checks(
    speed_mean: float,
    accel_mean: float,
    ph: phases.Phases,
    p: Processing,
    notes: list[str],
    *,
    speed_nominal: float,
    accel_nominal: float,
) -> list[str]:
    """Cross-checks against the sheet's set values: notes (appended) and the warnings among
    them (the sheet or the carriage is off)."""
    n_notes = len(notes)
    tol = p.nominal_tolerance
    if math.isfinite(speed_nominal) and speed_nominal > 0:
        if abs(speed_mean - speed_nominal) > tol * speed_nominal:
            notes.append(
                f"measured plateau speed {speed_mean:.3f} m/s differs from the set "
                f"{speed_nominal:g} m/s by more than {100 * tol:g} %"
            )
    if math.isfinite(accel_nominal) and accel_nominal > 0:
        if ph.accel is None:
            notes.append(
                f"no usable constant-acceleration stretch although the sheet sets "
                f"{accel_nominal:g} m/s² (absent, or shorter than {p.min_accel_s:g} s after "
                f"trimming {p.trim:.2f} s at each end); the run is used for its steady phase"
            )
        elif abs(accel_mean - accel_nominal) > 2 * tol * accel_nominal:
            notes.append(
                f"measured acceleration {accel_mean:.3f} m/s² differs from the set "
                f"{accel_nominal:g} m/s² by more than {200 * tol:g} %"
            )
    return [n for n in notes[n_notes:] if "differs from the set" in n]


#: A force channel whose filtered signal varies by less than this while the carriage moves at
#: speed shows no signal (a dead cell, an unplugged cable, a channel of zeros) [N].
DEAD_CHANNEL_SPAN_N = 1e-6


def check_force_signal(
    raw: RawRun, speed_f: np.ndarray, steady: tuple[int, int], ph: phases.Phases
) -> None:
    """Reject a run whose drag (or lift) channel is flat while the carriage moves.

    A channel recorded as a constant (all 0.0: a dead cell or an unplugged cable) would enter
    the fits as zero force at speed and move every coefficient; it is rejected, naming the
    channel ("drag channel shows no signal").
    """
    m0, m1 = ph.motion
    for name, x in (("drag", raw.drag), ("lift", raw.lift)):
        if x is None or m1 - m0 < 3:
            continue
        seg = x[m0:m1]
        if float(np.max(seg) - np.min(seg)) <= DEAD_CHANNEL_SPAN_N:
            raise RunError(
                f"{name} channel shows no signal: it reads {float(seg[0]):g} throughout the "
                f"run while the carriage moves at up to {float(np.max(speed_f)):.3f} m/s (a "
                "dead load cell, an unplugged cable, or the wrong column?)"
            )


def fit_samples(
    t: np.ndarray,
    speed_f: np.ndarray,
    accel_f: np.ndarray,
    drag_f: np.ndarray,
    lift_f: np.ndarray,
    steady: tuple[int, int],
    ph: phases.Phases,
    accel_mean: float,
    fs: float,
    p: Processing,
) -> dict[str, np.ndarray]:
    """Decimated fit samples of the steady and constant-acceleration windows.

    Each sample's acceleration is its window's mean: within a trimmed steady or constant-
    acceleration window the carriage's acceleration is constant, and the sample-by-sample
    derivative of the (noisy) speed would put noise into a regressor, which biases the fitted
    inertia toward zero (errors in variables: attenuation by var(noise)/var(a), ~0.2 % of the
    transverse added mass at 1 mm/s speed noise).
    """
    s0, s1 = steady
    rate = p.fit_sample_hz or 4.0 * p.cutoff_hz
    idx_s = conditioning.decimate_indices(s0, s1, fs, rate)
    idx_a = (
        conditioning.decimate_indices(ph.accel[0], ph.accel[1], fs, rate)
        if ph.accel is not None
        else np.array([], dtype=int)
    )
    idx = np.concatenate([idx_s, idx_a])
    a_steady = float(np.mean(accel_f[s0:s1]))
    a_accel = accel_mean if ph.accel is not None else math.nan
    return {
        "phase": np.concatenate(
            [np.full(idx_s.size, PHASE_STEADY), np.full(idx_a.size, PHASE_ACCEL)]
        ).astype(np.int8),
        "t": t[idx],
        "U": speed_f[idx],
        "a": np.concatenate([np.full(idx_s.size, a_steady), np.full(idx_a.size, a_accel)]),
        "drag": drag_f[idx],
        "lift": lift_f[idx],
    }


def thumbnail(
    t: np.ndarray, speed_f: np.ndarray, accel_f: np.ndarray, drag_f: np.ndarray,
    lift_f: np.ndarray, fs: float,
) -> dict[str, np.ndarray]:
    """The whole run (zeroed, filtered) at :data:`THUMB_HZ` for the report."""
    step = max(1, int(round(fs / THUMB_HZ)))
    return {
        "t": t[::step].copy(),
        "U": speed_f[::step].copy(),
        "a": accel_f[::step].copy(),
        "drag": drag_f[::step].copy(),
        "lift": lift_f[::step].copy(),
    }


def apply_tare(red: RunReduction, tare: TareModel | None) -> RunReduction:
    """Subtract a tare group's F_tare(U, a) sample by sample (docs/method.md "Sting tare").

    The steady means use the window means of U|U|, U and a, which equals averaging the
    sample-by-sample difference. Returns a new reduction; ``red`` is not changed.
    """
    if tare is None:
        return replace(
            red, drag_mean=red.drag_mean_raw, lift_mean=red.lift_mean_raw, tare_group=""
        )
    x = np.asarray(red.steady_regressors)
    tare_d = float(x @ tare.drag.coef)
    tare_l = float(x @ tare.lift.coef) if tare.lift is not None else 0.0
    s = dict(red.samples)
    s["drag"] = s["drag"] - tare.drag(s["U"], s["a"])
    th = dict(red.thumb)
    th["drag"] = th["drag"] - tare.drag(th["U"], th["a"])
    series = dict(red.series) if red.series is not None else None
    if series is not None:
        series["drag"] = series["drag"] - tare.drag(series["U"], series["a"])
    if tare.lift is not None and red.has_lift:
        s["lift"] = s["lift"] - tare.lift(s["U"], s["a"])
        th["lift"] = th["lift"] - tare.lift(th["U"], th["a"])
        if series is not None:
            series["lift"] = series["lift"] - tare.lift(series["U"], series["a"])
    notes = list(red.notes)
    warn = list(red.warnings)
    if not tare.covers(red.speed_mean):
        lo, hi = tare.speed_range
        msg = (
            f"plateau speed {red.speed_mean:.3f} m/s is outside the tare runs' range "
            f"{lo:.3f}–{hi:.3f} m/s of group '{tare.group}': the tare is extrapolated"
        )
        notes.append(msg)
        warn.append(msg)
    return replace(
        red,
        samples=s,
        thumb=th,
        series=series,
        tare_drag=tare_d,
        tare_lift=tare_l,
        tare_group=tare.group,
        drag_mean=red.drag_mean_raw - tare_d,
        lift_mean=(red.lift_mean_raw - tare_l) if red.has_lift else math.nan,
        notes=notes,
        warnings=warn,
    )


def force_coefficient(force: float, rho: float, area: float, speed: float) -> float:
    """C = F / (½ ρ A U²) [-].

    Parameters
    ----------
    force : float
        Force [N].
    rho : float
        Water density [kg/m³].
    area : float
        Reference area [m²].
    speed : float
        Speed [m/s].
    """
    q = 0.5 * rho * area * speed * speed
    return force / q if q > 0 else math.nan


def check_reduction(red: RunReduction) -> None:
    """Sanity checks on a reduced run that reject it with one sentence."""
    if not math.isfinite(red.drag_mean_raw):
        raise RunError("the steady drag mean is not finite")


def _internal_error_sentence(exc: BaseException) -> str:
    last = traceback.extract_tb(exc.__traceback__)[-1] if exc.__traceback__ else None
    where = f" in {Path(last.filename).name}:{last.lineno}" if last else ""
    return (
        f"an unexpected internal error ({type(exc).__name__}: {exc}{where}); "
        "please report it, and rerun with --debug for the traceback"
    )


def run_preview(raw: RawRun) -> dict[str, np.ndarray]:
    """A run's calibrated time [s], speed [m/s], drag and lift [N] at :data:`THUMB_HZ` (no zero,
    no filter): what the report shows of a run that was read but could not be reduced."""
    step = max(1, int(round(raw.fs / THUMB_HZ)))
    n = raw.time[::step].size
    return {
        "t": raw.time[::step].copy(),
        "U": raw.speed[::step].copy(),
        "drag": raw.drag[::step].copy(),
        "lift": raw.lift[::step].copy() if raw.lift is not None else np.full(n, np.nan),
    }


Record = tuple[int, RunReduction | None, str | None, dict[str, np.ndarray] | None]


def reduce_record(protocol: Protocol, row: dict[str, Any], *, debug: bool = False,
                  keep_series: bool = False) -> Record:
    """Read and reduce the run of one run-sheet row; never raises for a data problem.

    Returns (run, reduction, None, None), or (run, None, reason, preview) where ``reason`` is
    one sentence naming the run, its file and what is wrong, and ``preview`` is
    :func:`run_preview` of a run that was read but could not be reduced (None when it could
    not be read). An unexpected error (a bug) is reported the same way, or raised with
    ``debug``.
    """
    run = int(row["run"])
    file = str(row["file"])
    path = protocol.campaign.data_dir / file
    raw = None
    try:
        p = protocol.processing
        data, stamp = file_bytes_stamped(path)
        log = run_speed_log(protocol.speed_log, protocol.campaign.data_dir, file, run)
        raw = load_run(
            path,
            protocol.channels,
            max_nan_gap_s=p.max_nan_gap_s,
            max_bad_row_fraction=p.max_bad_row_fraction,
            do_despike=p.despike,
            data=data,
            options=protocol.read,
            balance=protocol.balance,
            speed_log=log,
        )
        # the zeros file at the run file's rate (one acquisition), tapered over the run's trim
        zeros = run_zero_levels(protocol.zeros, protocol.campaign.data_dir, file, run,
                                protocol.channels, protocol.read, protocol.balance,
                                fs=raw.fs, taper_s=p.trim)
        if zeros is not None:
            raw = with_zero_levels(raw, *zeros)
        ws = row.get("window_start_s", math.nan)
        we = row.get("window_end_s", math.nan)
        window = (float(ws), float(we)) if math.isfinite(ws) and math.isfinite(we) else None
        red = reduce_run(
            raw,
            p,
            run=run,
            file=file,
            window_s=window,
            speed_nominal=float(row.get("speed_nominal", math.nan)),
            accel_nominal=float(row.get("accel_nominal", math.nan)),
            keep_series=keep_series,
        )
        test = str(row.get("test", "")).strip().lower()
        if test == "accel" and red.windows["accel"] is None:
            # a run made for its acceleration without one: the engineer must hear of it
            red.warnings.extend(n for n in red.notes if n.startswith("no usable constant-acc"))
        elif test == "steady":  # made for its plateau: a missing stretch is no news
            red.notes = [n for n in red.notes if not n.startswith("no usable constant-acc")]
        red.file_stamp = stamp
        return run, red, None, None
    except RunError as exc:
        reason = exc.reason
        if file not in reason and Path(file).name not in reason:
            reason = f"{file}: {reason}"
        return run, None, f"run {run}: {reason}", _safe_preview(raw)
    except Exception as exc:  # noqa: BLE001 - a bug must not stop the day
        if debug:
            raise
        return run, None, f"run {run}: {file}: {_internal_error_sentence(exc)}", None


def _safe_preview(raw: RawRun | None) -> dict[str, np.ndarray] | None:
    if raw is None:
        return None
    try:
        return run_preview(raw)
    except Exception:  # noqa: BLE001 - a preview is a courtesy; the rejection stands without it
        return None


def crashed_record(row: dict[str, Any]) -> Record:
    """The rejection of a run whose worker process died while reducing it."""
    run, file = int(row["run"]), str(row["file"])
    return run, None, (
        f"run {run}: {file}: the process reducing it stopped abruptly (killed, out of memory, "
        "or a crash inside a reading library); the file is left as it is"
    ), None
