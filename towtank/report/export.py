"""The reduced time series of every usable run, for the lab's own tools (``--export``).

Each run is read again and conditioned exactly as the day's reduction did it
(:func:`towtank.reduce.run.reduce_record` with ``keep_series``), and its tare is subtracted
sample by sample (:func:`towtank.reduce.run.apply_tare`): the exported channels are the ones
the coefficients were fitted on, at the file's own sample rate.

========  ==================================================================================
format    files in the output folder's ``export/``
========  ==================================================================================
mat       ``run_NNN.mat`` (MATLAB v5, ``load('run_001.mat')``): vectors ``t, U, a, drag, lift,
          phase``, the cell array ``phase_names`` and the struct ``meta``
hdf5      ``runs.h5``: a group ``run_NNN`` per run with those datasets and ``meta`` as attributes
parquet   ``run_NNN.parquet``: columns ``t, U, a, drag, lift, phase, phase_name``; ``meta``
          as JSON in the schema's metadata (key ``towtank``)
simman    ``simman/``: the captive tests, static means and PMM periods with their Fourier
          coefficients and the model's particulars (:mod:`towtank.report.simman`)
========  ==================================================================================

Units: t [s] from the start of the file, U [m/s], a [m/s²], drag and lift [N] (zeroed,
drift-corrected, low-pass filtered, tare subtracted; SNAME signs as in runs.csv). ``phase`` is
0 still before, 1 acceleration, 2 steady (the window used), 3 deceleration, 4 still after,
−1 between phases. A NUL character in ``meta``'s text (the sheet's, the campaign's name) is
written as U+2400 (␀): HDF5 strings cannot hold one.

The runs are written one after another, each reduced again, written in every format and let
go before the next is read: the process holds one run's series at a time, whatever the day's
length. A storage failure (a full disk) in any format is an ``OSError`` with its errno, HDF5's
included (:class:`_NeverFailingFile`).
"""

from __future__ import annotations

import errno
import json
import math
import os
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import h5py
import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq
from scipy.io import savemat

from towtank.reduce.run import apply_tare, reduce_record
from towtank.report.simman import write_simman
from towtank.runtime.storage import os_error
from towtank.signal.phases import PHASE_NAMES

if TYPE_CHECKING:
    from towtank.reduce.run import RunReduction
    from towtank.results import DayResult

EXPORT_FORMATS = ("mat", "hdf5", "parquet", "simman")

#: Units of the exported channels.
UNITS = {"t": "s", "U": "m/s", "a": "m/s^2", "drag": "N", "lift": "N", "phase": "-"}

#: runs.csv columns copied into each run's ``meta``.
META_COLUMNS = ("run", "file", "config", "test", "angle_deg", "status", "speed_mean",
                "accel_mean", "drag_mean", "lift_mean", "tare_drag", "cd", "cl", "re",
                "water_temp_C", "rho", "nu", "tare_group", "fs_hz", "n_samples", "sha256")


def conditioned_runs(day: DayResult) -> Iterator[tuple[int, RunReduction | None, str | None]]:
    """Every usable run of the day reduced again with its whole conditioned time series
    (``RunReduction.series``), tare subtracted, one at a time: ``(run, reduction, None)``, or
    ``(run, None, sentence)`` for a run that could not be (its file changed or vanished since
    the day was reduced).

    A generator: the caller writes a run's series and lets it go before the next run is read,
    so that only one run's full-rate series is held at once (a day of 42 runs of 20 minutes at
    1 kHz is several GB of them)."""
    protocol = day.protocol
    rows = {int(r["run"]): r for r in day.sheet.to_dict("records")}
    for run in sorted(day.reductions):
        _, red, reason, _ = reduce_record(protocol, rows[run], keep_series=True)
        if red is None:
            yield run, None, f"run {run} is not exported: {reason}"
            continue
        config = str(rows[run]["config"])
        tare = (None if config == "sting" or protocol.tare.source == "none"
                else day.tares.get(str(rows[run]["tare_group"])))
        tared = apply_tare(red, tare)
        del red  # the untared series
        yield run, tared, None
        del tared  # before the next run is read


#: What stands for a NUL character ("\x00") in exported text: U+2400 SYMBOL FOR NULL. HDF5
#: strings cannot hold a NUL; the three formats carry the same text.
NUL_SUBSTITUTE = "\u2400"


def safe_text(text: str) -> str:
    """``text`` with each NUL character replaced by :data:`NUL_SUBSTITUTE`."""
    return text.replace("\x00", NUL_SUBSTITUTE)


