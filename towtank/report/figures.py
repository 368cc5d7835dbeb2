"""The report's figures, drawn only from what the day's stages computed.

Each ``fig_*`` function takes the result it draws (a :class:`~towtank.results.HullResult`,
:class:`~towtank.results.FinResult`, :class:`~towtank.results.ScalingResult`,
:class:`~towtank.results.TareResult`, with the run table or the run reductions where it draws
those too) and returns a :class:`matplotlib.figure.Figure` (or None when there is no data for
it); :func:`available_figures` binds each to the results of a day. Nothing is fitted
here: fit lines come from the stored parameters (``DampingFit.params``/``cov``, the
curve-difference quadratics of :class:`~towtank.analysis.hull.AddedMassFit`, the resistance curve of
:class:`~towtank.results.ScalingResult`), and reference curves are given functions evaluated on
a grid (:func:`towtank.reference.sandia.section_coefficients`,
:func:`towtank.analysis.fins.finite_span_coefficients`).

Figures are made with :class:`matplotlib.figure.Figure` directly (no pyplot state, Agg canvas,
vector output in the PDF) under one rc style, :func:`towtank.report.style.rc`.

=======================  ============================================================
function                 content (SUT-2 report figure)
=======================  ============================================================
fig_tare                 the sting tare against speed with its fit (towtank.report.tare_figure)
fig_added_mass           drag against speed per acceleration, α = 0 and 90° (Figs. 11–12)
fig_damping              C_D against α with the quadratic fit and its 95 % band (Fig. 13)
fig_fin_forces           fin drag and lift against speed per angle (Figs. 14–15)
fig_fin_coefficients     fin C_L, C_D against α with Sandia 2-D and finite span (Fig. 16)
fig_scaling              model and prototype resistance, Reynolds ranges
fig_captive              captive runs against the fitted derivatives (towtank.report.captive_figure)
run_thumbnail            one run: speed, drag and lift with the phases shaded (a captive
                         run: X, Y, N, towtank.report.captive_thumb)
thumbnail_twin           the forces' axes of a thumbnail (made once, reused page after page)
=======================  ============================================================
"""

from __future__ import annotations

import math
import textwrap
import warnings
from collections.abc import Callable, Mapping
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import matplotlib as mpl
import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

import towtank.report.style as style
from towtank.reduce.run import PHASE_ACCEL, PHASE_STEADY
from towtank.report.captive_thumb import (
    CaptiveTrace,
    captive_legend_handles,
    captive_thumbnail,
    captive_trace,
)
from towtank.report.figure_base import (
    PAGE_HEADER_IN,
    align_zero,
    figure_grid,
    fmt_number,
    literal,
    math_symbol,
    math_text,
    new_figure,
    place_legend,
    sci,
    styled,
)
from towtank.report.tare_figure import fig_tare
from towtank.stats.quantiles import normal_quantile, t95

if TYPE_CHECKING:  # towtank.results loads pandas, which `towtank inspect --png` never needs
    import pandas as pd
    from matplotlib.axes import Axes

    from towtank.ingest.protocol_types import Protocol
    from towtank.reduce.run import RunReduction
    from towtank.results import DayResult, FinResult, HullResult, ScalingResult



def _hull_of(hull: HullResult | DayResult | None) -> tuple[HullResult | None, DayResult | None]:
    """``hull`` as (the hull result, the day it came from): a day given in its place (the
    older call ``fig_damping(day)``) gives its ``hull``."""
    if hasattr(hull, "reductions"):  # a DayResult (not imported here: it loads pandas)
        day = cast("DayResult", hull)
        return day.hull, day
    return hull, None


# ----------------------------------------------------------------------- (a) added mass
ANGLE_OF = {"X_udot": 0.0, "Y_vdot": 90.0}

ADDED_MASS_CAPTION = (
    "Top: tare-corrected balance drag D of the constant-acceleration samples (coloured by "
    "acceleration level) and of the steady samples (grey), with the steady quadratic "
    "D_s(U) = q2·U|U| + q1·U and each level's quadratic D_a(U), drawn over the speed range the "
    "level shares with the steady runs (report eqs. 7–8). Bottom: their difference "
    "ΔD = D_a − D_s; its mean over that range divided by a gives m − X, the report's "
    "curve-difference estimate. Dotted: (m − X)·a of the joint regression "
    "D = k2·U|U| + k1·U + (m − X)·a over all samples, the primary estimate."
)


@styled
def fig_added_mass(hull: HullResult | DayResult | None,
                   reductions: Mapping[int, RunReduction] | None = None, *,
                   page: bool = False) -> Figure | None:
    """Drag against speed at each acceleration, with the steady curve and their difference.

    Columns: α = 0 (X_udot) and α = 90° (Y_vdot), those the day has. Top row: the
    constant-acceleration samples of each level, the steady samples, the steady quadratic
    D_s(U) and each level's quadratic D_a(U) over its speed range (report Figs. 11–12, from
    ``AddedMassFit.curve_difference``). Bottom row: ΔD(U) = D_a(U) − D_s(U) for each level,
    beside (m − X)·a of the joint regression (``AddedMassFit.M``).

    Parameters
    ----------
    hull : HullResult
        The hull result drawn (``day.hull``); a whole day is taken too (its ``hull`` and
        ``reductions``).
    reductions : mapping of int to RunReduction
        The reduced runs by run number (``day.reductions``), whose samples are drawn; needed
        with a HullResult.
    page : bool
        Lay the figure out as an A4 report page (room for header and footer).
    """
    result, day = _hull_of(hull)
    if day is not None and reductions is None:
        reductions = day.reductions
    hf = result.fit if result is not None else None
    fits = [hf.added_mass[s] for s in ANGLE_OF if hf is not None and s in hf.added_mass]
    if not fits:
        return None
    if reductions is None:
        raise TypeError("fig_added_mass(hull, reductions): the runs' reductions are needed "
                        "to draw their samples")
    fig = new_figure(page)
    gs = figure_grid(fig, 2, len(fits), page=page, hspace=0.4, wspace=0.28,
                     height_ratios=[1.35, 1.0],
                     title="Added mass: balance drag against speed at each acceleration",
                     text=ADDED_MASS_CAPTION)
    for col, am in enumerate(fits):
        _added_mass_column(fig.add_subplot(gs[0, col]), fig.add_subplot(gs[1, col]),
                           reductions, am)
    return fig


