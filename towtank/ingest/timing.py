"""Where a run's time comes from when the file has no time column (docs/formats.md §3.1, Time).

In this order: LVM's ``X_Value`` (a column, :data:`towtank.ingest.readers.TIME_COLUMN_KEY`),
LabVIEW waveform timing, a sample rate the file states as an attribute or scalar, ``[read]
sample_rate_hz``, a rate written in an HDF5 group's or dataset's name
(:func:`towtank.ingest.arrayfiles.rate_from_names`). The time is then t_k = k / rate [s].
"""

from __future__ import annotations

import numpy as np

from towtank.ingest.arrayfiles import FS_NAME_KEY
from towtank.ingest.readers import FS_ERROR_KEY, FS_KEY, TIME_COLUMN_KEY, WF_TIME_KEY


def stated_rate(cols: dict[str, np.ndarray], sample_rate_hz: float = 0.0) -> tuple[float, str]:
    """(sample rate [Hz], where it comes from) for a file without a time column or waveform
    timing, in this order: a rate the file states as an attribute or scalar (``fs``, ``dt``
    ...); ``[read] sample_rate_hz``; a rate written in an HDF5 group's or dataset's name
    (``/200.05 Hz/C.SPEED``, :func:`towtank.ingest.arrayfiles.rate_from_names`). (0.0, "")
    when there is none."""
    given = float(sample_rate_hz or 0.0)
    if FS_KEY in cols and FS_NAME_KEY not in cols:
        return float(cols[FS_KEY][0]), "the sample rate the file states"
    if given > 0:
        return given, f"[read] sample_rate_hz = {given:g} Hz"
    if FS_KEY in cols:
        return float(cols[FS_KEY][0]), f"{cols[FS_NAME_KEY].item()}"
    return 0.0, ""


def timing_note(cols: dict[str, np.ndarray], sample_rate_hz: float) -> str | None:
    """The run's note on a time built from a rate written in an HDF5 name, or from ``[read]
    sample_rate_hz`` where a name states another rate or the file's stated rate is not one
    (two different rates in names, ``fs = "fast"``); None otherwise."""
    if WF_TIME_KEY in cols:
        return None
    if FS_NAME_KEY not in cols:
        if FS_ERROR_KEY in cols and FS_KEY not in cols and sample_rate_hz > 0:
            return (f"time from [read] sample_rate_hz = {sample_rate_hz:g} Hz (the file has no "
                    f"time channel, and {cols[FS_ERROR_KEY].item()})")
        return None
    fs, source = stated_rate(cols, sample_rate_hz)
    named = float(cols[FS_KEY][0])
    if source.startswith("[read]"):
        if abs(named - fs) <= 1e-9 * fs:
            return None
        return (f"time from {source} (the file has no time channel, and "
                f"{cols[FS_NAME_KEY].item()} says {named:g} Hz)")
    return f"time from the sample rate {fs:g} Hz, {source} (the file has no time channel)"


def time_source_text(cols: dict[str, np.ndarray], used: dict[str, str], full_time: str,
                     sample_rate_hz: float) -> str:
    """Where a run's time came from, said for a person (``RawRun.time_source``): the column
    ``used["time"]`` names, else the file's timing by :func:`stated_rate`'s order."""
    col = used.get("time", "")
    if col in cols:
        if TIME_COLUMN_KEY in cols and cols[TIME_COLUMN_KEY].item()[0] == col:
            return f"the column '{col}' ({cols[TIME_COLUMN_KEY].item()[1]})"
        return f"the column '{col}'"
    if WF_TIME_KEY in cols:
        return "LabVIEW waveform timing (wf_increment)"
    fs, source = stated_rate(cols, sample_rate_hz)
    if fs > 0:
        return f"{fs:g} Hz, {source}" if not source.startswith("[read]") else source
    return col or full_time
