"""Run sheet reader (docs/formats.md §2, §2.1): one row per run, .csv or .xlsx.

Sheet-level faults (missing required columns, duplicated run numbers, an unreadable file) stop
the day with a :class:`~towtank.errors.ProtocolError`. A fault confined to one row (a typo in
``config``, a non-numeric angle) does not: the row's ``sheet_error`` holds one sentence and the
pipeline rejects that run while processing the rest.
"""

from __future__ import annotations

import csv
import difflib
import io
import math
import posixpath
import re
import zipfile
from pathlib import Path
from typing import Any
from xml.etree import ElementTree as ET  # noqa: N817 - the usual name

import numpy as np
import pandas as pd

from towtank.errors import ProtocolError
from towtank.ingest.protocol_types import CAPTIVE_TESTS, PMM_TESTS
from towtank.ingest.readers import EXTENSIONS, name_list
from towtank.ingest.sheetlayout import (
    STATUS_WORDS,
    TEST_WORDS,
    SheetOptions,
    header_names,
    words,
)
from towtank.ingest.values import shown
from towtank.reference.air import AIR_TEMPERATURE_RANGE_C
from towtank.reference.water import temperature_problem
from towtank.runtime.pathcheck import is_regular_file
from towtank.runtime.safefile import text_lines

REQUIRED = ("run", "file", "config", "angle_deg")
CONFIGS = ("hull", "fin", "sting")
TESTS = ("steady", "accel", *CAPTIVE_TESTS)
STATUSES = ("ok", "void")
#: The plane of a captive run: the model upright, or rolled onto its side (``[captive]
#: roll_deg``) for heave and pitch.
PLANES = ("horizontal", "vertical")
#: The captive runs' numeric columns (docs/formats.md, "Captive manoeuvring tests").
CAPTIVE_NUMERIC = ("drift_deg", "rudder_deg", "radius_m", "pmm_amplitude_m", "pmm_frequency_hz")
#: Largest run number taken (a run number is an identifier, not a quantity).
MAX_RUN_NUMBER = 999_999_999

NUMERIC = ("speed_nominal", "accel_nominal", "water_temp_C", "window_start_s", "window_end_s",
           *CAPTIVE_NUMERIC)
KNOWN = REQUIRED + (
    "plane",
    *CAPTIVE_NUMERIC,
    "test",
    "speed_nominal",
    "accel_nominal",
    "tare_group",
    "water_temp_C",
    "status",
    "remarks",
    "window_start_s",
    "window_end_s",
    "segment",
)
DEFAULT_TARE_GROUP = "default"
#: Most column names a run-sheet message lists (a sheet holds every known column, 14, and a
#: few of the lab's own); the rest are counted.
SHEET_COLUMNS_SHOWN = 16


def _read_table(path: Path, options: SheetOptions | None = None,
                warnings: list[str] | None = None) -> tuple[
        pd.DataFrame, list[int], dict[str, tuple[float, float]], list[str]]:
    """The sheet's table: (rows with the contract's column names, each row's line in the
    sheet (1-based), unit conversions of eq. 1 of :mod:`towtank.ingest.sheetlayout`, notes
    found below the table); warnings about the workbook are appended to ``warnings``."""
    opts = options or SheetOptions()
    suffix = path.suffix.lower()
    _check_size(path)
    try:
        if suffix == ".xlsx":
            grid = _read_xlsx(path, opts, warnings)
        elif suffix == ".csv":
            if opts.name:
                raise ProtocolError(f"{path.name}: [sheet] name = {opts.name!r} names a "
                                    "worksheet, but the run sheet is a CSV file (it has none).")
            grid = read_csv_grid(path, opts)
        else:
            raise ProtocolError(f"{path.name}: a run sheet must be .csv or .xlsx.")
    except ProtocolError:
        raise
    except Exception as exc:  # noqa: BLE001 - any reader failure is a sheet-level fault
        raise ProtocolError(f"{path.name}: the run sheet cannot be read ({exc}).") from None
    head = _header_index(grid, opts, path.name)
    names, units = header_names(list(grid[head]) if grid else [], opts, path.name)
    names = [n if n else f"Unnamed: {i}" for i, n in enumerate(names)]
    names = known_columns(names, path.name)
    body, lines, notes = _table_body(grid, head, len(names))
    df = pd.DataFrame(body, columns=names, dtype=object) if body else \
        pd.DataFrame(columns=names, dtype=object)
    return df, lines, units, notes