def _metas(day: DayResult) -> dict[int, dict[str, Any]]:
    """Each run's ``meta``: its runs.csv values (:data:`META_COLUMNS`), the campaign, units."""
    campaign = safe_text(str(day.protocol.name))
    units = ", ".join(f"{k} [{u}]" for k, u in UNITS.items())
    cols = [c for c in META_COLUMNS if c in day.runs.columns]
    out: dict[int, dict[str, Any]] = {}
    for rec in day.runs[["run", *[c for c in cols if c != "run"]]].to_dict("records"):
        meta: dict[str, Any] = {"campaign": campaign}
        for col in cols:
            v = rec[col]
            if isinstance(v, np.generic):
                v = v.item()
            if isinstance(v, float) and not math.isfinite(v):
                v = float("nan")
            if isinstance(v, str):
                v = safe_text(v)
            meta[col] = "" if v is None else v
        meta["units"] = units
        out[int(rec["run"])] = meta
    return out


def _write_mat(path: Path, series: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
    data: dict[str, Any] = {k: np.asarray(v, dtype=float)[:, None] for k, v in series.items()
                            if k != "phase"}
    data["phase"] = np.asarray(series["phase"], dtype=np.int8)[:, None]
    data["phase_names"] = np.array(PHASE_NAMES, dtype=object)
    data["meta"] = {k: (v if not isinstance(v, bool) else int(v)) for k, v in meta.items()}
    savemat(path, data, do_compression=True, oned_as="column")


def _write_parquet(path: Path, series: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
    # the system's allocator, not pyarrow's default (mimalloc), which keeps what a run freed
    # cached for the next: tens of MB more of this process's memory than a run needs
    pool = pa.system_memory_pool()
    names = np.array([*PHASE_NAMES, ""], dtype=object)
    columns = {k: pa.array(np.asarray(v), memory_pool=pool) for k, v in series.items()}
    columns["phase_name"] = pc.dictionary_encode(
        pa.array(names[np.asarray(series["phase"], dtype=int)], memory_pool=pool),
        memory_pool=pool)
    table = pa.table(columns)
    table = table.replace_schema_metadata(
        {"towtank": json.dumps({"meta": meta, "units": UNITS, "phase_names": PHASE_NAMES},
                               default=str)})
    pq.write_table(table, path, memory_pool=pool)


class _NeverFailingFile:
    """The binary file under ``runs.h5``, given to h5py's ``fileobj`` driver: it never reports
    a failed write to HDF5.

    HDF5 does not survive a write that fails (a full disk): the datasets still open cannot be
    closed (h5py prints an "Exception ignored" traceback for each, hundreds of lines), closing
    the file fails too, and at the interpreter's exit the library's own clean-up
    (``H5_term_library``) closes those datasets again on the freed file: a segmentation fault
    (exit 139). So the first write that fails is remembered in :attr:`error`; from then on
    writes are kept in memory (only what is still in HDF5's caches and the run being written:
    the exporter stops after it) and reads see them, HDF5 finishes and closes the file as if
    all went well, and :class:`_Hdf5Export` raises the remembered error.
    """

    #: the system call that writes (a seam for tests that fill the disk)
    _pwrite = staticmethod(os.pwrite)

    def __init__(self, path: Path) -> None:
        self._fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_TRUNC, 0o666)
        self._pos = 0
        self._size = 0
        self.error: OSError | None = None
        self._kept: list[tuple[int, bytes]] = []  # writes after the failure: (offset, bytes)

    def seek(self, pos: int, whence: int = 0) -> int:
        self._pos = pos if whence == 0 else self._pos + pos if whence == 1 else self._size + pos
        return self._pos

    def tell(self) -> int:
        return self._pos

    def write(self, data: Any) -> int:
        data = bytes(data)
        if self.error is None:
            try:
                view, at = memoryview(data), self._pos
                while view:
                    n = self._pwrite(self._fd, view, at)
                    view, at = view[n:], at + n
            except OSError as exc:
                self.error = exc
        if self.error is not None:
            self._kept.append((self._pos, data))
        self._pos += len(data)
        self._size = max(self._size, self._pos)
        return len(data)

    def read(self, n: int = -1) -> bytes:
        n = max(0, self._size - self._pos) if n is None or n < 0 else n
        data = bytearray(os.pread(self._fd, n, self._pos) if n else b"")
        data.extend(bytes(n - len(data)))  # past the end: zeros, as HDF5's own drivers read
        for at, kept in self._kept:
            lo, hi = max(at, self._pos), min(at + len(kept), self._pos + n)
            if lo < hi:
                data[lo - self._pos:hi - self._pos] = kept[lo - at:hi - at]
        self._pos += n
        return bytes(data)

    def readinto(self, buf: Any) -> int:
        view = memoryview(buf).cast("B")
        data = self.read(len(view))
        view[:len(data)] = data
        return len(data)

    def truncate(self, size: int | None = None) -> int:
        size = self._pos if size is None else size
        if self.error is None:
            try:
                os.ftruncate(self._fd, size)
            except OSError as exc:
                self.error = exc
        self._size = size
        return size

    def flush(self) -> None:
        pass

    def close(self) -> None:
        os.close(self._fd)


class _Hdf5Export:
    """``export/runs.h5``, written run by run; :meth:`close` raises the storage error (an
    ``OSError`` with its errno: ``ENOSPC``...) that a write met, once HDF5 has closed the file
    cleanly (:class:`_NeverFailingFile`)."""

    def __init__(self, path: Path, campaign: str) -> None:
        self.path = path
        self.sink = _NeverFailingFile(path)
        try:
            self.h5 = h5py.File(self.sink, "w")
        except BaseException:
            self.sink.close()
            raise
        self.h5.attrs["campaign"] = safe_text(campaign)
        self.h5.attrs["phase_names"] = ", ".join(PHASE_NAMES)
        self.h5.attrs["units"] = json.dumps(UNITS)

    @property
    def failed(self) -> bool:
        return self.sink.error is not None

    def add(self, name: str, series: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
        g = self.h5.create_group(name)
        for k, v in series.items():
            ds = g.create_dataset(k, data=np.asarray(v), compression="gzip")
            ds.attrs["unit"] = UNITS[k]
            del ds
        for k, v in meta.items():
            g.attrs[k] = v if not isinstance(v, bool) else int(v)

    def close(self) -> None:
        try:
            self.h5.close()
        finally:
            self.sink.close()
        if self.sink.error is not None:
            code = self.sink.error.errno or errno.EIO
            raise os_error(code, self.path) from self.sink.error


def export_runs(day: DayResult, folder: str | Path, formats: tuple[str, ...] | list[str]
                ) -> list[str]:
    """Write the reduced time series of the day's usable runs into ``folder/export/``.

    Run by run: each run is reduced again, written in every format, and let go before the next
    (:func:`conditioned_runs`), so that this process never holds more than one run's series.

    Parameters
    ----------
    day : DayResult
        The processed day.
    folder : path
        The output folder (the writers' temporary folder).
    formats : sequence of str
        Any of :data:`EXPORT_FORMATS`.

    Returns
    -------
    list of str
        A sentence per run that could not be exported (else empty).

    Raises
    ------
    OSError
        A storage failure (a full disk: ``ENOSPC``) in any format, HDF5's included.
    """
    formats = tuple(dict.fromkeys(formats))
    unknown = [f for f in formats if f not in EXPORT_FORMATS]
    if unknown:
        raise ValueError(f"unknown export format(s) {', '.join(unknown)}; use "
                         f"{', '.join(EXPORT_FORMATS)}")
    missing: list[str] = []
    if "simman" in formats:
        options = getattr(day.protocol, "captive", None)
        missing += write_simman(day, folder,
                                float(options.roll_deg) if options is not None else 90.0)
        formats = tuple(f for f in formats if f != "simman")
    if not formats:
        return missing
    metas = _metas(day)
    out = Path(folder) / "export"
    out.mkdir(parents=True, exist_ok=True)
    h5 = _Hdf5Export(out / "runs.h5", str(day.protocol.name)) if "hdf5" in formats else None
    try:
        for run, red, reason in conditioned_runs(day):
            if red is None:
                missing.append(str(reason))
                continue
            series = red.series
            assert series is not None
            del red
            meta = metas[run]
            name = f"run_{run:03d}"
            if "mat" in formats:
                _write_mat(out / f"{name}.mat", series, meta)
            if "parquet" in formats:
                _write_parquet(out / f"{name}.parquet", series, meta)
            if h5 is not None:
                h5.add(name, series, meta)
                if h5.failed:
                    break  # the disk is full: close() says so
            del series  # before the next run is read
    finally:
        if h5 is not None:
            h5.close()
    return missing
