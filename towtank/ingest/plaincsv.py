"""The fast path for plain CSV run files: pyarrow's parser, with the bookkeeping that lets every
message name the file's row (header = row 1) and the checks of a damaged file (a truncated last
line, rows with the wrong number of fields, blank lines).

Text in any other layout (a preamble, ``;`` with decimal commas, a units row) is read by
:func:`towtank.ingest.readers.read_text_columns`.
"""

from __future__ import annotations

import numpy as np

from towtank.errors import RunError
from towtank.ingest.readers import block_bytes, check_run_size, cut_last_line, truncation_error

ROWS_KEY = "__rows__"
INVALID_KEY = "__invalid_rows__"
_ROWS_KEY, _INVALID_KEY = ROWS_KEY, INVALID_KEY


def list_rows(rows: np.ndarray, limit: int = 5) -> str:
    """'row 7' or 'rows 7, 9, 12, …' for a message."""
    shown = ", ".join(str(int(r)) for r in rows[:limit])
    more = ", …" if rows.size > limit else ""
    return f"row{'s' if rows.size > 1 else ''} {shown}{more}"


_list_rows = list_rows


def _sniff_delimiter(header: bytes) -> str:
    if b"," in header:
        return ","
    if b";" in header:
        return ";"
    if b"\t" in header:
        return "\t"
    return ","


