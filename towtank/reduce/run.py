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
from towtank.ingest.calibration import UNITS
from towtank.ingest.describe import force_parts, unmapped_forces
from towtank.ingest.protocol import Processing, Protocol, channel_map
from towtank.ingest.protocol_types import CAPTIVE_TESTS
from towtank.ingest.readers import name_list
from towtank.ingest.runfile import RawRun, file_bytes_stamped, load_run
from towtank.ingest.speedlog import run_speed_log
from towtank.ingest.zerofile import run_zero_levels, with_zero_levels
from towtank.messages import Rejection
from towtank.reduce.captive_record import reduce_captive_record
from towtank.reduce.tare import TareModel
from towtank.signal import conditioning, phases
from towtank.signal.drift import check_drift

PHASE_STEADY = 0
PHASE_ACCEL = 1
THUMB_HZ = 10.0


@dataclass(frozen=True)
class RunReduction:
    """Everything the later stages need from one run (before tare); made whole, never
    changed after (:func:`apply_tare`, :func:`with_units` return a new one)."""

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
    notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()  # the notes the engineer must see
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
    #: "measured" (a speed channel or log), or "nominal": the run sheet's set speed of a run
    #: without a measured speed ([processing] speed_source = "nominal")
    speed_source: str = "measured"
    #: standard uncertainty of a set speed [m/s]: speed_tolerance·U/√3 (NaN when measured)
    speed_u: float = math.nan
    #: per channel read from the file: (its unit, where that came from: "file", "protocol",
    #: "assumed" or "unknown"), see :func:`towtank.ingest.calibration.unit_source`
    units: dict[str, tuple[str, str]] = field(default_factory=dict)
    #: the note (one of ``notes``) that the constant-acceleration stretch the sheet sets was
    #: not found, "" when none: a warning for a run made for its acceleration, nothing for
    #: one made for its plateau
    accel_missing: str = ""
    #: a captive run's reduction (:meth:`towtank.reduce.captive.CaptiveRun.to_arrays`), else
    #: empty
    captive: dict[str, np.ndarray] = field(default_factory=dict)


#: A run whose phases are not found and whose file lasts less than this [s] while its
#: carriage's speed changes faster than :data:`HINT_ACCEL_MS2` is on a wrong time scale.
HINT_SHORT_S = 5.0
#: Carriage accelerations [m/s²] beyond any towing carriage's few m/s².
HINT_ACCEL_MS2 = 5.0


def time_unit_hint(t: np.ndarray, accel: np.ndarray) -> str:
    """What to add to a run's rejection for phases not found when its time [s] looks in
    other units: a file shorter than :data:`HINT_SHORT_S` in which the carriage's speed
    changes at more than :data:`HINT_ACCEL_MS2` (``accel`` [m/s²], filtered) is a time in
    minutes (60 times too short, its accelerations 60 times too large); "" otherwise."""
    duration = float(t[-1] - t[0]) if t.size else 0.0
    finite = np.abs(accel[np.isfinite(accel)])
    peak = float(finite.max()) if finite.size else 0.0
    if 0.0 < duration < HINT_SHORT_S and peak > HINT_ACCEL_MS2:
        return (f" (the file lasts only {duration:.3g} s while the carriage's speed changes "
                f"at up to {peak:.3g} m/s², where a tow lasts tens of seconds at a few m/s²: "
                "is the time in minutes?)")
    return ""


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
    :func:`fit_samples` and :func:`thumbnail`. A run without a measured speed
    (``raw.speed_nominal`` set: ``speed_source = "nominal"``) goes to :func:`reduce_nominal`;
    a run whose zero does not come from the still window before the carriage moves (a zeros
    file, ``zero_at = "file_start"``) may start in motion.

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
    if math.isfinite(raw.speed_nominal):
        return reduce_nominal(raw, processing, run=run, file=file, window_s=window_s,
                              keep_series=keep_series)
    fs, t, p = raw.fs, raw.time, processing
    notes = list(raw.notes)
    filt, speed_f, accel_f = filter_channels(raw, p)
    try:
        ph = find_phases(t, speed_f, accel_f, fs, p, steady_required=window_s is None,
                         still_required=not raw.zero_levels and p.zero_at == "before_motion")
    except RunError as exc:  # the phases of a run on a wrong time scale are not found
        raise RunError(exc.reason + time_unit_hint(t, accel_f), exc.run, exc.file,
                       exc.kind) from None
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
    if not raw.extra:  # a captive run's drag is the balance's −fx
        check_drag_direction(drag_f[s0:s1], speed_mean)
    accel_mean = math.nan
    if ph.accel is not None:
        accel_mean = float(np.mean(accel_f[ph.accel[0] : ph.accel[1]]))
    checks = nominal_checks(speed_mean, accel_mean, ph, p,
                            speed_nominal=speed_nominal, accel_nominal=accel_nominal)
    notes += checks.notes
    warn = (
        list(raw.warnings)  # dropped rows: said, not only noted
        + manual_warnings
        + drift_warnings
        + list(checks.warnings)
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
        notes=tuple(notes),
        warnings=tuple(warn),
        accel_missing=checks.accel_missing,
        series=(series_of(t, speed_f, accel_f, drag_f, lift_f, ph, steady)
                if keep_series else None),
    )


