"""Carriage speed from its own file: the motion controller's log of each run (``[speed_log]``).

Many tanks log the carriage on the motion controller, in a file per run, at another rate and
on another clock than the balance. The log gives the speed directly, or the carriage position,
whose derivative is the speed. Its samples are brought onto the run file's time base by linear
interpolation after shifting the log's clock:

    t_run = t_log + offset_s                                                         (1)

    U(t_run) = interp(t_run; t_log + offset_s, U_log)                                (2)

    U_log = dx/dt (central differences, numpy.gradient) when the log gives position x  (3)

Before the log starts and after it ends the carriage must be still (the log's first and last
speeds are held); a log that stops while the carriage moves does not cover the run and rejects
it. The speed then goes through the same zero-phase filter as the forces (docs/method.md), so
a 100 Hz log and a 1 kHz balance give the same filtered speed.
"""

from __future__ import annotations

import hashlib
import math
from pathlib import Path, PurePosixPath
from typing import Any

import numpy as np

from towtank.errors import ProtocolError, RunError
from towtank.ingest.columns import fallback_time, file_bytes, read_columns
from towtank.ingest.protocol_types import SpeedLog
from towtank.ingest.readers import (
    FS_ERROR_KEY,
    TIME_COLUMN_KEY,
    column_unit,
    name_list,
    stated_units,
    unit_factor,
)

__all__ = ["SpeedLog", "log_path", "read_speed_log", "speed_on_run_time",
           "STILL_FRACTION"]

#: The log's first and last speeds count as "still" below this fraction of its peak speed [-].
STILL_FRACTION = 0.02


def log_path(spec: Any, data_dir: Path, file: str, run: int) -> Path:
    """The log (or zeros file: any spec with a ``file`` pattern) of the run in ``file``
    (relative to ``data_dir``) with number ``run``."""
    rel = PurePosixPath(str(file).replace("\\", "/"))
    name = rel.name
    stem = name.split(".", 1)[0] if not name.startswith(".") else name
    folder = str(rel.parent)
    return data_dir / spec.file.format(stem=stem, name=name, dir=folder, run=run)


def read_speed_log(path: Path, spec: SpeedLog, data: bytes) -> tuple[np.ndarray, np.ndarray]:
    """The log's time on the run file's clock [s] (eq. 1) and the carriage speed [m/s].

    The log is read in any layout towtank reads (format detected from its name and content),
    its columns' units taken from the file or header when no gain is given.
    """

    name = path.name
    cols, _ = read_columns(path, data)
    units = stated_units(cols)
    found = [c for c in cols if not c.startswith("__")]
    stripped = {c.strip(): c for c in found}

    def channel(col: tuple[str, float, float], canon: str) -> np.ndarray:
        column, gain, offset = col
        key = column if column in cols else stripped.get(column.strip())
        if key is None and column.strip() == "time" and TIME_COLUMN_KEY in cols:
            key = cols[TIME_COLUMN_KEY].item()[0]  # the file's own time (LVM X_Value)
        if key is None:
            listed = name_list(found)
            raise RunError(f"the speed log {name} has no column '{column}' ({canon}); columns "
                           f"found: {listed}")
        raw = np.asarray(cols[key])
        try:
            arr = raw.astype(np.float64)
        except (TypeError, ValueError):
            arr = np.array([_number(v) for v in raw], dtype=np.float64)
        if gain != 1.0 or offset != 0.0:
            return gain * (arr - offset)
        unit = column_unit(key, units)
        return arr * unit_factor("speed" if canon == "speed" else canon, unit, key, name)

    t = channel(spec.time, "time") if spec.time is not None else _own_time(cols, name)
    if spec.position:
        x = channel(spec.position, "position")
    elif spec.speed is not None:
        x = channel(spec.speed, "speed")
    else:
        raise ProtocolError(f"the speed log {name}: [speed_log] needs either 'speed' or "
                            "'position' (one of them).")
    ok = np.isfinite(t) & np.isfinite(x)
    t, x = t[ok], x[ok]
    if t.size < 3:
        raise RunError(f"the speed log {name} holds fewer than 3 numeric samples")
    if np.any(np.diff(t) <= 0):
        i = int(np.argmax(np.diff(t) <= 0))
        raise RunError(f"the speed log {name}: its time does not increase after t = {t[i]:.4g} s")
    u = np.gradient(x, t) if spec.position else x
    return t + spec.offset_s, u


