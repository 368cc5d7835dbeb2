"""Run files as labs record them: text in any local habit, LabVIEW TDMS and LVM, MATLAB, HDF5.

Every reader takes the file's bytes (read once: the same bytes give the sha256) and returns the
lab's raw columns, ``name -> float64 array`` (object arrays where a column holds text), with a
few private entries beside them that the channel mapping of :mod:`towtank.ingest.runfile` uses:

``__units__``
    0-d object array holding ``{column: unit}`` for the units a file states (a units row under
    the header, TDMS ``unit_string``, HDF5/MAT attributes); units in a header such as
    ``Speed (mm/s)`` are read from the name itself.
``__wf_time__``
    the time built from LabVIEW waveform timing (``wf_start_offset + k·wf_increment``) when
    the file has no time channel.
``__fs__``
    a sample rate the file states (``fs``, ``sample_rate``, ``Fs`` variables or attributes).

Formats (``[read] format``; ``auto`` takes the extension, then the content):

=========  ==================================================================================
csv        the fast pyarrow path for plain comma-separated text with its header on line 1;
           any other text (preamble, ``;``/tab/blank separated, decimal commas, units row)
           goes through :func:`read_text_columns`
tdms       LabVIEW TDMS via npTDMS; waveform timing when there is no time channel
lvm        LabVIEW Measurement text: header blocks ending in ``***End_of_Header***``, one or
           more segments
mat        MATLAB v4/v5/v7 (scipy.io.loadmat) and v7.3 (HDF5, h5py): vectors, or the fields
           of a struct (:mod:`towtank.ingest.arrayfiles`)
hdf5       HDF5 datasets of one group (h5py; :mod:`towtank.ingest.arrayfiles`)
=========  ==================================================================================

``__fs_error__`` holds, instead of ``__fs__``, why a sample rate the file states is not one
(``fs = "fast"``, ``dt = 0``): the run is rejected with it only if its time must come from it.
"""

from __future__ import annotations

import io
import logging
import math
import re
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from towtank.errors import RunError
from towtank.ingest.extensions import EXTENSIONS  # noqa: F401 - public here too
from towtank.reference.constants import STANDARD_GRAVITY
from towtank.runtime.safefile import text_lines

UNITS_KEY = "__units__"
WF_TIME_KEY = "__wf_time__"
FS_KEY = "__fs__"
FS_ERROR_KEY = "__fs_error__"
LABEL_KEY = "__label__"
ROWS_KEY = "__rows__"  # the file's line of each row (header = row 1), as plaincsv's
#: Sample indices where an LVM segment header starts new rows (:mod:`towtank.ingest.segments`).
LVM_HEADERS_KEY = "__lvm_headers__"
#: (column, how it was made) of a file's own time column under another name: LVM's
#: ``X_Value`` (the time of the first channel), or that column computed from ``X0`` and
#: ``Delta_X``; the channel ``time`` is taken from it when ``[channels]`` maps no time.
TIME_COLUMN_KEY = "__time_column__"

#: Extensions and the format each means (``auto``); ``.gz`` of a text format is text too.
#: Largest run file read [bytes] (after decompression): 1 GiB, about 8 hours of four channels
#: at 1 kHz in binary, 3 hours as text. A run's samples are held in memory several times
#: over while it is reduced; a larger file is rejected with one sentence, not left to the
#: out-of-memory killer.
MAX_RUN_FILE_BYTES = 1 << 30
#: Most rows one run file may hold: 5 000 000, 83 minutes at 1 kHz or 8 at 10 kHz (a tow run
#: lasts minutes). The reduction holds each channel it uses several times over as float64,
#: about 320 bytes a row for four channels, so a run at the cap takes about 1.6 GB; a longer
#: file is rejected with one sentence before it is parsed, not left to the out-of-memory
#: killer. The same for every format (:func:`check_run_size`).
MAX_RUN_ROWS = 5_000_000
#: Most values (rows × columns, every column of the file counted) one run file may hold:
#: 40 000 000, the row cap at 8 columns, or 32 channels for 20 minutes at 1 kHz (320 MB as
#: float64; a run at both caps takes about 2.3 GB while it is read and reduced).
MAX_RUN_VALUES = 40_000_000
#: Lines a text run file may hold beyond :data:`MAX_RUN_ROWS` (header, units row, preamble,
#: blank lines, LVM segment headers) before it is rejected unparsed.
TEXT_LINE_SLACK = 10_000

FORMATS = ("auto", "csv", "text", "tdms", "lvm", "mat", "hdf5")
DELIMITERS = {"auto": None, ",": ",", ";": ";", "\t": "\t", "tab": "\t",
              "whitespace": "whitespace", " ": "whitespace"}

#: Names of a sample-rate scalar in MATLAB/HDF5 files (case-insensitive) [Hz].
FS_NAMES = ("fs", "sample_rate", "samplerate", "sampling_rate", "sample_rate_hz", "rate")
DT_NAMES = ("dt", "wf_increment", "sample_interval", "increment")
_TIME_NAMES = ("time", "t", "time_s", "x_value", "zeit", "temps")
HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


@dataclass(frozen=True)
class ReadOptions:
    """How run files are read: the protocol's ``[read]`` section (docs/formats.md).

    Parameters
    ----------
    format : str
        ``auto`` (extension, then content), ``csv``, ``text``, ``tdms``, ``lvm``, ``mat``,
        ``hdf5``.
    delimiter : str
        Text files: ``auto``, ``","``, ``";"``, ``"\\t"`` or ``"whitespace"``.
    decimal : str
        Text files: ``"."``, ``","`` or ``auto`` (a decimal comma is recognised in ``;``, tab
        or blank separated files).
    skip_rows : int
        Text files: lines before the header row; 0 finds them automatically.
    group : str
        TDMS group, HDF5 group or MATLAB struct holding the channels ("" = the one that has
        them).
    sample_rate_hz : float
        Sample rate [Hz] for files with neither a time channel nor waveform timing (0 = none).
    segment : int
        Which acquisition, counted from 1, of a file holding several one after another is the
        run (0 = none chosen; the run sheet's ``segment`` column overrides it per run;
        :mod:`towtank.ingest.segments`).
    """

    format: str = "auto"
    delimiter: str = "auto"
    decimal: str = "auto"
    skip_rows: int = 0
    group: str = ""
    sample_rate_hz: float = 0.0
    segment: int = 0