#: Bounds of a run sheet: a campaign's sheet has hundreds of rows and a few kB of text; a
#: file beyond these is not a run sheet (or is one damaged) and is refused in one sentence
#: rather than read for minutes into all of the memory.
MAX_SHEET_BYTES = 64 << 20  # the file (a .csv, or an .xlsx as stored)
MAX_SHEET_UNPACKED = 256 << 20  # an .xlsx's parts once unzipped
MAX_SHEET_ROWS = 100_000


def _check_size(path: Path) -> None:
    try:
        size = path.stat().st_size
    except OSError:
        return  # the reader says what is wrong with it
    if size > MAX_SHEET_BYTES:
        raise ProtocolError(
            f"{path.name}: the run sheet is {size / 2**20:.0f} MiB, but towtank reads run sheets "
            f"up to {MAX_SHEET_BYTES >> 20} MiB (a day's sheet is a few kB): is it the right "
            "file?")


def _check_rows(path: Path, rows: int, where: str = "") -> None:
    if rows > MAX_SHEET_ROWS:
        raise ProtocolError(
            f"{path.name}: the run sheet{where} has {rows:,} rows, but towtank reads run sheets "
            f"of up to {MAX_SHEET_ROWS:,} rows (a day has hundreds): is it the right file, or "
            "are the empty rows below the table formatted?")


_CELL_REF = re.compile(rb'<(?:\w+:)?c\b[^>]*?\br="([A-Z]{1,3})(\d{1,7})"')
_MERGE_REF = re.compile(rb'(<(?:\w+:)?mergeCell\b[^>]*?\bref=")([A-Z]{1,3})(\d{1,7}):'
                        rb'([A-Z]{1,3})(\d{1,7})("[^>]*/>)')


def _column_number(letters: bytes) -> int:
    n = 0
    for ch in letters:
        n = n * 26 + (ch - 64)
    return n


def _column_letters(n: int) -> str:
    out = ""
    while n:
        n, r = divmod(n - 1, 26)
        out = chr(65 + r) + out
    return out


def _bounded_xlsx(path: Path) -> Path | io.BytesIO:
    """The workbook to open: ``path`` itself, or a copy in memory whose merged ranges are cut
    to the worksheet's used area (a range down to row 1,048,576 would make the reader create
    billions of cells). Refuses a workbook too large to be a run sheet."""
    try:
        zf = zipfile.ZipFile(path)
    except (zipfile.BadZipFile, OSError):
        return path  # openpyxl says what is wrong
    with zf:
        infos = zf.infolist()
        unpacked = sum(i.file_size for i in infos)
        if unpacked > MAX_SHEET_UNPACKED:
            raise ProtocolError(
                f"{path.name}: the workbook unpacks to {unpacked / 2**20:.0f} MiB, but towtank "
                f"reads run sheets up to {MAX_SHEET_UNPACKED >> 20} MiB (a day's sheet is a "
                "few kB; a huge remark or pasted data?).")
        changed: dict[str, bytes] = {}
        for info in infos:
            if not (info.filename.startswith("xl/worksheets/") and
                    info.filename.endswith(".xml")):
                continue
            xml = zf.read(info)
            cells = [(int(r), _column_number(c)) for c, r in _CELL_REF.findall(xml)]
            last_row = max((r for r, _ in cells), default=1)
            last_col = max((c for _, c in cells), default=1)
            _check_rows(path, last_row, f" (worksheet file {info.filename.rsplit('/', 1)[-1]})")

            def clip(m: re.Match[bytes], last_row: int = last_row,
                     last_col: int = last_col) -> bytes:
                c0, r0 = _column_number(m.group(2)), int(m.group(3))
                c1, r1 = _column_number(m.group(4)), int(m.group(5))
                c1, r1 = min(c1, max(c0, last_col)), min(r1, max(r0, last_row))
                ref = f"{_column_letters(c0)}{r0}:{_column_letters(c1)}{r1}".encode()
                return m.group(1) + ref + m.group(6)

            clipped = _MERGE_REF.sub(clip, xml)
            if clipped != xml:
                changed[info.filename] = clipped
        if not changed:
            return path
        buf = io.BytesIO()
        with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as out:
            for info in infos:
                out.writestr(info, changed.get(info.filename) or zf.read(info))
        buf.seek(0)
        return buf