def _own_time(cols: dict[str, Any], name: str) -> np.ndarray:
    """The time [s] a log without a time column carries (``[speed_log]`` without ``time``):
    its own timing, found as for a run file (LVM's ``X_Value``, LabVIEW waveform timing, a
    stated sample rate, a rate in an HDF5 group's name); RunError when it has none."""

    if TIME_COLUMN_KEY in cols:
        return np.asarray(cols[cols[TIME_COLUMN_KEY].item()[0]], dtype=np.float64)
    t = fallback_time(cols, {})
    if t is None:
        why = f" ({cols[FS_ERROR_KEY].item()})" if FS_ERROR_KEY in cols else ""
        raise RunError(f"the speed log {name} has no timing of its own{why}: give [speed_log] "
                       "time = { column = \"...\" }")
    return t


def _number(v: Any) -> float:
    try:
        return float(str(v).replace(",", "."))
    except ValueError:
        return math.nan


def speed_on_run_time(t_run: np.ndarray, t_log: np.ndarray, u_log: np.ndarray,
                      name: str) -> np.ndarray:
    """Carriage speed [m/s] at the run file's times (eq. 2); the log's end speeds are held
    where it does not reach, if the carriage is still there, else RunError."""
    peak = float(np.max(np.abs(u_log))) if u_log.size else 0.0
    still = STILL_FRACTION * peak
    before, after = t_run[0] < t_log[0], t_run[-1] > t_log[-1]
    moving_start, moving_end = abs(u_log[0]) > still, abs(u_log[-1]) > still
    if (before and moving_start) or (after and moving_end):
        raise RunError(
            f"the speed log {name} covers t = {t_log[0]:.2f}–{t_log[-1]:.2f} s of the run file's "
            f"{t_run[0]:.2f}–{t_run[-1]:.2f} s (offset_s applied) and the carriage moves at its "
            f"{'start' if before and moving_start else 'end'}: a wrong offset_s, or the log of "
            "another run?"
        )
    if t_log[-1] < t_run[0] or t_log[0] > t_run[-1]:
        raise RunError(
            f"the speed log {name} (t = {t_log[0]:.2f}–{t_log[-1]:.2f} s with offset_s) does "
            f"not overlap the run file ({t_run[0]:.2f}–{t_run[-1]:.2f} s): check offset_s"
        )
    return np.interp(t_run, t_log, u_log)


def log_sha(spec: Any, data_dir: Path, file: str, run: int) -> str:
    """sha256 of a run's speed log ("" without one or when it cannot be read): part of the
    run's cache key, since the reduction depends on the log's bytes as on the run file's."""
    if spec is None:
        return ""

    try:
        return hashlib.sha256(log_path(spec, data_dir, file, run).read_bytes()).hexdigest()
    except OSError:
        return ""


def run_speed_log(spec: SpeedLog | None, data_dir: Path, file: str,
                  run: int) -> tuple[np.ndarray, np.ndarray, str] | None:
    """The speed log of one run, read and on the run's clock, for
    :func:`towtank.ingest.runfile.load_run` (None without ``[speed_log]``)."""
    if spec is None:
        return None

    path = log_path(spec, data_dir, file, run)
    try:
        data = file_bytes(path)
    except RunError as exc:
        raise RunError(f"its speed log ([speed_log] file = {spec.file!r}): {exc.reason}") \
            from None
    t, u = read_speed_log(path, spec, data)
    return t, u, path.name
