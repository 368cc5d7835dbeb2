"""Run sheets as a lab types them by hand, from the generator's plain sheet.

A hand-typed sheet has a title and a date/operator line above its header, the lab's own
column names with units (``Run #``, ``Angle (deg)``, ``Speed (mm/s)``, ``Water temp (°C)``),
its own words for the status (``OK``, ``x``) and the test (``Steady``, ``Accel``), and notes
typed below the table; a layout's own columns (``Segment``, ``Window start (s)``, ``Window
end (s)``) are typed too. ``hand-xlsx`` is an Excel workbook with a notes tab first;
``hand-csv`` is a European Excel export: ``;`` separated, decimal commas, Latin-1 text.
The runs and their values are those of the plain sheet, so a day read from either must give
the same coefficients.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import Any

import openpyxl
import pandas as pd

from towtank.testing.days import pinned_xlsx

__all__ = ["HAND_SHEETS", "write_hand_typed_sheet", "HAND_HEADER", "HAND_NOTES"]

HAND_SHEETS = ("hand-xlsx", "hand-csv")

#: The lab's column names (hand-csv: speed in mm/s) for each contract column.
HAND_HEADER = {
    "run": "Run #",
    "file": "Data file",
    "config": "Config",
    "test": "Test type",
    "angle_deg": "Angle (deg)",
    "speed_nominal": "Speed (m/s)",
    "accel_nominal": "Accel (m/s²)",
    "tare_group": "Tare group",
    "water_temp_C": "Water temp (°C)",
    "status": "Status",
    "remarks": "Remarks",
    "window_start_s": "Window start (s)",
    "window_end_s": "Window end (s)",
    "segment": "Segment",
    "date": "Date",
}
#: Lines typed below the table.
HAND_NOTES = (
    "Notes: carriage serviced the day before; balance zeroed at 08:40.",
    "Run 7 repeated because of a wave from the wavemaker.",
)
_STATUS = {"ok": "OK", "void": "x"}
_TEST = {"steady": "Steady", "accel": "Accel"}


def _plain_rows(path: Path) -> pd.DataFrame:
    if path.suffix.lower() == ".xlsx":
        return pd.read_excel(path, dtype=object, keep_default_na=False)
    return pd.read_csv(path, dtype=str, keep_default_na=False)


def _hand_rows(plain: pd.DataFrame, speed_mm: bool) -> tuple[list[str], list[list[Any]]]:
    """The header and rows as typed: every column of the plain sheet (a layout's own, such as
    ``segment`` or the steady window, included), named as :data:`HAND_HEADER` says."""
    cols = list(plain.columns)
    header = [HAND_HEADER.get(c, c) for c in cols]
    if speed_mm and "speed_nominal" in cols:
        header[cols.index("speed_nominal")] = "Speed (mm/s)"
    rows = []
    for rec in plain.to_dict("records"):
        row: list[Any] = []
        for c in cols:
            v = rec[c]
            if c == "status":
                v = _STATUS.get(str(v).strip().lower(), v)
            elif c == "test":
                v = _TEST.get(str(v).strip().lower(), v)
            elif c == "speed_nominal" and speed_mm and str(v).strip():
                v = round(float(v) * 1000.0, 6)
            elif c in ("run", "segment") and str(v).strip():
                v = int(float(v))
            elif c in ("angle_deg", "speed_nominal", "accel_nominal", "water_temp_C",
                       "window_start_s", "window_end_s") and str(v).strip():
                v = float(v)
            row.append(v)
        rows.append(row)
    return header, rows


def write_hand_typed_sheet(plain_sheet: str | Path, style: str, out: str | Path) -> Path:
    """Write the plain run sheet ``plain_sheet`` again as a lab types it by hand.

    Parameters
    ----------
    plain_sheet : str or Path
        A run sheet in the contract's names (docs/formats.md §2), .csv or .xlsx.
    style : {"hand-xlsx", "hand-csv"}
        ``hand-xlsx``: a workbook whose first tab holds notes and whose ``Runs`` tab has a
        title row, a date/operator row and a blank row above the header, notes below.
        ``hand-csv``: the same in ``;``-separated Latin-1 text with decimal commas and the
        speed in mm/s.
    out : str or Path
        The file to write (may be ``plain_sheet`` itself).

    Returns
    -------
    Path
    """
    if style not in HAND_SHEETS:
        raise ValueError(f"style must be one of {', '.join(HAND_SHEETS)}, not {style!r}.")
    plain = _plain_rows(Path(plain_sheet))
    header, rows = _hand_rows(plain, speed_mm=style == "hand-csv")
    top = [["Towing tank run log: SUT-2 quarter-scale hull"],
           ["Operator: J. Smith", "", "Tank: 100 m"], []]
    bottom = [[], *[[n] for n in HAND_NOTES]]
    out = Path(out)
    if style == "hand-xlsx":
        out.write_bytes(_xlsx(top, header, rows, bottom))
    else:
        out.write_bytes(_csv(top, header, rows, bottom))
    return out


def _cell_text(v: Any) -> str:
    if isinstance(v, float):
        text = repr(v).replace(".", ",")
        return text[:-2] if text.endswith(",0") else text
    return str(v)


def _csv(top: list, header: list[str], rows: list, bottom: list) -> bytes:
    buf = io.StringIO()
    writer = csv.writer(buf, delimiter=";", lineterminator="\r\n")  # quotes a ';' in a note
    for r in [*top, header, *rows, *bottom]:
        writer.writerow([_cell_text(c) for c in r])
    return buf.getvalue().encode("latin-1", errors="replace")


def _xlsx(top: list, header: list[str], rows: list, bottom: list) -> bytes:
    wb = openpyxl.Workbook()
    notes = wb.active
    notes.title = "Notes"
    notes.append(["Test matrix agreed with the client on 14 May."])
    ws = wb.create_sheet("Runs")
    for r in [*top, header, *rows, *bottom]:
        ws.append(list(r))
    buf = io.BytesIO()
    wb.save(buf)
    return pinned_xlsx(buf.getvalue())
