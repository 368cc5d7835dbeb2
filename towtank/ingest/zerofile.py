"""The balance zero from its own file: a zeros file recorded per run (``[zeros]``).

Some tanks record the balance at rest, in still water, into a separate file before each run,
and take the zero of every force from it instead of from a still window of the run file. The
zeros file is read like the run file (same ``[read]``, ``[channels]`` and ``[balance]``); the
zero of each force is the mean of its calibrated samples F_k, k = 0 … n−1, weighted by a window
with cosine tapers of the run's trim (1.5 / cutoff_hz) at each end
(:func:`towtank.signal.conditioning.still_level`):

    F_zero = Σ w_k·F_k / Σ w_k,   w_k = sin²(π(k + 1)/(2(m + 1))) for k < m,
                                  mirrored for the last m samples, 1 between,   m = trim·fs  (1)

with fs the run file's sample rate (one acquisition). The plain mean of a file that is not a
whole number of mains periods long keeps part of a period of hum (up to 0.2 mN from 0.05 N of
50 Hz hum over 1.5 s), and a zeros file shared by the day's runs shifts every run's force by
that same amount; the tapers reject disturbances well above 1/trim, the hum to 0.0002 mN
over 1.5 s, at 1.1 times the plain mean's noise. F_zero replaces the pre-run still window's
mean as the zero of the run (docs/formats.md §3.4); the drift to the post-run window is then
taken from the file's start (docs/method.md).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from towtank.errors import RunError
from towtank.ingest.calibration import calibrate
from towtank.ingest.columns import file_bytes, read_columns
from towtank.ingest.protocol_types import ZeroFile, channel_map
from towtank.ingest.readers import stated_units
from towtank.ingest.runfile import map_channels
from towtank.ingest.speedlog import log_path
from towtank.signal.conditioning import still_level

__all__ = ["ZeroFile", "zero_levels", "run_zero_levels",
           "with_zero_levels"]


def zero_levels(path: Path, data: bytes, mapping: dict[str, Any], options: Any = None,
                balance: Any = None, *, fs: float | None = None,
                taper_s: float | None = None) -> dict[str, float]:
    """Zero of drag and lift [N] of a zeros file: the tapered mean of each calibrated force
    (eq. 1); lift only where mapped or found. The file needs no time or speed channel.

    Parameters
    ----------
    fs : float, optional
        Sample rate [Hz] (the run file's).
    taper_s : float, optional
        Duration of each taper [s] (the run's trim). Without ``fs`` or ``taper_s`` the tapers
        meet in the middle (the Hann window).
    """
    name = path.name
    cols, _ = read_columns(path, data, options)
    used: dict[str, str] = {}
    chans = map_channels(cols, mapping, f"the zeros file {name}", used=used, balance=balance,
                         external=("time", "speed", "accel"))
    numeric = {}
    for canon, raw in chans.items():
        arr = np.asarray(raw)
        if arr.dtype == object:
            arr = np.array([_number(v) for v in arr], dtype=np.float64)
        numeric[canon] = arr.astype(np.float64)
    full = channel_map(mapping)
    numeric = calibrate(numeric, full, used, stated_units(cols), name, [])
    out = {}
    for canon, arr in numeric.items():
        ok = arr[np.isfinite(arr)]
        if ok.size < 10:
            raise RunError(f"the zeros file {name} holds fewer than 10 numbers of {canon}")
        out[canon] = still_level(arr, fs, taper_s)
    return out


def _number(v: Any) -> float:
    try:
        return float(str(v).replace(",", "."))
    except ValueError:
        return float("nan")


def run_zero_levels(spec: ZeroFile | None, data_dir: Path, file: str, run: int,
                    mapping: dict[str, Any], options: Any = None,
                    balance: Any = None, *, fs: float | None = None,
                    taper_s: float | None = None) -> tuple[dict[str, float], str] | None:
    """The zeros of one run (levels, file name), None without ``[zeros]``; ``fs`` (the run
    file's rate [Hz]) and ``taper_s`` (the run's trim [s]) as in :func:`zero_levels`."""
    if spec is None:
        return None
    path = log_path(spec, data_dir, file, run)
    try:
        data = file_bytes(path)
    except RunError as exc:
        raise RunError(f"its zeros file ([zeros] file = {spec.file!r}): {exc.reason}") from None
    return zero_levels(path, data, mapping, options, balance, fs=fs,
                       taper_s=taper_s), path.name


def with_zero_levels(raw: Any, levels: dict[str, float], name: str) -> Any:
    """The run with its zeros from the zeros file ``name`` (and a note saying so)."""
    told = ", ".join(f"{k} {v:+.5g} N" for k, v in levels.items())
    return replace(raw, zero_levels=dict(levels),
                   notes=[*raw.notes, f"zeros from the zeros file {name} ({told})"])
