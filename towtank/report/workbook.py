"""report.xlsx: the day's workbook (docs/formats.md §5), written with openpyxl.

Sheets, always all of them (a sheet whose data the day lacks holds a one-line note saying why):

============  ===========================================================================
Summary       campaign, model, water, test date, program, run counts, the geometry used
              (areas, volume and where each came from), key results
Coefficients  the SUT-2 coefficient table: value, unit, 95 % interval, prime, reference,
              diff %, method, prototype value, second estimate, its method and agreement
Captive       (days with captive runs) the captive derivatives per plane: value, unit, 95 %
              interval, primes, method, runs; the fit's reduced chi^2 and notes
PMM           (days with captive runs) pmm.csv: the PMM runs' first harmonics
Runs          runs.csv: every run of the sheet with status, reason, phase windows, means
Fins          fins.csv, then the per-speed curves and the fin's constants
Scaling       scaling.csv, then the resistance curve, the form factor, the similarity statement
Quality       rejected and void runs, warnings, fit diagnostics
Provenance    inputs with sha256, program and library versions, settings
============  ===========================================================================

Numbers are stored as numbers with the exact floats of the CSV tables (openpyxl's own
"%.16g" drops the 17th digit, so floats are written as their shortest round-trip repr, as the
CSV writer does); units are in the headers ("speed_mean [m/s]"); the first table of each sheet
has a frozen header row and an autofilter. Rejected runs are filled red, void runs grey,
coefficients with |diff %| > 10 yellow.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import io
import json
import math
import re
import zipfile
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd
from openpyxl import Workbook
from openpyxl.cell import _writer
from openpyxl.styles import Alignment, Border, Font, PatternFill, Side
from openpyxl.utils import get_column_letter

import towtank.report.style as style
from towtank import __version__
from towtank.analysis.scaling import geometry_used
from towtank.reduce.tare import tare_table
from towtank.reference.sets import reference_name
from towtank.report.provenance import creation_date, provenance, report_date
from towtank.report.safetext import clean_text
from towtank.report.tables import missing_accel_note
from towtank.results import require

if TYPE_CHECKING:
    from openpyxl.worksheet.worksheet import Worksheet

    from towtank.ingest.protocol_types import Protocol
    from towtank.ingest.schema import Processing
    from towtank.results import DayResult, FinResult, HullResult, ScalingResult, TareResult

SHEETS = ("Summary", "Coefficients", "Captive", "PMM", "Runs", "Tare", "Fins", "Fin curves",
          "Fin control", "Scaling", "Scaling constants", "Form factor", "Quality",
          "Provenance")


def sheet_names(day: DayResult) -> list[str]:
    """The workbook's sheets, one table each: :data:`SHEETS` without the fin and scaling
    detail sheets a day has no data for."""
    fr, sr = day.fins, day.scaling
    captive = _captive_results(day)
    has = {"Captive": bool(captive), "PMM": bool(captive),
           "Fin curves": fr is not None and len(fr.table) > 0 and len(fr.curves) > 0,
           "Fin control": _has_control(fr),
           "Scaling constants": sr is not None,
           "Form factor": sr is not None and sr.form_factor is not None}
    return [name for name in SHEETS if has.get(name, True)]
DIFF_HIGHLIGHT_PCT = 10.0
MAX_WIDTH = 60

#: Units of known columns, shown in the header as "name [unit]".
UNITS: dict[str, str] = {
    # runs.csv
    "angle_deg": "deg", "speed_mean": "m/s", "accel_mean": "m/s²", "drag_mean": "N",
    "lift_mean": "N", "tare_drag": "N", "cd": "-", "cl": "-", "re": "-", "fn": "-",
    "speed_nominal": "m/s", "accel_nominal": "m/s²", "water_temp_C": "°C", "rho": "kg/m³",
    "nu": "m²/s", "speed_std": "m/s", "speed_u": "m/s", "drag_std": "N", "lift_tare": "N",
    "cd_lateral": "-",
    "zero_drag": "N", "drift_drag": "N", "zero_lift": "N", "drift_lift": "N", "fs_hz": "Hz",
    "n_samples": "-", "window_start_s": "s", "window_end_s": "s",
    # tare.csv
    "t2": "N s²/m²", "t2_ci_low": "N s²/m²", "t2_ci_high": "N s²/m²", "t1": "N s/m",
    "t1_ci_low": "N s/m", "t1_ci_high": "N s/m", "m_t": "kg", "m_t_ci_low": "kg",
    "m_t_ci_high": "kg", "residual_std": "N", "speed_min": "m/s", "speed_max": "m/s",
    "accel_min": "m/s²", "accel_max": "m/s²",
    # coefficients.csv
    "value": "SI", "ci_low": "SI", "ci_high": "SI", "prime": "-", "reference_prime": "-",
    "diff_pct": "%", "prototype_value": "SI", "std_error": "SI", "prime_ci_low": "-",
    "prime_ci_high": "-", "alt_value": "SI", "n_runs": "-", "u_regression": "SI",
    "u_tare": "SI", "u_mass": "SI", "dof": "-", "predicted": "-", "predicted_diff_pct": "%",
    # fins.csv and curves
    "cl_sandia": "-", "cd_sandia": "-", "cl_3d": "-", "cd_3d": "-", "speed_group": "m/s",
    "re_mean": "-", "lift_slope": "1/rad", "lift_slope_ci_low": "1/rad",
    "lift_slope_ci_high": "1/rad", "lift_slope_sandia_2d": "1/rad", "lift_slope_3d": "1/rad",
    "stall_angle_deg": "deg", "cl_max": "-", "cd_min": "-", "cd_min_angle_deg": "deg",
    # scaling.csv
    "speed_prototype": "m/s", "re_prototype": "-", "fn_prototype": "-",
    "speed_model_froude": "m/s", "speed_model_reynolds": "m/s", "drag_froude": "N",
    "drag_ittc57": "N", "re_model_froude": "-", "drag_recommended": "N",
    "cd_ref": "-", "ref_area_m2": "m²",
    # diagnostics
    "alpha_rad": "rad", "speed": "m/s", "fitted": "-", "resid": "-", "student": "-",
    "cooks": "-", "drag": "N", "cd90": "-", "cd_mean": "-", "cd_std": "-",
    # captive: coefficients, pmm.csv and runs.csv
    "prime_LT": "-", "frequency_hz": "Hz", "amplitude_m": "m", "omega_prime": "-",
    "cycles_used": "-", "fy_in": "N", "fy_quad": "N", "mz_in": "N m", "mz_quad": "N m",
    "fy_in_se": "N", "fy_quad_se": "N", "mz_in_se": "N m", "mz_quad_se": "N m",
    "captive_X_N": "N", "captive_Y_N": "N", "captive_N_Nm": "N m", "pmm_cycles": "-",
    "drift_deg": "deg", "rudder_deg": "deg", "radius_m": "m", "pmm_amplitude_m": "m",
    "pmm_frequency_hz": "Hz",
}
for _name in ("still_pre", "accel", "steady", "decel", "still_post"):
    UNITS[f"{_name}_start_s"] = UNITS[f"{_name}_end_s"] = "s"

#: Column order of the Coefficients sheet (then any further columns of the table).
COEFFICIENT_ORDER = (
    "symbol", "value", "unit", "ci_low", "ci_high", "prime", "reference_prime", "diff_pct",
    "method", "prototype_value", "alt_value", "alt_method", "agreement", "std_error",
    "prime_ci_low", "prime_ci_high", "n_runs",
)


# ------------------------------------------------------------------------------- cells
def text_cell(cell: Any, value: Any) -> Any:
    """``cell`` holding ``value``; text is stored as text, never as a formula (openpyxl takes a
    string beginning with ``=`` for one: a remark ``=HYPERLINK(...)`` would become a link)."""
    cell.value = value
    if isinstance(value, str) and cell.data_type == "f":
        cell.data_type = "s"
    return cell


def cell_value(v: Any) -> Any:
    """A value openpyxl stores faithfully: numbers as numbers, NaN as an empty cell.

    numpy scalars become Python numbers (the same float), missing values None, anything
    that is neither a number, a bool, a date nor a string its ``str``.
    """
    if v is None or v is pd.NA or v is pd.NaT:
        return None
    if isinstance(v, bool | np.bool_):
        return bool(v)
    if isinstance(v, int | np.integer):
        return int(v)
    if isinstance(v, float | np.floating):
        f = float(v)
        return f if math.isfinite(f) else None
    if isinstance(v, str):
        return clean_text(v)
    if isinstance(v, pd.Timestamp):
        return v.to_pydatetime()
    if isinstance(v, dt.datetime | dt.date):
        return v
    if isinstance(v, list | tuple | dict):
        return json.dumps(v, default=str)
    return str(v)


#: How a float is shown (the cell holds the full double): four significant digits or more.
SCI_FORMAT = "0.000E+00"
FIXED_FORMAT = "0.0000"


def display_format(value: float) -> str:
    """Excel number format for ``value``: scientific below 0.1 and from 10⁴, else 4 decimals."""
    a = abs(value)
    if a == 0.0 or not math.isfinite(a):
        return "General"
    return SCI_FORMAT if a < 0.1 or a >= 1e4 else FIXED_FORMAT


def column_format(values: Iterable[Any]) -> str | None:
    """One Excel number format for a whole column, so that a column never mixes notations
    (``9.999E-02`` beside ``0.2000``, ``3001.0000`` samples): whole numbers as ``0``; a
    column whose non-zero magnitudes all lie in 0.1–10⁴ with 4 decimals; anything else
    scientific. None for a column without numbers."""
    nums = [float(v) for v in values
            if isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)]
    if not nums:
        return None
    if all(v.is_integer() and abs(v) < 1e15 for v in nums):
        return "0"
    mags = [abs(v) for v in nums if v != 0.0]
    if all(0.1 <= m < 1e4 for m in mags):
        return FIXED_FORMAT
    return SCI_FORMAT


def header_label(column: str, units: dict[str, str] | None = None) -> str:
    """``speed_mean`` → ``speed_mean [m/s]``; columns without a unit keep their name."""
    unit = (UNITS if units is None else units).get(column)
    return f"{column} [{unit}]" if unit else column


def _styles() -> dict[str, Any]:
    return {
        "header_font": Font(bold=True),
        "header_fill": PatternFill("solid", fgColor=style.XL_HEADER_FILL),
        "header_border": Border(bottom=Side(style="thin", color="808080")),
        "header_align": Alignment(vertical="top", wrap_text=False),
        "title_font": Font(bold=True, size=12),
        "note_font": Font(italic=True, color=style.XL_NOTE_FONT_COLOR),
        "rejected": PatternFill("solid", fgColor=style.XL_REJECTED_FILL),
        "void": PatternFill("solid", fgColor=style.XL_VOID_FILL),
        "diff": PatternFill("solid", fgColor=style.XL_DIFF_FILL),
        "wrap": Alignment(wrap_text=True, vertical="top"),
    }


class SheetWriter:
    """Writes blocks (tables, key–value lists, notes) down one worksheet.

    The first table written gets the frozen header row and the autofilter.
    """

    def __init__(self, ws: Worksheet):
        self.ws = ws
        self.row = 1
        self.first_table: tuple[int, int, int] | None = None  # header row, last row, ncols
        self.st = _styles()
        self.widths: dict[int, int] = {}

    # -- low level
    def _put(self, row: int, col: int, value: Any, fmt: str | None = None) -> Any:
        cell = text_cell(self.ws.cell(row=row, column=col), cell_value(value))
        v = cell.value
        if isinstance(v, int | float) and not isinstance(v, bool):
            if fmt is not None:
                cell.number_format = fmt
            elif isinstance(v, float):
                cell.number_format = display_format(v)
        if v is not None:
            text = f"{v:.6g}" if isinstance(v, float) else str(v)
            w = max(len(line) for line in text.split("\n")) if text else 0
            self.widths[col] = max(self.widths.get(col, 0), w)
        return cell

    def _header(self, row: int, labels: list[str]) -> None:
        for j, label in enumerate(labels, start=1):
            c = self._put(row, j, label)
            c.font = self.st["header_font"]
            c.fill = self.st["header_fill"]
            c.border = self.st["header_border"]
            c.alignment = self.st["header_align"]

    # -- blocks
    def title(self, text: str) -> None:
        """A bold block title on its own row."""
        c = text_cell(self.ws.cell(row=self.row, column=1), cell_value(text))
        c.font = self.st["title_font"]
        self.row += 1

    def note(self, text: str) -> None:
        """An italic one-line note."""
        c = text_cell(self.ws.cell(row=self.row, column=1), cell_value(text))
        c.font = self.st["note_font"]
        self.row += 1

    def gap(self, n: int = 1) -> None:
        self.row += n

    def table(
        self,
        df: pd.DataFrame,
        *,
        columns: Iterable[str] | None = None,
        units: dict[str, str] | None = None,
        row_fill: Callable[[dict[str, Any]], str | None] | None = None,
        wrap: Iterable[str] = (),
        per_column: bool = True,
    ) -> tuple[int, int]:
        """Write ``df`` with a unit-labelled header; returns (header row, last row).

        With ``per_column`` every number of a column has that column's format
        (:func:`column_format`); without it (a key–value list, one quantity per row) each
        number has its own."""
        cols = list(columns) if columns is not None else list(df.columns)
        head = self.row
        self._header(head, [header_label(c, units) for c in cols])
        wrap = set(wrap)
        records = df.to_dict("records")
        formats = {c: column_format(cell_value(r.get(c)) for r in records) if per_column
                   else None for c in cols}
        for i, rec in enumerate(records, start=1):
            style = row_fill(rec) if row_fill else None
            fill = self.st.get(style) if style is not None else None
            for j, c in enumerate(cols, start=1):
                cell = self._put(head + i, j, rec.get(c), formats[c])
                if fill is not None:
                    cell.fill = fill
                if c in wrap:
                    cell.alignment = self.st["wrap"]
        last = head + len(df)
        if self.first_table is None:
            self.first_table = (head, last, len(cols))
        self.row = last + 1
        return head, last

    def pairs(self, rows: list[tuple[str, Any, str]], header: tuple[str, str, str] = (
            "item", "value", "unit")) -> tuple[int, int]:
        """A key–value–unit list as a table."""
        df = pd.DataFrame(rows, columns=list(header))
        df["value"] = pd.Series([r[1] for r in rows], dtype=object)
        return self.table(df, units={}, per_column=False)

    def finish(self, *, min_width: int = 6) -> None:
        """Freeze and filter the first table, size the columns."""
        ws = self.ws
        if self.first_table is not None:
            head, last, ncols = self.first_table
            ws.freeze_panes = ws.cell(row=head + 1, column=1)
            ws.auto_filter.ref = f"A{head}:{get_column_letter(ncols)}{max(last, head)}"
        for col, w in self.widths.items():
            ws.column_dimensions[get_column_letter(col)].width = min(max(w + 2, min_width),
                                                                     MAX_WIDTH)


def _fill_for_status(rec: dict[str, Any]) -> str | None:
    status = rec.get("status")
    return status if status in ("rejected", "void") else None


def _fill_for_diff(rec: dict[str, Any]) -> str | None:
    try:
        d = float(rec.get("diff_pct", math.nan))
    except (TypeError, ValueError):
        return None
    return "diff" if math.isfinite(d) and abs(d) > DIFF_HIGHLIGHT_PCT else None


def _note_sheet(w: SheetWriter, text: str) -> None:
    """A sheet the day has no data for: a header and the one-line reason."""
    w.table(pd.DataFrame({"note": [text]}), units={})


# ------------------------------------------------------------------------------- sheets
def _summary(w: SheetWriter, day: DayResult) -> None:
    p = day.protocol
    date, source = report_date(day)
    counts = day.runs["status"].value_counts()
    rows: list[tuple[str, Any, str]] = [
        ("campaign", p.name, ""),
        ("protocol", str(p.path), ""),
        ("test date", date or "not given", ""),
        ("test date source", source, ""),
        ("program", "towtank", ""),
        ("program version", __version__, ""),
        ("water", p.water.type, ""),
        ("water temperature", p.water.temperature_C, "°C"),
    ]
    fluid = "air" if p.water.is_air else "water"
    if p.water.is_air:  # the medium named: air, its temperature, pressure and humidity
        rows[-2:] = [("medium", "air", ""), ("air temperature", p.water.temperature_C, "°C"),
                     ("air pressure", p.water.pressure_Pa, "Pa"),
                     ("relative humidity", p.water.relative_humidity_pct, "%")]
    ok = day.runs[day.runs["status"] == "ok"]
    if ok["rho"].notna().any():
        rows += [(f"{fluid} density (mean of runs)", float(ok["rho"].mean()), "kg/m³"),
                 ("kinematic viscosity (mean of runs)", float(ok["nu"].mean()), "m²/s")]
    m = p.model
    if m is not None:
        rows += [("model", m.name or "", ""), ("model length L", m.length_m, "m")]
        if m.diameter_m is not None:
            rows.append(("model diameter D", m.diameter_m, "m"))
        rows.append(("model mass", m.mass_kg, "kg"))
        if m.scale is not None:
            rows.append(("scale λ", m.scale, "-"))
    if p.fin is not None:
        rows += [("fin section", p.fin.section, ""), ("fin chord", p.fin.chord_m, "m"),
                 ("fin span", p.fin.span_m, "m")]
    if day.hull is not None:
        rows.append(("reference set (reference_prime)", reference_name(p.campaign.reference),
                     ""))
    rows += [
        ("runs in the sheet", int(len(day.runs)), ""),
        ("runs ok", int(counts.get("ok", 0)), ""),
        ("runs rejected", int(counts.get("rejected", 0)), ""),
        ("runs void", int(counts.get("void", 0)), ""),
        ("warnings", len(day.warnings), ""),
    ]
    w.pairs(rows)
    if m is not None:
        w.gap()
        w.title("Geometry used")
        w.table(pd.DataFrame(geometry_used(day.protocol, day.scaling)),
                columns=["quantity", "symbol", "value", "unit", "source"], units={})
        w.note(f"geometry_source: {m.geometry_source}")
    w.gap()
    w.title("Key results")
    if day.hull is not None and len(day.coefficients):
        cols = [c for c in ("symbol", "value", "unit", "ci_low", "ci_high", "prime",
                            "reference_prime", "diff_pct") if c in day.coefficients]
        w.table(day.coefficients, columns=cols, row_fill=_fill_for_diff)
    else:
        w.note("No hull coefficients: " + _why_no_hull(day.protocol))
    if day.fins is not None and len(day.fins.curves):
        w.gap()
        w.title("Fin: lift slope and stall per speed group")
        cols = ["speed_group", "re_mean", "lift_slope", "lift_slope_ci_low",
                "lift_slope_ci_high", "stall_angle_deg", "cl_max", "cd_min"]
        w.table(day.fins.curves, columns=[c for c in cols if c in day.fins.curves])
    if day.scaling is not None:
        w.gap()
        w.title("Prototype resistance")
        sr = day.scaling
        cols = [c for c in ("speed_prototype", "drag_recommended", "recommended",
                            "drag_ittc57", "drag_froude") if c in sr.table]
        w.table(sr.table, columns=cols)
        if sr.recommendation is not None:
            w.note(sr.recommendation.rule)


def _why_no_hull(protocol: Protocol) -> str:
    if protocol.model is None:
        return "the protocol has no [model] (a fin day)."
    return "the day has no usable hull runs; see the Quality sheet."


def _coefficients(w: SheetWriter, hull: HullResult | None, coef: pd.DataFrame,
                  protocol: Protocol) -> None:
    """coefficients.csv's table (``coef``: the hull's coefficients with their prototype and
    predicted values) with the hull fit's ρ and L in its note."""
    if hull is None or len(coef) == 0:
        _note_sheet(w, "No hull coefficients: " + _why_no_hull(protocol))
        return
    cols = [c for c in COEFFICIENT_ORDER if c in coef.columns]
    cols += [c for c in coef.columns if c not in cols]
    w.table(coef, columns=cols, row_fill=_fill_for_diff)
    w.gap()
    w.note(f"value, ci_low, ci_high, prototype_value, alt_value in the row's unit (SI, model "
           f"scale for value; prototype scale for prototype_value); prime non-dimensional. "
           f"Rows with |diff_pct| > {DIFF_HIGHLIGHT_PCT:g} are highlighted.")
    hf = hull.fit
    w.note(f"prime = value/(½ρL³) (added mass) or value/(½ρL²) (damping) with ρ = "
           f"{hf.rho:.3f} kg/m³, the density of the protocol's "
           f"{'air' if protocol.water.is_air else 'water'} ([water]; each run's C_D is taken "
           "with its own), and L = "
           f"{hf.length:g} m. diff_pct = (prime − reference_prime)/|reference_prime|·100, signed: "
           "negative where the prime is more negative than the reference (e.g. a larger added "
           "mass); empty where the reference is 0.")


