"""The captive page's figure: the day's captive runs against the joint fit of the derivatives.

Four rows of two panels (the force equation left, the moment equation right; Y and N, or Z
and M for the vertical plane):

1. static drift: each drift run's steady mean on the prime scale (Y' = Y / (1/2 rho L^2 U^2),
   N' = N / (1/2 rho L^3 U^2)) with its 95 % error bar, against the drift angle, and the fit's
   curve with its 95 % confidence band;
2. rotating arm: the same against r' = r L / U = L / R, one curve per drift angle;
3. one PMM run's cycle-averaged loads over one period (:attr:`CaptiveRun.period`) beside the
   fit's prediction from the same motion;
4. the derivatives a PMM run measures, run by run (the fit's ``by_run`` table), against
   omega' = omega L / U, each over its joint value, with the joint value's 95 % band.

Nothing is fitted here: curves and bands come from the fit's estimates and covariance
(:attr:`towtank.analysis.captive.CaptiveFit.cov`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

import towtank.report.style as style
from towtank.analysis.captive import mapped_rows, plane_names
from towtank.reduce.captive import (
    PMM_TESTS,
    REGRESSORS,
    ROW_COLUMNS,
    STATIC_BLOCKS,
    arm_kinematics,
    body_kinematics,
    kinematics_at,
    regressors,
)
from towtank.report.figure_base import figure_grid, math_symbol, new_figure, styled
from towtank.stats.quantiles import t_quantile

if TYPE_CHECKING:
    from towtank.analysis.captive import CaptiveFit
    from towtank.reduce.captive import CaptiveRun

#: Points of a fitted curve.
CURVE_POINTS = 121
#: The level of a run's error bar.
BAR_LEVEL = 0.95


def _rows_frame(reg: dict[str, np.ndarray], loads: dict[str, np.ndarray] | None = None
                ) -> pd.DataFrame:
    """Component rows (:data:`ROW_COLUMNS`) from regressor arrays (and loads, else NaN)."""
    n = len(next(iter(reg.values())))
    nan = np.full(n, math.nan)
    data: dict[str, Any] = {"component": ["mean"] * n}
    for q in ("X", "Y", "N"):
        data[q] = (loads or {}).get(q, nan)
        data[f"{q}_se"] = nan
    data.update({k: np.asarray(reg[k], dtype=float) for k in REGRESSORS})
    return pd.DataFrame(data, columns=list(ROW_COLUMNS))


def plane_rows(run: CaptiveRun, rows: pd.DataFrame, roll_deg: float) -> pd.DataFrame:
    """``rows`` (rig axes, horizontal names) in the plane's names as the fit sees them
    (:func:`towtank.analysis.captive.mapped_rows`)."""
    return mapped_rows(replace(run, rows=rows), roll_deg)


def predict(fit: CaptiveFit, rows: pd.DataFrame, eq: str, level: float = 0.95
            ) -> tuple[np.ndarray, np.ndarray]:
    """The fit's ``eq`` load at ``rows`` (plane names) and the half-width of its confidence
    band of ``level`` [the load's unit]; NaN without the equation's covariance."""
    cov = fit.cov.get(eq)
    if cov is None or cov.empty:
        nan = np.full(len(rows), math.nan)
        return nan, nan
    names = list(cov.index)
    X = rows[[n.split("_", 1)[1] for n in names]].to_numpy(dtype=float)
    b = np.array([fit.estimates[n].value for n in names])
    C = cov.to_numpy(dtype=float)
    dof = fit.estimates[names[0]].dof
    half = t_quantile(dof, 1.0 - level) * np.sqrt(np.maximum(np.einsum("ij,jk,ik->i", X, C, X),
                                                             0.0))
    return X @ b, half


def _prime_scale(fit: CaptiveFit, speed: np.ndarray | float, moment: bool) -> np.ndarray:
    """1/2 rho L^2 U^2 (force) or 1/2 rho L^3 U^2 (moment)."""
    return 0.5 * fit.rho * fit.length_m ** (3 if moment else 2) * np.asarray(speed) ** 2


def static_points(fit: CaptiveFit, tests: tuple[str, ...], roll_deg: float) -> pd.DataFrame:
    """The static runs of ``tests``: run, drift_deg, rudder_deg, radius_m, speed and each
    load's prime (plane names) with its 95 % half-width (NaN without a standard error)."""
    (ef, em), _ = plane_names(fit.plane)
    recs = []
    for r in fit.runs:
        if r.test not in tests:
            continue
        m = mapped_rows(r, roll_deg).iloc[0]
        rec: dict[str, Any] = {"run": r.run, "drift_deg": r.drift_deg,
                               "rudder_deg": r.rudder_deg, "radius_m": r.radius_m,
                               "speed": r.speed}
        for eq, moment in ((ef, False), (em, True)):
            s = float(_prime_scale(fit, r.speed, moment))
            rec[eq] = float(m[eq]) / s
            # the steady mean's standard error is from STATIC_BLOCKS block means
            k = t_quantile(STATIC_BLOCKS - 1, 1.0 - BAR_LEVEL)
            rec[f"{eq}_half"] = k * float(m[f"{eq}_se"]) / s
        recs.append(rec)
    return pd.DataFrame(recs)


def drift_curve(fit: CaptiveFit, beta_deg: np.ndarray, roll_deg: float, eq: str, moment: bool,
                run: CaptiveRun) -> tuple[np.ndarray, np.ndarray]:
    """The prime of ``eq`` against the drift angle ``beta_deg`` [deg] at U = 1 m/s (a static
    load's prime does not depend on U) with its 95 % half-width."""
    kin = kinematics_at(body_kinematics(np.ones_like(beta_deg), np.radians(beta_deg)),
                        fit.ref_x_m)
    rows = plane_rows(run, _rows_frame(regressors(kin, 0.0)), roll_deg)
    mean, half = predict(fit, rows, eq)
    s = _prime_scale(fit, 1.0, moment)
    return mean / s, half / s


def arm_curve(fit: CaptiveFit, r_prime: np.ndarray, drift_deg: float, roll_deg: float,
              eq: str, moment: bool, run: CaptiveRun) -> tuple[np.ndarray, np.ndarray]:
    """The prime of ``eq`` against r' = L/R [-] at the drift ``drift_deg`` [deg], U = 1 m/s,
    with its 95 % half-width; the kinematics (drift at O) taken at the point the fit refers
    to (v_P = v + x_P r)."""
    reg: dict[str, list[float]] = {k: [] for k in REGRESSORS}
    for rp in r_prime:
        radius = fit.length_m / rp if rp != 0 else math.inf
        kin = kinematics_at(arm_kinematics(np.array([1.0]), math.radians(drift_deg), radius),
                            fit.ref_x_m)
        for k, v in regressors(kin, 0.0).items():
            reg[k].append(float(v[0]))
    rows = plane_rows(run, _rows_frame({k: np.array(v) for k, v in reg.items()}), roll_deg)
    mean, half = predict(fit, rows, eq)
    s = _prime_scale(fit, 1.0, moment)
    return mean / s, half / s


def shown_pmm_run(fit: CaptiveFit) -> CaptiveRun | None:
    """The PMM run the page shows: the one with the most kept cycles (the first such)."""
    pmm = [r for r in fit.runs if r.test in PMM_TESTS and len(r.period)]
    return max(pmm, key=lambda r: r.cycles_used) if pmm else None


def pmm_prediction(fit: CaptiveFit, run: CaptiveRun, roll_deg: float
                   ) -> tuple[pd.DataFrame, dict[str, tuple[np.ndarray, np.ndarray]]]:
    """The run's cycle-averaged period in the plane's names (t, loads) and the fit's
    prediction of each load from the same motion: {eq: (mean, 95 % half-width)}."""
    p = run.period
    kin = {k: p[k].to_numpy(dtype=float) for k in ("u", "v", "r", "udot", "vdot", "rdot")}
    loads = {q: p[q].to_numpy(dtype=float) for q in ("X", "Y", "N")}
    rows = plane_rows(run, _rows_frame(regressors(kin, math.radians(run.rudder_deg)), loads),
                      roll_deg)
    rows.insert(0, "t", p["t"].to_numpy(dtype=float))
    (ef, em), _ = plane_names(fit.plane)
    return rows, {eq: predict(fit, rows, eq) for eq in (ef, em)}


def _no_data(ax: Any, text: str) -> None:
    ax.text(0.5, 0.5, text, ha="center", va="center", transform=ax.transAxes, fontsize=8,
            color="#555555")
    ax.set_xticks([])
    ax.set_yticks([])


def _draw_static(ax: Any, pts: pd.DataFrame, x: str, eq: str, label: str | None,
                 color: str) -> None:
    """The runs' primes with their 95 % error bars."""
    half = pts[f"{eq}_half"].to_numpy(dtype=float)
    ax.errorbar(pts[x], pts[eq], yerr=np.where(np.isfinite(half), half, 0.0), fmt="o",
                ms=3.5, color=color, ecolor="#555555", elinewidth=0.8, capsize=2,
                zorder=3, label=label)


def _static_row(fig: Figure, cells: Any, eqs: tuple[tuple[str, bool], ...], empty: bool,
                empty_text: str, draw: Callable[[Any, str, bool], None], xlabel: str,
                title: str) -> None:
    """A row of two panels (force, moment) of static runs: ``draw(ax, eq, moment)`` each, or
    ``empty_text`` without runs."""
    sub = cells.subgridspec(1, 2, wspace=0.3)
    for col, (eq, moment) in enumerate(eqs):
        ax = fig.add_subplot(sub[0, col])
        if empty:
            _no_data(ax, empty_text)
        else:
            draw(ax, eq, moment)
            ax.legend(loc="best", fontsize=6.5)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(_prime_label(eq))
        ax.set_title(f"{title}: {eq}'", loc="left", fontsize=8.5)


def _draw_curve(ax: Any, x: np.ndarray, mean: np.ndarray, half: np.ndarray, color: str,
                label: str) -> None:
    ax.fill_between(x, mean - half, mean + half, color=color, alpha=0.18, lw=0, zorder=1)
    ax.plot(x, mean, color=color, lw=1.3, zorder=2, label=label)


def _prime_label(eq: str) -> str:
    return f"${eq}'$"


def captive_caption(fit: CaptiveFit) -> str:
    """The figure's caption."""
    (ef, em), regs = plane_names(fit.plane)
    rig = (" The drift angle and r' are the rig's (the model rolled on it); the loads are the "
           "plane's." if fit.plane == "vertical" else "")
    return (f"Primes {ef}' = {ef}/(½ρL²U²), {em}' = {em}/(½ρL³U²) with L = "
            f"{fit.length_m:g} m. Points: each run's steady mean with its 95 % error bar "
            "(none for a lab's table of means); lines: the joint fit of all the captive runs "
            "with its 95 % confidence band, drawn from the fitted derivatives (the offsets "
            f"{ef}_uu, {em}_uu included). PMM: the cycle-averaged loads of the run shown "
            f"(inertia removed, moment {fit.moment_point()}) against the fit's prediction "
            "from the same motion. Last row: each PMM run's derivative (from the component "
            "where its regressor is largest, the other terms held at the joint fit) over the "
            f"joint value, with 95 % bars; the bands are the joint values' intervals.{rig}")


@styled
def fig_captive(fit: CaptiveFit | None, roll_deg: float = 90.0, *, page: bool = False
                ) -> Figure | None:
    """The captive page's figure of ``fit`` (a plane's result); None without derivatives.

    Parameters
    ----------
    fit : CaptiveFit or None
        ``day.captive`` or ``day.captive_vertical``.
    roll_deg : float
        The model's roll on the rig for vertical runs [deg] (``[captive] roll_deg``).
    page : bool
        Draw it as an A4 report page.
    """
    if fit is None or not fit.estimates:
        return None
    (ef, em), regs = plane_names(fit.plane)
    fig = new_figure(page)
    title = ("Captive tests, vertical plane: loads against the fitted derivatives"
             if fit.plane == "vertical" else "Captive tests: loads against the fitted derivatives")
    gs = figure_grid(fig, 4, 2, page=page, title=title, text=captive_caption(fit),
                     top_in=0.55, xlabel_in=0.35, left=0.1, right=0.97, hspace=0.55,
                     wspace=0.3)
    eqs = ((ef, False), (em, True))
    # 1. static drift
    drift = static_points(fit, ("drift",), roll_deg)

    def draw_drift(ax: Any, eq: str, moment: bool) -> None:
        b = drift["drift_deg"].to_numpy(dtype=float)
        pad = max(1.0, 0.05 * float(np.ptp(b)))
        grid = np.linspace(b.min() - pad, b.max() + pad, CURVE_POINTS)
        mean, half = drift_curve(fit, grid, roll_deg, eq, moment, fit.runs[0])
        _draw_curve(ax, grid, mean, half, style.FIT_COLOR, "fit, 95 % band")
        _draw_static(ax, drift, "drift_deg", eq, "drift runs", style.PALETTE[0])

    _static_row(fig, gs[0, :], eqs, drift.empty, "no static drift runs", draw_drift,
                r"drift $\beta$ [deg]", "Static drift")
    # 2. rotating arm
    arm = static_points(fit, ("arm",), roll_deg)
    if not arm.empty:
        arm["r_prime"] = fit.length_m / arm["radius_m"]

    def draw_arm(ax: Any, eq: str, moment: bool) -> None:
        rp = arm["r_prime"].to_numpy(dtype=float)
        grid = np.linspace(min(0.0, float(rp.min())), max(0.0, float(rp.max())), CURVE_POINTS)
        for i, (d, grp) in enumerate(arm.groupby(arm["drift_deg"].round(2), sort=True)):
            color = style.PALETTE[i % len(style.PALETTE)]
            mean, half = arm_curve(fit, grid, float(d), roll_deg, eq, moment, fit.runs[0])
            _draw_curve(ax, grid, mean, half, color, f"fit, β = {d:g}°")
            _draw_static(ax, grp, "r_prime", eq, None, color)

    _static_row(fig, gs[1, :], eqs, arm.empty, "no rotating-arm runs", draw_arm,
                r"$r' = rL/U$ [-]", "Rotating arm")
    # 3. one PMM run over a period
    run = shown_pmm_run(fit)
    for col, (eq, moment) in enumerate(eqs):
        ax = fig.add_subplot(gs[2, col])
        unit = "N m" if moment else "N"
        if run is None:
            _no_data(ax, "no PMM runs")
        else:
            rows, pred = pmm_prediction(fit, run, roll_deg)
            mean, half = pred[eq]
            t = rows["t"].to_numpy(dtype=float)
            _draw_curve(ax, t, mean, half, style.FIT_COLOR, "fit's prediction, 95 % band")
            ax.plot(t, rows[eq], "o", ms=2.5, color=style.PALETTE[0],
                    label=f"run {run.run}, {run.cycles_used} cycles averaged")
            ax.legend(loc="best", fontsize=6.5)
            ax.set_title(f"PMM run {run.run} ({run.test}, {run.frequency_hz:.3g} Hz, "
                         f"y0 {run.amplitude_m:.3g} m): {eq}", loc="left", fontsize=8.5)
        ax.set_xlabel("t over one period [s]")
        ax.set_ylabel(f"{eq} [{unit}]")
    # 4. derivatives against omega'
    by_run = fit.by_run
    cycles = {r.run: r.cycles_used for r in fit.runs}
    for col, (eq, _moment) in enumerate(eqs):
        ax = fig.add_subplot(gs[3, col])
        mine = by_run[by_run["symbol"].str.startswith(f"{eq}_")] if len(by_run) else by_run
        if mine.empty:
            _no_data(ax, "no PMM derivatives run by run")
        else:
            om = mine["omega_prime"].to_numpy(dtype=float)
            span = (float(om.min()) - 0.1, float(om.max()) + 0.1)
            for i, (sym, grp) in enumerate(mine.groupby("symbol", sort=False)):
                est = fit.estimates.get(str(sym))
                if est is None or est.value == 0:
                    continue
                color = style.PALETTE[(i + 1) % len(style.PALETTE)]
                ax.fill_between(span, est.ci_low / est.value, est.ci_high / est.value,
                                color=color, alpha=0.15, lw=0)
                # each run's value is from its cycles' scatter: t on cycles - 1 dof
                k = np.array([t_quantile(max(cycles.get(int(r), 2) - 1, 1), 1.0 - BAR_LEVEL)
                              for r in grp["run"]])
                ax.errorbar(grp["omega_prime"], grp["value"] / est.value,
                            yerr=k * grp["std_error"] / abs(est.value), fmt="o", ms=3.5,
                            color=color, elinewidth=0.8, capsize=2, label=math_symbol(str(sym)))
            ax.axhline(1.0, color="#444444", lw=0.7)
            ax.set_xlim(*span)
            ax.legend(loc="best", fontsize=6.5, ncol=2)
        ax.set_xlabel(r"$\omega' = \omega L/U$ [-]")
        ax.set_ylabel("run's value / joint value")
        ax.set_title(f"Derivatives against ω': {eq}", loc="left", fontsize=8.5)
    return fig


__all__ = ["fig_captive", "pmm_prediction", "predict", "static_points"]
