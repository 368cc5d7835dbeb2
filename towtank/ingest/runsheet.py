"""Run sheet reader (FORMATS.md §2): one row per run, .csv or .xlsx.

Sheet-level faults (missing required columns, duplicated run numbers, an unreadable file) stop
the day with a :class:`~towtank.errors.ProtocolError`. A fault confined to one row (a typo in
``config``, a non-numeric angle) does not: the row's ``sheet_error`` holds one sentence and the
pipeline rejects that run while processing the rest.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from towtank.errors import ProtocolError

REQUIRED = ("run", "file", "config", "angle_deg")
CONFIGS = ("hull", "fin", "sting")
TESTS = ("steady", "accel")
STATUSES = ("ok", "void")
NUMERIC = ("speed_nominal", "accel_nominal", "water_temp_C", "window_start_s", "window_end_s")
KNOWN = REQUIRED + (
    "test",
    "speed_nominal",
    "accel_nominal",
    "tare_group",
    "water_temp_C",
    "status",
    "remarks",
    "window_start_s",
    "window_end_s",
)
DEFAULT_TARE_GROUP = "default"


def _read_table(path: Path) -> pd.DataFrame:
    suffix = path.suffix.lower()
    try:
        if suffix == ".xlsx":
            df = _read_xlsx(path)
        elif suffix == ".csv":
            df = pd.read_csv(path, dtype=str, keep_default_na=False, skipinitialspace=True)
        else:
            raise ProtocolError(f"{path.name}: a run sheet must be .csv or .xlsx.")
    except ProtocolError:
        raise
    except Exception as exc:  # noqa: BLE001 - any reader failure is a sheet-level fault
        raise ProtocolError(f"{path.name}: the run sheet cannot be read ({exc}).") from None
    df.columns = known_columns([str(c).strip() for c in df.columns], path.name)
    # drop rows that are entirely empty (trailing rows in spreadsheets)
    blank = df.apply(lambda col: col.map(_is_blank)).all(axis=1)
    return df.loc[~blank].reset_index(drop=True)


#: How close (difflib ratio) an unknown column name must be to a known one to be taken for a
#: misspelling of it (``water_temp``, ``tare_grp``, ``remark``; not ``air_temp_C``, ``start_s``).
MISSPELLING_RATIO = 0.85
_UNIT_SUFFIX = re.compile(r"_(c|f|k|s|ms|min|deg|rad|m_s|m_s2|kn)$")


def _norm(name: str) -> str:
    return re.sub(r"[\s\-]+", "_", name.strip()).lower()


def known_columns(columns: list[str], src: str) -> list[str]:
    """The sheet's column names with the FORMATS §2 ones spelt as the contract spells them.

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
    import difflib

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


