"""The day's CSV tables (docs/formats.md §5): runs.csv, coefficients.csv, fins.csv, scaling.csv;
and the runs table's note on runs without a mean acceleration."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from towtank.reduce.tare import tare_table
from towtank.report.safetext import csv_text

if TYPE_CHECKING:
    import pandas as pd

    from towtank.ingest.schema import Processing
    from towtank.results import DayResult


def write_csv(df: pd.DataFrame, path: Path) -> None:
    """A deterministic CSV: full float precision, '\\n' line ends, no index; text cells (and
    column names) a spreadsheet would run as formulas neutralised
    (:func:`towtank.report.safetext.csv_text`)."""
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
    write_csv(day.table("fins"), out / "fins.csv")
    if day.fins is not None:
        write_csv(day.fins.curves, out / "fin_curves.csv")
        if day.fins.control is not None:
            write_csv(day.fins.control, out / "fin_control.csv")
    write_csv(day.table("scaling"), out / "scaling.csv")
    write_csv(tare_table(getattr(day, "tares", None) or {}), out / "tare.csv")
    if day.captive_results:
        write_csv(day.pmm, out / "pmm.csv")


def missing_accel_note(runs: pd.DataFrame, processing: Processing, run_ids: list[int]
                       ) -> tuple[list[int], str]:
    """The usable runs of ``run_ids`` with no acceleration in the table, and why (a footnote).

    A run has no mean acceleration when no constant-acceleration stretch of at least
    [processing] min_accel_s remains once the trim is cut from each end: at a low speed the
    ramp to U at the set acceleration lasts only U/a. Such a run is used for its plateau only.

    Parameters
    ----------
    runs : DataFrame
        runs.csv's table (``day.runs``): status, accel_mean [m/s²], speed_nominal [m/s] and
        accel_nominal [m/s²] of each run.
    processing : Processing
        The protocol's [processing] (``min_accel_s`` [s], ``trim`` [s]).
    run_ids : list of int
        The runs to look at (one page of the runs table).
    """
    runs = runs.set_index("run", drop=False)
    blank = [int(r) for r in run_ids if runs.loc[r, "status"] == "ok"
             and not math.isfinite(float(runs.loc[r, "accel_mean"]))]
    if not blank:
        return [], ""
    p = processing
    sel = runs.loc[blank]
    ramp = (sel["speed_nominal"] / sel["accel_nominal"]).to_numpy(float)
    ramp = ramp[np.isfinite(ramp) & (ramp > 0)]
    lasted = ""
    if ramp.size:
        lo, hi = float(ramp.min()), float(ramp.max())
        span = f"{lo:.2g} s" if math.isclose(lo, hi, rel_tol=0.05) else f"{lo:.2g}–{hi:.2g} s"
        lasted = f"; the ramp to U at the set a lasted only U/a = {span}"
    which = "Run" if len(blank) == 1 else "Runs"
    text = (f"¹ {which} {_run_list(blank)}, no a: no constant-acceleration stretch of at least "
            f"{p.min_accel_s:g} s once {p.trim:.3g} s is trimmed from each end{lasted}, "
            + ("so it gives its plateau samples only." if len(blank) == 1
               else "so they give their plateau samples only."))
    return blank, text


def _run_list(runs: list[int]) -> str:
    """1, 36–38: consecutive runs as ranges."""
    parts, start = [], None
    for k, r in enumerate(runs):
        if start is None:
            start = r
        if k + 1 == len(runs) or runs[k + 1] != r + 1:
            parts.append(str(start) if start == r else f"{start}–{r}")
            start = None
    return ", ".join(parts)
