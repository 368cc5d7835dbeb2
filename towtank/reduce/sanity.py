"""Whether a run's reduction read back from the cache is one :func:`~towtank.reduce.run.
reduce_run` can have made.

The cache (:mod:`towtank.runtime.cache`) checks every record's fields against their types; a
record of the right types can still be no reduction at all: bool or integer samples, a NaN or
infinite mean, an empty or ragged sample table, a negative sample count. Such a record would
stop the day later (a singular fit, a math domain error), so :func:`reduction_problem` checks
every value against what a reduction produces, and the cache takes a record it finds fault
with as a miss: the run is reduced again and its fresh reduction replaces the record.
"""

from __future__ import annotations

import math
import re

import numpy as np

from towtank.reduce.run import PHASE_ACCEL, PHASE_STEADY, THUMB_HZ, RunReduction
from towtank.runtime.records import table_length
from towtank.signal.phases import PHASE_NAMES

__all__ = ["reduction_problem", "sane_reduction"]

#: The columns of the fit samples and of the whole-run series (floats, then the phase).
SAMPLE_COLUMNS = ("t", "U", "a", "drag", "lift")
#: Where a channel's unit came from (:func:`towtank.ingest.calibration.unit_source`).
UNIT_SOURCES = ("file", "protocol", "assumed", "unknown")
SPEED_SOURCES = ("measured", "nominal")
_SHA256 = re.compile(r"[0-9a-f]{64}")


def _finite(*values: float) -> bool:
    return all(math.isfinite(v) for v in values)


def _lift_ok(values: np.ndarray | float, has_lift: bool) -> bool:
    """Lift values are finite on a run with a lift channel, NaN on one without."""
    x = np.asarray(values)
    return bool(np.isfinite(x).all()) if has_lift else bool(np.isnan(x).all())


def _windows_problem(windows: dict[str, tuple[float, float] | None]) -> str | None:
    if set(windows) != set(PHASE_NAMES):
        return "its phase windows are not the five phases"
    if windows["steady"] is None:
        return "it has no steady window"
    for name, w in windows.items():
        if w is not None and not (_finite(*w) and w[0] <= w[1]):
            return f"its {name} window is not a time span"
    return None


def _tables_problem(red: RunReduction) -> str | None:
    """The sample tables: columns, dtypes and lengths as :func:`~towtank.reduce.run.
    fit_samples`, :func:`~towtank.reduce.run.thumbnail` and ``series_of`` make them."""
    n_fit = table_length(red.samples, SAMPLE_COLUMNS, ("phase",))
    n_thumb = table_length(red.thumb, SAMPLE_COLUMNS)
    if n_fit is None or n_thumb is None:
        return "its sample tables are not columns of floats of one length"
    step = max(1, int(round(red.fs / THUMB_HZ)))
    if n_thumb != -(-red.n_samples // step) or n_fit > red.n_samples:
        return "its sample tables do not match its sample count"
    if red.series is not None and (
            table_length(red.series, SAMPLE_COLUMNS, ("phase",)) != red.n_samples
            or not np.isin(red.series["phase"], np.arange(-1, len(PHASE_NAMES))).all()):
        return "its whole-run series is not one of the run's samples"
    s, th = red.samples, red.thumb
    if not np.isin(s["phase"], (PHASE_STEADY, PHASE_ACCEL)).all():
        return "a fit sample is of no phase"
    if not all(np.isfinite(s[k]).all() for k in ("t", "U", "a", "drag")) \
            or not all(np.isfinite(th[k]).all() for k in ("t", "drag")) \
            or np.isinf(th["U"]).any() or np.isinf(th["a"]).any():
        return "its samples are not finite"
    if not (_lift_ok(s["lift"], red.has_lift) and _lift_ok(th["lift"], red.has_lift)):
        return "its lift samples do not match its lift channel"
    accel_samples = int(np.count_nonzero(s["phase"] == PHASE_ACCEL))
    if math.isnan(red.accel_mean) != (accel_samples == 0):
        return "its acceleration mean does not match its acceleration samples"
    return None


def _means_problem(red: RunReduction) -> str | None:
    """The scalars: finite where a reduction always has a value, NaN where it has none."""
    if not (_finite(red.fs, red.duration_s) and red.fs > 0 and red.duration_s >= 0
            and red.n_samples >= 2):
        return "its sample rate, duration or sample count is not one of a run"
    if not _finite(red.speed_level, red.speed_mean, red.zero_drag, red.drift_drag,
                   red.drag_mean_raw, red.drag_std, *red.steady_regressors) \
            or red.drag_std < 0 or math.isinf(red.accel_mean):
        return "a mean of it is not finite"
    if not _lift_ok(np.array([red.zero_lift, red.drift_lift, red.lift_mean_raw]),
                    red.has_lift):
        return "its lift means do not match its lift channel"
    measured = red.speed_source == "measured"
    # measured: the spread of the measured speed, no set speed's uncertainty; nominal: the
    # reverse
    given, absent = (red.speed_std, red.speed_u) if measured else (red.speed_u, red.speed_std)
    if red.speed_source not in SPEED_SOURCES or not (_finite(given) and given >= 0
                                                      and math.isnan(absent)):
        return "its speed's spread does not match its speed source"
    if (red.tare_drag, red.tare_lift, red.tare_group) != (0.0, 0.0, "") \
            or not (math.isnan(red.drag_mean) and math.isnan(red.lift_mean)):
        return "it holds a tare, which is applied after the cache"
    return None


def reduction_problem(red: RunReduction) -> str | None:
    """Why ``red`` is no reduction :func:`~towtank.reduce.run.reduce_run` can have made
    (before its tare), in a few words, or None when it is one.

    Checked: the file name and sha256; the sample rate [Hz] finite > 0, the sample count >=
    2 and the duration [s] finite >= 0; the fit samples, thumbnail and series as columns of
    float64 (the phase an integer of a known phase) of one non-zero length consistent with
    the sample count; the phase windows [s]; every mean [N, m/s, m/s²] finite, the lift's
    finite with a lift channel and NaN without; the acceleration mean NaN exactly when there
    is no acceleration sample; the speed's spread as its source gives it; no tare yet; the
    channels' unit sources.
    """
    if not red.file or not _SHA256.fullmatch(red.sha256):
        return "it names no file or no sha256"
    if red.file_stamp is not None and min(red.file_stamp) < 0:
        return "its file stamp is not one of a file"
    if any(src not in UNIT_SOURCES for _, src in red.units.values()):
        return "a channel's unit source is unknown"
    return (_means_problem(red) or _windows_problem(red.windows)
            or _tables_problem(red))


def sane_reduction(red: RunReduction) -> bool:
    """Whether ``red`` is a reduction :func:`~towtank.reduce.run.reduce_run` can have made
    (:func:`reduction_problem` finds nothing): the cache's check of a record read back."""
    return reduction_problem(red) is None