def _line_table(data: bytes, delim: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """Per line of the file: 1-based number, field count, emptiness; and the header's index.

    A plain count of delimiters (numeric run files do not quote fields); it is used only to
    give messages the rows a text editor shows, never to parse values.
    """
    buf = np.frombuffer(data, dtype=np.uint8)
    nl = np.flatnonzero(buf == 10)
    starts = np.concatenate(([0], nl + 1))
    ends = np.concatenate((nl, [buf.size]))
    if starts[-1] >= buf.size:  # nothing after the final line break
        starts, ends = starts[:-1], ends[:-1]
    if starts.size == 0:
        return np.array([], int), np.array([], int), np.array([], bool), 0
    last = np.maximum(ends - 1, 0)
    cr = (ends > starts) & (buf[last] == 13)
    eff_end = ends - cr
    empty = eff_end <= starts
    cum = np.concatenate(([0], np.cumsum(buf == ord(delim))))
    nfields = cum[eff_end] - cum[starts] + 1
    numbers = np.arange(1, starts.size + 1)
    nonempty = np.flatnonzero(~empty)
    header = int(nonempty[0]) if nonempty.size else 0
    return numbers, nfields, empty, header


def _truncated_tail(data: bytes, delim: str, n_header: int,
                    name: str = "the file") -> RunError | None:
    """The truncation sentence when the file does not end with a line break and its last line
    is cut short (:func:`towtank.ingest.readers.cut_last_line`: fewer fields than the header,
    or a last value that is empty or not a number, ``1.2e``, ``-``), else None.

    A complete last line without a final line break is fine (many programs write no final
    line break); a number cut to a shorter number cannot be told from a complete one, and is
    at worst one odd sample at the end of the still window.
    """
    if data.endswith((b"\n", b"\r")):
        return None
    start = data.rfind(b"\n") + 1
    last = data[start:].rstrip(b"\r")
    if not last.strip():
        return None
    above = None  # the last non-blank line above it, unless that is the header
    end = start - 1
    while end > 0:
        begin = data.rfind(b"\n", 0, end) + 1
        line = data[begin:end].rstrip(b"\r")
        if line.strip():
            header_line = not data[:begin].strip()
            above = None if header_line else line
            break
        end = begin - 1
    cut = cut_last_line(last, delim, n_header, above)
    if cut is None:
        return None
    return truncation_error(name, data.count(b"\n") + 1, cut[0], n_header, cut[1])




def _arrow_table(data: bytes, delim: str, handler, whole: bool = False):  # noqa: ANN001
    # loaded on use: pyarrow only when a CSV is read: not for towtank predict, simulate
    # or a protocol's check
    import pyarrow as pa
    import pyarrow.csv as pacsv

    block = max(block_bytes(data), len(data) + 1) if whole else block_bytes(data)
    return pacsv.read_csv(
        pa.BufferReader(data),
        read_options=pacsv.ReadOptions(block_size=block),
        parse_options=pacsv.ParseOptions(delimiter=delim, invalid_row_handler=handler),
        convert_options=pacsv.ConvertOptions(
            strings_can_be_null=True,
            null_values=["", "NaN", "nan", "NA", "N/A", "null", "NULL"],
        ),
    )


def _numeric_column(column) -> np.ndarray:  # noqa: ANN001 - a pyarrow ChunkedArray
    """A numeric Arrow column as float64, NaN where a value is missing.

    Read from the Arrow buffers (values and validity bitmap, the Arrow columnar format)
    rather than with ``to_numpy``, which loads pandas: the reduction's worker processes never
    need pandas otherwise, and loading it costs each of them about 0.3 s.
    """
    parts = []
    for chunk in column.chunks:
        n, off = len(chunk), chunk.offset
        validity, data = chunk.buffers()[:2]
        dtype = np.dtype(chunk.type.to_pandas_dtype())
        values = np.frombuffer(data, dtype=dtype, count=off + n)[off:].astype(np.float64)
        if chunk.null_count:
            bits = np.unpackbits(np.frombuffer(validity, dtype=np.uint8), bitorder="little")
            values[~bits[off : off + n].astype(bool)] = np.nan
        parts.append(values)
    if not parts:
        return np.array([], dtype=np.float64)
    return parts[0] if len(parts) == 1 else np.concatenate(parts)


def read_csv_columns(data: bytes, name: str) -> tuple[dict[str, np.ndarray], list[str]]:
    """Parse CSV text (already decompressed) into columns.

    Returns the columns (float64 where numeric, object arrays where some values are text) and
    notes. Two private entries come with them: ``__rows__``, the file row of every data row
    (header = row 1), and ``__invalid_rows__``, the rows skipped for a wrong number of fields.
    A UTF-8 byte-order mark, Windows line ends and blank lines are accepted. A last line cut
    short is a RunError naming its row (:func:`towtank.ingest.readers.truncation_error`).
    """
    # loaded on use: pyarrow only when a CSV is read: not for towtank predict, simulate
    # or a protocol's check
    import pyarrow as pa

    if data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]
    if not data or data.isspace():
        raise RunError(f"{name} is empty (0 data rows)")
    if not data.isascii():
        try:
            data.decode("utf-8")
        except UnicodeDecodeError:  # not UTF-8: read it as Latin-1 (every byte is a character)
            data = data.decode("latin-1").encode("utf-8")
    first = len(data) - len(data.lstrip(b"\r\n")) if data[:1] in (b"\r", b"\n") else 0
    end = data.find(b"\n", first)
    header_line = data[first : end if end >= 0 else len(data)]
    delim = _sniff_delimiter(header_line)
    n_header = header_line.rstrip(b"\r").count(delim.encode()) + 1
    cut = _truncated_tail(data, delim, n_header, name)
    if cut is not None:
        raise cut
    n_lines = data.count(b"\n") + (not data.endswith(b"\n"))
    check_run_size(name, n_lines - 1, n_header)  # before pyarrow holds the values

    notes: list[str] = []
    n_invalid = [0]

    def handler(row) -> str:  # noqa: ANN001 - pyarrow.csv.InvalidRow
        n_invalid[0] += 1
        return "skip"

    table = None
    errors: list[str] = []
    for whole in (False, True):  # the second time, column types are inferred from all rows
        n_invalid[0] = 0
        try:
            table = _arrow_table(data, delim, handler, whole)
            break
        except (pa.ArrowException, UnicodeDecodeError, ValueError) as exc:
            errors.append(str(exc).splitlines()[0] if str(exc) else type(exc).__name__)
    if table is None:
        raise RunError(f"{name} is not a readable CSV table ({errors[-1]})")
    if table.num_columns == 0 or table.num_rows == 0:
        raise RunError(f"{name} has a header but no data rows")

    # file rows of the data rows (and of the skipped ones) for the messages
    rows = np.arange(table.num_rows) + 2
    invalid_rows = np.array([], dtype=int)
    # blank lines shift the rows: more line breaks than header + rows + skipped rows tells
    # (faster than searching for b"\n\n" and b"\n\r\n")
    if n_invalid[0] or n_lines > table.num_rows + 1 or data.startswith((b"\n", b"\r")):
        numbers, nfields, empty, header = _line_table(data, delim)
        body = np.arange(numbers.size) > header
        good = body & ~empty & (nfields == n_header)
        bad = body & ~empty & (nfields != n_header)
        if int(good.sum()) == table.num_rows:
            rows = numbers[good]
            invalid_rows = numbers[bad]
        else:
            invalid_rows = np.full(n_invalid[0], -1)
    if n_invalid[0]:
        if invalid_rows.size != n_invalid[0]:
            invalid_rows = np.full(n_invalid[0], -1)
        known = invalid_rows.size and int(invalid_rows.min()) > 0
        where = _list_rows(invalid_rows) if known else "rows"
        notes.append(
            f"{n_invalid[0]} row(s) with the wrong number of fields skipped ({where})"
        )

    cols: dict[str, np.ndarray] = {}
    seen: set[str] = set()
    for col_name, column in zip(table.column_names, table.columns, strict=True):
        key = col_name.strip()
        if key in seen:
            key = f"{key} (duplicate)"
        seen.add(key)
        if pa.types.is_floating(column.type) or pa.types.is_integer(column.type):
            cols[key] = _numeric_column(column)
        elif pa.types.is_null(column.type):
            cols[key] = np.full(table.num_rows, np.nan)
        elif pa.types.is_timestamp(column.type):
            ns = column.cast(pa.int64()).to_numpy(zero_copy_only=False).astype(np.float64)
            t0 = float(ns[np.isfinite(ns)][0]) if np.isfinite(ns).any() else 0.0
            cols[key] = (ns - t0) * 1e-9
        else:
            cols[key] = column.to_numpy(zero_copy_only=False)
    cols[_ROWS_KEY] = rows
    cols[_INVALID_KEY] = invalid_rows
    return cols, notes