def _captive_results(day: DayResult) -> tuple[Any, ...]:
    """The day's captive results (horizontal plane first); () for a day without."""
    return tuple(getattr(day, "captive_results", ()) or ())


#: Column order of the Captive sheet.
CAPTIVE_ORDER = ("symbol", "value", "unit", "ci_low", "ci_high", "std_error", "dof", "prime",
                 "prime_ci_low", "prime_ci_high", "prime_LT", "n_runs", "method")


def _captive(w: SheetWriter, day: DayResult) -> None:
    """Each plane's captive derivatives (coefficients.csv's captive rows) with the fit's
    reduced chi^2 and notes."""
    for i, fit in enumerate(_captive_results(day)):
        if i:
            w.gap()
        letters = "Z, M" if fit.plane == "vertical" else "Y, N"
        w.title(f"Captive derivatives, {fit.plane} plane ({letters}): {len(fit.runs)} runs")
        w.table(fit.table(), columns=CAPTIVE_ORDER)
        w.note(f"value, ci_low, ci_high, std_error in the row's unit (SI, model scale), the "
               f"moments {fit.moment_point()}; "
               f"intervals 95 %, Student's t on dof; prime = value/(½ρL^k) with ρ = "
               f"{fit.rho:.3f} kg/m³, L = {fit.length_m:g} m"
               + (f"; prime_LT = value/(½ρTL^(k−1)), T = {fit.draught_m:g} m"
                  if fit.draught_m is not None else "") + ".")
        for eq, chi2 in fit.chi2_reduced.items():
            w.note(f"{eq}: reduced chi^2 of the fit {chi2:.4g}")
        for n in fit.notes:
            w.note(n)


