"""The report's quality section as a text flow: rejected and void runs, warnings, fit
diagnostics with the uncertainty budget, and notes on individual runs, laid out top-down over
as many pages as it needs (:func:`quality_flow`, :func:`paginate`; drawn by
:mod:`towtank.report.pdf`)."""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

import towtank.report.style as style
from towtank.analysis.daywide import group_rejections, grouped_warnings, run_ranges, run_reason
from towtank.analysis.hull import mirrored
from towtank.reduce.run import units_notes
from towtank.report.figure_base import PAGE_FOOTER_IN, PAGE_HEADER_IN

if TYPE_CHECKING:
    import pandas as pd

    from towtank.reduce.run import RunReduction
    from towtank.results import DayResult, HullResult

PAGE_H = style.PAGE_SIZE[1]


@dataclass
class Flow:
    """Text laid out top-down over as many pages as it needs (for the quality section)."""

    items: list[tuple[str, str]] = field(default_factory=list)

    def h(self, text: str) -> None:
        self.items.append(("h", text))

    def p(self, text: str) -> None:
        self.items.append(("p", text))

    def li(self, text: str) -> None:
        self.items.append(("li", text))

    def mono(self, text: str) -> None:
        self.items.append(("mono", text))

    def gap(self) -> None:
        self.items.append(("gap", ""))


LINE_IN = {"h": 0.30, "p": 0.165, "li": 0.165, "mono": 0.15, "gap": 0.1}
WRAP = {"p": 112, "li": 108, "mono": 118}


def _flow_groups(flow: Flow) -> list[list[tuple[str, str]]]:
    """The flow's items as groups of single lines (wrapped; list items with a hanging indent).

    A group (one paragraph, list item or table line; a heading with the group after it) is
    kept on one page when it fits on one.
    """
    groups: list[list[tuple[str, str]]] = []
    for kind, text in flow.items:
        if kind == "p":
            lines = [("p", line) for line in textwrap.wrap(text, WRAP["p"]) or [""]]
        elif kind == "li":
            wrapped = textwrap.wrap(text, WRAP["li"], initial_indent="•  ",
                                    subsequent_indent="   ") or ["•"]
            lines = [("li", line) for line in wrapped]
        elif kind == "mono":
            lines = [("mono", line[: WRAP["mono"]]) for line in text.split("\n")]
        else:
            lines = [(kind, text)]
        if groups and groups[-1][-1][0] == "h":
            groups[-1].extend(lines)  # a heading stays with what follows it
        else:
            groups.append(lines)
    return groups


def _height(lines: list[tuple[str, str]]) -> float:
    return sum(LINE_IN[kind] for kind, _ in lines)


def paginate(flow: Flow, height_in: float) -> list[list[tuple[str, str]]]:
    """Split the flow into pages of ``height_in``, keeping each group together if it fits."""
    pages: list[list[tuple[str, str]]] = [[]]
    used = 0.0
    for group in _flow_groups(flow):
        need = _height(group)
        if used + need > height_in and pages[-1] and need <= height_in:
            pages.append([])
            used = 0.0
        for line in group:  # a group taller than a page flows on line by line
            if used + LINE_IN[line[0]] > height_in and pages[-1]:
                pages.append([])
                used = 0.0
            if not pages[-1] and line[0] == "gap":
                continue
            pages[-1].append(line)
            used += LINE_IN[line[0]]
    return pages


QUALITY_HEIGHT_IN = PAGE_H - PAGE_HEADER_IN - PAGE_FOOTER_IN - 0.6