def _read_xlsx(path: Path) -> pd.DataFrame:
    """The run-sheet worksheet as text-or-number cells, header in the first row.

    The worksheet is the first one whose header holds the required columns (a notes tab may
    come first). Formulas give the values Excel saved with them. A merged range (a tare group
    or a temperature typed once over several runs) gives its value to every cell it covers,
    as the reader of the sheet sees it; a plain reader would leave all but the first cell
    empty.

    Raises
    ------
    ProtocolError
        No worksheet has the required columns; or a formula has no saved value (a workbook
        written by a program and never saved by Excel), which would read as an empty cell.
    """
    import openpyxl

    wb = openpyxl.load_workbook(path, data_only=True)
    required = {_norm(c) for c in REQUIRED}

    def header(ws: Any) -> list[str]:
        first = next(ws.iter_rows(max_row=1, values_only=True), ())
        return [str(h).strip() for h in first if h is not None]

    chosen = next((ws for ws in wb.worksheets
                   if required <= {_norm(h) for h in header(ws)}), None)
    if chosen is None:
        names = ", ".join(repr(ws.title) for ws in wb.worksheets)
        found = header(wb.worksheets[0])
        missing = [c for c in REQUIRED if _norm(c) not in {_norm(h) for h in found}]
        wb.close()
        raise ProtocolError(
            f"{path.name}: no worksheet has the required columns {', '.join(REQUIRED)} in its "
            f"first row; the first, {names.split(', ')[0]}, lacks {', '.join(missing)} "
            f"(columns found: {', '.join(found) or 'none'}; worksheets: {names})."
        )
    ws = chosen
    for rng in list(ws.merged_cells.ranges):
        value = ws.cell(rng.min_row, rng.min_col).value
        ws.unmerge_cells(str(rng))
        for row in ws.iter_rows(min_row=rng.min_row, max_row=rng.max_row,
                                min_col=rng.min_col, max_col=rng.max_col):
            for cell in row:
                cell.value = value
    rows = list(ws.iter_rows(values_only=True))
    blanks = [r for r in _unsaved_formulas(path, ws) if r[1] > 1]
    wb.close()
    if blanks:
        cells = ", ".join(f"{col}{row}" for col, row in blanks[:5])
        more = f" and {len(blanks) - 5} more" if len(blanks) > 5 else ""
        raise ProtocolError(
            f"{path.name}: the cell(s) {cells}{more} hold formulas with no saved value (the "
            "workbook was written by a program, not saved by Excel), so they would read as "
            "empty; open and save the sheet in Excel, or type the values."
        )
    if not rows:
        return pd.DataFrame()
    head = [f"Unnamed: {i}" if h is None else str(h) for i, h in enumerate(rows[0])]
    return pd.DataFrame([list(r) for r in rows[1:]], columns=head, dtype=object)


def _unsaved_formulas(path: Path, values: Any) -> list[tuple[str, int]]:
    """(column letter, row) of the formula cells of ``values`` (a worksheet read with its
    saved values) that have no saved value; the formulas are read from ``path``."""
    import openpyxl

    wb = openpyxl.load_workbook(path, data_only=False)
    formulas = wb[values.title]
    out = [(cell.column_letter, cell.row)
           for row in formulas.iter_rows() for cell in row
           if cell.data_type == "f" and values[cell.coordinate].value is None]
    wb.close()
    return out


def _is_blank(v: object) -> bool:
    if v is None:
        return True
    if isinstance(v, float) and math.isnan(v):
        return True
    return isinstance(v, str) and not v.strip()


def _as_float(v: object) -> float:
    if _is_blank(v):
        return float("nan")
    if isinstance(v, bool):
        raise ValueError(v)
    if isinstance(v, int | float | np.integer | np.floating):
        return float(v)
    return float(str(v).strip())


def _as_text(v: object) -> str:
    if _is_blank(v):
        return ""
    if isinstance(v, float) and v.is_integer():
        return str(int(v))
    return str(v).strip()


