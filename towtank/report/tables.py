"""The day's CSV tables (FORMATS.md §5): runs.csv, coefficients.csv, fins.csv, scaling.csv."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from towtank.report.outputs import write_csv

if TYPE_CHECKING:
    from towtank.pipeline import DayResult


def write_tables(day: DayResult, out: Path) -> None:
    """Write the CSV tables the day has data for."""
    write_csv(day.runs, out / "runs.csv")
    if day.hull is not None:
        write_csv(day.hull.coefficients, out / "coefficients.csv")
    if day.fins is not None:
        write_csv(day.fins.table, out / "fins.csv")
        write_csv(day.fins.curves, out / "fin_curves.csv")
        if day.fins.control is not None:
            write_csv(day.fins.control, out / "fin_control.csv")
    if day.scaling is not None:
        write_csv(day.scaling.table, out / "scaling.csv")