def check_run_size(name: str, rows: int, columns: int = 1, *, exact: bool = True) -> None:
    """Raise the one sentence of a run file holding more than :data:`MAX_RUN_ROWS` rows or
    :data:`MAX_RUN_VALUES` values (``rows`` × ``columns``); ``exact`` False when ``rows`` is a
    count of lines read so far (the file holds at least that many)."""
    if rows > MAX_RUN_ROWS:
        held = f"{rows:,} rows" if exact else f"more than {MAX_RUN_ROWS:,} rows"
    elif rows * columns > MAX_RUN_VALUES:
        held = f"{rows * columns:,} values ({rows:,} rows of {columns} columns)"
    else:
        return
    raise RunError(
        f"{name} is too long for one run: it holds {held}, and towtank reads at most "
        f"{MAX_RUN_ROWS:,} rows ({MAX_RUN_ROWS / 60e3:.0f} min at 1 kHz) and {MAX_RUN_VALUES:,} "
        "values from one run file, to bound the memory a run takes: split the recording into "
        "its runs"
    )


def file_format(path: Path, data: bytes, options: ReadOptions | None = None) -> tuple[str, bool]:
    """(format, gzipped) of a run file: the ``[read] format``, else its extension and content.

    Raises RunError for an extension towtank does not read (naming the ones it does).
    """
    fmt = (options or ReadOptions()).format
    name = path.name.lower()
    gz = name.endswith(".gz")
    stem = name[:-3] if gz else name
    if fmt != "auto":
        return fmt, gz or data[:2] == b"\x1f\x8b"
    suffix = Path(stem).suffix
    if suffix in EXTENSIONS:
        kind = EXTENSIONS[suffix]
        if kind == "mat" and (data[512:520] == HDF5_SIGNATURE or data[:8] == HDF5_SIGNATURE):
            return "mat", False
        return kind, gz
    if data[:8] == HDF5_SIGNATURE:
        return "hdf5", False
    if data[:4] == b"TDSm":
        return "tdms", False
    if data[:10] == b"LabVIEW Me":
        return "lvm", gz
    known = ", ".join(sorted({*EXTENSIONS, ".csv.gz"}))
    raise RunError(
        f"{path.name}: towtank does not know the format of a '{suffix or 'no extension'}' file "
        f"(it reads {known}); name the format with [read] format"
    )


#: Most names a message lists (columns, groups, variables); the rest are counted.
NAMES_SHOWN = 6


def name_list(names: Iterable[str], limit: int = NAMES_SHOWN, *, quoted: bool = True) -> str:
    """Names for a sentence: the first ``limit`` and the count of the rest.

    ``"'c1', 'c2', 'c3' and 39,997 more"`` (``limit=3``); every name when there are no more
    than ``limit``; ``"none"`` for none. ``quoted`` writes each name as Python's ``repr``
    (quoted, a line break or control character escaped: the sentence stays one line).

    Parameters
    ----------
    names : iterable of str
        The names, in the order to list them.
    limit : int
        Most names written out.
    quoted : bool
        Quote each name.
    """
    every = [str(n) for n in names]
    shown = [repr(n) if quoted else n for n in every[:limit]]
    rest = len(every) - len(shown)
    if not shown:
        return "none"
    return ", ".join(shown) + (f" and {rest:,} more" if rest > 0 else "")


def units_entry(units: dict[str, str]) -> np.ndarray:
    holder = np.empty((), dtype=object)
    holder[()] = {k: v for k, v in units.items() if v}
    return holder


def stated_units(cols: dict[str, Any]) -> dict[str, str]:
    """``{column: unit}`` stated by the file (see module docstring)."""
    entry = cols.get(UNITS_KEY)
    return dict(entry.item()) if entry is not None else {}


# ------------------------------------------------------------------------------------- text
_NUMBER = re.compile(rb"^\s*[-+]?(\d+([.,]\d*)?|[.,]\d+)([eE][-+]?\d+)?\s*$")


def _split(line: bytes, delim: str) -> list[bytes]:
    if delim == "whitespace":
        return line.split()
    return line.split(delim.encode())


def _is_number(field: bytes) -> bool:
    return bool(_NUMBER.match(field)) or field.strip().lower() in (b"nan", b"inf", b"-inf", b"")


def _numeric_line(line: bytes, delim: str, n: int | None = None) -> bool:
    fields = _split(line.rstrip(b"\r"), delim)
    if n is not None and len(fields) != n:
        return False
    values = [f for f in fields if f.strip()]
    return bool(values) and all(_is_number(f) for f in fields)


def truncation_error(name: str, row: int, given: int, expected: int,
                     cut: str | None = None) -> RunError:
    """The one sentence of a text run file whose last line is cut short (docs/formats.md §3):
    the same for every text layout (CSV, European text, whitespace text, LVM)."""
    what = (f"row {row} ends in {cut!r}, a number cut short" if cut else
            f"row {row} has {given} of {expected} values")
    return RunError(f"{name} ends in the middle of a line ({what}; a truncated file): was it "
                    "copied before the recording finished?")


def _complete_number(field: bytes) -> bool:
    text = field.strip()
    return bool(text) and (bool(_NUMBER.match(text)) or
                           text.lower().lstrip(b"+-") in (b"nan", b"inf", b"infinity"))