def quality_flow(day: DayResult) -> Flow:
    """The quality section's content: run status, warnings, fit diagnostics, run notes."""
    f = Flow()
    runs = day.runs
    counts = runs["status"].value_counts()
    f.h("Run status")
    f.p(f"{len(runs)} runs in the sheet: {int(counts.get('ok', 0))} ok, "
        f"{int(counts.get('rejected', 0))} rejected by the program, "
        f"{int(counts.get('void', 0))} voided by the operator.")
    bad = runs[runs["status"] != "ok"]
    if len(bad):
        day_wide = [g for g in group_rejections(runs, day.rejected) if g.day_wide]
        for g in day_wide:
            f.li(f"rejected — {g.sentence}")
        grouped = {r for g in day_wide for r in g.runs}
        for r in bad.itertuples():
            if int(r.run) in grouped:
                continue
            reason = run_reason(int(r.run), r.reason, day.rejected)
            f.li(f"run {int(r.run)} ({r.config}, α = {fmt_num(r.angle_deg)}°, {r.file}): "
                 f"{r.status} — {reason}")
    else:
        f.p("Every run of the sheet was used.")
    f.gap()
    f.h("Warnings")
    if day.warnings:
        for w in day.warnings:
            f.li(str(w))
    else:
        f.p("None.")
    _diagnostics_flow(f, day.hull, day.coefficients)
    notes = runs[runs["notes"].fillna("").astype(str).str.len() > 0]
    f.gap()
    f.h("Notes on individual runs")
    if len(notes):
        own_text = _own_notes(day.reductions)
        kept = notes.assign(notes=[own_text.get(int(r.run), str(r.notes))
                                   for r in notes.itertuples()])
        if (kept["notes"].astype(str) != notes["notes"].astype(str)).any():
            f.p("Notes said once for the day under Warnings (a channel without a unit label, a "
                "channel left unmapped in many runs) are not repeated here; runs.csv keeps them.")
        shared, own = shared_notes(kept)
        for text, numbers in shared.items():
            f.li(f"runs {run_ranges(numbers)}: {text}")
        for run, texts in own.items():
            f.li(f"run {run}: {'; '.join(texts)}")
    else:
        f.p("No run needed a repair (gaps, spikes, dropped rows) or a cross-check note.")
    return f


#: A run note written word for word on this many runs or more is listed once, with the runs.
SHARED_NOTE_RUNS = 3


def shared_notes(notes: pd.DataFrame) -> tuple[dict[str, list[int]], dict[int, list[str]]]:
    """The runs' notes (runs.csv's ``notes``, each run's joined by "; ") as ({note written on
    :data:`SHARED_NOTE_RUNS` runs or more: their numbers}, {run: its other notes}), in the
    order they first appear: a note every run of a day carries (the time from a rate in an
    HDF5 group's name, a unit converted) is said once, not once per run."""
    per_run: dict[int, list[str]] = {}
    for r in notes.itertuples():
        parts = [p.strip() for p in str(r.notes).split("; ") if p.strip()]
        per_run[int(r.run)] = list(dict.fromkeys(parts))
    where: dict[str, list[int]] = {}
    for run, parts in per_run.items():
        for p in parts:
            where.setdefault(p, []).append(run)
    shared = {p: runs for p, runs in where.items() if len(runs) >= SHARED_NOTE_RUNS}
    own = {run: [p for p in parts if p not in shared] for run, parts in per_run.items()}
    return shared, {run: parts for run, parts in own.items() if parts}


def _own_notes(reductions: dict[int, RunReduction]) -> dict[int, str]:
    """Each reduced run's notes without those the day says once (runs.csv keeps them all): the
    run's units without a label (:func:`towtank.analysis.daywide.unit_label_sentences`) and
    warnings grouped over many runs (:func:`towtank.analysis.daywide.grouped_warnings`)."""
    reds = sorted(reductions.values(), key=lambda r: r.run)
    grouped = grouped_warnings([(r.run, r.file, w) for r in reds for w in r.warnings])
    out = {}
    for r in reds:
        skip = set(units_notes(r.units))
        out[r.run] = "; ".join(n for n in r.notes if n not in skip and (r.run, n) not in grouped)
    return out


