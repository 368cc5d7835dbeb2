"""The day's CSV tables (FORMATS.md §5): runs.csv, coefficients.csv, fins.csv, scaling.csv."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from towtank.report.outputs import write_csv

if TYPE_CHECKING:
    from towtank.pipeline import DayResult


def write_tables(day: DayResult, out: Path) -> None:
    """Write the four FORMATS §5 tables, and the fin extensions the day has data for.

    runs.csv, coefficients.csv, fins.csv and scaling.csv are always written, with their header
    only when the day has no row for them (a hull day has no fin run, a fin day no hull
    coefficient): a tool reading the folder finds every file of the contract.
    """
    import pandas as pd

    from towtank.fins import FIN_TABLE_COLUMNS
    from towtank.fit import COEFFICIENT_COLUMNS, COEFFICIENT_EXTRA_COLUMNS
    from towtank.similarity import SCALING_COLUMNS

    def empty(columns: list[str] | tuple[str, ...]) -> pd.DataFrame:
        return pd.DataFrame(columns=list(columns))

    write_csv(day.runs, out / "runs.csv")
    write_csv(day.hull.coefficients if day.hull is not None
              else empty(COEFFICIENT_COLUMNS + COEFFICIENT_EXTRA_COLUMNS), out / "coefficients.csv")
    write_csv(day.fins.table if day.fins is not None else empty(FIN_TABLE_COLUMNS),
              out / "fins.csv")
    if day.fins is not None:
        write_csv(day.fins.curves, out / "fin_curves.csv")
        if day.fins.control is not None:
            write_csv(day.fins.control, out / "fin_control.csv")
    write_csv(day.scaling.table if day.scaling is not None else empty(SCALING_COLUMNS),
              out / "scaling.csv")
