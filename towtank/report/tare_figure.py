"""The sting tare figure of the report: the sting runs' steady means against speed with the
fitted tare T = t2·U|U| + t1·U + m_t·a (docs/method.md, "Sting tare") and its 95 % band."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.figure import Figure

import towtank.report.style as style
from towtank.report.figure_base import (
    figure_grid,
    literal,
    new_figure,
    place_legend,
    styled,
)
from towtank.stats.quantiles import t95

if TYPE_CHECKING:
    import pandas as pd

    from towtank.reduce.tare import TareFit
    from towtank.results import TareResult


#: Units of the tare coefficients t2, t1, m_t of T = t2·U|U| + t1·U + m_t·a.
TARE_UNITS = ("N s²/m²", "N s/m", "kg")


def _interval(fit: TareFit) -> np.ndarray:
    """Half-widths of the 95 % intervals of (t2, t1, m_t): Student's t at the fit's dof."""
    se = np.sqrt(np.maximum(np.diag(np.asarray(fit.cov, dtype=float)), 0.0))
    return t95(fit.dof) * se


def tare_terms(fit: TareFit) -> str:
    """The fitted coefficients of one channel with their 95 % intervals, e.g.
    ``t2 = 0.08001 ± 0.0012 N s²/m², t1 = …, m_t = … kg``."""
    half = _interval(fit)
    return ", ".join(
        f"{name} = {float(v):.4g} ± {float(h):.2g} {unit}" if math.isfinite(h) and h > 0
        else f"{name} = {float(v):.4g} {unit}"
        for name, v, h, unit in zip(("t2", "t1", "m_t"), fit.coef, half, TARE_UNITS,
                                    strict=True))


def tare_caption(tare: TareResult) -> str:
    """Caption of :func:`fig_tare`: the model and, per tare group and channel, its fitted
    coefficients with their 95 % intervals.

    Parameters
    ----------
    tare : TareResult
        The day's sting tare (``day.tare``).
    """
    models = tare.models
    parts = []
    for channel in ("drag", "lift"):
        for group in sorted(models):
            fit = getattr(models[group], channel)
            if fit is None:
                continue
            parts.append(f"{channel.capitalize()}, group {group} (runs "
                         f"{_run_list(models[group].runs)}): {tare_terms(fit)}.")
    return ("The sting alone, towed like the model: the steady means of the sting runs (points) "
            "and the fitted tare T = t2·U|U| + t1·U + m_t·a at a = 0 (line) with its 95 % "
            "confidence band (shaded), per tare group; the tare is subtracted sample by sample "
            "from the group's model runs (with m_t·a while accelerating) and its uncertainty is "
            "part of every coefficient's interval. Coefficients with their 95 % intervals "
            "(Student's t): " + " ".join(parts) + " tare.csv and the workbook's Tare sheet "
            "give every term with its interval.")


def _run_list(runs: tuple[int, ...]) -> str:
    """Run numbers as ranges: (1, 2, 3, 5) -> "1–3, 5"."""
    out: list[str] = []
    start: int | None = None
    prev = 0  # the last run of the range from start; set with start
    for r in sorted(runs):
        if start is None:
            start = prev = r
        elif r == prev + 1:
            prev = r
        else:
            out.append(f"{start}–{prev}" if prev != start else f"{start}")
            start = prev = r
    if start is not None:
        out.append(f"{start}–{prev}" if prev != start else f"{start}")
    return ", ".join(out)


@styled
def fig_tare(tare: TareResult, runs: pd.DataFrame, *, page: bool = False) -> Figure | None:
    """Sting tare against speed: the sting runs' steady drag and lift with the fitted tare.

    Parameters
    ----------
    tare : TareResult
        The sting tare drawn (``day.tare``): T = t2·U|U| + t1·U + m_t·a per tare group.
    runs : DataFrame
        runs.csv's table (``day.runs``): its valid sting runs' steady means [N] against
        speed [m/s] are drawn as points.
    page : bool
        Lay the figure out as an A4 report page.
    """
    tares = tare.models
    if not tares:
        return None
    has_lift = any(m.lift is not None for m in tares.values())
    fig = new_figure(page)
    gs = figure_grid(fig, 1, 2 if has_lift else 1, page=page, wspace=0.3,
                     title="Sting tare", text=tare_caption(tare))
    sting = runs[(runs["config"] == "sting") & (runs["status"] == "ok")]
    channels = [("drag", "drag_mean", r"Tare drag $T_D$ [N]")]
    if has_lift:
        channels.append(("lift", "lift_mean", r"Tare lift $T_L$ [N]"))
    for col, (channel, column, label) in enumerate(channels):
        ax = fig.add_subplot(gs[0, col])
        for i, group in enumerate(sorted(tares)):
            model = tares[group]
            fit = model.drag if channel == "drag" else model.lift
            if fit is None:
                continue
            color = style.PALETTE[i % len(style.PALETTE)]
            pts = sting[sting["tare_group"].astype(str) == str(group)]
            lo, hi = model.speed_range
            u = np.linspace(0.0, hi * 1.05, 120)
            a = np.zeros_like(u)
            curve = fit(u, a)
            band = t95(fit.dof) * fit.std_error(u, a)
            name = literal(f"group {group}") if len(tares) > 1 else "fitted tare"
            ax.fill_between(u, curve - band, curve + band, color=color, alpha=0.25, lw=0,
                            label=f"{name}: 95 % confidence band")
            ax.plot(u, curve, color=color, lw=1.2, label=f"{name}, a = 0")
            if column in pts:
                ax.plot(pts["speed_mean"], pts[column], "o", color=color, ms=4, mec="black",
                        mew=0.4, label="sting runs, steady means")
        ax.set_xlim(left=0)
        ax.set_xlabel(r"Carriage speed $U$ [m/s]")
        ax.set_ylabel(label)
        ax.set_title(channel.capitalize())
        place_legend(ax, fontsize=6.8)
    return fig