#: A run without a measured speed has its drift taken to the file's last still window only
#: when the force there is within this fraction of the plateau force of its zero, and flat
#: within it too (the carriage back at rest, not a file that ends while towing or braking).
NOMINAL_REST_FRACTION = 0.25
NOMINAL_REST_FLAT = 0.1


def rest_at_end(t: np.ndarray, drag_f: np.ndarray, steady: tuple[int, int], fs: float,
                p: Processing) -> tuple[int, int] | None:
    """The file's last ``zero_window_s`` (clear of the end by ``trim_s``) as a post-run still
    window of a run without a measured speed, when the force shows the carriage at rest there:
    at least ``max(drift_settle_s, 1 s)`` after the steady window, within
    :data:`NOMINAL_REST_FRACTION` of the plateau force of its zero and flat within
    :data:`NOMINAL_REST_FLAT` of it (``drag_f`` [N] zeroed at the file's start); else None."""
    n = t.size
    end = n - int(round(p.trim * fs))
    start = end - max(int(p.zero_window_s * fs), 2)
    if start < steady[1] + int(max(p.drift_settle_s, 1.0) * fs) or start < 0:
        return None
    level = abs(float(np.mean(drag_f[steady[0]:steady[1]])))
    x = drag_f[start:end]
    if abs(float(np.mean(x))) > NOMINAL_REST_FRACTION * level or \
            float(np.ptp(x)) > NOMINAL_REST_FLAT * level:
        return None
    return start, end