def cut_last_line(last: bytes, delim: str, expected: int,
                  above: bytes | None = None) -> tuple[int, str | None] | None:
    """Whether the last line of a file that does not end in a line break is cut short.

    The line is cut when it has fewer fields than ``expected`` (the header's, or the line
    above's when that has fewer: a trailing separator the header lacks), or when its last
    field is not a complete number (empty, ``1.2e``, ``-``) where the same field of the line
    above (``above``, the last complete data line, if any) is one. A complete line without a
    final line break is not cut (many programs write none); a number cut to a shorter number
    (``0.12`` of ``0.125``) cannot be told from a complete one.

    Returns None when the line is complete, else (fields given, the cut value or None).
    """
    fields = _split(last.rstrip(b"\r"), delim)
    if above is not None:
        width = len(_split(above.rstrip(b"\r"), delim))
        if 1 < width < expected:
            expected = width
    if len(fields) < expected:
        if fields and not fields[-1].strip() and delim != "whitespace":
            return len(fields) - 1, None
        return len(fields), None
    if len(fields) > expected:
        return None  # a malformed row: skipped and counted with the others
    tail = fields[expected - 1]
    if _complete_number(tail):
        return None
    if above is not None:
        prev = _split(above.rstrip(b"\r"), delim)
        if len(prev) < expected or not _complete_number(prev[expected - 1]):
            return None  # the field above is not a number either: text, or always empty
    if not tail.strip():
        return expected - 1, None
    return expected, tail.strip().decode("utf-8", "replace")


def _unterminated(data: bytes) -> bool:
    """The file's last line has text and no line break after it."""
    end = data.rstrip(b" \t")
    return bool(end) and not end.endswith((b"\n", b"\r"))


def _guess_delimiter(lines: list[bytes]) -> str:
    """The separator under which the longest block of lines at the end of the file splits into
    the same number (> 1) of numeric fields; ``;`` before tab before ``,`` before blanks on a
    tie. Without numeric lines, the separator that splits the last lines most regularly."""
    tail = [ln for ln in lines[-200:] if ln.strip()]
    best, best_len = ",", 0
    for delim in (";", "\t", ",", "whitespace"):
        n = len(_split(tail[-1].rstrip(b"\r"), delim)) if tail else 0
        if n < 2:
            continue
        k = 0
        while k < len(tail) and _numeric_line(tail[-1 - k], delim, n):
            k += 1
        if k > best_len:
            best, best_len = delim, k
    if best_len:
        return best
    for delim in (";", "\t", ",", "whitespace"):
        counts = {len(_split(ln.rstrip(b"\r"), delim)) for ln in tail[-5:]}
        if len(counts) == 1 and counts.pop() > 1:
            return delim
    return ","


def _guess_decimal(lines: list[bytes], delim: str) -> str:
    """',' when the numbers of the data lines use a decimal comma (never with ',' separators)."""
    if delim == ",":
        return "."
    numeric = [ln for ln in lines[-20:] if _numeric_line(ln, delim)]
    sample = b" ".join(numeric or lines[-20:])  # a date in a short file's preamble aside
    commas = len(re.findall(rb"\d,\d", sample))
    points = len(re.findall(rb"\d\.\d", sample))
    return "," if commas > points else "."


def _header_row(lines: list[bytes], delim: str) -> tuple[int, int]:
    """(header line, first data line) in ``lines``: the data are the last block of numeric
    lines with the same number of fields; the header is the non-numeric line above it with that
    number of fields (a units row between them is allowed)."""
    n_fields = len(_split(lines[-1].rstrip(b"\r"), delim)) if lines else 0
    first = _first_data_line(lines, delim, n_fields)
    if first is None:  # the data are the last block of numeric lines
        first = len(lines)
        while first > 0 and (_numeric_line(lines[first - 1], delim, n_fields)
                             or not lines[first - 1].strip()):
            first -= 1
    while first < len(lines) and not lines[first].strip():
        first += 1
    head = first - 1
    while head >= 0 and not lines[head].strip():
        head -= 1
    if head < 0:
        return -1, first
    if head > 0 and len(_split(lines[head - 1].rstrip(b"\r"), delim)) == n_fields and \
            _looks_like_units(lines[head], delim):
        return head - 1, first  # header, units row, data
    return head, first


def _first_data_line(lines: list[bytes], delim: str, n_fields: int,
                     run: int = 20) -> int | None:
    """The first line, from the top, that starts ``run`` numeric lines of ``n_fields`` fields
    running to the end of the file or ``run`` of them at least (a long file is not walked line
    by line); None when no such line is within the first 1000."""
    n = len(lines)
    for i in range(min(n, 1000)):
        if not _numeric_line(lines[i], delim, n_fields):
            continue
        block = [ln for ln in lines[i : i + 2 * run] if ln.strip()][:run]
        if all(_numeric_line(ln, delim, n_fields) for ln in block) and \
                all(_numeric_line(ln, delim, n_fields) for ln in lines[-run:] if ln.strip()):
            return i
    return None


def _looks_like_units(line: bytes, delim: str) -> bool:
    fields = [f.strip().decode("utf-8", "replace") for f in _split(line.rstrip(b"\r"), delim)]
    units = [f.strip("()[] ") for f in fields if f]
    return bool(units) and all(len(u) <= 8 and not _is_number(u.encode()) for u in units) and \
        any(u in _UNIT_WORDS for u in units)