def _added_mass_column(ax: Axes, ax_d: Axes, reductions: Mapping[int, RunReduction],
                       am: Any) -> None:
    cd = am.curve_difference
    levels = cd.levels
    q = cd.steady_quadratic
    parts = [reductions[r].samples for r in am.runs if r in reductions]
    s = {k: np.concatenate([p[k] for p in parts]) for k in ("phase", "U", "a", "drag")}
    st = s["phase"] == PHASE_STEADY
    acc = s["phase"] == PHASE_ACCEL
    ax.plot(s["U"][st], s["drag"][st], "o", ms=3.2, color=style.STEADY_SAMPLE_COLOR,
            alpha=0.7, mew=0, zorder=6)
    handles = [Line2D([], [], ls="", marker="o", ms=4, color=style.STEADY_SAMPLE_COLOR,
                      label="steady samples")]
    shown = np.zeros(s["U"].size, dtype=bool)
    dmax = 0.0
    for i, lv in enumerate(levels):
        color = style.PALETTE[(i + 1) % len(style.PALETTE)]
        sel = acc & (np.abs(s["a"] - lv.accel) <= 0.15 * abs(lv.accel))
        shown |= sel
        ax.plot(s["U"][sel], s["drag"][sel], "o", ms=2.0, mew=0, color=color, alpha=0.5,
                zorder=2)
        u = np.linspace(lv.speed_range[0], lv.speed_range[1], 60)
        d_a = np.polyval(lv.quadratic, u)
        ax.plot(u, d_a, color=color, lw=1.7, zorder=4)
        handles.append(Line2D([], [], color=color, marker="o", ms=3,
                              label=f"$a$ = {lv.accel:.2f} m/s²: samples, $D_a(U)$"))
        if q is not None:
            diff = d_a - (q[0] * u * np.abs(u) + q[1] * u)
            ax_d.plot(u, diff, color=color, lw=1.6)
            dmax = max(dmax, float(np.max(diff)))
        ax_d.axhline(am.M * lv.accel, color=color, ls=":", lw=1.2)
        dmax = max(dmax, am.M * lv.accel)
    other = acc & ~shown
    if other.any():
        ax.plot(s["U"][other], s["drag"][other], "o", ms=2, mew=0, color="#cfcfcf", zorder=1)
    if q is not None:
        umax = float(np.nanmax(s["U"])) if s["U"].size else 1.0
        u = np.linspace(0.0, umax, 80)
        ax.plot(u, q[0] * u * np.abs(u) + q[1] * u, color="black", lw=1.4, ls="--", zorder=5)
        handles.append(Line2D([], [], color="black", ls="--", label="steady $D_s(U)$"))
    angle = ANGLE_OF.get(am.symbol, math.nan)
    est = am.estimate
    ax.set_title(rf"$\alpha$ = {angle:g}°: {math_symbol(am.symbol)} = {fmt_number(est.value)} kg")
    ax.set_xlabel(r"Speed $U$ [m/s]")
    ax.set_ylabel(r"Drag $D$ [N]")
    ax.set_xlim(left=0)
    ax.set_ylim(bottom=min(0.0, ax.get_ylim()[0]))
    place_legend(ax, handles, fontsize=6.8)

    ax_d.set_title(r"Difference $\Delta D = D_a(U) - D_s(U)$", fontsize=8.8)
    ax_d.set_xlabel(r"Speed $U$ [m/s]")
    ax_d.set_ylabel(r"$\Delta D$ [N]")
    ax_d.set_xlim(ax.get_xlim())
    ax_d.set_ylim(0, dmax * 1.15 if dmax > 0 else 1.0)
    alt = est.alt_value if math.isfinite(est.alt_value) else math.nan
    title = "\n".join([
        f"joint regression: {fmt_number(est.value)} kg "
        f"[{fmt_number(est.ci_low)}, {fmt_number(est.ci_high)}]",
        f"curve difference: {fmt_number(alt)} kg" + (
            f" ({est.agreement.verdict})" if est.agreement is not None else ""),
        math_text(f"m = {fmt_number(am.mass)} kg, m − {am.symbol} = {fmt_number(am.M)} kg"),
    ])
    place_legend(ax_d, [Line2D([], [], color="#555555", lw=1.5, label=r"$D_a - D_s$"),
                        Line2D([], [], color="#555555", ls=":",
                               label=math_text(f"(m − {am.symbol})·a, joint"))],
                 fontsize=6.8, title=title, title_fontsize=6.8, alignment="left", ncol=2)


