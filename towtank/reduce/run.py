"""Per-run reduction: from a run's calibrated channels to its phases, means and fit samples.

:func:`reduce_run` takes a :class:`~towtank.ingest.runfile.RawRun` and does, in this order
(METHOD.md,
"A run"): filter the speed and find the phases from it; zero the forces on the still window
before the run and remove the drift to the still window after it; filter the forces with the
same zero-phase low-pass as the speed; take acceleration from the filtered speed (or from an
accel channel filtered the same way); average over the trimmed steady window; keep decimated
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
from towtank.ingest.runfile import RawRun, file_bytes, load_run
from towtank.reduce.tare import TareModel
from towtank.signal import conditioning, phases

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
) -> RunReduction:
    """Reduce one run (before tare).

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
    """
    fs = raw.fs
    t = raw.time
    p = processing
    notes = list(raw.notes)
    if p.cutoff_hz >= 0.5 * fs:
        raise RunError(
            f"the low-pass cut-off of [processing] cutoff_hz = {p.cutoff_hz:g} Hz is not below "
            f"half the file's sample rate ({fs:g} Hz / 2), so the run cannot be filtered"
        )
    # one zero-phase filter, identical for every channel
    forces = [raw.drag] + ([raw.lift] if raw.lift is not None else [])
    stack = np.column_stack([raw.speed] + forces + ([raw.accel] if raw.accel is not None else []))
    filt = conditioning.lowpass(stack, fs, p.cutoff_hz, p.filter_order)
    speed_f = filt[:, 0]
    if raw.accel is not None:
        accel_f = filt[:, -1]
    else:
        accel_f = conditioning.derivative(speed_f, fs)

    ph = phases.detect_phases(
        t,
        speed_f,
        accel_f,
        fs,
        trim_s=p.trim,
        min_steady_s=p.min_steady_s,
        min_accel_s=p.min_accel_s,
        zero_window_s=p.zero_window_s,
        steady_tolerance=p.steady_tolerance,
        steady_required=window_s is None,
    )
    windows = ph.windows_s(t)
    manual_warnings: list[str] = []
    if window_s is None:
        assert ph.steady is not None
        steady = ph.steady
        window_source = "detected"
    else:
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

    # zero and drift: on the raw forces' still windows, then the same filter (linear, so the
    # order does not matter) -- subtract the zero line from the filtered force
    zero_d, z_d, drift_d = conditioning.zero_line(t, raw.drag, ph.still_pre, ph.still_post)
    drag_f = filt[:, 1] - zero_d
    if raw.lift is not None:
        zero_l, z_l, drift_l = conditioning.zero_line(t, raw.lift, ph.still_pre, ph.still_post)
        lift_f = filt[:, 2] - zero_l
    else:
        z_l = drift_l = math.nan
        lift_f = np.full(t.shape, np.nan)
    if ph.still_post is None:
        notes.append("the file does not end at rest: zero held constant (no drift correction)")

    s0, s1 = steady
    u_s = speed_f[s0:s1]
    speed_mean = float(np.mean(u_s))
    accel_mean = math.nan
    if ph.accel is not None:
        accel_mean = float(np.mean(accel_f[ph.accel[0] : ph.accel[1]]))

    # cross-checks against the sheet's set values (warnings: the sheet or the carriage is off)
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

    warn = (
        [n for n in raw.notes if WARNED_REPAIRS in n]  # dropped rows: said, not only noted
        + manual_warnings
        + [n for n in notes[n_notes:] if "differs from the set" in n]
    )

    # decimated fit samples: steady and constant-acceleration windows
    rate = p.fit_sample_hz or 4.0 * p.cutoff_hz
    idx_s = conditioning.decimate_indices(s0, s1, fs, rate)
    idx_a = (
        conditioning.decimate_indices(ph.accel[0], ph.accel[1], fs, rate)
        if ph.accel is not None
        else np.array([], dtype=int)
    )
    idx = np.concatenate([idx_s, idx_a])
    # Each sample's acceleration is its window's mean: within a trimmed steady or constant-
    # acceleration window the carriage's acceleration is constant, and the sample-by-sample
    # derivative of the (noisy) speed would put noise into a regressor, which biases the fitted
    # inertia toward zero (errors in variables: attenuation by var(noise)/var(a), ~0.2 % of the
    # transverse added mass at 1 mm/s speed noise).
    a_steady = float(np.mean(accel_f[s0:s1]))
    a_accel = accel_mean if ph.accel is not None else math.nan
    samples = {
        "phase": np.concatenate(
            [np.full(idx_s.size, PHASE_STEADY), np.full(idx_a.size, PHASE_ACCEL)]
        ).astype(np.int8),
        "t": t[idx],
        "U": speed_f[idx],
        "a": np.concatenate([np.full(idx_s.size, a_steady), np.full(idx_a.size, a_accel)]),
        "drag": drag_f[idx],
        "lift": lift_f[idx],
    }
    step = max(1, int(round(fs / THUMB_HZ)))
    thumb = {
        "t": t[::step].copy(),
        "U": speed_f[::step].copy(),
        "a": accel_f[::step].copy(),
        "drag": drag_f[::step].copy(),
        "lift": lift_f[::step].copy(),
    }
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
        zero_drag=z_d,
        drift_drag=drift_d,
        zero_lift=z_l,
        drift_lift=drift_l,
        drag_mean_raw=float(np.mean(drag_f[s0:s1])),
        drag_std=float(np.std(drag_f[s0:s1])),
        lift_mean_raw=float(np.mean(lift_f[s0:s1])) if raw.lift is not None else math.nan,
        steady_regressors=(
            float(np.mean(u_s * np.abs(u_s))),
            speed_mean,
            float(np.mean(a_s)),
        ),
        samples=samples,
        thumb=thumb,
        has_lift=raw.lift is not None,
        notes=notes,
        warnings=warn,
    )


def apply_tare(red: RunReduction, tare: TareModel | None) -> RunReduction:
    """Subtract a tare group's F_tare(U, a) sample by sample (METHOD.md "Sting tare").

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
    if tare.lift is not None and red.has_lift:
        s["lift"] = s["lift"] - tare.lift(s["U"], s["a"])
        th["lift"] = th["lift"] - tare.lift(th["U"], th["a"])
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


def reduce_record(protocol: Protocol, row: dict[str, Any], *, debug: bool = False) -> Record:
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
        data = file_bytes(path)
        raw = load_run(
            path,
            protocol.channels,
            max_nan_gap_s=p.max_nan_gap_s,
            max_bad_row_fraction=p.max_bad_row_fraction,
            do_despike=p.despike,
            data=data,
            options=protocol.read,
            balance=protocol.balance,
        )
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
        )
        if str(row.get("test", "")).strip().lower() == "accel" and red.windows["accel"] is None:
            # a run made for its acceleration without one: the engineer must hear of it
            red.warnings.extend(n for n in red.notes if n.startswith("no usable constant-acc"))
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