def read_run_sheet(path: str | Path, default_temperature_C: float) -> pd.DataFrame:
    """Read and validate a run sheet.

    Parameters
    ----------
    path : str or Path
        The run sheet, .csv or .xlsx (first worksheet).
    default_temperature_C : float
        Water temperature for rows without ``water_temp_C`` [°C].

    Returns
    -------
    pandas.DataFrame
        One row per run in sheet order with typed columns: run (int), file, config, test,
        angle_deg [deg], speed_nominal [m/s], accel_nominal [m/s²], tare_group,
        water_temp_C [°C], status, remarks, window_start_s, window_end_s [s], sheet_row
        (1-based row in the sheet, header = row 1), sheet_error (one sentence, or "") and
        every extra column of the sheet, unchanged.

    Raises
    ------
    ProtocolError
        Missing required columns, duplicated run numbers, unreadable sheet, no rows.
    """
    path = Path(path)
    src = path.name
    raw = _read_table(path)
    missing = [c for c in REQUIRED if c not in raw.columns]
    if missing:
        found = ", ".join(raw.columns) or "none"
        raise ProtocolError(
            f"{src}: the run sheet lacks the required column(s) {', '.join(missing)} "
            f"(columns found: {found})."
        )
    if raw.empty:
        raise ProtocolError(f"{src}: the run sheet has no runs.")

    rows = []
    for i, rec in enumerate(raw.to_dict("records")):
        sheet_row = i + 2
        errors: list[str] = []
        run_text = _as_text(rec["run"])
        try:
            run_f = float(run_text)
            if not run_f.is_integer():
                raise ValueError
            run = int(run_f)
        except ValueError:
            raise ProtocolError(
                f"{src}: row {sheet_row} has run number {run_text!r}, which is not a whole number."
            ) from None
        out: dict[str, object] = {"run": run, "sheet_row": sheet_row}
        out["file"] = _as_text(rec["file"])
        if not out["file"]:
            errors.append("the sheet gives no data file")
        config = _as_text(rec["config"]).lower()
        if config not in CONFIGS:
            errors.append(f"config {config!r} is not one of {', '.join(CONFIGS)}")
        out["config"] = config
        test = _as_text(rec.get("test", "")).lower()
        if test and test not in TESTS:
            errors.append(f"test {test!r} is not one of {', '.join(TESTS)}")
        out["test"] = test
        try:
            out["angle_deg"] = _as_float(rec["angle_deg"])
            if math.isnan(out["angle_deg"]):  # type: ignore[arg-type]
                raise ValueError
        except ValueError:
            errors.append(f"angle_deg {_as_text(rec['angle_deg'])!r} is not a number")
            out["angle_deg"] = float("nan")
        for col in NUMERIC:
            try:
                out[col] = _as_float(rec.get(col))
            except ValueError:
                errors.append(f"{col} {_as_text(rec.get(col))!r} is not a number")
                out[col] = float("nan")
        if math.isnan(out["water_temp_C"]):  # type: ignore[arg-type]
            out["water_temp_C"] = float(default_temperature_C)
        status = _as_text(rec.get("status", "")).lower() or "ok"
        if status not in STATUSES:
            errors.append(f"status {status!r} is not one of {', '.join(STATUSES)}")
        out["status"] = status
        out["tare_group"] = _as_text(rec.get("tare_group", "")) or DEFAULT_TARE_GROUP
        out["remarks"] = _as_text(rec.get("remarks", ""))
        ws, we = out["window_start_s"], out["window_end_s"]
        if math.isnan(ws) != math.isnan(we):  # type: ignore[arg-type]
            errors.append("window_start_s and window_end_s must be given together")
        elif not math.isnan(ws) and not we > ws:  # type: ignore[operator, arg-type]
            errors.append(f"window_end_s ({we}) must be after window_start_s ({ws})")
        for col in raw.columns:
            if col not in KNOWN:
                out[col] = rec[col]
        out["sheet_error"] = (
            f"row {sheet_row} of {src}: " + "; ".join(errors) + "." if errors else ""
        )
        rows.append(out)

    df = pd.DataFrame(rows)
    dup = df["run"][df["run"].duplicated(keep=False)]
    if not dup.empty:
        numbers = sorted(set(dup.tolist()))
        where = {
            r: df.loc[df["run"] == r, "sheet_row"].tolist() for r in numbers
        }
        detail = "; ".join(f"run {r} on rows {', '.join(map(str, w))}" for r, w in where.items())
        raise ProtocolError(f"{src}: duplicated run numbers ({detail}).")
    return df


def unlisted_files(sheet: pd.DataFrame, data_dir: Path) -> list[str]:
    """Data files in ``data_dir`` that no row of the sheet names (the lab may have forgotten)."""
    named = {Path(f).as_posix() for f in sheet["file"]}
    out = []
    for p in sorted(data_dir.rglob("*")):
        if not p.is_file() or p.name.startswith("."):
            continue
        if not p.name.lower().endswith((".csv", ".csv.gz", ".tdms")):
            continue
        rel = p.relative_to(data_dir).as_posix()
        if rel not in named:
            out.append(rel)
    return out