# -------------------------------------------------------------------------- (b) damping
def cd_alpha_curve(params: np.ndarray, cov: np.ndarray, dof: int,
                   alpha_deg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """C_D(α) = a·α² + b·α + c on a grid and the half-width of its 95 % confidence band.

    Parameters
    ----------
    params : ndarray
        (a, b, c) of the stored fit, α in rad.
    cov : ndarray
        Their 3×3 covariance.
    dof : int
        Residual degrees of freedom of the fit.
    alpha_deg : ndarray
        Grid of angles [deg].

    Returns
    -------
    mean, half_width : ndarray
        C_D on the grid and the half-width of the 95 % confidence band of the mean [-].
    """
    a = np.radians(np.asarray(alpha_deg, dtype=float))
    x = np.column_stack([a**2, a, np.ones_like(a)])
    mean = x @ np.asarray(params, dtype=float)
    var = np.einsum("ij,jk,ik->i", x, np.asarray(cov, dtype=float), x)
    return mean, t95(dof) * np.sqrt(np.maximum(var, 0.0))


def damping_caption(alpha_max_deg: float | None) -> str:
    """Caption of :func:`fig_damping`.

    Parameters
    ----------
    alpha_max_deg : float or None
        The largest |α| of the damping fit, the protocol's ``damping_alpha_max_deg`` [deg]
        (None: not stated).
    """
    limit = (f"with |α| ≤ {alpha_max_deg:g}° " if alpha_max_deg is not None
             else "in the damping fit's angle range ")
    return (
        f"C_D = R/(½ρAU²) of each steady hull run {limit}(A the frontal area), coloured by "
        "speed; the line is the stored quadratic fit C_D(α) = aα² + bα + c (α in rad) and the "
        "band its 95 % confidence interval from the fit's covariance. X_u|u| = −½ρA·c, "
        "X_uv = −½ρA·b, X_v|v| = −½ρA·(a − c/2), Y_uv = −½ρA·c. Runs circled in red are "
        "flagged as outliers (|studentized residual| > 3 or large Cook's distance). Bottom "
        "right: C_D,90 on the lateral area from the transverse tows (band and dashed lines: its "
        "95 % interval, Student's t at the fit's degrees of freedom times its standard error "
        "with the tare's), which gives Y_v|v| = −½ρA_lat·C_D,90."
    )


@styled
def fig_damping(hull: HullResult | DayResult | None, alpha_max_deg: float | None = None, *,
                page: bool = False) -> Figure | None:
    """C_D against α with the stored quadratic fit and its 95 % band (report Fig. 13).

    Below: the fit's studentized residuals per run, and the transverse runs' C_D,90.

    Parameters
    ----------
    hull : HullResult
        The hull result drawn (``day.hull``); a whole day is taken too (its ``hull`` and
        its protocol's ``damping_alpha_max_deg``).
    alpha_max_deg : float, optional
        The largest |α| of the damping fit, ``[processing] damping_alpha_max_deg`` [deg],
        stated in the caption.
    page : bool
        Lay the figure out as an A4 report page.
    """
    result, day = _hull_of(hull)
    if day is not None and alpha_max_deg is None:
        alpha_max_deg = day.protocol.processing.damping_alpha_max_deg
    hf = result.fit if result is not None else None
    if hf is None or hf.damping is None:
        return None
    dm = hf.damping
    runs = dm.runs
    has_90 = dm.transverse_runs is not None and len(dm.transverse_runs) > 0
    fig = new_figure(page)
    gs = figure_grid(fig, 2, 2, page=page, hspace=0.42, wspace=0.32, height_ratios=[1.5, 1.0],
                     right=0.93, title="Damping: drag coefficient against angle of attack",
                     text=damping_caption(alpha_max_deg))
    ax = fig.add_subplot(gs[0, :])
    angles = runs["angle_deg"].to_numpy(float)
    lo, hi = float(np.min(angles)), float(np.max(angles))
    pad = max(1.0, 0.05 * (hi - lo))
    grid = np.linspace(lo - pad, hi + pad, 200)
    mean, half = cd_alpha_curve(dm.params, dm.cov, dm.dof, grid)
    se = np.sqrt(np.maximum(np.diag(dm.cov), 0.0))
    fit_label = "\n".join(
        [r"fit $C_D = a\,\alpha^2 + b\,\alpha + c$ ($\alpha$ in rad):"]
        + [f"{n} = {fmt_number(v, 5)} ± {fmt_number(e, 2)} (s.e.)"
           for n, v, e in zip("abc", dm.params, se, strict=True)]
        + [f"{len(runs)} runs, {dm.dof} residual d.o.f."]
    )
    ax.fill_between(grid, mean - half, mean + half, color=style.BAND_COLOR, alpha=0.6, lw=0,
                    label="95 % confidence band of the fit", zorder=1)
    ax.plot(grid, mean, color=style.FIT_COLOR, lw=1.6, zorder=2, label=fit_label)
    sc = ax.scatter(angles, runs["cd"], c=runs["speed"], cmap="viridis", s=22, zorder=3,
                    edgecolors="black", linewidths=0.4, label="steady hull runs")
    out = runs[runs["run"].isin(dm.outliers)]
    if len(out):
        ax.scatter(out["angle_deg"], out["cd"], s=90, facecolors="none",
                   edgecolors=style.OUTLIER_COLOR, linewidths=1.2, zorder=4, label="outlier")
        for r in out.itertuples():
            ax.annotate(f"run {int(r.run)}", (r.angle_deg, r.cd), xytext=(7, -3),
                        textcoords="offset points", fontsize=7, color=style.OUTLIER_COLOR,
                        va="top")
    cb = fig.colorbar(sc, ax=ax, pad=0.01, fraction=0.04)
    cb.set_label(r"Speed $U$ [m/s]")
    ax.set_xlabel(r"Angle of attack $\alpha$ [deg]")
    ax.set_ylabel(r"Drag coefficient $C_D$ [-] (frontal area)")
    place_legend(ax, fontsize=7)
    ax.set_title(r"$C_D(\alpha)$ of the steady hull runs (report eqs. 13–15)")

    ax_r = fig.add_subplot(gs[1, 0] if has_90 else gs[1, :])
    ax_r.axhspan(-3, 3, color="#eeeeee", lw=0, zorder=0)
    ax_r.axhline(0, color="#777777", lw=0.8)
    flagged = runs["run"].isin(dm.outliers).to_numpy()
    ax_r.scatter(angles[~flagged], runs["student"][~flagged], color=style.FIT_COLOR, s=16,
                 zorder=3)
    ax_r.scatter(angles[flagged], runs["student"][flagged], color=style.OUTLIER_COLOR, s=16,
                 zorder=3)
    mid = 0.5 * (grid[0] + grid[-1])
    for r in runs[flagged].itertuples():  # the label on the side away from the nearer axis
        right = r.angle_deg < mid
        ax_r.annotate(f"run {int(r.run)}", (r.angle_deg, r.student),
                      xytext=(6 if right else -6, 0), textcoords="offset points", fontsize=7,
                      color=style.OUTLIER_COLOR, ha="left" if right else "right",
                      va="center", annotation_clip=False)
    lim = max(3.5, float(np.nanmax(np.abs(runs["student"]))) * 1.15)
    ax_r.set_ylim(-lim, lim)
    ax_r.set_xlim(grid[0], grid[-1])
    ax_r.set_xlabel(r"Angle of attack $\alpha$ [deg]")
    ax_r.set_ylabel("Studentized residual [-]")
    ax_r.set_title("Fit residuals (shaded: within ±3)", fontsize=8.8)

    if has_90:
        _transverse_panel(fig.add_subplot(gs[1, 1]), dm, hf.estimates.get("Y_v|v|"))
    return fig


def cd90_interval(dm: Any, estimate: Any = None) -> tuple[float, float]:
    """Half-width of the 95 % interval of C_D,90 and its degrees of freedom.

    The interval is the transverse fit's own (the one of Y_v|v| = −½ρA_lat·C_D,90, so the
    same relative width): Student's t at the estimate's Welch–Satterthwaite degrees of freedom
    times the combined standard error of C_D,90 (regression and tare); the normal quantile
    when the degrees of freedom are not known.

    Parameters
    ----------
    dm : DampingFit
        The damping fit with ``cd90`` [-] and ``cd90_se`` [-].
    estimate : Estimate, optional
        The Y_v|v| estimate of the same fit (its ``dof``).
    """
    se = float(dm.cd90_se)
    dof = float(getattr(estimate, "dof", math.nan))
    if not math.isfinite(se) or se <= 0:
        return 0.0, dof
    q = t95(dof) if math.isfinite(dof) and dof > 0 else normal_quantile()
    return q * se, dof


def _transverse_panel(ax: Axes, dm: Any, estimate: Any = None) -> None:
    tr = dm.transverse_runs
    cd90 = float(dm.cd90)
    half, dof = cd90_interval(dm, estimate)
    xmax = float(tr["speed"].max()) * 1.1
    ax.plot(tr["speed"], tr["cd90"], "o", color=style.PALETTE[1], ms=4.5, zorder=4,
            label="transverse runs")
    ax.axhline(cd90, color=style.FIT_COLOR, lw=1.0, zorder=3,
               label=rf"$C_{{D,90}}$ = {fmt_number(cd90)} (OLS of $R$ on $U|U|$)")
    if half > 0:
        nu = f", ν = {dof:.3g}" if math.isfinite(dof) else ""
        ax.fill_between([0.0, xmax], cd90 - half, cd90 + half, color=style.BAND_COLOR,
                        alpha=0.8, lw=0, zorder=1,
                        label=f"95 % interval ± {fmt_number(half, 2)} (Student's t{nu})")
        for edge in (cd90 - half, cd90 + half):
            ax.axhline(edge, color=style.FIT_COLOR, lw=0.6, ls="--", zorder=2)
    ax.set_xlim(0, xmax)
    spread = max(float(np.ptp(tr["cd90"])), 2 * half, 0.005 * abs(cd90))
    ax.set_ylim(cd90 - 1.3 * spread, cd90 + 1.3 * spread)
    ax.set_xlabel(r"Speed $U$ [m/s]")
    ax.set_ylabel(r"$C_{D,90}$ [-] (lateral area)")
    ax.set_title(r"Transverse tow, $\alpha$ = 90°", fontsize=8.8)
    place_legend(ax, fontsize=6.8)


# ----------------------------------------------------------------------------- (c,d) fins
def _fin_result(fins: FinResult | DayResult | None) -> FinResult | None:
    """The fin result of ``fins``: itself, or a day's ``fins``."""
    if hasattr(fins, "reductions"):  # a DayResult (not imported here: it loads pandas)
        return cast("DayResult", fins).fins
    return fins


@styled
def fig_fin_forces(fins: FinResult | DayResult | None, *, page: bool = False
                   ) -> Figure | None:
    """Fin drag (top) and lift (bottom) against speed, one line per angle (report Figs. 14–15).

    Parameters
    ----------
    fins : FinResult or DayResult
        The fin result drawn (``day.fins``), or the day whose it is.
    page : bool
        Lay the figure out as an A4 report page.
    """
    fr = _fin_result(fins)
    if fr is None or len(fr.force_vs_speed) == 0:
        return None
    fv = fr.force_vs_speed
    angles = sorted(fv["angle_deg"].unique())
    # qualitative colours and a marker per angle: ten shades of one colour map cannot be told
    # apart where the lines cross
    cmap = mpl.colormaps["tab10" if len(angles) <= 10 else "tab20"]
    colors = {a: cmap(i % cmap.N) for i, a in enumerate(angles)}
    markers = {a: "osD^vP*Xh<>p"[i % 12] for i, a in enumerate(angles)}
    fig = new_figure(page)
    gs = figure_grid(fig, 2, 1, page=page, hspace=0.32, right=0.84,
                     title="Fin forces against carriage speed at each angle of attack",
                     text="Steady-phase means of the fin runs, zero, drift and sting tare removed. "
                     "Each line joins the runs at one angle of attack α. The drag axis is "
                     "logarithmic when the drags span more than a factor of 30, so that the small "
                     "drags of the low angles stay apart.")
    axes = [fig.add_subplot(gs[i, 0]) for i in range(2)]
    for col, ax, name in (("drag_mean", axes[0], "Drag"), ("lift_mean", axes[1], "Lift")):
        for a in angles:
            sel = fv[fv["angle_deg"] == a]
            ax.plot(sel["speed_mean"], sel[col], "-", marker=markers[a], color=colors[a], ms=4,
                    lw=1.1)
        values = fv[col].to_numpy(dtype=float)
        positive = values[np.isfinite(values) & (values > 0)]
        if (col == "drag_mean" and positive.size == np.isfinite(values).sum() and positive.size
                and positive.max() > 30 * positive.min()):
            ax.set_yscale("log")
        sym = "D" if col == "drag_mean" else "L"
        ax.set_ylabel(rf"{name} ${sym}$ [N]")
        ax.set_xlabel(r"Speed $U$ [m/s]")
        ax.set_title(f"{name} against speed (report Fig. {14 if sym == 'D' else 15})")
    handles = [Line2D([], [], color=colors[a], marker=markers[a], ms=4, label=f"{a:g}")
               for a in angles]
    fig.legend(handles=handles, title=r"$\alpha$ [deg]", loc="center left",
               bbox_to_anchor=(0.855, 0.5), fontsize=7.5, title_fontsize=8)
    return fig


def _section_curves(alpha: np.ndarray, re: float, aspect_ratio: float,
                    e: float) -> tuple[np.ndarray, ...]:
    """Sandia 2-D and lifting-line curves of one Re on an angle grid (evaluation only)."""
    # loaded on use: `towtank inspect --png` draws a run with this module and never a fin
    # figure; analysis.fins and reference.sandia load pandas
    from towtank.analysis import fins
    from towtank.reference import sandia

    res = np.full(alpha.shape, re)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sandia.SandiaRangeWarning)
        cl2, cd2 = sandia.section_coefficients(alpha, res)
        cl3, cd3 = fins.finite_span_coefficients(alpha, res, aspect_ratio, e)
    # lifting-line theory holds for attached flow only: draw the finite-span expectation up to
    # the angle whose effective angle α − α_i reaches the 2-D section's stall (its first local
    # maximum of C_L); beyond it the self-consistent solution jumps between branches
    attached = fins.attached_flow(alpha, cl3, res, aspect_ratio, e)
    cl3, cd3 = np.where(attached, cl3, np.nan), np.where(attached, cd3, np.nan)
    return cl2, cd2, cl3, cd3