def read_text_columns(
    data: bytes, name: str, options: ReadOptions | None = None
) -> tuple[dict[str, np.ndarray], list[str]]:
    """Columns of a text run file as a lab's software wrote it.

    Finds the header (lines before it, a title, a date, the operator's notes, are skipped; or
    ``skip_rows`` of them), the separator (``;``, tab, ``,`` or blanks), a decimal comma, and
    a units row under the header. Values that are not numbers are kept as text (the run's
    checks count and drop such rows).
    """
    # loaded on use: pandas for a text column only: the reduction's workers and towtank
    # inspect never load it
    import pandas as pd

    opts = options or ReadOptions()
    if data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]
    try:
        data.decode("utf-8")
    except UnicodeDecodeError:
        data = data.decode("latin-1").encode("utf-8")
    lines = data.splitlines()
    while lines and not lines[-1].strip():
        lines.pop()
    if not lines:
        raise RunError(f"{name} is empty (0 data rows)")
    # a last line with no line break may be cut short: the layout is found without it
    last = lines.pop() if _unterminated(data) and len(lines) > 1 else None
    delim = DELIMITERS.get(opts.delimiter, opts.delimiter) or _guess_delimiter(lines)
    decimal = opts.decimal if opts.decimal in (".", ",") else \
        _guess_decimal(lines + [last] if last is not None else lines, delim)
    if delim == "," and decimal == ",":
        raise RunError(f"{name}: a decimal comma cannot be read in comma-separated columns")
    if opts.skip_rows:
        head = opts.skip_rows
        first = head + 1
        if first < len(lines) and not _numeric_line(lines[first], delim) and \
                _looks_like_units(lines[first], delim):
            first += 1
    else:
        head, first = _header_row(lines, delim)
    if last is not None and first <= len(lines):
        width = len(_split(lines[head].rstrip(b"\r"), delim)) if head >= 0 else \
            len(_split(lines[min(first, len(lines) - 1)].rstrip(b"\r"), delim))
        above = lines[-1] if first < len(lines) else None
        cut = cut_last_line(last, delim, width, above)
        if cut is not None:
            raise truncation_error(name, len(lines) + 1, cut[0], width, cut[1])
        lines.append(last)
    if first >= len(lines):
        raise RunError(f"{name}: no rows of numbers found under a header")
    header = (
        [f.strip().decode("utf-8", "replace").strip('"') for f in
         _split(lines[head].rstrip(b"\r"), delim)]
        if head >= 0 else [f"column {i + 1}" for i in range(len(_split(lines[first], delim)))]
    )
    units: dict[str, str] = {}
    if first - head == 2:  # a units row
        row = [f.strip().decode("utf-8", "replace").strip("()[]\" ")
               for f in _split(lines[head + 1].rstrip(b"\r"), delim)]
        units = dict(zip(header, row, strict=False))
    body = b"\n".join(lines[first:])
    fast = _numeric_body(body, header, delim, decimal)
    if fast is not None:
        frame_len = len(next(iter(fast.values()))) if fast else 0
        return _text_result(fast, units, delim, decimal, head, first, frame_len)
    sep = r"\s+" if delim == "whitespace" else delim
    try:
        frame = pd.read_csv(io.BytesIO(body), sep=sep, header=None, decimal=decimal,
                            names=header, engine="c" if delim != "whitespace" else "python",
                            skip_blank_lines=True, on_bad_lines="skip", dtype=str)
    except Exception as exc:  # noqa: BLE001 - pandas raises many types for odd text
        raise RunError(f"{name} is not a readable text table ({exc})") from None
    cols = {}
    bad_numbers = 0
    for col in frame.columns:
        text = frame[col].str.strip()
        if decimal == ",":
            text = text.str.replace(",", ".", regex=False)
        values = pd.to_numeric(text, errors="coerce").to_numpy(dtype=np.float64)
        n_text = int((np.isnan(values) & text.notna().to_numpy()
                      & ~text.str.lower().isin(["nan", ""]).to_numpy()).sum())
        if n_text and n_text == text.notna().sum():
            cols[str(col)] = frame[col].to_numpy(dtype=object)
        elif n_text:
            cols[str(col)] = np.where(np.isnan(values), frame[col].to_numpy(dtype=object),
                                      values.astype(object))
            bad_numbers += n_text
        else:
            cols[str(col)] = values
    return _text_result(cols, units, delim, decimal, head, first, len(frame))


def _numeric_body(body: bytes, header: list[str], delim: str,
                  decimal: str) -> dict[str, np.ndarray] | None:
    """The body's columns through pyarrow when every cell is a number (decimal commas turned
    to points first: the separator is then not a comma); None sends it to the general path."""
    if delim == "whitespace" or len(set(header)) != len(header) or not body.strip():
        return None
    # loaded on use: pyarrow only when a text file is read: not for towtank predict,
    # simulate or a protocol's check
    import pyarrow as pa
    from pyarrow import csv as pacsv

    if decimal == ",":
        body = body.replace(b",", b".")
    try:
        table = pacsv.read_csv(
            io.BytesIO(body),
            read_options=pacsv.ReadOptions(column_names=header, block_size=block_bytes(body)),
            parse_options=pacsv.ParseOptions(delimiter=delim),
            convert_options=pacsv.ConvertOptions(
                column_types={h: pa.float64() for h in header}, strings_can_be_null=True),
        )
    except (pa.ArrowInvalid, pa.ArrowTypeError, ValueError):
        return None
    return {h: table.column(j).to_numpy(zero_copy_only=False).astype(np.float64, copy=False)
            for j, h in enumerate(header)}


def block_bytes(body: bytes) -> int:
    """pyarrow's CSV block size [bytes] for a table of text: 4 MiB, or 1024 of its lines when
    they are longer (pyarrow's work per block grows with the number of columns, so a file of
    very many columns read in small blocks would take time growing as their square)."""
    first = body.find(b"\n")
    line = len(body) + 1 if first < 0 else first + 1
    return int(min(max(1 << 22, 1024 * line), 1 << 30))


