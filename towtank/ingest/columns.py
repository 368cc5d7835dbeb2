"""A run file's bytes and columns: the file primitives every reader of the day shares.

:func:`file_bytes` opens a run file (a speed log, a zeros file) read-only, only when it is a
regular file no larger than :data:`towtank.ingest.readers.MAX_RUN_FILE_BYTES`;
:func:`read_columns` reads its columns in raw units in the format of ``[read]`` (plain CSV,
other text, LVM, TDMS, MATLAB, HDF5, gzip-compressed text); :func:`fallback_time` is the time
of a file without a time column. Calibrating and checking the channels of a run is
:mod:`towtank.ingest.runfile`'s.
"""

from __future__ import annotations

import gzip
import hashlib
import io
import os
import stat
import unicodedata
import zlib
from pathlib import Path

import numpy as np

from towtank.errors import RunError
from towtank.ingest import readers
from towtank.ingest.arrayfiles import read_hdf5_columns, read_mat_columns
from towtank.ingest.plaincsv import read_csv_columns
from towtank.ingest.protocol_types import ChannelMap, channel_map
from towtank.ingest.readers import (
    WF_TIME_KEY,
    ReadOptions,
    file_format,
    plain_csv,
    read_lvm_columns,
    read_tdms_columns,
    read_text_columns,
)
from towtank.ingest.timing import stated_rate

__all__ = ["fallback_time", "file_bytes", "file_bytes_stamped", "read_columns", "sha256_bytes"]


def _too_large(name: str, what: str, size: int | None = None) -> str:
    amount = f"{size / 2**30:.1f} GiB" if size is not None else "larger than that"
    return (f"{name} is too large for one run ({what} {amount}; towtank reads run files up to "
            f"{readers.MAX_RUN_FILE_BYTES / 2**30:g} GiB): split the recording into its runs")


def file_bytes(path: Path) -> bytes:
    """The file's bytes, opened read-only; a missing or unreadable file is a RunError.

    Only a regular file is opened: a named pipe or a device would block the read forever.
    """
    return file_bytes_stamped(path)[0]


def file_bytes_stamped(path: Path) -> tuple[bytes, tuple[int, int, int, int] | None]:
    """:func:`file_bytes` and the file's (size, mtime_ns, ctime_ns, inode) as it was read, or
    None for the stamp when the file changed while it was being read.

    The stamp is what the cache may remember with the sha256 of these bytes: a stat taken
    later could belong to a newer version of the file.
    """
    try:
        mode = os.stat(path).st_mode
        if not stat.S_ISREG(mode) and not stat.S_ISDIR(mode):
            raise RunError(f"{path.name} is not a regular file (a pipe, socket or device)")
        size = os.stat(path).st_size
        if size > readers.MAX_RUN_FILE_BYTES:
            raise RunError(_too_large(path.name, "it is", size))
        with open(path, "rb") as fh:
            before = os.fstat(fh.fileno())
            data = fh.read()
            after = os.fstat(fh.fileno())
        stamps = [(st.st_size, st.st_mtime_ns, st.st_ctime_ns, st.st_ino) for st in (before, after)]
        return data, (stamps[0] if stamps[0] == stamps[1] and len(data) == before.st_size
                      else None)
    except FileNotFoundError:
        raise RunError(
            f"the data file {path.name} is not found in {path.parent}{_near_name(path)}"
        ) from None
    except IsADirectoryError:
        raise RunError(f"{path.name} is a folder, not a data file") from None
    except OSError as exc:
        raise RunError(f"{path.name} cannot be read ({exc.strerror or exc})") from None


def _near_name(path: Path) -> str:
    """'; did you mean ...?' for a file of the folder whose name differs only in case or in
    Unicode normalisation (a sheet typed on another system), else ''."""
    def key(name: str) -> str:
        return unicodedata.normalize("NFC", name).casefold()

    try:
        names = [p.name for p in path.parent.iterdir()]
    except OSError:
        return ""
    same = [n for n in names if key(n) == key(path.name) and n != path.name]
    return f"; did you mean {same[0]!r}?" if same else ""