@styled
def fig_fin_coefficients(fins: FinResult | DayResult | None, *, page: bool = False
                         ) -> Figure | None:
    """Fin C_L and C_D against α beside the Sandia 2-D section and the finite-span expectation.

    One colour per speed group; the Sandia NACA 0015 curves at the group's mean Re (solid) and
    the lifting-line expectation for the fin's aspect ratio (dashed) (report Fig. 16).

    Parameters
    ----------
    fins : FinResult or DayResult
        The fin result drawn (``day.fins``), or the day whose it is.
    page : bool
        Lay the figure out as an A4 report page.
    """
    fr = _fin_result(fins)
    if fr is None or len(fr.table) == 0:
        return None
    tab = fr.table
    if len(fr.curves):
        groups = fr.curves[["speed_group", "re_mean"]].to_numpy(float)
    else:
        groups = np.array([[g, tab.loc[tab["speed_group"] == g, "re"].mean()]
                           for g in sorted(tab["speed_group"].dropna().unique())])
    amin = min(0.0, float(tab["angle_deg"].min()) - 2.0)
    amax = min(180.0, float(tab["angle_deg"].max()) + 5.0)
    grid = np.linspace(amin, amax, int(round((amax - amin) / 0.25)) + 1)
    fig = new_figure(page)
    text = (
        "C_L = L/(½ρSU²), C_D = D/(½ρSU²) on the planform S = chord × span, Re on the chord. "
        "Solid: two-dimensional NACA 0015 data of Sheldahl & Klimas (1981, SAND80-2114) "
        "interpolated at each speed group's mean Re; dashed: the finite-span expectation from "
        "Prandtl's lifting line for the fin's effective aspect ratio "
        f"(AR = {fr.aspect_ratio:.3g}, e = {fr.oswald_e:.3g}), which lowers the lift slope and "
        "adds induced drag; it is drawn for attached flow only, up to the angle whose "
        "effective angle reaches the section's stall."
    )
    n_rows = math.ceil(len(groups) / 4)
    gs = figure_grid(fig, 2, 1, page=page, hspace=0.3, top_in=1.2 + 0.17 * n_rows,
                     title="Fin lift and drag coefficients against angle of attack", text=text)
    ax_l, ax_d = fig.add_subplot(gs[0, 0]), fig.add_subplot(gs[1, 0])
    group_handles = []
    for i, (g, re_g) in enumerate(groups):
        color = style.PALETTE[i % len(style.PALETTE)]
        sel = tab[tab["speed_group"] == g]
        curves = _section_curves(grid, float(re_g), fr.aspect_ratio, fr.oswald_e)
        for ax, meas, two, three in ((ax_l, "cl", curves[0], curves[2]),
                                     (ax_d, "cd", curves[1], curves[3])):
            ax.plot(grid, two, color=color, lw=1.0, alpha=0.9)
            ax.plot(grid, three, color=color, lw=1.0, ls="--", alpha=0.9)
            ax.plot(sel["angle_deg"], sel[meas], "o", color=color, ms=5, mec="black", mew=0.4,
                    zorder=4)
        group_handles.append(Patch(color=color, label=f"$U$ ≈ {g:.2f} m/s, Re = {sci(re_g)}"))
    style_handles = [
        Line2D([], [], ls="", marker="o", color="#777777", mec="black", mew=0.4,
               label="measured"),
        Line2D([], [], color="#777777", label="Sandia NACA 0015, 2-D section"),
        Line2D([], [], color="#777777", ls="--",
               label=f"finite span (lifting line, AR = {fr.aspect_ratio:.3g})"),
    ]
    h = fig.get_size_inches()[1]
    y0 = 1 - ((PAGE_HEADER_IN if page else 0.0) + 0.45) / h
    ncol = min(len(group_handles), 4)
    fig.legend(handles=group_handles, loc="upper center", bbox_to_anchor=(0.52, y0),
               ncol=ncol, fontsize=7.2, frameon=False)
    fig.legend(handles=style_handles, loc="upper center", ncol=3, fontsize=7.2, frameon=False,
               bbox_to_anchor=(0.52, y0 - (0.05 + 0.17 * n_rows) / h))
    ax_l.set_ylabel(r"Lift coefficient $C_L$ [-]")
    ax_d.set_ylabel(r"Drag coefficient $C_D$ [-]")
    for ax in (ax_l, ax_d):
        ax.set_xlabel(r"Angle of attack $\alpha$ [deg]")
        ax.set_xlim(amin, amax)
    ax_l.set_title(r"$C_L(\alpha)$ (report Fig. 16)")
    ax_d.set_title(r"$C_D(\alpha)$")
    return fig