def _text_result(cols: dict[str, np.ndarray], units: dict[str, str], delim: str, decimal: str,
                 head: int, first: int, n_rows: int) -> tuple[dict[str, np.ndarray], list[str]]:
    notes = []
    if head > 0:
        notes.append(f"{head} line(s) before the header skipped")
    cols[UNITS_KEY] = units_entry(units)
    cols["__text_layout__"] = np.array([delim, decimal, str(head + 1), str(first - head == 2)],
                                       dtype=object)
    cols["__rows__"] = np.arange(n_rows) + first + 1
    return cols, notes


def text_layout(cols: dict[str, Any]) -> dict[str, str] | None:
    """What :func:`read_text_columns` detected (separator, decimal, header line, units row)."""
    entry = cols.get("__text_layout__")
    if entry is None:
        return None
    delim, decimal, header, units = (str(v) for v in entry)
    return {"delimiter": {"\t": "tab"}.get(delim, delim), "decimal": decimal,
            "header_line": header, "units_row": units}


# -------------------------------------------------------------------------------------- LVM
def read_lvm_columns(
    data: bytes, name: str, options: ReadOptions | None = None
) -> tuple[dict[str, np.ndarray], list[str]]:
    """Columns of a LabVIEW Measurement (.lvm) file, every segment joined.

    The file header and each segment's header end in ``***End_of_Header***``; the segment's
    data start with a column-name line (``X_Value`` is the time of the first channel). The
    header's ``Separator`` and ``Decimal_Separator`` are used; a segment without times gets them
    from its ``Delta_X`` and ``X0``.
    """
    text = data.decode("utf-8", "replace") if isinstance(data, bytes) else data
    lines = text_lines(text)
    sep, dec = "\t", "."
    for ln in lines[:40]:
        key, _, value = ln.partition("\t")
        if key.strip() == "Separator":
            sep = {"Tab": "\t", "Comma": ",", "Semicolon": ";"}.get(value.strip(), "\t")
        elif key.strip() == "Decimal_Separator":
            dec = value.strip() or "."
    marks = [i for i, ln in enumerate(lines) if ln.strip().startswith("***End_of_Header***")]
    cut_at_end = _unterminated(data if isinstance(data, bytes) else data.encode())
    if len(marks) < 2:
        raise RunError(f"{name} is not a LabVIEW measurement file (no segment header found)")
    segments: list[dict[str, np.ndarray]] = []
    computed = False
    head_from = marks[0] + 1
    for k in range(1, len(marks)):
        seg_head = lines[head_from : marks[k]]
        i = marks[k] + 1
        while i < len(lines) and not lines[i].strip():
            i += 1
        if i >= len(lines):
            break
        names = [c.strip() for c in lines[i].split(sep)]
        i += 1
        if k + 1 == len(marks) and cut_at_end and len(lines) - 1 >= i:
            _lvm_cut_line(lines, i, names, sep, dec, name)
        end = marks[k + 1] if k + 1 < len(marks) else len(lines)
        while end > i and not _lvm_data_line(lines[end - 1], sep):
            end -= 1  # back over the next segment's header (a few lines)
        fast = _lvm_block(lines[i:end], names, sep, dec)
        head_vals = {ln.split(sep)[0].strip(): ln.split(sep)[1:] for ln in seg_head if sep in ln}
        seg: dict[str, np.ndarray] = {}
        if fast is not None:
            seg, n_rows = fast
            line_no = np.arange(i, end) + 1
            if line_no.size != n_rows:  # blank lines among the data (pyarrow skips them)
                line_no = np.array([j + 1 for j in range(i, end) if lines[j].strip()])
            i = end
        else:
            table = []
            first_line = i + 1
            while i < len(lines) and _lvm_data_line(lines[i], sep):
                table.append(lines[i].split(sep))
                i += 1
            n_rows = len(table)
            line_no = np.arange(n_rows) + first_line
            for j, col in enumerate(names):
                if not col or col.lower() == "comment":
                    continue
                raw = [r[j].strip() if j < len(r) else "" for r in table]
                if dec == ",":
                    raw = [v.replace(",", ".") for v in raw]
                vals = np.array([float(v) if v else np.nan for v in raw], dtype=np.float64) \
                    if all(_is_number(v.encode()) for v in raw) else np.array(raw, dtype=object)
                seg[col] = vals
        head_from = i
        units = dict(zip([c for c in names if c and c != "X_Value"],
                         [u.strip() for u in head_vals.get("Y_Unit_Label", [])], strict=False))
        if (head_vals.get("X_Dimension") or [""])[0].strip().lower() == "time":
            units["X_Value"] = "s"  # an X axis of time is in seconds in LabVIEW's format
        if "X_Value" in seg and (seg["X_Value"].dtype == object
                                 or np.isnan(seg["X_Value"]).all()):
            dx = _first_float(head_vals.get("Delta_X"))
            x0 = _first_float(head_vals.get("X0")) or 0.0
            if dx:
                seg["X_Value"] = x0 + dx * np.arange(n_rows)
                computed = True
        seg[UNITS_KEY] = units_entry(units)
        if n_rows:
            if line_no.size == n_rows:
                seg[ROWS_KEY] = line_no.astype(np.int64)
            segments.append(seg)
    if not segments:
        raise RunError(f"{name} holds no data rows")
    names = [c for c in segments[0] if c not in (UNITS_KEY, ROWS_KEY)]
    lengths = [_seg_len(s) for s in segments]
    cols = {c: _joined(segments, lengths, c) for c in names}
    if "X_Value" in cols and "time" not in {c.lower() for c in cols}:
        how = ("LabVIEW's X_Value, computed from the segment headers' X0 and Delta_X: the "
               "column holds no times" if computed else "LabVIEW's X_Value, the time of the "
               "first channel")
        holder = np.empty((), dtype=object)
        holder[()] = ("X_Value", how)
        cols[TIME_COLUMN_KEY] = holder  # the time channel when [channels] maps none
    cols[UNITS_KEY] = segments[0][UNITS_KEY]
    if all(ROWS_KEY in s for s in segments):  # the file's line of each row (messages)
        cols[ROWS_KEY] = np.concatenate([s[ROWS_KEY] for s in segments])
    if len(segments) > 1:  # where each LVM segment header starts new rows (sample indices)
        cols[LVM_HEADERS_KEY] = np.cumsum(lengths[:-1]).astype(np.int64)
    notes = [f"{len(segments)} LVM segments joined"] if len(segments) > 1 else []
    return cols, notes