def read_csv_grid(path: Path, opts: SheetOptions) -> list[list[Any]]:
    """A CSV sheet's cells as text, separated by ``,``, ``;`` or tab (found from the lines)."""
    raw = path.read_bytes()
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")  # an Excel export on a European system
    lines = text_lines(text)
    delim = opts.delimiter
    if delim == "auto":
        sample = [ln for ln in lines[:40] if ln.strip()]
        counts = {d: sum(ln.count(d) for ln in sample) for d in (";", "\t", ",")}
        delim = ";" if counts[";"] >= max(1, counts[","] // 2) else \
            "\t" if counts["\t"] > counts[","] else ","
    _check_rows(path, len(lines))
    grid = [row for row in csv.reader(lines, delimiter=delim, skipinitialspace=True)]
    decimal = opts.decimal if opts.decimal != "auto" else ("," if delim != "," else ".")
    if decimal == ",":
        grid = [[_decimal_comma(c) for c in row] for row in grid]
    return grid


_COMMA_NUMBER = re.compile(r"^\s*[-+]?\d+,\d*\s*$|^\s*[-+]?,\d+\s*$")


def _decimal_comma(cell: str) -> str:
    return cell.replace(",", ".") if _COMMA_NUMBER.match(cell) else cell


def _header_index(grid: list[list[Any]], opts: SheetOptions, src: str) -> int:
    """0-based row of the header: ``[sheet] header_row``, else the first of the first 30 rows
    that names the required columns (title, date and operator rows above it are skipped)."""
    if opts.header_row:
        if opts.header_row > len(grid):
            raise ProtocolError(f"{src}: [sheet] header_row = {opts.header_row}, but the sheet "
                                f"has {len(grid)} rows.")
        return opts.header_row - 1
    for i, row in enumerate(grid[:30]):
        try:
            names, _ = header_names(list(row), opts, src)
        except ProtocolError:
            continue
        normed = {_norm(n) for n in names if n}
        if {_norm(c) for c in REQUIRED} <= normed:
            return i
    return 0  # the missing columns are named by the caller


def _is_note(row: list[Any]) -> bool:
    """A line of text below (or in) the table, not a run: fewer filled cells than the required
    columns, none of them a number (a run row has its run number; a note typed with a ``;`` in
    a CSV sheet fills two cells)."""
    filled = [c for c in row if not _is_blank(c)]
    if not filled or len(filled) >= len(REQUIRED):
        return False
    for cell in filled:
        try:
            float(str(cell).strip())
            return False
        except ValueError:
            continue
    return True


def _table_body(grid: list[list[Any]], head: int, width: int) -> tuple[
        list[list[Any]], list[int], list[str]]:
    """The table's rows under the header, each padded to ``width``, their lines (1-based),
    and the notes typed among or below them (a line of one text cell), which are not runs."""
    body, lines, notes = [], [], []
    for k, row in enumerate(grid[head + 1:], start=head + 2):
        row = list(row)
        if all(_is_blank(c) for c in row):
            continue
        if _is_note(row):
            notes.append("; ".join(str(c).strip() for c in row if not _is_blank(c)))
            continue
        body.append((row + [None] * width)[:width])
        lines.append(k)
    return body, lines, notes


#: How close (difflib ratio) an unknown column name must be to a known one to be taken for a
#: misspelling of it (``water_temp``, ``tare_grp``, ``remark``; not ``air_temp_C``, ``start_s``).
MISSPELLING_RATIO = 0.85
_UNIT_SUFFIX = re.compile(r"_(c|f|k|s|ms|min|deg|rad|m_s|m_s2|kn)$")


def _norm(name: str) -> str:
    return re.sub(r"[\s\-]+", "_", name.strip()).lower()


def known_columns(columns: list[str], src: str) -> list[str]:
    """The sheet's column names with the docs/formats.md §2 ones spelt as the contract spells them.

    A known column written in another case or with spaces or hyphens for underscores
    (``Status``, ``Tare group``) is renamed to its contract name. A column that is not known
    but is close to a known one is an error: read as an extra column it would silently lose
    what it says (a void run processed, every run at the default temperature). So is the
    same known column twice (``status`` and ``Status``).

    Raises
    ------
    ProtocolError
        Naming the column and the known column it resembles (or the unit it is in).
    """
    by_norm = {_norm(k): k for k in KNOWN}
    out = [c if c in KNOWN else by_norm.get(_norm(c), c) for c in columns]
    seen: dict[str, str] = {}
    for original, name in zip(columns, out, strict=True):
        if name in KNOWN:
            if name in seen:
                raise ProtocolError(
                    f"{src}: the run sheet has the column {name!r} twice ({seen[name]!r} and "
                    f"{original!r}); keep one."
                )
            seen[name] = original
    absent = {_norm(k): k for k in KNOWN if k not in out}
    for c in out:
        if c in KNOWN:
            continue
        close = difflib.get_close_matches(_norm(c), list(absent), n=1, cutoff=MISSPELLING_RATIO)
        if not close:
            continue
        known = absent[close[0]]
        unit_c, unit_k = _UNIT_SUFFIX.search(_norm(c)), _UNIT_SUFFIX.search(_norm(known))
        if unit_c and unit_k and unit_c.group(1) != unit_k.group(1):
            raise ProtocolError(
                f"{src}: the run sheet's column {c!r} looks like {known!r} in another unit; "
                f"towtank reads {known!r} only: convert the values and name the column so."
            )
        raise ProtocolError(
            f"{src}: the run sheet's column {c!r} looks like a misspelling of {known!r}; "
            "rename it (other columns are carried to the reports as they are, so a misspelt "
            "one would be silently ignored)."
        )
    return out


def _read_xlsx(path: Path, opts: SheetOptions | None = None,
               warnings: list[str] | None = None) -> list[list[Any]]:
    """The run-sheet worksheet's cells, as text or numbers.

    The worksheet (docs/formats.md §2) is the one ``[sheet] name`` names (hidden or not);
    else, among the *visible* worksheets whose header row (within the first 30 rows) names
    the required columns, the workbook's active one, or failing that the first (a notes tab
    may come first). A hidden or very hidden worksheet is never taken unless named: what
    Excel does not show is not what the operator checked. When several visible worksheets
    have the columns, a warning (appended to ``warnings``) names the one used.

    Formulas give the values Excel saved with them; a formula whose saved value is an empty
    string (``=IF(…,"",…)``) is an empty cell. A merged range (a tare group or a temperature
    typed once over several runs) gives its value to every cell it covers, as the reader of
    the sheet sees it; a plain reader would leave all but the first cell empty.

    Raises
    ------
    ProtocolError
        The named worksheet does not exist; no visible worksheet has the required columns;
        or a formula has no saved value at all (a workbook written by a program and never
        saved by Excel), which would read as an empty cell.
    """
    # loaded on use: openpyxl only for an .xlsx sheet
    import openpyxl

    opts = opts or SheetOptions()
    source = _bounded_xlsx(path)
    wb = openpyxl.load_workbook(_reopen(source), data_only=True)
    try:
        ws = _run_worksheet(wb, path.name, opts, warnings)
        for rng in list(ws.merged_cells.ranges):
            value = ws.cell(rng.min_row, rng.min_col).value
            ws.unmerge_cells(str(rng))
            for row in ws.iter_rows(min_row=rng.min_row, max_row=rng.max_row,
                                    min_col=rng.min_col, max_col=rng.max_col):
                for cell in row:
                    cell.value = value
        rows = [list(r) for r in ws.iter_rows(values_only=True)]
        title = ws.title
    finally:
        wb.close()
    blanks = [r for r in _unsaved_formulas(_reopen(source), title) if r[1] > 1]
    if blanks:
        cells = ", ".join(f"{col}{row}" for col, row in blanks[:5])
        more = f" and {len(blanks) - 5} more" if len(blanks) > 5 else ""
        raise ProtocolError(
            f"{path.name}: the cell(s) {cells}{more} hold formulas with no saved value (the "
            "workbook was written by a program, not saved by Excel), so they would read as "
            "empty; open and save the sheet in Excel, or type the values."
        )
    return rows


def _state(ws: Any) -> str:
    """'visible', 'hidden' or 'very hidden' (Excel's words) of a worksheet."""
    state = getattr(ws, "sheet_state", "visible") or "visible"
    return "very hidden" if state == "veryHidden" else state


def _run_worksheet(wb: Any, src: str, opts: SheetOptions, warnings: list[str] | None) -> Any:
    """The worksheet holding the runs (see :func:`_read_xlsx`)."""
    def top(ws: Any) -> list[list[Any]]:
        return [list(r) for r in ws.iter_rows(max_row=30, values_only=True)]

    def has_columns(ws: Any) -> bool:
        grid = top(ws)
        i = _header_index(grid, opts, src)
        names, _ = header_names(grid[i] if grid else [], opts, src)
        return {_norm(c) for c in REQUIRED} <= {_norm(str(n)) for n in names if n}

    def listed(sheets: list[Any]) -> str:
        return name_list((repr(ws.title) + ("" if _state(ws) == "visible" else
                                            f" ({_state(ws)})") for ws in sheets),
                         SHEET_COLUMNS_SHOWN, quoted=False)

    sheets = list(wb.worksheets)
    if opts.name:
        named = [ws for ws in sheets if ws.title == opts.name] or \
            [ws for ws in sheets if ws.title.strip().casefold() == opts.name.strip().casefold()]
        if len(named) != 1:
            raise ProtocolError(
                f"{src}: [sheet] name = {opts.name!r}, but the workbook has no worksheet of that "
                f"name (worksheets: {listed(sheets)})."
            )
        return named[0]  # its columns are checked with the rest of the sheet
    visible = [ws for ws in sheets if _state(ws) == "visible"]
    candidates = [ws for ws in visible if has_columns(ws)]
    if not candidates:
        hidden = [ws for ws in sheets if _state(ws) != "visible" and has_columns(ws)]
        if hidden:
            raise ProtocolError(
                f"{src}: no visible worksheet has the required columns {', '.join(REQUIRED)}; "
                f"the {_state(hidden[0])} worksheet {hidden[0].title!r} has them, but a hidden "
                "worksheet is read only when [sheet] name names it (worksheets: "
                f"{listed(sheets)})."
            )
        first = top(visible[0] if visible else sheets[0])
        found = [str(h).strip() for h in (first[0] if first else []) if h is not None]
        missing = [c for c in REQUIRED if _norm(c) not in {_norm(h) for h in found}]
        name = repr((visible or sheets)[0].title)
        raise ProtocolError(
            f"{src}: no worksheet has the required columns {', '.join(REQUIRED)} in a "
            f"header row (within its first 30 rows); the first, {name}, lacks "
            f"{', '.join(missing)} (columns found: "
            f"{name_list(found, SHEET_COLUMNS_SHOWN, quoted=False)}; worksheets: "
            f"{listed(sheets)}; the lab's own column names can be mapped in [sheet] columns)."
        )
    active = wb.active
    chosen = next((ws for ws in candidates if ws is active), candidates[0])
    if len(candidates) > 1 and warnings is not None:
        why = "the active one" if chosen is active else "the first"
        warnings.append(
            f"the workbook {src} has {len(candidates)} visible worksheets with the run sheet's "
            f"columns ({listed(candidates)}); {chosen.title!r} is used ({why}): name another "
            "in [sheet] name if it is not the right one."
        )
    return chosen


def _reopen(source: Path | io.BytesIO) -> Path | io.BytesIO:
    """A workbook source to open once more (a file again, or a fresh view of the bytes)."""
    return io.BytesIO(source.getvalue()) if isinstance(source, io.BytesIO) else source


_MAIN_NS = "{http://schemas.openxmlformats.org/spreadsheetml/2006/main}"
_REL_NS = "{http://schemas.openxmlformats.org/officeDocument/2006/relationships}"
_PKG_NS = "{http://schemas.openxmlformats.org/package/2006/relationships}"


def _worksheet_part(zf: zipfile.ZipFile, title: str) -> str | None:
    """The zip member holding worksheet ``title`` (``xl/worksheets/sheetN.xml``)."""
    book = ET.fromstring(zf.read("xl/workbook.xml"))
    rid = next((el.get(f"{_REL_NS}id") for el in book.iter(f"{_MAIN_NS}sheet")
                if el.get("name") == title), None)
    rels = ET.fromstring(zf.read("xl/_rels/workbook.xml.rels"))
    target = next((el.get("Target") for el in rels.iter(f"{_PKG_NS}Relationship")
                   if el.get("Id") == rid), None)
    if rid is None or target is None:
        return None
    return target.lstrip("/") if target.startswith("/") else \
        posixpath.normpath(posixpath.join("xl", target))


def _unsaved_formulas(source: Path | io.BytesIO, title: str) -> list[tuple[str, int]]:
    """(column letter, row) of the formula cells of worksheet ``title`` that have no saved
    value: no ``<v>`` element, or an empty one that is not a text result (``t="str"``: Excel
    saves the empty string a formula such as ``=IF(…,"",…)`` returns as ``<v></v>``, which
    is a value, an empty cell). A program that writes formulas without computing them (as
    openpyxl does) leaves ``<v/>`` with no type, or no ``<v>`` at all."""
    with zipfile.ZipFile(source) as zf:
        part = _worksheet_part(zf, title)
        if part is None or part not in zf.namelist():
            return []
        out = []
        with zf.open(part) as fh:
            for _, el in ET.iterparse(fh):
                if el.tag != f"{_MAIN_NS}c":
                    continue
                if el.find(f"{_MAIN_NS}f") is not None:
                    v = el.find(f"{_MAIN_NS}v")
                    saved = v is not None and (bool(v.text) or el.get("t") == "str")
                    if not saved:
                        m = re.match(r"([A-Z]+)(\d+)$", el.get("r") or "")
                        if m:
                            out.append((m.group(1), int(m.group(2))))
                el.clear()
    return out


def _is_blank(v: object) -> bool:
    if v is None:
        return True
    if isinstance(v, float) and math.isnan(v):
        return True
    return isinstance(v, str) and not v.strip()


def _as_float(v: object) -> float:
    """A sheet cell as a number, NaN when blank; ValueError for anything else: text, true/false,
    an infinite number or one too large for a float (a 310-digit integer)."""
    if _is_blank(v):
        return float("nan")
    if isinstance(v, bool):
        raise ValueError(v)
    try:
        out = float(v) if isinstance(v, int | float | np.integer | np.floating) else \
            float(str(v).strip())
    except OverflowError:
        raise ValueError(v) from None
    if math.isinf(out):
        raise ValueError(v)
    return out


def _as_text(v: object) -> str:
    if _is_blank(v):
        return ""
    if isinstance(v, float) and v.is_integer():
        return str(int(v))
    return str(v).strip()


def read_run_sheet(path: str | Path, default_temperature_C: float,
                   options: SheetOptions | None = None, *, air: bool = False) -> pd.DataFrame:
    """Read and validate a run sheet.

    Parameters
    ----------
    path : str or Path
        The run sheet, .csv or .xlsx (its worksheet chosen as in docs/formats.md §2).
    default_temperature_C : float
        Water temperature for rows without ``water_temp_C`` [°C].
    options : SheetOptions, optional
        The protocol's ``[sheet]``: header row, the lab's column names, CSV separator and
        decimal mark (:mod:`towtank.ingest.sheetlayout`).
    air : bool, default False
        The medium is air ([water] type = "air"): ``water_temp_C`` is the air temperature,
        checked against -60–150 °C instead of the liquid range of water.

    Returns
    -------
    pandas.DataFrame
        One row per run in sheet order with typed columns: run (int), file, config, test,
        angle_deg [deg], speed_nominal [m/s], accel_nominal [m/s²], tare_group,
        water_temp_C [°C], status, remarks, window_start_s, window_end_s [s], and where the
        sheet has captive runs or their columns: plane, drift_deg, rudder_deg [deg],
        radius_m, pmm_amplitude_m [m], pmm_frequency_hz [Hz] (a captive row's angle_deg is
        its drift angle, its blank rudder_deg 0; NaN where not set), segment (the
        run's acquisition in a file holding several, from 1; NaN = none given), sheet_row
        (1-based row in the sheet, header = row 1), sheet_error (one sentence, or "") and
        every extra column of the sheet, unchanged. ``.attrs["notes"]`` holds the lines of
        text typed among or below the table (not runs), ``.attrs["warnings"]`` sentences
        about the workbook for the day's warnings (several worksheets with the columns).

    Raises
    ------
    ProtocolError
        Missing required columns, duplicated run numbers, unreadable sheet, no rows.
    """
    path = Path(path)
    src = path.name
    warnings: list[str] = []
    raw, lines, units, notes = _read_table(path, options, warnings)
    if "angle_deg" not in raw.columns and "drift_deg" in raw.columns:
        raw["angle_deg"] = None  # a captive sheet: each row's angle is its drift angle
    missing = [c for c in REQUIRED if c not in raw.columns]
    if missing:
        found = name_list(map(str, raw.columns), SHEET_COLUMNS_SHOWN, quoted=False)
        raise ProtocolError(
            f"{src}: the run sheet lacks the required column(s) {', '.join(missing)} "
            f"(columns found: {found})."
        )
    if raw.empty:
        raise ProtocolError(f"{src}: the run sheet has no runs.")

    rows = []
    for i, rec in enumerate(raw.to_dict("records")):
        sheet_row = lines[i]
        errors: list[str] = []
        run_text = _as_text(rec["run"])
        try:
            run_f = float(run_text)
            if not run_f.is_integer():
                raise ValueError
            if not 0 <= run_f <= MAX_RUN_NUMBER:
                raise ValueError
            run = int(run_f)
        except (ValueError, OverflowError):
            status = words(_as_text(rec.get("status", "")), STATUS_WORDS)
            if status == "void" or not _as_text(rec["file"]):
                # not a run: a voided row (never an error) or a total or note line
                notes.append(f"row {sheet_row} is left aside: its run number {run_text!r} is "
                             "not a whole number and it "
                             + ("is void" if status == "void" else "names no data file"))
                continue
            raise ProtocolError(
                f"{src}: row {sheet_row} has run number {run_text!r}, which is not a whole number "
                f"from 0 to {MAX_RUN_NUMBER}."
            ) from None
        out: dict[str, Any] = {"run": run, "sheet_row": sheet_row}
        out["file"] = _as_text(rec["file"])
        if not out["file"]:
            errors.append("the sheet gives no data file")
        config = _as_text(rec["config"]).lower()
        if config not in CONFIGS:
            errors.append(f"config {config!r} is not one of {', '.join(CONFIGS)}")
        out["config"] = config
        test = words(_as_text(rec.get("test", "")), TEST_WORDS)
        if test and test not in TESTS:
            errors.append(f"test {test!r} is not one of {', '.join(TESTS)}")
        out["test"] = test
        captive = test in CAPTIVE_TESTS
        try:
            out["angle_deg"] = _converted(_as_float(rec["angle_deg"]), units.get("angle_deg"))
            if math.isnan(out["angle_deg"]) and not captive:
                raise ValueError
        except ValueError:
            errors.append(f"angle_deg {shown(_as_text(rec['angle_deg']))} is not a number")
            out["angle_deg"] = float("nan")
        for col in NUMERIC:
            try:
                out[col] = _converted(_as_float(rec.get(col)), units.get(col))
            except ValueError:
                errors.append(f"{col} {shown(_as_text(rec.get(col)))} is not a number")
                out[col] = float("nan")
        out["plane"] = _as_text(rec.get("plane", "")).lower() or "horizontal"
        if captive:
            errors += _captive_row(out, config)
        elif out["plane"] not in PLANES:
            errors.append(f"plane {out['plane']!r} is not one of {', '.join(PLANES)}")
        if math.isnan(out["water_temp_C"]):
            out["water_temp_C"] = float(default_temperature_C)
        else:
            problem = (temperature_problem(out["water_temp_C"],
                                           AIR_TEMPERATURE_RANGE_C, "of air in a test rig")
                       if air else temperature_problem(out["water_temp_C"]))
            if problem is not None:
                errors.append(f"water_temp_C: {problem}")
                out["water_temp_C"] = float(default_temperature_C)
        status = words(_as_text(rec.get("status", "")), STATUS_WORDS) or "ok"
        if status not in STATUSES:
            errors.append(f"status {status!r} is not one of {', '.join(STATUSES)} (or a word "
                          "for them: x, bad, skip, excluded...; good, valid, ✓...)")
        out["status"] = status
        out["tare_group"] = _as_text(rec.get("tare_group", "")) or DEFAULT_TARE_GROUP
        out["remarks"] = _as_text(rec.get("remarks", ""))
        if "segment" in raw.columns:
            out["segment"] = _segment(rec.get("segment"), errors)
        ws, we = out["window_start_s"], out["window_end_s"]
        if math.isnan(ws) != math.isnan(we):
            errors.append("window_start_s and window_end_s must be given together")
        elif not math.isnan(ws) and not we > ws:
            errors.append(f"window_end_s ({we}) must be after window_start_s ({ws})")
        for col in raw.columns:
            if col not in KNOWN:
                out[col] = rec[col]
        out["sheet_error"] = (
            f"row {sheet_row} of {src}: " + "; ".join(errors) + "." if errors else ""
        )
        rows.append(out)

    if not rows:
        raise ProtocolError(f"{src}: the run sheet has no runs.")
    df = pd.DataFrame(rows)
    captive_columns = ("plane", *CAPTIVE_NUMERIC)
    if not df["test"].isin(CAPTIVE_TESTS).any() and \
            not any(c in raw.columns for c in captive_columns):
        df = df.drop(columns=list(captive_columns))  # a sheet of resistance tests as it was
    dup = df["run"][df["run"].duplicated(keep=False)]
    if not dup.empty:
        numbers = sorted(set(dup.tolist()))
        where = {
            r: df.loc[df["run"] == r, "sheet_row"].tolist() for r in numbers
        }
        detail = "; ".join(f"run {r} on rows {', '.join(map(str, w))}" for r, w in where.items())
        raise ProtocolError(f"{src}: duplicated run numbers ({detail}).")
    if "segment" in df.columns:  # whole numbers (runs.csv carries them as written)
        df["segment"] = df["segment"].astype("Int64")
    for col in ANGLE_COLUMNS:
        if col in df.columns and units.get(col) is None:  # a unit in the header is its own
            said = radian_angles_warning(df[col].to_numpy(dtype=float), col, src)
            warnings += [said] if said else []
    df.attrs["notes"] = notes
    df.attrs["warnings"] = warnings
    return df


#: The sheet's angle columns [deg] checked for angles typed in radians.
ANGLE_COLUMNS = ("angle_deg", "drift_deg", "rudder_deg")
#: How close [deg] each angle read as radians must come to a whole or half degree.
RADIAN_GRID_TOL_DEG = 0.03


def radian_angles_warning(angles: np.ndarray, column: str, src: str) -> str | None:
    """One sentence when the angles of ``column`` (read as degrees) look typed in radians:
    at least two different non-zero angles, all within ±π/2 (a tow at a fraction of a degree
    is no test programme), each a whole or half degree when read as radians (to
    :data:`RADIAN_GRID_TOL_DEG`, enough for values rounded to 3 decimals) while the values
    themselves are not whole or half degrees. Else None."""
    a = np.abs(angles[np.isfinite(angles)])
    a = a[a > 0.0]
    if np.unique(np.round(a, 6)).size < 2 or a.max() > math.pi / 2 + 1e-3:
        return None
    deg = np.degrees(a)
    on_grid = np.abs(2.0 * deg - np.round(2.0 * deg)) <= 2.0 * RADIAN_GRID_TOL_DEG
    already = np.abs(2.0 * a - np.round(2.0 * a)) <= 1e-9
    if not on_grid.all() or already.all():
        return None
    i = int(np.argmax(a))
    return (f"{src}: every {column} of the run sheet lies within ±π/2 and is a whole or half "
            f"degree when read as radians ({a[i]:g} = {deg[i]:.2f}°): were the angles typed in "
            "radians? towtank reads them as degrees (write them in degrees, or give the "
            "column's unit in its header: Angle [rad]).")


#: Largest |drift_deg| and |rudder_deg| of a captive run [deg].
MAX_CAPTIVE_ANGLE_DEG = 90.0


def _captive_row(out: dict[str, Any], config: str) -> list[str]:
    """A captive row's checks (its problems, one clause each), and its angles settled: the
    drift angle is ``drift_deg``, else ``angle_deg`` (the two must agree when both are
    given), else 0; ``angle_deg`` is set to it (runs.csv's angle of a captive run)."""
    errors = []
    test = out["test"]
    if config != "hull":
        errors.append(f"test {test!r} is a captive test of the hull, but config is {config!r}")
    drift, angle = out["drift_deg"], out["angle_deg"]
    if not math.isnan(drift) and not math.isnan(angle) and abs(drift - angle) > 1e-9:
        errors.append(f"drift_deg ({drift:g}) and angle_deg ({angle:g}) differ; give one")
    drift = drift if not math.isnan(drift) else angle if not math.isnan(angle) else 0.0
    out["drift_deg"] = out["angle_deg"] = drift
    for col in ("drift_deg", "rudder_deg"):
        if abs(out[col]) > MAX_CAPTIVE_ANGLE_DEG:
            errors.append(f"{col} {out[col]:g} is beyond ±{MAX_CAPTIVE_ANGLE_DEG:g}° (radians?)")
    if math.isnan(out["rudder_deg"]):
        out["rudder_deg"] = 0.0
    radius = out["radius_m"]
    if test == "arm" and not (abs(radius) > 0):
        errors.append("an arm run needs radius_m, the radius of the model's path (not 0)")
    if test in PMM_TESTS:
        for col in ("pmm_amplitude_m", "pmm_frequency_hz"):
            if not out[col] > 0:
                errors.append(f"a PMM run ({test}) needs {col} (a positive number)")
    if out["plane"] not in PLANES:
        errors.append(f"plane {out['plane']!r} is not one of {', '.join(PLANES)}")
    return errors


def _segment(value: Any, errors: list[str]) -> float:
    """The run's acquisition in a file holding several (``segment``, counted from 1), NaN when
    the sheet gives none; anything but a whole number from 1 is a row error."""
    text = _as_text(value)
    if not text:
        return math.nan
    try:
        k = float(text)
    except ValueError:
        k = math.nan
    if not (math.isfinite(k) and k.is_integer() and 1 <= k <= 1_000_000):
        errors.append(f"segment {text!r} is not a whole number from 1 (the file's first "
                      "acquisition is 1)")
        return math.nan
    return float(k)


def _converted(value: float, unit: tuple[float, float] | None) -> float:
    """A sheet value in the contract's unit (eq. 1 of :mod:`towtank.ingest.sheetlayout`)."""
    return value if unit is None or math.isnan(value) else unit[0] * value + unit[1]


def unlisted_files(sheet: pd.DataFrame, data_dir: Path) -> list[str]:
    """Data files in ``data_dir`` that no row of the sheet names (the lab may have forgotten):
    every file with an extension towtank reads as a run file
    (:data:`towtank.ingest.readers.EXTENSIONS`, and those of text formats gzipped)."""
    suffixes = tuple(EXTENSIONS) + tuple(f"{e}.gz" for e, kind in EXTENSIONS.items()
                                         if kind in ("csv", "text"))
    named = {Path(f).as_posix() for f in sheet["file"]}
    out = []
    for p in sorted(data_dir.rglob("*")):
        if not is_regular_file(p) or p.name.startswith("."):
            continue
        if not p.name.lower().endswith(suffixes):
            continue
        rel = p.relative_to(data_dir).as_posix()
        if rel not in named:
            out.append(rel)
    return out