# ------------------------------------------------------------------------------ (f) scaling


def scaling_caption(sr: ScalingResult) -> str:
    """Caption of :func:`fig_scaling`, from the scaling result it draws."""
    k2, k1 = sr.resistance
    ff = sr.form_factor
    ff_text = (f"Form factor 1 + k = {ff.one_plus_k:.3f} ± {ff.std:.3f} (mean and s.d. over "
               f"{ff.n} tested speeds, {ff.n_runs} runs)."
               if ff is not None else "No form factor (no wetted area or too few runs).")
    return (
        "Left: steady zero-angle model resistance with the resistance curve "
        f"R = k2·U|U| + k1·U (k2 = {k2:.4g} N s²/m², k1 = {k1:.4g} N s/m) and the model speeds "
        "that correspond to the prototype speeds by Froude scaling (hollow: outside the tested "
        "range, so extrapolated). Right: prototype resistance by Froude scaling of that curve "
        "(λ³ρ_p/ρ_m) and by the ITTC-57 friction line with the form factor. " + ff_text
        + "\n\n" + sr.statement
    )


@styled
def fig_scaling(scaling: ScalingResult | None, runs: pd.DataFrame, protocol: Protocol, *,
                page: bool = False) -> Figure | None:
    """Model resistance, prototype resistance (Froude and ITTC-57) and the Re ranges.

    Parameters
    ----------
    scaling : ScalingResult
        The scaling result drawn (``day.scaling``).
    runs : DataFrame
        runs.csv's table (``day.runs``): the steady zero-angle hull runs are drawn with the
        resistance curve, and the Re range of the hull runs.
    protocol : Protocol
        The day's protocol: the model's medium, the prototype's and ``[processing]
        damping_alpha_max_deg`` (the hull runs whose Re range is shown).
    page : bool
        Lay the figure out as an A4 report page.
    """
    sr = scaling
    if sr is None:
        return None
    tab = sr.table
    ok_hull = runs[(runs["config"] == "hull") & (runs["status"] == "ok")]
    zero = ok_hull[np.abs(ok_hull["angle_deg"]) <= 0.5]
    k2, k1 = sr.resistance
    lo, hi = sr.tested_speed_range
    fig = new_figure(page)
    gs = figure_grid(fig, 2, 2, page=page, hspace=0.42, wspace=0.3, height_ratios=[1.5, 0.8],
                     title=f"Scaling to the prototype (λ = {sr.scale:g})",
                     text=scaling_caption(sr))

    ax_m = fig.add_subplot(gs[0, 0])
    umax = max(hi, float(tab["speed_model_froude"].max())) * 1.08
    u = np.linspace(0.0, umax, 120)
    ax_m.axvspan(lo, hi, color="#e5f5e0", lw=0, label="tested speed range")
    ax_m.plot(u, k2 * u * np.abs(u) + k1 * u, color="black", lw=1.3,
              label=r"$R = k_2 U|U| + k_1 U$")
    ax_m.plot(zero["speed_mean"], zero["drag_mean"], "o", color=style.PALETTE[0], ms=4.5,
              mec="black", mew=0.4, label=r"steady runs, $\alpha$ = 0")
    uf = tab["speed_model_froude"].to_numpy(float)
    inside = tab["froude_in_tested_range"].to_numpy(bool)
    rf = k2 * uf * np.abs(uf) + k1 * uf
    ax_m.plot(uf[inside], rf[inside], "D", color=style.PALETTE[1], ms=5,
              label="Froude-equivalent speeds")
    if (~inside).any():
        ax_m.plot(uf[~inside], rf[~inside], "D", mfc="white", mec=style.PALETTE[1], ms=5,
                  label="… outside the tested range")
    ax_m.set_xlim(0, umax)
    ax_m.set_ylim(bottom=0)
    ax_m.set_xlabel(r"Model speed $U_m$ [m/s]")
    ax_m.set_ylabel(r"Model resistance $R_m$ [N]")
    ax_m.set_title("Model (air)" if protocol.water.is_air else "Model (tank water)")
    place_legend(ax_m, fontsize=6.8)

    ax_p = fig.add_subplot(gs[0, 1])
    up = tab["speed_prototype"].to_numpy(float)
    dfr = tab["drag_froude"].to_numpy(float)
    ax_p.plot(up, dfr, "-", color=style.PALETTE[1], lw=1.1)
    rec = (str(tab["recommended"].iloc[0]) if "recommended" in tab and len(tab) else "none")
    ax_p.plot(up[inside], dfr[inside], "D", color=style.PALETTE[1], ms=5,
              label="Froude-scaled model resistance (comparison only)")
    if (~inside).any():
        ax_p.plot(up[~inside], dfr[~inside], "D", mfc="white", mec=style.PALETTE[1], ms=5,
                  label="… extrapolated")
    if tab["drag_ittc57"].notna().any():
        ax_p.plot(up, tab["drag_ittc57"], "s-", color=style.PALETTE[2], ms=4.5, lw=1.1,
                  label=r"ITTC-57, $(1+k)\,C_F$"
                  + (" (recommended)" if rec == "drag_ittc57" else ""))
    ax_p.set_xlim(0, float(up.max()) * 1.08)
    ax_p.set_ylim(bottom=0)
    ax_p.set_xlabel(r"Prototype speed $U_p$ [m/s]")
    ax_p.set_ylabel(r"Prototype resistance $R_p$ [N]")
    proto = protocol.prototype
    ax_p.set_title(f"Prototype ({proto.water.medium})" if proto is not None else "Prototype")
    place_legend(ax_p, fontsize=6.8)

    near = ok_hull[np.abs(ok_hull["angle_deg"]) <= protocol.processing.damping_alpha_max_deg]
    _reynolds_panel(fig.add_subplot(gs[1, :]), sr, near["re"])
    return fig


