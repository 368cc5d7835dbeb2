"""The vehicle outputs of a processed day: predicted.csv, model.json and the figure of measured
beside predicted primes (docs/formats.md, section 6)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import matplotlib as mpl
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.transforms import blended_transform_factory

import towtank.report.style as style
from towtank.report.figure_base import (
    figure_grid,
    fmt_number,
    math_symbol,
    new_figure,
    place_legend,
)
from towtank.vehicle.assumptions import ASSUMED, guessed, origin
from towtank.vehicle.model import write_model


def write_vehicle(day: Any, folder: Path, figure: bool = True) -> None:
    """Write predicted.csv and model.json of ``day.vehicle`` into ``folder``, and with
    ``figure`` (and the protocol's [report] figures) figures/predicted_vs_measured.png."""
    folder = Path(folder)
    day.vehicle.predicted.to_csv(folder / "predicted.csv", index=False, float_format="%.6g")
    write_model(day.vehicle.model, folder / "model.json")
    report = getattr(day.protocol, "report", None)
    if figure and getattr(report, "figures", True) and "predicted" in day.coefficients:
        fig = predicted_figure(day.coefficients)
        if fig is not None:
            (folder / "figures").mkdir(exist_ok=True)
            fig.savefig(folder / "figures" / "predicted_vs_measured.png", dpi=150,
                        facecolor="white", metadata={"Software": None})


PREDICTED_TITLE = "Measured beside predicted coefficients"


def predicted_caption() -> str:
    """Caption of the predicted-vs-measured figure (:func:`fig_predicted`)."""
    return (
        "Each coefficient the [vehicle] geometry predicts, as a prime (added mass over ½ρL³, "
        "damping over ½ρL²), divided by the size of its prediction |predicted prime|: the "
        "prediction lies at −1 or +1 (hollow diamond), the measurement (filled circle) with its "
        "95 % interval (including the length uncertainty) where it falls. The prediction is "
        "semi-empirical (towtank's documentation, method chapter, \"Prediction from "
        "geometry\"): Lamb's k1 for the axial added mass, strip theory with Lamb's k2 for the "
        "transverse ones, ITTC-57 friction with Hoerner's form factor for the axial drag, "
        "cross-flow drag (c_dc = 1.1, Prestero 2001) for Y_v|v| and Hoerner's body lift "
        "(c_ydβ = 1.2) for Y_uv. Right: the numbers, "
        "and diff = (measured − predicted)/|predicted|; a difference beyond ±50 % is also a "
        "warning on the quality page. Y_uv and Z_uw differ by design on a hull day: the SUT-2 "
        "method measures only the drag's side component (Y_uv = X_u|u|), while the prediction "
        "includes the hull's lift."
    )


def predicted_rows(coefficients: Any) -> Any:
    """The rows of ``coefficients`` with a finite, non-zero prediction (those the
    predicted-vs-measured figure draws); None without a table.

    Parameters
    ----------
    coefficients : DataFrame or None
        coefficients.csv's table, with its ``predicted`` column [-] when the day has a
        [vehicle] (docs/formats.md); without that column no row is kept.
    """
    if coefficients is None or "predicted" not in coefficients:
        return coefficients.iloc[0:0] if coefficients is not None else None
    keep = []
    for p in coefficients["predicted"]:
        try:
            keep.append(math.isfinite(float(p)) and float(p) != 0)
        except (TypeError, ValueError):
            keep.append(False)
    return coefficients[keep]


def _draw_predicted(ax: Any, rows: Any, *, symbol: Any = str, numbers: bool = False) -> None:
    """Measured (95 %) and predicted primes of ``rows`` over |predicted| on ``ax``, one row
    per coefficient; with ``numbers`` their values to the right of the axes."""
    meas_color, pred_color = style.PALETTE[0], style.PALETTE[1]
    right = blended_transform_factory(ax.transAxes, ax.transData)
    lows, highs = [0.0], [0.0]
    for i, (_, r) in enumerate(rows.iterrows()):
        pred = float(r["predicted"])
        scale = abs(pred)
        meas = float(r["prime"]) / scale
        lo = float(r.get("prime_ci_low", math.nan)) / scale
        hi = float(r.get("prime_ci_high", math.nan)) / scale
        if math.isfinite(lo) and math.isfinite(hi):
            ax.errorbar(meas, i, xerr=[[max(meas - lo, 0.0)], [max(hi - meas, 0.0)]], fmt="o",
                        color=meas_color, ms=5, capsize=3, zorder=3)
            lows.append(lo)
            highs.append(hi)
        else:
            ax.plot(meas, i, "o", color=meas_color, ms=5, zorder=3)
        lows += [meas, pred / scale]
        highs += [meas, pred / scale]
        ax.plot(pred / scale, i, "D", mfc="white", mec=pred_color, mew=1.3, ms=6, zorder=4)
        if numbers:
            diff = (float(r["prime"]) - pred) / scale * 100
            ax.text(1.03, i, f"{fmt_number(float(r['prime']) * 1e3)}", transform=right,
                    va="center", ha="left", fontsize=7.5)
            ax.text(1.25, i, f"{fmt_number(pred * 1e3)}", transform=right, va="center", ha="left",
                    fontsize=7.5)
            ax.text(1.47, i, f"{diff:+.0f} %".replace("-", "\u2212"), transform=right,
                    va="center", ha="left", fontsize=7.5,
                    color=style.OUTLIER_COLOR if abs(diff) > 50 else "black")
    if numbers:
        for x, head in ((1.03, "measured\nprime·10³"), (1.25, "predicted\nprime·10³"),
                        (1.47, "diff")):
            ax.text(x, 1.0, head, transform=ax.transAxes, va="bottom", ha="left",
                    fontsize=7.5, fontweight="bold")
    ax.set_yticks(range(len(rows)), [symbol(s) for s in rows["symbol"]])
    if numbers:  # the report page: room for larger symbols
        ax.tick_params(axis="y", labelsize=9.5)
    ax.set_ylim(len(rows) - 0.5, -0.8 if numbers else -0.5)
    lo, hi = min(lows), max(highs)
    pad = 0.08 * (hi - lo)
    ax.set_xlim(lo - pad, hi + pad)
    ax.axvline(0.0, color="0.5", lw=0.8)
    ax.grid(False, axis="y")
    ax.set_xlabel("prime / |predicted prime| [-]")
    place_legend(ax, [
        Line2D([], [], ls="", marker="o", color=meas_color, label="measured, 95 % interval"),
        Line2D([], [], ls="", marker="D", mfc="white", mec=pred_color, mew=1.3,
               label="predicted from the geometry (±1)"),
    ], fontsize=7)


def predicted_figure(coefficients: Any) -> Any:
    """Measured primes with their 95 % intervals beside the predicted ones, each divided by
    |predicted| (the prediction at ±1); None when no coefficient has a prediction.

    Parameters
    ----------
    coefficients : DataFrame
        coefficients.csv's table with its ``predicted`` column (docs/formats.md).
    """
    rows = predicted_rows(coefficients)
    if rows is None or rows.empty:
        return None
    with mpl.rc_context(style.rc()):
        fig = Figure(figsize=(6.5, 0.45 * len(rows) + 1.4), layout="constrained")
        ax = fig.add_subplot()
        ax.set_title(PREDICTED_TITLE, loc="left", fontsize=9)
        _draw_predicted(ax, rows)
    return fig


def fig_predicted(coefficients: Any, *, page: bool = False,
                  assumptions: list[dict[str, Any]] | None = None) -> Any:
    """The predicted-vs-measured figure of a day with a [vehicle], as a report page: the
    primes over |predicted| (:func:`predicted_figure`) with their numbers and a caption, and
    below them the table of the model's guessed inputs (:func:`assumption_rows`); None when
    no coefficient has a prediction.

    Parameters
    ----------
    coefficients : DataFrame
        coefficients.csv's table with its ``predicted`` column (``day.coefficients``,
        docs/formats.md).
    page : bool
        Lay the figure out as an A4 report page.
    assumptions : list of dict, optional
        model.json ``assumptions`` (``day.vehicle.model``)
    """
    rows = predicted_rows(coefficients)
    if rows is None or rows.empty:
        return None
    table = assumption_rows(assumptions)
    with mpl.rc_context(style.rc()):
        fig = new_figure(page)
        height = fig.get_size_inches()[1]
        # the table's rows, its heading and the axes' x label below the axes [in]
        below = ASSUMPTION_ROW_IN * (len(table) + 2) + 0.6 if table else 0.0
        # the axes keep ~0.85 in per coefficient (the whole height left from 9 on)
        used = min(0.85 * len(rows) + 0.6, height - 4.0 - below)
        free = max(height - used - 4.0, 0.0)
        gs = figure_grid(fig, 2, 1, page=page, right=0.6, left=0.14, hspace=0.0,
                         height_ratios=[used, max(free, 1e-3)], title=PREDICTED_TITLE,
                         text=predicted_caption() + (ASSUMPTIONS_CAPTION if table else ""))
        _draw_predicted(fig.add_subplot(gs[0, 0]), rows, symbol=math_symbol, numbers=True)
        if table:
            _draw_assumptions(fig.add_subplot(gs[1, 0]), table, height)
    return fig


#: Height of a row of the assumptions' table on the vehicle page [in].
ASSUMPTION_ROW_IN = 0.19
#: Most characters of a note in that table (the whole note is in model.json).
NOTE_CHARS = 52
#: The caption's sentence on that table.
ASSUMPTIONS_CAPTION = (
    " Below: the inputs of the model that were not measured (model.json 'assumptions'): "
    "'default' is towtank's choice where the protocol gives nothing, 'assumed' a value the "
    "protocol marks as a guess ([vehicle.assumed]); the manoeuvres simulated from this model "
    "rest on them.")


def _shown(value: Any, width: int = 26, digits: int = 4) -> str:
    """An assumption's value in a table cell: numbers to ``digits`` significant digits (3 in
    lists and tables), lists and tables joined, cut to ``width`` characters."""
    if isinstance(value, dict):
        text = ", ".join(f"{k} {_shown(v, width, 3)}" for k, v in value.items())
    elif isinstance(value, (list, tuple)):
        text = ", ".join(_shown(v, width, 3) for v in value)
    elif isinstance(value, float):
        text = fmt_number(value, digits)
    else:
        text = str(value)
    return text if len(text) <= width else text[:width - 1] + "…"


def assumption_rows(assumptions: list[dict[str, Any]] | None) -> list[tuple[str, str, str, str]]:
    """(input, value, source, note) of the guessed inputs
    (:func:`towtank.vehicle.assumptions.guessed`: the defaults and the protocol's assumed
    inputs) for the vehicle page; source "default" or "assumed", the note without its
    "assumed: " and cut to fit."""
    out = []
    for a in guessed(assumptions or []):
        note = str(a["note"]).removeprefix(ASSUMED)
        out.append((str(a["input"]), _shown(a.get("value")), origin(a),
                    note if len(note) <= NOTE_CHARS else note[:NOTE_CHARS - 1] + "…"))
    return out


def _draw_assumptions(ax: Any, table: list[tuple[str, str, str, str]], height_in: float) -> None:
    """The assumptions' table in the axes ``ax`` (turned off), starting 0.6 in below its top
    (the x label of the axes above), across the caption's width (8 % to 92 % of the page)."""
    ax.axis("off")
    pos = ax.get_position()
    ax_h = pos.height * height_in
    top = 1.0 - 0.6 / ax_h
    left = (0.08 - pos.x0) / pos.width
    ax.text(left, top, "Assumed, not measured (model.json 'assumptions')",
            transform=ax.transAxes, fontsize=8.5, fontweight="bold", va="bottom")
    rows_h = ASSUMPTION_ROW_IN * (len(table) + 1) / ax_h
    cells = ax.table(cellText=[list(r) for r in table],
                     colLabels=["input", "value", "source", "note"],
                     colWidths=[0.25, 0.24, 0.09, 0.42], cellLoc="left", colLoc="left",
                     bbox=[left, top - 0.04 / ax_h - rows_h, 0.84 / pos.width, rows_h])
    cells.auto_set_font_size(False)
    cells.set_fontsize(7)
    for (r, _c), cell in cells.get_celld().items():
        cell.set_edgecolor("#bbbbbb")
        cell.set_linewidth(0.4)
        if r == 0:
            cell.set_text_props(fontweight="bold")
            cell.set_facecolor("#eeeeee")