def _pmm(w: SheetWriter, day: DayResult) -> None:
    """pmm.csv, or a note that the day has no PMM runs."""
    pmm = day.pmm
    if len(pmm) == 0:
        _note_sheet(w, "No PMM runs: the day's captive runs are all static (drift, rudder, "
                    "arm).")
        return
    w.table(pmm)
    results = _captive_results(day)
    about = results[0].moment_point() if results else "about O"
    w.note(f"First harmonics of Y [N] and N [N m] {about}, inertia removed: in = coefficient "
           "of sin(ωt), in phase with the sway y; quad = of cos(ωt); *_se their standard "
           "errors over the kept cycles; omega_prime = ωL/U.")


def _runs(w: SheetWriter, runs: pd.DataFrame, processing: Processing) -> None:
    w.table(runs, row_fill=_fill_for_status)
    w.gap()
    w.note("Rejected runs are filled red, runs voided in the sheet grey; phase windows "
           "*_start_s/*_end_s in seconds from the start of the file.")
    w.note("cd_ref: each run's C_D on the area its test uses, named in ref_area (frontal: "
           "hull runs; lateral: transverse tows at α = 90°, the C_D,90 of Y_v|v|; fin: chord × "
           "span); cd keeps the frontal area for every hull run.")
    blank, why = _missing_accel(runs, processing)
    if blank:
        w.note(why)