def _reynolds_panel(ax: Axes, sr: ScalingResult, model_re: pd.Series) -> None:
    """The Reynolds ranges of the model tests (``model_re``: the hull runs' Re [-]), of the
    form-factor runs, of the model at the Froude speeds and of the prototype."""
    tab = sr.table
    bars = []
    if model_re.notna().any():
        bars.append(("model tests", float(model_re.min()), float(model_re.max()),
                     style.PALETTE[0]))
    if sr.form_factor is not None:
        bars.append(("form-factor runs", *sr.form_factor.re_range, style.PALETTE[2]))
    bars.append(("model at the Froude speeds", float(tab["re_model_froude"].min()),
                 float(tab["re_model_froude"].max()), style.PALETTE[1]))
    bars.append(("prototype", float(tab["re_prototype"].min()),
                 float(tab["re_prototype"].max()), style.PALETTE[3]))
    for i, (name, b0, b1, color) in enumerate(reversed(bars)):
        if b1 / b0 < 1.03:  # a single Re: widen the bar a little so it shows
            b0, b1 = b0 / 1.015, b1 * 1.015
        ax.barh(i, b1 - b0, left=b0, height=0.6, color=color, alpha=0.85)
        ax.text(b1 * 1.06, i, f"{name}: {sci(b0)} – {sci(b1)}", va="center", fontsize=7.5)
    ax.set_yticks([])
    ax.set_xscale("log")
    xs = [b[1] for b in bars] + [b[2] for b in bars]
    ax.set_xlim(min(xs) / 2, max(xs) * 12)
    ax.set_ylim(-0.6, len(bars) - 0.4)
    ax.set_xlabel(r"Reynolds number Re = $UL/\nu$ [-] (on the hull length)")
    ax.set_title("Reynolds number ranges")
    ax.grid(axis="y", visible=False)


# ------------------------------------------------------------------------------ (g) a run
#: Axis labels of a run thumbnail: the speed (left) and the forces (right), with units.
SPEED_LABEL = r"speed $U$ [m/s]"
FORCE_LABEL = r"drag $D$, lift $L$ [N]"
#: The same, short, for the report's appendix (its legend names U, D and L).
SPEED_LABEL_SHORT = r"$U$ [m/s]"
FORCE_LABEL_SHORT = r"$D$, $L$ [N]"


def thumbnail_twin(ax: Axes) -> Axes:
    """The twin axes of a thumbnail for the forces, under the transparent speed axes."""
    twin = ax.twinx()
    # the force axes lie below: shading, then forces; the speed axes on top are transparent
    ax.set_zorder(twin.get_zorder() + 1)
    ax.patch.set_visible(False)
    # horizontal gridlines belong to the forces (read against them), not to the speed
    ax.grid(axis="y", visible=False)
    twin.grid(axis="x", visible=False)
    twin.grid(axis="y", visible=True)
    twin.spines["right"].set_visible(True)
    return twin


