"""The day's CSV tables (docs/formats.md §5): runs.csv, coefficients.csv, fins.csv, scaling.csv."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import pandas as pd

    from towtank.pipeline import DayResult


def write_csv(df: pd.DataFrame, path: Path) -> None:
    """A deterministic CSV: full float precision, '\\n' line ends, no index; text cells (and
    column names) a spreadsheet would run as formulas neutralised
    (:func:`towtank.report.safetext.csv_text`)."""
    from towtank.report.safetext import csv_text

    out = df.copy(deep=False)
    for col in out.columns:
        if out[col].dtype == object or str(out[col].dtype) in ("string", "str"):
            out[col] = out[col].map(lambda v: csv_text(v) if isinstance(v, str) else v)
    out.columns = [csv_text(str(c)) for c in out.columns]
    out.to_csv(path, index=False, lineterminator="\n")


def write_tables(day: DayResult, out: Path) -> None:
    """Write the four docs/formats.md §5 tables, and the fin extensions the day has data for.

    runs.csv, coefficients.csv, fins.csv and scaling.csv are always written, with their header
    only when the day has no row for them (a hull day has no fin run, a fin day no hull
    coefficient): a tool reading the folder finds every file of the contract.
    """
    write_csv(day.runs, out / "runs.csv")
    write_csv(day.coefficients, out / "coefficients.csv")
    write_csv(day.fins, out / "fins.csv")
    if day.fin_result is not None:
        write_csv(day.fin_result.curves, out / "fin_curves.csv")
        if day.fin_result.control is not None:
            write_csv(day.fin_result.control, out / "fin_control.csv")
    write_csv(day.scaling, out / "scaling.csv")
    from towtank.reduce.tare import tare_table

    write_csv(tare_table(getattr(day, "tares", None) or {}), out / "tare.csv")
