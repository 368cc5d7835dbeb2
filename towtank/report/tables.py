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