def run_thumbnail(
    ax: Axes,
    reduction: RunReduction,
    *,
    title: str | None = None,
    show_lift: bool | None = None,
    labels: bool = True,
    linewidth: float = 1.0,
    twin: Axes | None = None,
) -> Axes:
    """Speed (left axis) and drag/lift (right axis) of one run with its phases shaded.

    Draws from ``reduction.thumb`` (the whole run at 10 Hz, zero and drift removed; tare removed
    after :func:`towtank.reduce.run.apply_tare`) and ``reduction.windows``. A captive run is
    drawn as what it measured instead: X, Y and N against time with its kept window or PMM
    cycles shaded (:func:`towtank.report.captive_thumb.captive_thumbnail`).

    Parameters
    ----------
    ax : Axes
        Where to draw the speed; a twin axis is added for the forces.
    reduction : RunReduction
        The run.
    title : str, optional
        Axes title.
    show_lift : bool, optional
        Draw the lift (default: when the run has a lift channel).
    labels : bool
        Axis labels with units.
    linewidth : float
        Line width [pt].
    twin : Axes, optional
        The forces' axes from :func:`thumbnail_twin` (made here when not given).

    Returns
    -------
    Axes
        The twin axes of the forces.
    """
    ax2 = thumbnail_twin(ax) if twin is None else twin
    ct = captive_trace(reduction)
    if ct is not None:  # a captive run: what its balance measured
        captive_thumbnail(ax, ax2, ct, reduction.windows, linewidth=linewidth, labels=labels)
        if title:
            ax.set_title(title)
        return ax2
    th = reduction.thumb
    for name, (color, _label) in style.PHASE_SHADES.items():
        w = reduction.windows.get(name)
        if w is not None:
            ax2.axvspan(w[0], w[1], color=color, lw=0, zorder=0)
    lift = reduction.has_lift if show_lift is None else show_lift
    _traces(ax, ax2, th, lift=lift, linewidth=linewidth)
    if labels:
        ax.set_xlabel(r"$t$ [s]")
        ax.set_ylabel(SPEED_LABEL)
        ax2.set_ylabel(FORCE_LABEL)
    if title:
        ax.set_title(title)
    return ax2


def preview_thumbnail(ax: Axes, preview: dict[str, np.ndarray], *, twin: Axes | None = None,
                      linewidth: float = 1.0) -> Axes:
    """The thumbnail of a run that was read but could not be reduced, drawn greyed.

    Draws ``preview`` (:func:`towtank.reduce.run.run_preview`: calibrated speed and forces at
    10 Hz, no zero, no filter, no phases), so that the reader sees what made the run unusable.

    Parameters
    ----------
    ax : Axes
        Where to draw the speed [m/s]; the forces [N] go on the twin axes.
    preview : dict of ndarray
        t [s], U [m/s], drag [N], lift [N].
    twin : Axes, optional
        The forces' axes from :func:`thumbnail_twin` (made here when not given).
    linewidth : float
        Line width [pt].

    Returns
    -------
    Axes
        The twin axes of the forces.
    """
    ax2 = thumbnail_twin(ax) if twin is None else twin
    ax2.set_visible(True)
    ax.set_axis_on()
    _traces(ax, ax2, preview, lift=True, linewidth=linewidth, alpha=0.45)
    return ax2


def _traces(ax: Axes, ax2: Axes, th: dict[str, np.ndarray], *, lift: bool, linewidth: float,
            alpha: float = 1.0) -> None:
    """Speed on ``ax``, drag (and lift, where it has values) on ``ax2``, and their limits."""
    t = np.asarray(th["t"], dtype=float)
    u = np.asarray(th["U"], dtype=float)
    forces = [np.asarray(th["drag"], dtype=float)]
    ax.plot(t, u, color=style.SPEED_COLOR, lw=linewidth, alpha=alpha, zorder=3)
    ax2.plot(t, forces[0], color=style.DRAG_COLOR, lw=linewidth * 0.9, alpha=alpha, zorder=2)
    lift_f = np.asarray(th["lift"], dtype=float)
    if lift and np.isfinite(lift_f).any():
        ax2.plot(t, lift_f, color=style.LIFT_COLOR, lw=linewidth * 0.9, alpha=alpha, zorder=2)
        forces.append(lift_f)
    finite = t[np.isfinite(t)]
    if finite.size >= 2:
        ax.set_xlim(float(finite.min()), float(finite.max()))
    ax.set_ylim(*thumbnail_ylim(u, above=0.08, below=0.05))
    # the forces keep to the lower two thirds, so that a force that grows like U² is not
    # drawn on top of the speed it follows
    ax2.set_ylim(*thumbnail_ylim(np.concatenate(forces), above=0.55, below=0.08))
    align_zero(ax, ax2)  # one zero line for speed and forces


def thumbnail_ylim(values: np.ndarray, *, above: float, below: float) -> tuple[float, float]:
    """Axis limits around the finite ``values``, with margins as fractions of their range.

    Zero is always inside the range (speeds and forces are read against it).
    """
    v = values[np.isfinite(values)]
    lo = min(float(v.min()), 0.0) if v.size else 0.0
    hi = max(float(v.max()), 0.0) if v.size else 1.0
    span = hi - lo if hi > lo else max(abs(hi), 1e-3)
    return lo - below * span, hi + above * span


def thumbnail_legend_handles(show_lift: bool = True) -> list[Any]:
    """Legend entries for :func:`run_thumbnail`: lines and phase shades."""
    handles: list[Any] = [
        Line2D([], [], color=style.SPEED_COLOR, label="speed $U$ [m/s] (left)"),
        Line2D([], [], color=style.DRAG_COLOR, label="drag $D$ [N] (right)"),
    ]
    if show_lift:
        handles.append(Line2D([], [], color=style.LIFT_COLOR, label="lift $L$ [N] (right)"))
    seen = set()
    for color, label in style.PHASE_SHADES.values():
        if color + label.split()[0] in seen or label == "still after":
            continue
        seen.add(color + label.split()[0])
        handles.append(Patch(color=color, label=label))
    return handles


@styled
def fig_preview(preview: dict[str, np.ndarray], title: str, note: str = "") -> Figure:
    """A stand-alone figure of a run that was read but could not be reduced (for ``towtank
    inspect``): its calibrated traces greyed (:func:`preview_thumbnail`), the reason below.

    Parameters
    ----------
    preview : dict
        :func:`towtank.reduce.run.run_preview` of the run.
    title : str
        Figure title.
    note : str
        Text under the plot (the reason the run cannot be reduced).
    """
    fig = Figure(figsize=(9.0, 4.8))
    bottom = 0.21 if note else 0.14
    ax = fig.add_axes((0.08, bottom, 0.84, 0.86 - bottom))
    twin = thumbnail_twin(ax)
    preview_thumbnail(ax, preview, twin=twin, linewidth=1.3)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("speed U [m/s] (grey)")
    twin.set_ylabel("drag D (blue), lift L (orange) [N]")
    ax.set_title(literal(title), loc="left", fontsize=9.5)
    if note:
        fig.text(0.08, 0.035, literal(textwrap.fill(note, 120)), fontsize=7.5, va="bottom",
                 color="#7a0000")
    return fig