def _missing_accel(runs: pd.DataFrame, processing: Processing) -> tuple[list[int], str]:
    """The usable runs without accel_mean and why (as the PDF's runs table says)."""
    blank, text = missing_accel_note(runs, processing, [int(r) for r in runs["run"]])
    return blank, "accel_mean empty: " + text.removeprefix("¹ ") if blank else ""


def _tare(w: SheetWriter, tare: TareResult) -> None:
    table = tare_table(tare.models)
    if len(table) == 0:
        _note_sheet(w, "No sting tare was fitted: the day has no sting runs, or its tare "
                    "comes from a table or is none ([tare] in the protocol).")
        return
    w.table(table)
    w.gap()
    w.note("Sting tare T = t2·U|U| + t1·U + m_t·a per tare group and force channel, fitted "
           "on the sting runs' steady and constant-acceleration samples (covariance clustered "
           "by sting run); 95 % intervals with Student's t at dof. It is subtracted sample by "
           "sample from the group's model runs, and its uncertainty is part of every "
           "coefficient's interval.")


def _fins(w: SheetWriter, fr: FinResult | None, protocol: Protocol) -> None:
    if fr is None or len(fr.table) == 0:
        why = ("the protocol has no [fin]." if protocol.fin is None
               else "the day has no usable fin runs; see the Quality sheet.")
        _note_sheet(w, "No fin data: " + why)
        return
    w.table(fr.table)
    w.gap()
    w.note(f"Effective aspect ratio {fr.aspect_ratio:.4g}, span efficiency e = "
           f"{fr.oswald_e:.3g}; per-speed curves on the Fin curves sheet"
           + (", control derivatives on the Fin control sheet." if _has_control(fr) else "."))