def _lvm_cut_line(lines: list[str], first: int, names: list[str], sep: str, dec: str,
                  name: str) -> None:
    """Raise the truncation sentence when the file's last line (it has no line break after
    it), a data line of the last segment, is cut short (:func:`cut_last_line`). LabVIEW ends
    each line with a comment column, usually empty: the last value checked is the one before
    it; the line above sets the width when it has fewer fields than the column names (no
    trailing separator)."""
    last = lines[-1]
    if not last.strip():
        return  # the cut fell in the blank lines after the data: nothing is lost
    above = next((ln for ln in reversed(lines[first:-1]) if ln.strip()), None)

    def enc(text: str) -> bytes:
        return (text.replace(",", ".") if dec == "," and sep != "," else text).encode()

    comment = bool(names) and names[-1].lower() == "comment"
    expected = len(names) - comment
    fields = last.split(sep)
    if comment and len(fields) == expected + 1:
        fields = fields[:-1]  # the comment (any text) is not checked
    prev = above.split(sep)[:expected] if above is not None else None
    trimmed = sep.join(fields)
    cut = cut_last_line(enc(trimmed), sep, expected,
                        enc(sep.join(prev)) if prev is not None else None)
    if cut is not None:
        raise truncation_error(name, len(lines), cut[0], expected, cut[1])


def _lvm_block(block: list[str], names: list[str], sep: str,
               dec: str) -> tuple[dict[str, np.ndarray], int] | None:
    """A segment's data lines through pyarrow when every named cell is a number (the comment
    column aside); None sends the segment to the line-by-line reader."""
    # loaded on use: pyarrow only when a text file is read: not for towtank predict,
    # simulate or a protocol's check
    import pyarrow as pa
    from pyarrow import csv as pacsv

    if not block or sep == "," and dec == ",":
        return None
    keep = [j for j, c in enumerate(names) if c and c.lower() != "comment"]
    body = "\n".join(block).encode()
    if dec == ",":
        body = body.replace(b",", b".")
    width = len(block[0].split(sep))
    cols = [f"c{j}" for j in range(width)]
    if any(j >= width for j in keep):
        return None
    numeric = set(keep)
    try:  # every column typed (none inferred, none left out by name: both cost columns²)
        table = pacsv.read_csv(
            io.BytesIO(body),
            read_options=pacsv.ReadOptions(column_names=cols, block_size=block_bytes(body)),
            parse_options=pacsv.ParseOptions(delimiter=sep),
            convert_options=pacsv.ConvertOptions(column_types={
                c: pa.float64() if j in numeric else pa.string() for j, c in enumerate(cols)}),
        )
    except (pa.ArrowInvalid, pa.ArrowTypeError, ValueError):
        return None
    return ({names[j]: table.column(j).to_numpy(zero_copy_only=False).astype(np.float64)
             for j in keep}, table.num_rows)


def _lvm_data_line(line: str, sep: str) -> bool:
    """A data row of an LVM segment: numbers (or empty fields), the comment column aside."""
    fields = [f.strip() for f in line.split(sep)]
    values = [f for f in fields if f]
    return bool(values) and all(_is_number(f.replace(",", ".").encode()) for f in values[:-1]) \
        and (_is_number(values[-1].replace(",", ".").encode()) or len(values) > 1)


def _seg_len(seg: dict[str, np.ndarray]) -> int:
    return max((v.size for k, v in seg.items() if k not in (UNITS_KEY, ROWS_KEY)), default=0)


def _joined(segments: list[dict[str, np.ndarray]], lengths: list[int], col: str) -> np.ndarray:
    """Column ``col`` of every segment one after another (NaN where a segment lacks it);
    ``lengths`` holds each segment's rows (:func:`_seg_len`, computed once per segment)."""
    return np.concatenate([np.asarray(s[col]) if col in s else np.full(n, np.nan)
                           for s, n in zip(segments, lengths, strict=True)])


def _first_float(values: list[str] | None) -> float | None:
    for v in values or []:
        try:
            return float(v.replace(",", "."))
        except ValueError:
            continue
    return None


# ------------------------------------------------------------------------------------- TDMS
#: npTDMS warnings (how the message starts) after which the values read are not the whole
#: recording: the file ends inside a segment (:func:`read_tdms_columns` rejects the run).
_TDMS_CUT = ("Last segment", "Data size", "Cropping data")
#: npTDMS warning after which a channel's raw DAQmx values are left unscaled.
_TDMS_UNSCALED = "Unsupported scale type"
#: Longest npTDMS message quoted in a sentence [characters].
_TDMS_QUOTED = 160


@dataclass
class TdmsLog:
    """npTDMS's warnings during one read: the first few messages, and how many there were."""

    messages: list[str] = field(default_factory=list)
    count: int = 0

    def add(self, text: str) -> None:
        self.count += 1
        if len(self.messages) < 3:
            self.messages.append(text if len(text) <= _TDMS_QUOTED else
                                 text[: _TDMS_QUOTED - 1] + "…")

    def first(self, starts: tuple[str, ...] | str = "") -> str | None:
        """The first message starting with one of ``starts`` (any message for "")."""
        return next((m for m in self.messages if m.startswith(starts)), None)

    def said(self, message: str) -> str:
        """``npTDMS: 'message'`` and the count of the others, for a sentence."""
        more = self.count - 1
        return f"npTDMS: {message!r}" + (f" and {more:,} more warning{'s' * (more > 1)}"
                                          if more > 0 else "")