def fig_run(reduction: RunReduction, title: str, note: str = "") -> Figure:
    """A stand-alone figure of one run (for ``towtank inspect`` and ``watch``); a captive run
    as :func:`fig_captive_run` draws it.

    Parameters
    ----------
    reduction : RunReduction
        The run.
    title : str
        Figure title.
    note : str
        Text under the plot (e.g. the steady means).
    """
    ct = captive_trace(reduction)
    if ct is not None:
        return fig_captive_run(ct, reduction.windows, title, note)
    fig, ax = _run_axes(note)
    run_thumbnail(ax, reduction, linewidth=1.3)
    _run_texts(fig, ax, title, note, thumbnail_legend_handles(reduction.has_lift))
    return fig


def fig_captive_run(ct: CaptiveTrace, windows: dict[str, tuple[float, float] | None],
                    title: str, note: str = "") -> Figure:
    """A stand-alone figure of one captive run: X, Y [N] and N [N m] against time, the kept
    window or PMM cycles shaded, a PMM run's motion along the top
    (:func:`towtank.report.captive_thumb.captive_thumbnail`).

    Parameters
    ----------
    ct : CaptiveTrace
        The run's load trace and kept cycles.
    windows : dict
        The run's phase windows [s].
    title : str
        Figure title.
    note : str
        Text under the plot.
    """
    fig, ax = _run_axes(note)
    captive_thumbnail(ax, thumbnail_twin(ax), ct, windows, linewidth=1.3, fontsize=7.0)
    _run_texts(fig, ax, title, note, captive_legend_handles(ct.pmm, "yaw" in ct.motion))
    return fig


def legend_columns(entries: int) -> int:
    """Columns of a run plot's legend: one row of up to 7 entries, else two rows."""
    return 7 if entries <= 7 else -(-entries // 2)


def _run_axes(note: str) -> tuple[Figure, Axes]:
    fig = Figure(figsize=(9.0, 4.8))
    bottom = 0.21 if note else 0.14
    return fig, fig.add_axes((0.08, bottom, 0.84, 0.86 - bottom))


def _run_texts(fig: Figure, ax: Axes, title: str, note: str, handles: list[Any]) -> None:
    ax.set_title(literal(title), loc="left", fontsize=9.5)
    fig.legend(handles=handles, loc="upper right", ncol=legend_columns(len(handles)),
               fontsize=6.8, bbox_to_anchor=(0.99, 0.995), frameon=False)
    if note:
        fig.text(0.08, 0.035, literal(note), fontsize=7.5,
                 family="DejaVu Sans Mono", va="bottom", color="#333333")


def fig_captive(fit: Any, roll_deg: float = 90.0, *, page: bool = False) -> Figure | None:
    """The captive page's figure (:func:`towtank.report.captive_figure.fig_captive`)."""
    # loaded on use: the captive figure loads pandas, which inspect's plot of one run never
    # needs
    from towtank.report.captive_figure import fig_captive as draw

    return draw(fit, roll_deg, page=page)


# ----------------------------------------------------------------------------- all figures
#: name, report section, function; the order of the PDF's figure pages.
FIGURES: tuple[tuple[str, str, Callable[..., Figure | None]], ...] = (
    ("tare", "Tare", fig_tare),
    ("added_mass", "Added mass", fig_added_mass),
    ("damping", "Damping", fig_damping),
    ("fin_forces", "Fins", fig_fin_forces),
    ("fin_coefficients", "Fins", fig_fin_coefficients),
    ("scaling", "Scaling", fig_scaling),
    ("captive", "Captive", fig_captive),
    ("captive_vertical", "Captive, vertical plane", fig_captive),
)


def _figure_arguments(name: str, day: DayResult) -> tuple[Any, ...]:
    """What figure ``name`` of :data:`FIGURES` draws, taken from the day."""
    p = day.protocol
    return {
        "tare": lambda: (day.tare, day.runs),
        "added_mass": lambda: (day.hull, day.reductions),
        "damping": lambda: (day.hull, p.processing.damping_alpha_max_deg),
        "fin_forces": lambda: (day.fins,),
        "fin_coefficients": lambda: (day.fins,),
        "scaling": lambda: (day.scaling, day.runs, p),
        "captive": lambda: (day.captive, captive_roll_deg(p)),
        "captive_vertical": lambda: (day.captive_vertical, captive_roll_deg(p)),
    }[name]()


def captive_roll_deg(protocol: Any) -> float:
    """The model's roll on the rig of vertical-plane runs [deg] ([captive] roll_deg, 90)."""
    options = getattr(protocol, "captive", None)
    return float(options.roll_deg) if options is not None else 90.0


def available_figures(day: DayResult) -> list[tuple[str, str, Callable[..., Figure | None]]]:
    """The entries of :data:`FIGURES` the day has data for (without drawing them), each
    function bound to the results it draws: call it with ``page=`` only."""
    hf = day.hull.fit if day.hull is not None else None
    has = {
        "tare": bool(getattr(day, "tares", None)),
        "added_mass": hf is not None and bool(hf.added_mass),
        "damping": hf is not None and hf.damping is not None,
        "fin_forces": day.fins is not None and len(day.fins.force_vs_speed) > 0,
        "fin_coefficients": day.fins is not None and len(day.fins.table) > 0,
        "scaling": day.scaling is not None,
        "captive": bool(getattr(getattr(day, "captive", None), "estimates", None)),
        "captive_vertical": bool(getattr(getattr(day, "captive_vertical", None), "estimates",
                                         None)),
    }
    return [(name, section, partial(func, *_figure_arguments(name, day)))
            for name, section, func in FIGURES if has[name]]


def write_figures(day: DayResult, folder: str | Path) -> list[Path]:
    """Save every figure the day has as ``folder/figures/<name>.png`` (150 dpi).

    Parameters
    ----------
    day : DayResult
        The processed day.
    folder : path
        The output folder (the report writers' temporary folder).

    Returns
    -------
    list of Path
        The files written.
    """
    out = Path(folder) / "figures"
    out.mkdir(parents=True, exist_ok=True)
    written = []
    with mpl.rc_context(style.rc()):
        for name, _section, func in available_figures(day):
            fig = func()
            if fig is None:
                continue
            path = out / f"{name}.png"
            fig.savefig(path, dpi=style.PNG_DPI, facecolor="white",
                        metadata={"Software": None})
            written.append(path)
    return written