def _has_control(fr: FinResult | None) -> bool:
    return fr is not None and fr.control is not None and len(fr.control) > 0


def _fin_curves(w: SheetWriter, fr: FinResult) -> None:
    w.table(fr.curves)
    w.gap()
    w.note("Lift slope over the linear range of each speed group with its 95 % interval, "
           "beside the same fit through the 2-D Sandia section and the finite-span "
           "expectation (lifting line); slopes in 1/rad, angles in degrees.")


def _fin_control(w: SheetWriter, fr: FinResult) -> None:
    w.table(fr.control)


def _scaling(w: SheetWriter, sr: ScalingResult | None, protocol: Protocol) -> None:
    if sr is None:
        if protocol.model is None:
            why = "the protocol has no [model] (a fin day)."
        elif protocol.prototype is None:
            why = "the protocol has no [prototype]."
        else:
            why = "too few steady zero-angle hull runs; see the Quality sheet."
        _note_sheet(w, "No scaling: " + why)
        return
    w.table(sr.table)
    w.gap()
    if sr.recommendation is not None:
        w.note(sr.recommendation.rule)
    if sr.form_factor_trend_text:
        w.note(sr.form_factor_trend_text)
    w.note("Resistance curve, form factor and water on the Scaling constants sheet"
           + ("; the form factor per tested speed on the Form factor sheet."
              if sr.form_factor is not None else "."))