def reduce_nominal(
    raw: RawRun,
    p: Processing,
    *,
    run: int,
    file: str,
    window_s: tuple[float, float] | None = None,
    keep_series: bool = False,
) -> RunReduction:
    """Reduce a run without a measured speed (``[processing] speed_source = "nominal"``).

    The speed is the run sheet's set speed U (``raw.speed_nominal``) over the steady window,
    with the standard uncertainty of a rectangular tolerance, u(U) = speed_tolerance·U/√3
    (GUM, JCGM 100:2008, §4.3.7). The steady window is the sheet's (``window_s``), else the
    force's plateau (:func:`towtank.signal.phases.force_plateau`). The zero is the zeros file's
    (``[zeros]``), else the filtered force's mean over the file's first ``zero_window_s`` (no
    speed tells when the carriage moves). With ``drift = "linear"`` and the file ending at rest
    by its force (:func:`rest_at_end`), the drift to that last window is removed as for any run
    (with the same check, :func:`towtank.signal.drift.drift_verdict`); else the zero is held.
    No acceleration is known: such a run gives no sample to an added-mass fit (its steady
    samples have U = the set speed and a = 0).
    """
    fs, t = raw.fs, raw.time
    u_set = float(raw.speed_nominal)
    notes = list(raw.notes)
    if not u_set > 0:
        raise RunError("speed_source = \"nominal\" needs the run's set speed, speed_nominal, "
                       "in the run sheet")
    if p.cutoff_hz >= 0.5 * fs:
        raise RunError(
            f"the low-pass cut-off of [processing] cutoff_hz = {p.cutoff_hz:g} Hz is not below "
            f"half the file's sample rate ({fs:g} Hz / 2), so the run cannot be filtered")
    has_lift = raw.lift is not None
    forces = [raw.drag] + ([raw.lift] if raw.lift is not None else [])
    filt = conditioning.lowpass(np.column_stack(forces), fs, p.cutoff_hz, p.filter_order)
    levels = raw.zero_levels or {}
    n = t.size
    pre = (0, min(n, max(int(p.zero_window_s * fs), 2)))
    names = ["drag"] + (["lift"] if has_lift else [])
    zeros = [float(levels[k]) if k in levels else float(np.mean(filt[pre[0]:pre[1], i]))
             for i, k in enumerate(names)]
    from_start = [k for k in names if k not in levels]
    if window_s is not None:
        steady = phases.manual_window(t, *window_s)
        window_source = f"manual {window_s[0]:g}–{window_s[1]:g} s (set speed, no speed channel)"
    else:
        steady = phases.force_plateau(filt[:, 0], fs, zero=zeros[0], trim_s=p.trim,
                                      min_steady_s=p.min_steady_s)
        window_source = "from the force (set speed, no speed channel)"
    s0, s1 = steady
    post = rest_at_end(t, filt[:, 0] - zeros[0], steady, fs, p) if p.drift == "linear" else None
    steady_force = max(abs(float(np.mean(filt[s0:s1, i])) - zeros[i]) for i in range(len(names)))
    zeroed: list[np.ndarray] = []
    drifts: list[float] = []
    warnings: list[str] = []
    for i, name in enumerate(names):
        w = None if name in levels else pre
        if post is not None:
            check_drift(t, filt[:, i], w, post, steady_force, name, levels.get(name), notes,
                         warnings)
        line, _, drift = conditioning.zero_line(t, filt[:, i], w, post, level=levels.get(name))
        zeroed.append(filt[:, i] - line)
        drifts.append(drift)
    if from_start:
        notes.append(f"no measured speed: the {' and '.join(from_start)} zero is the mean of "
                     f"the file's first {t[pre[1] - 1] - t[0]:.2f} s")
    notes.append(f"no measured speed: the drift is taken to the file's last "
                 f"{t[post[1] - 1] - t[post[0]]:.2f} s, where the force is back at rest"
                 if post is not None else
                 "no measured speed: the zero is held constant (no drift correction: the file "
                 "does not end at rest by its force, or drift = \"none\")")
    drag_f = zeroed[0]
    lift_f = zeroed[1] if has_lift else np.full(n, np.nan)
    if not raw.extra:  # a captive run's drag is the balance's −fx
        check_drag_direction(drag_f[s0:s1], u_set)
    u_u = p.speed_tolerance * u_set / math.sqrt(3.0)
    notes.append(f"speed: the set speed {u_set:g} m/s of the run sheet (no speed channel; "
                 f"u = {u_u:.2g} m/s from speed_tolerance = {p.speed_tolerance:g}); no "
                 "acceleration, so the run is not used for the added masses")
    speed = np.full(n, np.nan)
    speed[s0:s1] = u_set  # the set speed over the steady window; unknown elsewhere
    accel = np.zeros(n)
    ph = phases.Phases(still_pre=None if not from_start else pre, accel=None, steady=steady,
                       decel=None, still_post=post, motion=steady, speed_level=u_set,
                       accel_level=None)
    windows = ph.windows_s(t)
    return RunReduction(
        run=run, file=file, sha256=raw.sha256, fs=fs, n_samples=raw.n,
        duration_s=float(t[-1] - t[0]), windows=windows, window_source=window_source,
        speed_level=u_set, speed_mean=u_set, speed_std=math.nan, accel_mean=math.nan,
        zero_drag=zeros[0], drift_drag=drifts[0],
        zero_lift=zeros[1] if has_lift else math.nan,
        drift_lift=drifts[1] if has_lift else math.nan,
        drag_mean_raw=float(np.mean(drag_f[s0:s1])), drag_std=float(np.std(drag_f[s0:s1])),
        lift_mean_raw=float(np.mean(lift_f[s0:s1])) if has_lift else math.nan,
        steady_regressors=(u_set * u_set, u_set, 0.0),
        samples=fit_samples(t, speed, accel, drag_f, lift_f, steady, ph, math.nan, fs, p),
        thumb=thumbnail(t, speed, accel, drag_f, lift_f, fs),
        has_lift=has_lift, notes=tuple(notes), warnings=tuple(warnings),
        series=series_of(t, speed, accel, drag_f, lift_f, ph, steady) if keep_series else None,
        speed_source="nominal", speed_u=u_u,
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
    *, steady_required: bool, still_required: bool = True,
) -> phases.Phases:
    """The run's phases from the filtered speed, with the protocol's settings; a run may start
    in motion (``still_required`` False) when its zero comes from a zeros file or from
    ``zero_at = "file_start"``."""
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
        still_required=still_required,
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
    A run that starts in motion (``ph.still_pre`` None) takes a force's zero from ``levels``
    (held from the file's start, drift to the post-run window as usual), else from the still
    window after the stop, held constant (``zero_at = "file_start"``; no drift correction);
    with neither it is rejected.
    """
    levels = levels or {}
    pre = ph.still_pre
    cols = [(1, "drag")] + ([(2, "lift")] if has_lift else [])
    after = [name for _, name in cols if pre is None and name not in levels]
    if after:
        if ph.still_post is None:
            raise RunError(
                "the file starts in motion and does not end at rest: there is no still window "
                "for the zero (give the balance zero in a zeros file, [zeros])")
        w = ph.still_post
        notes.append(
            f"the file starts in motion: the {' and '.join(after)} zero is the still window "
            f"after the stop ({t[w[0]]:.2f}–{t[w[1] - 1]:.2f} s), held constant (no drift "
            "correction)")
    post = ph.still_post if p.drift == "linear" else None
    if p.drift == "linear" and ph.still_post is None:
        notes.append("the file does not end at rest: zero held constant (no drift correction)")
    elif p.drift == "none":
        notes.append("zero held constant ([processing] drift = \"none\")")
    out: list[np.ndarray] = []
    zeros: list[float] = []
    warnings: list[str] = []

    def base(k: int, name: str) -> float:
        if name in levels:
            return float(levels[name])
        w = pre if pre is not None else ph.still_post
        assert w is not None
        return float(np.mean(filt[w[0] : w[1], k]))

    steady_force = max(
        abs(float(np.mean(filt[steady[0] : steady[1], k])) - base(k, name)) for k, name in cols
    )
    for k, name in cols:
        force = filt[:, k]
        if name in after:  # the zero after the stop, constant
            z = base(k, name)
            out.append(force - z)
            zeros += [z, 0.0]
            continue
        if post is not None and post[1] - post[0] >= 2:
            check_drift(t, force, pre, post, steady_force, name, levels.get(name), notes,
                         warnings)
        zero, z, drift = conditioning.zero_line(t, force, pre, post, level=levels.get(name))
        out.append(force - zero)
        zeros += [z, drift]
    if not has_lift:
        out.append(np.full(t.shape, np.nan))
        zeros += [math.nan, math.nan]
    return out[0], out[1], (zeros[0], zeros[1], zeros[2], zeros[3]), warnings


@dataclass(frozen=True)
class NominalChecks:
    """What :func:`nominal_checks` found: every note in order, the warnings among them
    (the sheet or the carriage is off) and the note of a missing acceleration stretch ("" for
    none; one of ``notes``, a warning only for a run made for its acceleration)."""

    notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()
    accel_missing: str = ""


def nominal_checks(
    speed_mean: float,
    accel_mean: float,
    ph: phases.Phases,
    p: Processing,
    *,
    speed_nominal: float,
    accel_nominal: float,
) -> NominalChecks:
    """Cross-checks of the measured plateau speed [m/s] and acceleration [m/s²] against
    the sheet's set values."""
    notes: list[str] = []
    warnings: list[str] = []
    accel_missing = ""
    tol = p.nominal_tolerance
    if math.isfinite(speed_nominal) and speed_nominal > 0:
        if abs(speed_mean - speed_nominal) > tol * speed_nominal:
            warnings.append(
                f"measured plateau speed {speed_mean:.3f} m/s differs from the set "
                f"{speed_nominal:g} m/s by more than {100 * tol:g} %"
            )
            notes.append(warnings[-1])
    if math.isfinite(accel_nominal) and accel_nominal > 0:
        if ph.accel is None:
            accel_missing = (
                f"no usable constant-acceleration stretch although the sheet sets "
                f"{accel_nominal:g} m/s² (absent, or shorter than {p.min_accel_s:g} s after "
                f"trimming {p.trim:.2f} s at each end); the run is used for its steady phase"
            )
            notes.append(accel_missing)
        elif abs(accel_mean - accel_nominal) > 2 * tol * accel_nominal:
            warnings.append(
                f"measured acceleration {accel_mean:.3f} m/s² differs from the set "
                f"{accel_nominal:g} m/s² by more than {200 * tol:g} %"
            )
            notes.append(warnings[-1])
    return NominalChecks(tuple(notes), tuple(warnings), accel_missing)


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


#: Blocks of the steady window whose means give the steady drag's standard error for
#: :func:`check_drag_direction` (block means outlast the filtered noise's correlation).
DIRECTION_BLOCKS = 8
#: How many of those standard errors the steady drag must lie on the side of the motion to
#: be rejected (t with 7 degrees of freedom: 5 is p < 0.002 for a drag that is truly 0).
DIRECTION_SIGMAS = 5.0


def check_drag_direction(drag: np.ndarray, speed: float) -> None:
    """Reject a run whose steady drag [N] (zero and drift removed, tare still in) points
    along the tow at the mean steady ``speed`` [m/s]: every towed body's drag opposes its
    motion (positive for a forward tow, negative for a backward one), so a drag on the other
    side of zero by :data:`DIRECTION_SIGMAS` standard errors of its
    :data:`DIRECTION_BLOCKS` block means is a reversed drag channel, a drag and lift cable
    swapped, or a zero taken while towing. Captive runs, whose drag is the balance's −fx,
    are not checked."""
    if not speed or drag.size < 2 * DIRECTION_BLOCKS:
        return
    along = drag * math.copysign(1.0, speed)
    means = np.array([b.mean() for b in np.array_split(along, DIRECTION_BLOCKS)])
    mean = float(along.mean())
    se = float(np.std(means, ddof=1)) / math.sqrt(DIRECTION_BLOCKS)
    if mean < -DIRECTION_SIGMAS * se:
        raise RunError(
            f"the steady drag is {mean * math.copysign(1.0, speed):+.3g} N at "
            f"{speed:+.3g} m/s, {-mean / se:.0f} standard errors on the side of the motion, "
            "where a towed body's drag opposes it (is the drag channel's sign reversed, the "
            "drag and lift cables swapped, or the zero taken while towing?)")


def check_fin_lift(raw: RawRun, config: str, file: str) -> None:
    """Reject a fin run without its lift: a lift column that holds no numbers (every cell
    blank), or no lift column in the file at all.

    The reader leaves a blank column out with a note ("the lift column holds no numbers"), and
    a lift column the protocol does not name is optional, which is right for a hull run (its
    lift is a check, used in no coefficient) but not for a fin run: its C_L is what the fin
    analysis is for, and without it the run would be kept with its lift dropped, its speed
    group losing a slope angle to no visible cause. The sentence names the channel and its
    column, as :func:`check_force_signal` does for a channel of one constant value, or the
    columns the file has.
    """
    if config.strip().lower() != "fin" or raw.lift is not None:
        return
    if "lift" in raw.blank:
        raise RunError(
            f"{file}: the lift channel (column '{raw.blank['lift']}') holds no numbers, every "
            "cell blank, and a fin run needs its lift (a channel not recorded, an unplugged "
            "cable, or the wrong column?)"
        )
    raise RunError(
        f"{file}: the file has no lift column (columns found: {name_list(raw.columns)}), and "
        "a fin run needs its lift (a channel not recorded, or a lift column under another "
        "name: map it under [channels] lift)"
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
    series = dict(red.series) if red.series is not None else None
    # the whole-run curves need the speed at every sample: a run without a measured speed
    # keeps its tare in them (its set speed is known over the steady window only)
    curves = [c for c in (th, series) if c is not None and red.speed_source == "measured"]
    for c in curves:
        c["drag"] = c["drag"] - tare.drag(c["U"], c["a"])
    if tare.lift is not None and red.has_lift:
        s["lift"] = s["lift"] - tare.lift(s["U"], s["a"])
        for c in curves:
            c["lift"] = c["lift"] - tare.lift(c["U"], c["a"])
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
        notes=tuple(notes),
        warnings=tuple(warn),
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


Record = tuple[int, RunReduction | None, Rejection | None, dict[str, np.ndarray] | None]


def sheet_segment(row: dict[str, Any]) -> int | None:
    """The run sheet's ``segment`` of a row (the run's acquisition in a file holding several,
    from 1), None when the sheet gives none (``[read] segment`` then applies)."""
    value = row.get("segment", math.nan)
    try:
        k = float(value)
    except (TypeError, ValueError):
        return None
    return int(k) if math.isfinite(k) and k >= 1 else None


def reduce_record(protocol: Protocol, row: dict[str, Any], *, debug: bool = False,
                  keep_series: bool = False) -> Record:
    """Read and reduce the run of one run-sheet row; never raises for a data problem.

    Returns (run, reduction, None, None), or (run, None, rejection, preview) where
    ``rejection`` (:class:`towtank.messages.Rejection`) says what is wrong, and ``preview`` is
    :func:`run_preview` of a run that was read but could not be reduced (None when it could
    not be read). An unexpected error (a bug) is reported the same way, or raised with
    ``debug``.
    """
    run = int(row["run"])
    file = str(row["file"])
    raw = None
    try:
        p = protocol.processing
        nominal = None
        if p.speed_source == "nominal":  # no measured speed: the sheet's set speed
            nominal = float(row.get("speed_nominal", math.nan))
            if not (math.isfinite(nominal) and nominal > 0):
                raise RunError("[processing] speed_source = \"nominal\" takes the speed from "
                               "the run sheet, and the run has no speed_nominal there")
        folder = protocol.campaign.data_dir
        raw, stamp = load_record(protocol, folder, file, run, speed_nominal=nominal,
                                 segment=sheet_segment(row), test=str(row.get("test", "")))
        raw = zeroed_record(protocol, raw, folder, file, run)
        ws = row.get("window_start_s", math.nan)
        we = row.get("window_end_s", math.nan)
        window = (float(ws), float(we)) if math.isfinite(ws) and math.isfinite(we) else None
        red = reduce_read(
            protocol,
            raw,
            run=run,
            file=file,
            window_s=window,
            speed_nominal=float(row.get("speed_nominal", math.nan)),
            accel_nominal=float(row.get("accel_nominal", math.nan)),
            test=str(row.get("test", "")),
            keep_series=keep_series,
            row=row,
        )
        return run, replace(red, file_stamp=stamp), None, None
    except RunError as exc:
        return run, None, Rejection.of_run_error(run, file, exc.reason), _safe_preview(raw)
    except Exception as exc:  # noqa: BLE001 - a bug must not stop the day
        if debug:
            raise
        return run, None, Rejection(run, file, "reduce", _internal_error_sentence(exc),
                                    "internal_error"), None


Stamp = tuple[int, int, int, int]  # (size, mtime_ns, ctime_ns, inode)

def load_record(protocol: Protocol | None, folder: Path, file: str, run: int, *,
                speed_nominal: float | None = None, segment: int | None = None,
                test: str = "") -> tuple[RawRun, Stamp | None]:
    """Load one run's file as the day does, zeros aside (:func:`zeroed_record`).

    ``folder / file`` is the file: the data folder and the run sheet's name for it (the
    carriage log of ``[speed_log]`` is found from both and the run number ``run``).
    ``protocol``: its ``[channels]``, ``[read]``, ``[balance]`` and ``[processing]`` checks;
    None: the canonical channel names in SI units and the default checks.
    ``speed_nominal``: the set speed [m/s] of a run without a measured speed
    (``speed_source = "nominal"``; no carriage log then). ``segment``: the acquisition of a
    file holding several, counted from 1. ``test``: the sheet's test (a captive test reads
    the balance's and the PMM's channels too, :func:`towtank.ingest.runfile.load_run`).
    Returns the run and the file's (size, mtime_ns,
    ctime_ns, inode) as its bytes were read (None when it changed meanwhile).
    """
    path = folder / file
    data, stamp = file_bytes_stamped(path)
    p = Processing() if protocol is None else protocol.processing
    log = (run_speed_log(protocol.speed_log, folder, file, run)
           if protocol is not None and speed_nominal is None else None)
    raw = load_run(
        path,
        channel_map({}) if protocol is None else protocol.channels,
        max_nan_gap_s=p.max_nan_gap_s,
        max_bad_row_fraction=p.max_bad_row_fraction,
        do_despike=p.despike,
        data=data,
        options=None if protocol is None else protocol.read,
        balance=None if protocol is None else protocol.balance,
        speed_log=log,
        speed_nominal=speed_nominal,
        segment=segment,
        test=test,
    )
    return raw, stamp


def zeroed_record(protocol: Protocol | None, raw: RawRun, folder: Path, file: str,
                  run: int) -> RawRun:
    """The run with the zeros of the protocol's ``[zeros]`` file (at the run file's rate,
    tapered over the run's trim); the run as it is without ``[zeros]``."""
    if protocol is None:
        return raw
    zeros = run_zero_levels(protocol.zeros, folder, file, run, protocol.channels,
                            protocol.read, protocol.balance, fs=raw.fs,
                            taper_s=protocol.processing.trim)
    return with_zero_levels(raw, *zeros) if zeros is not None else raw


def reduce_read(protocol: Protocol | None, raw: RawRun, *, run: int, file: str,
                window_s: tuple[float, float] | None = None,
                speed_nominal: float = math.nan, accel_nominal: float = math.nan,
                test: str = "", keep_series: bool = False,
                row: dict[str, Any] | None = None) -> RunReduction:
    """Reduce a run read by :func:`load_record` as the day does (before tare).

    :func:`reduce_run` with the protocol's ``[processing]``, then: a note and a warning per
    channel that looks like a force and that no ``[channels]`` entry uses
    (:func:`unmapped_force_warnings`), the channels' units with their notes
    (:func:`units_notes`), and by the sheet's ``test``: an ``accel`` run without a usable
    constant-acceleration stretch is warned of, a ``steady`` run is not noted for it, a
    captive test is reduced to its loads (``RunReduction.captive``,
    :func:`towtank.reduce.captive_record.reduce_captive_record`) with the settings of its run
    sheet ``row`` (a captive test needs the protocol and the row).
    ``window_s`` [s], ``speed_nominal`` [m/s], ``accel_nominal`` [m/s²]: the sheet's; a run
    whose ``row`` says config ``fin`` and whose lift column holds no numbers is rejected first
    (:func:`check_fin_lift`).
    """
    check_fin_lift(raw, str((row or {}).get("config", "")), file)
    red = reduce_run(raw, Processing() if protocol is None else protocol.processing,
                     run=run, file=file, window_s=window_s, speed_nominal=speed_nominal,
                     accel_nominal=accel_nominal, keep_series=keep_series)
    columns = tuple(c for c in raw.columns if c not in raw.extra_columns)
    unmapped = (() if protocol is None
                else tuple(unmapped_force_warnings(protocol, columns, file)))
    notes = (*red.notes, *unmapped, *units_notes(raw.units))
    warnings = (*red.warnings, *unmapped)
    kind = test.strip().lower()
    if red.accel_missing and kind == "accel" and red.windows["accel"] is None:
        # a run made for its acceleration without one: the engineer must hear of it
        warnings = (*warnings, red.accel_missing)
    elif red.accel_missing and kind == "steady":  # made for its plateau: no news
        notes = tuple(n for n in notes if n != red.accel_missing)
    captive: dict[str, np.ndarray] = {}
    if test in CAPTIVE_TESTS:
        if protocol is None or row is None:
            raise RunError(f"a {test} run is reduced with its run sheet row's settings and the "
                           "protocol's [model]: the protocol and its sheet's row are needed")
        captive, more, warned = reduce_captive_record(protocol, raw, red.windows, row,
                                                      run=run, file=file)
        notes, warnings = (*notes, *more), (*warnings, *warned)
    return replace(red, notes=notes, warnings=warnings, units=dict(raw.units), captive=captive)


def unmapped_force_warnings(protocol: Protocol, columns: tuple[str, ...], file: str
                            ) -> list[str]:
    """One sentence per channel of the run file that looks like a force, or a load cell of
    one, and that no [channels] (or [balance]) entry uses: ``DragR`` beside a mapped ``DragL``
    is half the drag left out (:func:`towtank.ingest.describe.unmapped_forces`)."""
    used: set[str] = set()
    for cm in channel_map(protocol.channels).values():
        used.update(cm.columns or (cm.column,))
    if protocol.balance is not None:
        used.update(protocol.balance.inputs)
    out = []
    parts = force_parts([c for c in columns if not c.startswith("__")])
    for c in unmapped_forces(columns, used):
        cells = next((v for v in parts.values() if c in v), None)
        hint = (f"if the force is the sum of its load cells, map it as columns = "
                f"[{', '.join(chr(34) + x + chr(34) for x in cells)}]" if cells else
                "map it in [channels] if it is part of a force")
        out.append(f"{file}: the channel '{c}' looks like a force or a load cell of one, but "
                   f"no [channels] entry uses it, so it is in no force ({hint})")
    return out


def record_units(red: RunReduction, raw: RawRun) -> RunReduction:
    """``red`` with the run's units and their sources (``raw.units``) and notes (in
    runs.csv) naming the channels whose unit was assumed (:func:`units_notes`): a new
    reduction, ``red`` is not changed."""
    return replace(red, units=dict(raw.units), notes=(*red.notes, *units_notes(raw.units)))


def units_notes(units: dict[str, tuple[str, str]]) -> list[str]:
    """The notes of a run whose channels had no unit label (``drag and lift had no unit label:
    taken as N``) or one towtank does not convert (``drag's unit label 'lb' is not one towtank
    converts: taken as N``); [] when every unit was stated and known."""
    by_unit: dict[str, list[str]] = {}
    out = []
    for canon, (unit, source) in units.items():
        if source == "assumed":
            by_unit.setdefault(unit, []).append(canon)
    if by_unit:
        names = [c for chans in by_unit.values() for c in chans]
        taken = "; ".join(f"{_and(chans)} taken as {u}" for u, chans in by_unit.items()) \
            if len(by_unit) > 1 else f"taken as {next(iter(by_unit))}"
        out.append(f"{_and(names)} had no unit label: {taken}")
    out += [f"{canon}'s unit label '{unit}' is not one towtank converts: taken as "
            f"{UNITS.get(canon, 'SI')}" for canon, (unit, source) in units.items()
            if source == "unknown"]
    return out


def _and(names: list[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]


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
    return run, None, Rejection(
        run, file, "reduce",
        "the process reducing it stopped abruptly (killed, out of memory, or a crash inside "
        "a reading library); the file is left as it is", "crashed"), None