_TDMS_LOG: ContextVar[TdmsLog | None] = ContextVar("towtank_tdms_log", default=None)


class _TdmsLogFilter(logging.Filter):
    """On each npTDMS logger: a record logged while towtank reads a TDMS file (in this thread
    or task) is kept in that read's :class:`TdmsLog` and goes to no handler; other records
    pass."""

    def filter(self, record: logging.LogRecord) -> bool:
        caught = _TDMS_LOG.get()
        if caught is None:
            return True
        caught.add(record.getMessage())
        return False


_TDMS_FILTER = _TdmsLogFilter()


@contextmanager
def nptdms_quiet() -> Iterator[TdmsLog]:
    """npTDMS's log records kept, not written, while the block runs (npTDMS writes each
    warning to stderr: a damaged file of many segments gives one line per segment)."""
    for logger_name, logger in list(logging.root.manager.loggerDict.items()):
        if logger_name.split(".")[0] == "nptdms" and isinstance(logger, logging.Logger) \
                and _TDMS_FILTER not in logger.filters:
            logger.addFilter(_TDMS_FILTER)
    caught = TdmsLog()
    token = _TDMS_LOG.set(caught)
    try:
        yield caught
    finally:
        _TDMS_LOG.reset(token)


def read_tdms_columns(
    data: bytes, name: str, options: ReadOptions | None = None
) -> tuple[dict[str, np.ndarray], list[str]]:
    """All numeric channels of a TDMS file, keyed by channel name (and ``group/channel``).

    LabVIEW's waveform timing (``wf_increment``, ``wf_start_offset``) gives ``__wf_time__``
    when a channel carries it; ``unit_string`` properties give the units. With several groups
    the channels of ``[read] group`` (or of every group) are listed.
    """
    # loaded on use: npTDMS only for a TDMS file
    from nptdms import TdmsFile

    opts = options or ReadOptions()
    if not data:
        raise RunError(f"{name} is empty (0 bytes)")
    cols: dict[str, np.ndarray] = {}
    units: dict[str, str] = {}
    wf: tuple[float, float, int] | None = None
    with nptdms_quiet() as caught:
        try:
            # the channels' lengths from the metadata: a file holding more than a run may is
            # rejected before its values are read (a 2-byte integer is held as 8)
            with TdmsFile.open(io.BytesIO(data)) as tdms:
                lengths = [len(channel) for group in tdms.groups()
                           for channel in group.channels()]
                check_run_size(name, max(lengths, default=0), len(lengths))
                wf = _tdms_channels(tdms, name, opts, cols, units)
        except RunError:
            raise
        except Exception as exc:  # noqa: BLE001 - nptdms raises many types for damaged files
            reason = f"{type(exc).__name__}: {exc}"
            first = caught.first()
            also = f"; {caught.said(first)}" if first else ""
            raise RunError(f"{name} is not a readable TDMS file ({reason}{also})") from None
    cut = caught.first(_TDMS_CUT)
    if cut is not None:
        raise RunError(f"{name} is cut short inside a TDMS segment ({caught.said(cut)}; a "
                       "truncated or damaged file): was it copied before the recording "
                       "finished?")
    unscaled = caught.first(_TDMS_UNSCALED)
    if unscaled is not None:
        raise RunError(f"{name}: npTDMS cannot scale its raw DAQmx values "
                       f"({caught.said(unscaled)}), so they would be read unscaled")
    if not cols:
        raise RunError(f"{name} holds no numeric channels")
    if wf is not None:
        cols[WF_TIME_KEY] = wf[0] + wf[1] * np.arange(wf[2], dtype=np.float64)
    cols[UNITS_KEY] = units_entry(units)
    cols[LABEL_KEY] = np.array([], dtype=float)
    first = caught.first()
    return cols, [caught.said(first)] if first else []


def _tdms_channels(tdms: Any, name: str, opts: ReadOptions, cols: dict[str, np.ndarray],
                   units: dict[str, str]) -> tuple[float, float, int] | None:
    """The numeric channels of an open :class:`nptdms.TdmsFile` into ``cols`` (by name and
    ``group/channel``), their ``unit_string`` into ``units``; returns the first channel's
    waveform timing (start [s], increment [s], samples), or None."""
    wf: tuple[float, float, int] | None = None
    groups = tdms.groups()
    if opts.group:
        groups = [g for g in groups if g.name == opts.group]
        if not groups:
            found = name_list(g.name for g in tdms.groups())
            raise RunError(f"{name} has no TDMS group '{opts.group}' (groups: {found})")
    for group in groups:
        for channel in group.channels():
            arr = np.asarray(channel[:])
            if arr.dtype.kind not in "fiu":
                continue
            with np.errstate(invalid="ignore", over="ignore"):
                arr = arr.astype(np.float64, copy=False)
            cols.setdefault(channel.name, arr)
            cols[f"{group.name}/{channel.name}"] = arr
            props = channel.properties
            if "unit_string" in props:
                units.setdefault(channel.name, str(props["unit_string"]))
            inc = props.get("wf_increment")
            if wf is None and inc:
                wf = (float(props.get("wf_start_offset", 0.0) or 0.0), float(inc), arr.size)
    return wf