def _scaling_constants(w: SheetWriter, sr: ScalingResult, protocol: Protocol) -> None:
    k2, k1 = sr.resistance
    rows: list[tuple[str, Any, str]] = [
        ("scale λ", sr.scale, "-"),
        ("resistance R = k2·U|U| + k1·U: k2", k2, "N s²/m²"),
        ("resistance R = k2·U|U| + k1·U: k1", k1, "N s/m"),
        ("tested model speed, lowest", sr.tested_speed_range[0], "m/s"),
        ("tested model speed, highest", sr.tested_speed_range[1], "m/s"),
    ]
    ff = sr.form_factor
    if ff is not None:
        rows += [("form factor 1 + k (mean over tested speeds)", float(ff.one_plus_k), "-"),
                 ("form factor standard deviation over speeds", float(ff.std), "-"),
                 ("form factor tested speeds", int(ff.n), "-"),
                 ("form factor runs", int(ff.n_runs), "-"),
                 ("form factor Re, lowest", float(ff.re_range[0]), "-"),
                 ("form factor Re, highest", float(ff.re_range[1]), "-")]
    else:
        rows.append(("form factor 1 + k", None, "-"))
    rows += [("prototype length L_p", sr.length_prototype, "m"),
             ("prototype wetted area S_p = λ²·S_m", sr.wetted_area_prototype, "m²"),
             ("roughness allowance ΔC_F", sr.delta_cf, "-")]
    t_m = protocol.water.temperature_C
    fm = "air" if protocol.water.is_air else "water"
    proto = protocol.prototype
    fp = "air" if proto is not None and proto.water.is_air else "water"
    rows += [(f"model {fm} density at the protocol's {t_m:g} °C (Froude force ratio)",
              sr.rho_m, "kg/m³"),
             (f"model {fm} kinematic viscosity at {t_m:g} °C (Reynolds speed ratio)", sr.nu_m,
              "m²/s"),
             (f"prototype {fp} density", sr.rho_p, "kg/m³"),
             (f"prototype {fp} kinematic viscosity", sr.nu_p, "m²/s")]
    w.pairs(rows)
    w.gap()
    w.title("Similarity")
    c = text_cell(w.ws.cell(row=w.row, column=1), cell_value(sr.statement))
    c.alignment = w.st["wrap"]
    w.ws.merge_cells(start_row=w.row, start_column=1, end_row=w.row, end_column=3)
    w.ws.row_dimensions[w.row].height = 15 * (1 + len(sr.statement) // 80)
    w.row += 1


def _form_factor(w: SheetWriter, sr: ScalingResult) -> None:
    ff = require(sr.form_factor, "form factor")
    data = {"speed": ff.speeds, "runs": ff.speed_runs, "one_plus_k": ff.speed_values}
    units = {"speed": "m/s", "runs": "-", "one_plus_k": "-"}
    if len(ff.speed_reynolds) == len(ff.speeds):
        data["re"], units["re"] = ff.speed_reynolds, "-"
    w.table(pd.DataFrame(data), units=units)
    trend = sr.form_factor_trend
    if trend is not None and math.isfinite(trend.slope):
        w.gap()
        w.pairs([("slope d(1 + k)/dRe", trend.slope, "-"),
                 ("slope, 95 % interval low", trend.ci_low, "-"),
                 ("slope, 95 % interval high", trend.ci_high, "-"),
                 ("slope p-value", trend.p_value, "-"),
                 ("trend with Re significant", "yes" if trend.significant else "no", "")])
        w.note(sr.form_factor_trend_text)


def _quality(w: SheetWriter, day: DayResult) -> None:
    runs = day.runs
    bad = runs[runs["status"] != "ok"]
    cols = ["run", "file", "config", "angle_deg", "status", "reason"]
    w.table(bad, columns=cols, row_fill=_fill_for_status, wrap=("reason",))
    if bad.empty:
        w.note("Every run of the sheet was used: none rejected, none void.")
    w.gap()
    w.title("Warnings")
    if day.warnings:
        w.table(pd.DataFrame({"warning": [str(n) for n in day.warnings]}), wrap=("warning",))
    else:
        w.note("None.")
    hf = day.hull.fit if day.hull is not None else None
    if hf is not None:
        _fit_diagnostics(w, hf)
    notes = runs[runs["notes"].fillna("").astype(str).str.len() > 0]
    w.gap()
    w.title("Notes on individual runs")
    if len(notes):
        w.table(notes, columns=["run", "file", "notes"])
    else:
        w.note("None.")
    w.ws.column_dimensions["F"].width = MAX_WIDTH


def _fit_diagnostics(w: SheetWriter, hf: Any) -> None:
    dm = hf.damping
    if dm is not None:
        w.gap()
        w.title("C_D(α) fit: residuals, studentized residuals and Cook's distance per run")
        t = dm.runs.copy()
        t["outlier"] = t["run"].isin(dm.outliers)
        w.table(t)
        w.note("Outliers (|studentized residual| > 3 or large Cook's distance): "
               + (", ".join(map(str, dm.outliers)) if dm.outliers else "none") + ".")
        if dm.transverse_runs is not None and len(dm.transverse_runs):
            w.gap()
            w.title("Transverse runs (α = 90°): C_D,90 on the lateral area")
            w.table(dm.transverse_runs, units={**UNITS, "resid": "N"})
    if hf.repeats is not None and len(hf.repeats):
        w.gap()
        w.title("Repeat spread: runs at the same angle and speed (within 3 %)")
        w.table(hf.repeats, units={**UNITS, "drag_std": "N", "speed": "m/s"})
    if hf.added_mass:
        w.gap()
        w.title("Added mass: joint regression D = k2·U|U| + k1·U + M·a (M = m − X)")
        rows = []
        for sym, am in hf.added_mass.items():
            e = am.estimate
            rows.append({"symbol": sym, "mass": am.mass, "M": am.M, "M_se": am.M_se,
                         "k2": am.k2, "k1": am.k1, "dof": am.dof, "runs": " ".join(
                             map(str, am.runs)), "value": e.value, "alt_value": e.alt_value,
                         "agreement": str(e.agreement or "")})
        w.table(pd.DataFrame(rows), units={**UNITS, "mass": "kg", "M": "kg", "M_se": "kg",
                                           "k2": "N s²/m²", "k1": "N s/m", "value": "kg",
                                           "alt_value": "kg"})
        w.gap()
        w.title("Added mass: mean residual of the joint regression by run")
        res = [{"symbol": s, "run": r, "mean_residual": v}
               for s, am in hf.added_mass.items() for r, v in am.residual_by_run.items()]
        w.table(pd.DataFrame(res), units={"mean_residual": "N"})
        w.gap()
        w.title("Added mass: curve difference per acceleration level (report eqs. 7–8)")
        lv_rows = []
        for s, am in hf.added_mass.items():
            for lv in am.curve_difference.levels:
                p2, p1, p0 = lv.quadratic
                lv_rows.append({"symbol": s, "accel": lv.accel,
                                "speed_low": lv.speed_range[0],
                                "speed_high": lv.speed_range[1], "n": lv.n,
                                "delta_drag": lv.delta_drag, "M": lv.M,
                                "value": lv.value, "p2": p2, "p1": p1, "p0": p0})
        if lv_rows:
            w.table(pd.DataFrame(lv_rows), units={
                "accel": "m/s²", "speed_low": "m/s", "speed_high": "m/s", "n": "samples",
                "delta_drag": "N", "M": "kg", "value": "kg", "p2": "N s²/m²", "p1": "N s/m",
                "p0": "N"})
        else:
            w.note("No curve-difference levels.")
    for m in hf.messages:
        w.note(m)


def _provenance(w: SheetWriter, day: DayResult) -> None:
    prov = provenance(day)
    rows: list[tuple[str, Any, str]] = []
    for key in ("program", "version", "python", "protocol", "campaign"):
        rows.append((key, prov.get(key), ""))
    for lib, ver in (prov.get("libraries") or {}).items():
        rows.append((f"library {lib}", ver, ""))
    for k, v in (prov.get("runs") or {}).items():
        rows.append((f"runs {k}", v, ""))
    w.pairs(rows)
    w.gap()
    w.title("Inputs")
    inputs = pd.DataFrame(prov.get("inputs") or [], columns=["path", "sha256"])
    w.table(inputs)
    w.gap()
    w.title("Settings")
    flat = list(_flatten(prov.get("settings") or {}))
    w.table(pd.DataFrame(flat, columns=["setting", "value"]).astype({"value": object}))
    extra = {k: v for k, v in prov.items()
             if k not in ("program", "version", "python", "protocol", "campaign", "libraries",
                          "runs", "inputs", "settings")}
    if extra:
        w.gap()
        w.title("Other")
        w.table(pd.DataFrame(list(_flatten(extra)), columns=["item", "value"]))


def _flatten(d: dict[str, Any], prefix: str = "") -> Iterable[tuple[str, Any]]:
    for k, v in d.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            yield from _flatten(v, key + ".")
        elif isinstance(v, list | tuple):
            yield key, json.dumps(list(v), default=str)
        elif v is None or isinstance(v, bool | int | float | str):
            yield key, v
        else:
            yield key, str(v)


#: Each sheet's writer, given the results it shows from the day (:func:`sheet_names` says
#: which sheets a day has).
WRITERS: dict[str, Callable[[SheetWriter, DayResult], None]] = {
    "Summary": _summary,
    "Coefficients": lambda w, day: _coefficients(w, day.hull, day.coefficients, day.protocol),
    "Captive": _captive,
    "PMM": _pmm,
    "Runs": lambda w, day: _runs(w, day.runs, day.protocol.processing),
    "Tare": lambda w, day: _tare(w, day.tare),
    "Fins": lambda w, day: _fins(w, day.fins, day.protocol),
    "Fin curves": lambda w, day: _fin_curves(w, require(day.fins, "fin")),
    "Fin control": lambda w, day: _fin_control(w, require(day.fins, "fin")),
    "Scaling": lambda w, day: _scaling(w, day.scaling, day.protocol),
    "Scaling constants": lambda w, day: _scaling_constants(
        w, require(day.scaling, "scaling"), day.protocol),
    "Form factor": lambda w, day: _form_factor(w, require(day.scaling, "scaling")),
    "Quality": _quality,
    "Provenance": _provenance,
}


# ------------------------------------------------------------------------------- writer
@contextlib.contextmanager
def exact_floats() -> Iterator[None]:
    """While saving, write floats as ``repr`` (round-trip exact) instead of openpyxl's "%.16g".

    openpyxl formats every number of a cell with ``"%.16g"``, which is not always enough to
    give back the same double (17 significant digits may be needed); the CSV tables carry the
    shortest round-trip repr, and the workbook must hold the same floats.
    """
    original = _writer.safe_string

    def exact(value: Any) -> str:
        if isinstance(value, float) and math.isfinite(value):
            return repr(float(value))
        return original(value)

    _writer.safe_string = exact
    try:
        yield
    finally:
        _writer.safe_string = original


def write_workbook(day: DayResult, folder: str | Path) -> Path:
    """Write ``folder/report.xlsx``.

    Parameters
    ----------
    day : DayResult
        The processed day.
    folder : path
        The output folder (the report writers' temporary folder).

    Returns
    -------
    Path
        The workbook written.
    """
    wb = Workbook()
    wb.remove(wb.active)
    for name in sheet_names(day):
        w = SheetWriter(wb.create_sheet(name))
        WRITERS[name](w, day)
        w.finish()
    stamp = creation_date(report_date(day)[0]) or dt.datetime(2000, 1, 1, tzinfo=dt.UTC)
    stamp = stamp.replace(tzinfo=None)
    wb.properties.creator = "towtank"
    wb.properties.title = clean_text(f"{day.protocol.name}: towing-tank test workbook")
    for ws in wb.worksheets:  # towtank writes no formula: any text a formula would be is text
        for row in ws.iter_rows():
            for cell in row:
                if cell.data_type == "f":
                    cell.data_type = "s"
    wb.properties.created = stamp
    buf = io.BytesIO()
    with exact_floats():
        wb.save(buf)
    path = Path(folder) / "report.xlsx"
    path.write_bytes(_pinned(buf.getvalue(), stamp))
    return path


def _pinned(data: bytes, stamp: dt.datetime) -> bytes:
    """The workbook's zip with the save time and the entries' dates fixed (reproducible)."""
    iso = stamp.strftime("%Y-%m-%dT%H:%M:%SZ").encode()
    out = io.BytesIO()
    with zipfile.ZipFile(io.BytesIO(data)) as src, \
            zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as dst:
        for info in src.infolist():
            body = src.read(info.filename)
            if info.filename == "docProps/core.xml":
                body = re.sub(rb"(<dcterms:modified[^>]*>)[^<]*(</dcterms:modified>)",
                              rb"\g<1>" + iso + rb"\g<2>", body)
            zi = zipfile.ZipInfo(info.filename, date_time=(1980, 1, 1, 0, 0, 0))
            zi.compress_type = zipfile.ZIP_DEFLATED
            zi.external_attr = info.external_attr
            dst.writestr(zi, body)
    return out.getvalue()