def sha256_bytes(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def read_columns(
    path: Path, data: bytes | None = None, options: ReadOptions | None = None
) -> tuple[dict[str, np.ndarray], list[str]]:
    """Read a run file's columns (raw units) from its bytes, in the format of ``[read]``.

    Plain CSV goes through pyarrow (:func:`read_csv_columns`); other text, LVM, TDMS, MATLAB
    and HDF5 through :mod:`towtank.ingest.readers`. A file holding more rows or values than a
    run may (:func:`towtank.ingest.readers.check_run_size`) is a RunError: text before it is
    parsed (a gzip-compressed one while it is decompressed), every format once read.
    """
    cols, notes = _read_columns(path, data, options)
    arrays = {id(v): v for k, v in cols.items() if not k.startswith("__")}.values()
    rows = max((np.asarray(v).shape[0] if np.ndim(v) else 1 for v in arrays), default=0)
    readers.check_run_size(path.name, rows, len(arrays))
    return cols, notes


def gunzip(data: bytes, name: str) -> bytes:
    """The text of a gzip-compressed run file, decompressed 4 MiB at a time: a RunError once
    more than :data:`~towtank.ingest.readers.MAX_RUN_FILE_BYTES` bytes or more lines than a run
    may hold have come out, before the memory for the rest is spent."""
    if not data:
        raise RunError(f"{name} is empty (0 bytes)")
    max_lines = readers.MAX_RUN_ROWS + readers.TEXT_LINE_SLACK
    chunks, size, lines = [], 0, 0
    try:
        with gzip.GzipFile(fileobj=io.BytesIO(data)) as gzf:
            while block := gzf.read(1 << 22):
                size += len(block)
                lines += block.count(b"\n")
                if size > readers.MAX_RUN_FILE_BYTES:
                    raise RunError(_too_large(name, "decompressed, it is"))
                if lines > max_lines:
                    readers.check_run_size(name, lines, exact=False)
                chunks.append(block)
    except EOFError:
        raise RunError(
            f"{name} cannot be decompressed: the gzip stream ends early (truncated file)"
        ) from None
    except (OSError, zlib.error) as exc:
        raise RunError(f"{name} cannot be decompressed ({exc})") from None
    return b"".join(chunks)


def _read_columns(
    path: Path, data: bytes | None = None, options: ReadOptions | None = None
) -> tuple[dict[str, np.ndarray], list[str]]:
    if data is None:
        data = file_bytes(path)
    fmt, gz = file_format(path, data, options)
    if fmt == "tdms":
        return read_tdms_columns(data, path.name, options)
    if fmt == "mat":
        return read_mat_columns(data, path.name, options)
    if fmt == "hdf5":
        return read_hdf5_columns(data, path.name, options)
    if gz:
        data = gunzip(data, path.name)
    elif data[:2] == b"\x1f\x8b":
        raise RunError(
            f"{path.name} is gzip-compressed although its name does not end in .gz "
            f"(rename it {path.name}.gz)"
        )
    nul = data.find(b"\x00", 0, 65536)
    if nul >= 0:
        raise RunError(
            f"{path.name} is not a text file: it holds NUL bytes (the first at byte {nul}), "
            "as a file the DAQ never finished writing does"
        )
    max_lines = readers.MAX_RUN_ROWS + readers.TEXT_LINE_SLACK
    if len(data) > max_lines and data.count(b"\n") > max_lines:  # too many lines to parse
        readers.check_run_size(path.name, data.count(b"\n"), exact=False)
    if fmt == "lvm":
        return read_lvm_columns(data, path.name, options)
    opts = options or ReadOptions()
    if (fmt == "csv" and opts.delimiter in ("auto", ",") and opts.decimal in ("auto", ".")
            and not opts.skip_rows and plain_csv(data)):
        return read_csv_columns(data, path.name)
    return read_text_columns(data, path.name, opts)


def fallback_time(
    cols: dict[str, np.ndarray], mapping: dict[str, ChannelMap], sample_rate_hz: float = 0.0
) -> np.ndarray | None:
    """Time [s] of a file without a time column: LabVIEW waveform timing, else ``k/fs`` with the
    file's stated sample rate or ``[read] sample_rate_hz``; None when there is neither."""
    if WF_TIME_KEY in cols:
        return np.asarray(cols[WF_TIME_KEY], dtype=np.float64)
    fs, _ = stated_rate(cols, sample_rate_hz)
    if fs <= 0:
        return None
    full = channel_map(mapping)
    ref = cols.get(full["drag"].column)
    if ref is None:
        ref = next((v for k, v in cols.items() if not k.startswith("__")), None)
    return None if ref is None else np.arange(np.asarray(ref).size, dtype=np.float64) / fs