def plain_csv(data: bytes) -> bool:
    """Whether text is plain CSV for the fast path: header on its first line, then numbers,
    no units row, no decimal comma. Damaged rows further down do not matter here (the fast
    path's own checks name them)."""
    lines = data[:65536].lstrip(b"\r\n\xef\xbb\xbf").splitlines()[:40]
    lines = [ln for ln in lines if ln.strip()]
    if len(lines) < 3:
        return True
    header = lines[0]
    delim = "," if b"," in header else ";" if b";" in header else "\t" if b"\t" in header else ","
    n = len(_split(header.rstrip(b"\r"), delim))
    body = lines[1:]
    same = sum(len(_split(ln.rstrip(b"\r"), delim)) == n for ln in body)
    if same < 0.8 * len(body) or n == 1:
        return False  # a preamble (title, date, notes) above the header, or another separator
    if not _numeric_line(body[0], delim) and _numeric_line(body[1], delim):
        return False  # a units row under the header
    if delim != "," and len(re.findall(rb"\d,\d", b" ".join(body))) > 0:
        return False  # decimal commas
    return True


# ------------------------------------------------------------------------------------ units
#: Unit spellings per quantity and the factor to SI [SI per unit].
UNIT_FACTORS: dict[str, dict[str, float]] = {
    "time": {"s": 1.0, "sec": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "min": 60.0},
    "speed": {"m/s": 1.0, "mm/s": 1e-3, "cm/s": 1e-2, "km/h": 1 / 3.6, "kn": 0.514444,
              "knots": 0.514444, "kt": 0.514444, "m s-1": 1.0, "m.s-1": 1.0},
    "accel": {"m/s^2": 1.0, "m/s²": 1.0, "m/s2": 1.0, "mm/s^2": 1e-3, "mm/s²": 1e-3,
              "m s-2": 1.0, "g": STANDARD_GRAVITY},
    "length": {"m": 1.0, "mm": 1e-3, "cm": 1e-2},
    "force": {"n": 1.0, "kn": 1e3, "mn": 1e-3, "kgf": STANDARD_GRAVITY, "lbf": 4.4482216152605,
              "gf": STANDARD_GRAVITY * 1e-3},
    "moment": {"n m": 1.0, "nm": 1.0, "n.m": 1.0, "n·m": 1.0, "n*m": 1.0, "kn m": 1e3,
               "knm": 1e3, "n mm": 1e-3, "nmm": 1e-3, "n.mm": 1e-3, "kgf m": STANDARD_GRAVITY,
               "kgfm": STANDARD_GRAVITY, "kgf.m": STANDARD_GRAVITY},
    "angle": {"deg": 1.0, "°": 1.0, "degree": 1.0, "degrees": 1.0, "rad": 180.0 / math.pi},
}
_VOLTS = {"v": 1.0, "mv": 1e-3, "µv": 1e-6, "uv": 1e-6}
_UNIT_WORDS = {u for table in UNIT_FACTORS.values() for u in table} | set(_VOLTS) | {
    "N", "V", "mV", "kN", "mN", "-", "deg", "°", "rad", "Hz", "%"}
_UNIT_IN_NAME = re.compile(r"[\(\[]\s*([^\)\]]+?)\s*[\)\]]\s*$")
_QUANTITY = {"time": "time", "speed": "speed", "accel": "accel", "drag": "force",
             "lift": "force", "position": "length", "fx": "force", "fy": "force",
             "mz": "moment", "sway": "length", "yaw": "angle"}


def known_units(canon: str) -> list[str]:
    """The units towtank converts to SI for channel ``canon`` ([] for a channel it does not
    know)."""
    shown = {"n": "N", "kn": "kN", "mn": "mN"} if _QUANTITY.get(canon) == "force" else \
        {u: u.replace("n", "N") for u in UNIT_FACTORS["moment"]} \
        if _QUANTITY.get(canon) == "moment" else {}
    return [shown.get(u, u) for u in UNIT_FACTORS.get(_QUANTITY.get(canon, ""), {})]


def converts(canon: str, unit: str) -> bool:
    """True when towtank knows ``unit`` for channel ``canon`` (:data:`UNIT_FACTORS`), or it
    is a voltage (a raw signal that needs a gain)."""
    key = unit.strip().lower()
    return is_volts(unit) or key in {u.lower() for u in known_units(canon)}


#: A time unit at the end of a time column's name after ``_`` or a blank (``time_us``, ``t ms``).
_TIME_UNIT_SUFFIX = re.compile(r"[_\s](s|sec|ms|us|µs|min)$", re.IGNORECASE)


def column_unit(column: str, stated: dict[str, str], canon: str | None = None) -> str | None:
    """The unit of a column: stated by the file, else written in its name in brackets
    (``Speed (mm/s)``, ``t [s]``), else, for the time (``canon = "time"``), a time unit ending
    its name (``time_us``, ``Time_ms``)."""
    if stated.get(column):
        return stated[column].strip()
    m = _UNIT_IN_NAME.search(column)
    if m:
        return m.group(1).strip()
    m = _TIME_UNIT_SUFFIX.search(column.strip()) if canon == "time" else None
    return m.group(1).lower() if m else None


def is_volts(unit: str | None) -> bool:
    """True for a unit of voltage (V, mV, µV): a raw bridge or amplifier signal."""
    return unit is not None and unit.strip().lower() in _VOLTS


def unit_factor(canon: str, unit: str | None, column: str, name: str) -> float:
    """Factor that brings a column's values in ``unit`` to the SI unit of channel ``canon``.

    1 for the SI unit and for units towtank does not know; a voltage is a RunError, since a
    channel recorded in volts needs its calibration (``gain`` in ``[channels]``).
    """
    if not unit:
        return 1.0
    key = unit.strip()
    quantity = _QUANTITY.get(canon)
    table = UNIT_FACTORS.get(quantity or "", {})
    for k, v in table.items():
        if key == k or key.lower() == k.lower():
            return v
    if key.lower() in _VOLTS:
        raise RunError(
            f"{name}: the {canon} column '{column}' is recorded in {key}: give its calibration "
            f"in [channels] ({canon} = {{ column = \"{column}\", gain = <N per {key}> }})"
        )
    return 1.0