def _diagnostics_flow(f: Flow, hull: HullResult | None, coefficients: pd.DataFrame) -> None:
    """The hull fit's diagnostics (``coefficients``: coefficients.csv's table, for the lift
    slope's comparison with a prediction)."""
    hf = hull.fit if hull is not None else None
    if hf is None:
        return
    f.gap()
    f.h("Fit diagnostics")
    for sym, am in hf.added_mass.items():
        est = am.estimate
        resid = ", ".join(f"{r}: {1e3 * v:+.2f}" for r, v in am.residual_by_run.items())
        f.li(f"{sym}: joint regression {est.value:.5g} kg [{est.ci_low:.5g}, {est.ci_high:.5g}] "
             f"over {len(am.runs)} runs (m − {sym} = {am.M:.5g} ± {am.M_se:.2g} kg); curve "
             f"difference {fmt_num(est.alt_value, 5)} kg: {est.agreement or 'not available'}. "
             f"Mean residual of the joint regression by run [mN]: {resid}.")
        levels = am.curve_difference.levels
        if levels:
            f.mono(f"     a [m/s²]   speed range [m/s]   samples   mean ΔD [N]   m − X [kg]"
                   f"   {sym} [kg]")
            for lv in levels:
                lo, hi = lv.speed_range
                speeds = f"{lo:.3f} – {hi:.3f}"
                f.mono(f"     {lv.accel:8.3f}   {speeds:>17s}   {lv.n:7d}   "
                       f"{lv.delta_drag:11.5f}   {lv.M:10.5f}   {lv.value:8.5f}")
    dm = hf.damping
    if dm is not None:
        t = dm.runs
        worst = t.iloc[int(np.argmax(np.abs(t["student"].to_numpy())))]
        f.li(f"C_D(α) fit over {len(t)} runs ({dm.dof} residual d.o.f.): largest |studentized "
             f"residual| {abs(worst['student']):.2f} (run {int(worst['run'])}), largest Cook's "
             f"distance {t['cooks'].max():.2f} (run {int(t.loc[t['cooks'].idxmax(), 'run'])}); "
             + (f"outliers: runs {', '.join(map(str, dm.outliers))}." if dm.outliers
                else "no outliers."))
    rep = hf.repeats
    if rep is not None and len(rep):
        f.li("Repeat runs (same angle and speed within 3 %): spread of C_D between repeats "
             "(C_D on the area of the run's test, as in the Runs table and runs.csv's cd_ref: "
             "frontal, lateral at α = 90°).")
        f.mono("     α [deg]   U [m/s]   n   runs              C_D mean     C_D s.d.   "
               "drag s.d. [mN]")
        for r in rep.itertuples():
            f.mono(f"     {r.angle_deg:7.1f}   {r.speed:7.3f}   {r.n:d}   {r.runs:<16s}"
                   f"  {r.cd_mean:9.5f}   {r.cd_std:9.2e}   {1e3 * r.drag_std:8.3f}")
    if getattr(hf, "lift_slope", None):
        f.li(lift_slope_text(hf, coefficients))
    _budget_flow(f, hf)


def lift_slope_text(hf: Any, coefficients: Any = None) -> str:
    """The hull's measured lift slope and what it is for: a check, used in no coefficient.

    The SUT-2 method (report eq. 15) takes Y_uv = −½ρA·c from the drag's side component
    alone; with the hull's lift the cross-flow force for small α is ½ρA·U²·(∂C_L/∂α + c)·α, so
    Y_uv would be −½ρA·(∂C_L/∂α + c), the quantity a geometry prediction gives.
    """
    s, lo, hi = hf.lift_slope
    text = (f"Hull lift-curve slope ∂C_L/∂α = {s:.4f} /rad [{lo:.4f}, {hi:.4f}] (95 %, C_L on "
            "the frontal area), shown as a check and used in no coefficient: the SUT-2 method "
            "takes Y_uv = −½ρA·c from the drag's side component alone (report eq. 15).")
    dm = hf.damping
    if dm is None:
        return text
    c = float(dm.params[2])
    with_lift = -0.5 * dm.rho * dm.area * (s + c)
    prime = with_lift / (0.5 * dm.rho * hf.length**2)
    text += (f" With the hull's lift, Y_uv = −½ρA·(∂C_L/∂α + c) = {with_lift:.4g} kg/m (prime "
             f"{prime:.4g})")
    pred = math.nan
    if coefficients is not None and "predicted" in coefficients:
        rows = coefficients[coefficients["symbol"] == "Y_uv"]
        if len(rows):
            pred = float(rows["predicted"].iloc[0])
    if math.isfinite(pred):
        text += f", against the prime {pred:.4g} predicted from the [vehicle] geometry."
    else:
        text += "."
    return text


def _budget_flow(f: Flow, hf: Any) -> None:
    """The uncertainty budget behind each interval (coefficients.csv's u_* columns)."""
    mirrors = mirrored(hf.estimates)
    rows = [e for sym, e in hf.estimates.items()
            if sym not in mirrors and math.isfinite(e.u_regression)]
    if not rows:
        return
    f.li("Uncertainty budget: standard uncertainties of each coefficient's parts, in its own "
         "unit; u_c² = u_fit² + u_tare² + u_mass², 95 % half-width = t(ν)·u_c (ν by "
         "Welch–Satterthwaite).")
    f.mono("     coefficient        u_fit      u_tare      u_mass         u_c       ν"
           "   half-width")
    for e in rows:
        f.mono(f"     {e.symbol:<14s} {e.u_regression:10.3e}  {e.u_tare:10.3e}  "
               f"{e.u_mass:10.3e}  {e.std_error:10.3e}  {_dof(e.dof):>6s}   "
               f"{(e.ci_high - e.ci_low) / 2:10.3e}")


def _dof(nu: float) -> str:
    return "∞" if not math.isfinite(nu) or nu > 1e6 else f"{nu:.1f}"


def fmt_num(x: Any, digits: int = 4) -> str:
    try:
        v = float(x)
    except (TypeError, ValueError):
        return str(x)
    return "–" if not math.isfinite(v) else f"{v:.{digits}g}"
