"""report.pdf: the day's printed report, laid out like a towing-tank test report.

Pages (A4 portrait), in order:

1. title page: campaign, model, fin, test date, program version, contents, and for a hull day
   the equations cited as "report eq. N" with the SUT-2 report's reference;
2. summary: the day's facts, the coefficient table (SUT-2 Table 4 style), fin and scaling
   tables where the day has them;
3. figure pages, one section each where the day has data: "Tare", "Added mass", "Damping",
   "Fins", "Scaling" (:mod:`towtank.report.figures`), and "Vehicle" (measured beside
   predicted, :func:`towtank.report.vehicle.fig_predicted`) when the day has a [vehicle];
4. "Fin runs": the fin runs against the Sandia section and the finite span, when they do not
   fit on the summary page;
5. "Runs": one row per run of the sheet (config, test, α, U, a, drag, C_D on the area its test
   uses and that area, Re, tare, status), a blank acceleration explained below the table;
6. quality: rejected and void runs, warnings, fit diagnostics and the uncertainty budget
   (:mod:`towtank.report.quality`; continued over more pages when long);
7. appendix: every run of the sheet as a thumbnail, 3 × 4 per page, phases shaded.

The pages are drawn by matplotlib's :class:`~matplotlib.backends.backend_pdf.PdfPages`, in
groups on all the cores at once, and joined with pypdf (:func:`write_pdf`). The metadata's
CreationDate is fixed from the report date so the same day gives the same file.
"""

from __future__ import annotations

import itertools
import math
import textwrap
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import matplotlib as mpl
import numpy as np
from matplotlib.backends.backend_pdf import PdfPages
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import MaxNLocator
from pypdf import PdfWriter

import towtank.report.figures as figures
import towtank.report.style as style
from towtank import __version__
from towtank.analysis.captive import TEST_NAMES as CAPTIVE_TEST_NAMES
from towtank.analysis.daywide import group_rejections, run_reason
from towtank.analysis.hull import mirrored
from towtank.analysis.scaling import geometry_used
from towtank.ingest.protocol_types import CAPTIVE_TESTS
from towtank.messages import Rejection
from towtank.reduce.captive import moment_point, protocol_reference_x
from towtank.reference.sets import reference_name
from towtank.report.captive_thumb import (
    CAPTIVE_LOADS_LABEL,
    CAPTIVE_MOMENT_LABEL,
    captive_legend_handles,
    captive_trace,
)
from towtank.report.figure_base import (
    PAGE_FOOTER_IN,
    PAGE_HEADER_IN,
    literal,
    math_symbol,
    math_text,
    sci,
    true_minus,
)
from towtank.report.pagetable import page_table
from towtank.report.provenance import captive_provenance, creation_date, report_date
from towtank.report.quality import (
    LINE_IN,
    QUALITY_HEIGHT_IN,
    fmt_num,
    paginate,
    quality_flow,
)
from towtank.report.tables import missing_accel_note
from towtank.report.vehicle import fig_predicted, predicted_rows
from towtank.results import require
from towtank.runtime.parallel import run_beside

if TYPE_CHECKING:
    import pandas as pd

    from towtank.analysis.captive import CaptiveFit
    from towtank.ingest.protocol_types import Fin, Model, Protocol, Water
    from towtank.results import DayResult, FinResult, ScalingResult

PAGE_W, PAGE_H = style.PAGE_SIZE
MARGIN_IN = 0.6  # left and right page margin [in]
THUMB_COLS, THUMB_ROWS = 3, 4
THUMBS_PER_PAGE = THUMB_COLS * THUMB_ROWS
DIFF_HIGHLIGHT_PCT = 10.0  # |diff %| above which a coefficient is highlighted



# ------------------------------------------------------------------------------ page plan
@dataclass
class Page:
    """One page of the report: its kind, section title and what it draws."""

    kind: str  # title | summary | figure | captive | runs | fin_runs | quality | thumbs
    section: str
    payload: Any = None
    subtitle: str = ""
    number: str = ""  # section number: 1, 2, ... in order of appearance; "A" the appendix


def thumbnail_runs(runs: pd.DataFrame, reductions: Mapping[int, Any],
                   previews: Mapping[int, Any], rejected: Mapping[int, Rejection]
                   ) -> list[int]:
    """The runs the appendix draws: all but those a day-wide fault rejected before anything
    was read (their thumbnails would be empty; the quality page says the fault once).

    Parameters
    ----------
    runs : DataFrame
        runs.csv's table (``day.runs``).
    reductions, previews : mapping of int
        The reduced runs and the previews of rejected runs that were read, by run number
        (``day.reductions``, ``day.previews``).
    rejected : mapping of int to Rejection
        The day's rejections (``day.rejected``).
    """
    skip = {r for g in group_rejections(runs, rejected) if g.day_wide for r in g.runs
            if previews.get(r) is None}
    drawn = [r for r in runs["run"].astype(int) if r not in skip]
    if skip and not any(r in reductions or previews.get(r) is not None for r in drawn):
        return []  # what is left has nothing to draw either (void runs)
    return drawn


def vehicle_pages(day: DayResult) -> list[Page]:
    """The "Vehicle" page of a day with a [vehicle]: its measured coefficients beside those
    predicted from the geometry and the table of the model's guessed inputs
    (:func:`towtank.report.vehicle.fig_predicted`); none without a prediction."""
    rows = predicted_rows(getattr(day, "coefficients", None))
    if rows is None or rows.empty:
        return []
    vehicle = getattr(day, "vehicle", None)
    model = getattr(vehicle, "model", None) or {}
    return [Page("figure", "Vehicle",
                 ("predicted_vs_measured", partial(fig_predicted, day.coefficients,
                                                   assumptions=model.get("assumptions"))))]


#: The captive figures of :data:`towtank.report.figures.FIGURES`, each the DayResult
#: attribute of its result; each gets a page with its derivatives' table before it.
CAPTIVE_FIGURES = ("captive", "captive_vertical")


def page_plan(day: DayResult) -> list[Page]:
    """Every page of the report, in order (known before anything is drawn)."""
    pages = [Page("title", "Title"), Page("summary", "Summary")]
    for name, section, func in figures.available_figures(day):
        if name in CAPTIVE_FIGURES:  # the derivatives' table first, then their figure
            pages.append(Page("captive", section, getattr(day, name)))
        pages.append(Page("figure", section, (name, func)))
    pages += vehicle_pages(day)
    fr = day.fins
    if fr is not None and len(fr.table) and not fin_runs_fit(fr):
        fin_ids = [int(r) for r in fr.table["run"]]
        for k in range(0, len(fin_ids), RUNS_PER_PAGE):
            chunk = fin_ids[k:k + RUNS_PER_PAGE]
            pages.append(Page("fin_runs", "Fin runs", chunk,
                              subtitle=f"runs {chunk[0]}–{chunk[-1]}" if len(chunk) > 1 else ""))
    ids = [int(r) for r in day.runs["run"]]
    for k in range(0, len(ids), RUNS_PER_PAGE):
        chunk = ids[k:k + RUNS_PER_PAGE]
        pages.append(Page("runs", "Runs", chunk,
                          subtitle=f"runs {chunk[0]}–{chunk[-1]}" if len(chunk) > 1 else ""))
    q = paginate(quality_flow(day), QUALITY_HEIGHT_IN)
    for i, part in enumerate(q):
        pages.append(Page("quality", "Quality", part,
                          subtitle=f"continued ({i + 1} of {len(q)})" if i else ""))
    runs = thumbnail_runs(day.runs, day.reductions, day.previews, day.rejected)
    for k in range(0, len(runs), THUMBS_PER_PAGE):
        chunk = runs[k:k + THUMBS_PER_PAGE]
        pages.append(Page("thumbs", "Appendix", chunk,
                          subtitle=f"run thumbnails, runs {chunk[0]}–{chunk[-1]}"
                          if len(chunk) > 1 else f"run thumbnail, run {chunk[0]}"))
    numbers: dict[str, str] = {}
    for page in pages[1:]:
        if page.section not in numbers:
            numbers[page.section] = ("A" if page.kind == "thumbs"
                                     else str(len([n for n in numbers.values() if n != "A"]) + 1))
        page.number = numbers[page.section]
    return pages


# --------------------------------------------------------------------------------- drawing
def _page() -> Figure:
    return Figure(figsize=style.PAGE_SIZE)


def _y(inches_from_top: float) -> float:
    return 1 - inches_from_top / PAGE_H


def _decorate(fig: Figure, name: str, page: Page, number: int, total: int) -> None:
    """Section header, rule and footer of a page."""
    x0, x1 = MARGIN_IN / PAGE_W, 1 - MARGIN_IN / PAGE_W
    if page.kind != "title":
        head = f"{page.number}  {page.section}" if page.number else page.section
        fig.text(x0, _y(0.5), head, fontsize=14, fontweight="bold", va="baseline")
        if page.subtitle:
            fig.text(x1, _y(0.5), page.subtitle, fontsize=8.5, ha="right", va="baseline",
                     color="#555555")
        fig.add_artist(Line2D([x0, x1], [_y(0.62)] * 2, color="#444444", lw=0.8))
    fig.add_artist(Line2D([x0, x1], [0.42 / PAGE_H] * 2, color="#aaaaaa", lw=0.5))
    fig.text(x0, 0.25 / PAGE_H, literal(name), fontsize=7, color="#555555")
    fig.text(x1, 0.25 / PAGE_H, f"towtank {__version__}   ·   page {number} of {total}",
             fontsize=7, color="#555555", ha="right")


def _medium_word(water: Water) -> str:
    """"air" or "water": the tests' medium (the protocol's [water]) in one word."""
    return "air" if water.is_air else "water"


def _medium_label(water: Water) -> str:
    """The title page's label of the medium's line: "Water" or "Air"."""
    return _medium_word(water).capitalize()


def _water_text(w: Water, runs: pd.DataFrame) -> str:
    """The medium (the protocol's [water]) with the runs' temperatures and mean ρ, ν."""
    ok = runs[runs["status"] == "ok"]
    rho = ok["rho"].dropna()
    nu = ok["nu"].dropna()
    temps = runs["water_temp_C"].dropna()
    t = (f"{temps.min():.1f}–{temps.max():.1f} °C" if len(temps) and temps.min() != temps.max()
         else f"{w.temperature_C:g} °C")
    out = f"{w.medium}, {t}"
    if w.is_air:
        out += f", {w.pressure_Pa:.6g} Pa, {w.relative_humidity_pct:g} % relative humidity"
    if len(rho):
        out += (f"; ρ = {rho.mean():.{4 if w.is_air else 2}f} kg/m³, "
                f"ν = {sci(nu.mean(), 4)} m²/s "
                "(mean of the runs)")
    return out


def _model_text(m: Model | None) -> str:
    if m is None:
        return "none (no hull runs)"
    parts = [m.name or "model", f"L = {m.length_m:g} m"]
    if m.diameter_m is not None:
        parts.append(f"D = {m.diameter_m:g} m")
    parts.append(f"m = {m.mass_kg:g} kg")
    if m.scale is not None:
        parts.append(f"scale λ = {m.scale:g}")
    return ", ".join(parts)


def geometry_text(day: DayResult) -> str | None:
    """The hull geometry used, each quantity with its source; None without a [model]."""
    short = {"π D²/4 from diameter_m": "π D²/4",
             "L·D from length_m and diameter_m (default)": "L·D, the default",
             "computed from the [model.myring] Myring description": "Myring description"}
    parts = []
    for g in geometry_used(day.protocol, day.scaling):
        source = short.get(g["source"], g["source"])
        if source.startswith("given in the protocol ("):
            source = "given as " + source.removeprefix("given in the protocol (").rstrip(")")
        if g["value"] is None:
            parts.append(f"{g['symbol']} not known")
        elif g["symbol"] == "S_p":
            parts.append(f"prototype S_p = λ²·S_m = {fmt_num(g['value'])} {g['unit']}")
        else:
            parts.append(f"{g['symbol']} = {fmt_num(g['value'])} {g['unit']} ({source})")
    return "; ".join(parts) + "." if parts else None


def _fin_text(fin: Fin | None, fins: FinResult | None) -> str | None:
    if fin is None:
        return None
    return (f"{fin.section}, chord {fin.chord_m:g} m, span {fin.span_m:g} m"
            + (f", effective aspect ratio {fins.aspect_ratio:.3g}" if fins else ""))


def _counts(day: DayResult) -> str:
    c = day.runs["status"].value_counts()
    return (f"{len(day.runs)} in the sheet: {int(c.get('ok', 0))} ok, "
            f"{int(c.get('rejected', 0))} rejected, {int(c.get('void', 0))} void"
            f"{day.means_text}")


def _draw_title(fig: Figure, day: DayResult, plan: list[Page]) -> None:
    date, source = report_date(day)
    proto = day.protocol
    x0 = MARGIN_IN / PAGE_W + 0.03
    title = "Test report, model in air" if day.protocol.water.is_air else "Towing-tank test report"
    fig.text(x0, _y(1.6), title, fontsize=24, fontweight="bold")
    fig.add_artist(Line2D([x0, 1 - x0], [_y(1.85)] * 2, color="#0072B2", lw=2.0))
    fig.text(x0, _y(2.4), literal(textwrap.fill(day.protocol.name, 48)), fontsize=16,
             va="top")
    rows = [
        ("Model", _model_text(proto.model) if proto.model is not None else None),
        ("Fin", _fin_text(proto.fin, day.fins)),
        (_medium_label(proto.water), _water_text(proto.water, day.runs)),
        ("Test date", date or "not given"),
        ("Runs", _counts(day)),
        ("Protocol", str(day.protocol.path.name)),
        ("Program", f"towtank {__version__}"),
    ]
    y = 3.7
    for label, value in rows:
        if value is None:
            continue
        wrapped = textwrap.fill(value, 70)
        fig.text(x0, _y(y), label, fontsize=10, fontweight="bold", va="top")
        fig.text(x0 + 1.5 / PAGE_W, _y(y), literal(wrapped), fontsize=10, va="top")
        y += 0.3 + 0.19 * wrapped.count("\n")
    if date and source != "given on the command line":
        fig.text(x0 + 1.5 / PAGE_W, _y(y - 0.05), f"(test date: {source})", fontsize=7.5,
                 color="#666666", va="top")
        y += 0.2
    y += 0.5
    fig.text(x0, _y(y), "Contents", fontsize=12, fontweight="bold", va="top")
    y += 0.4
    seen: dict[str, tuple[int, str]] = {}
    for i, p in enumerate(plan, start=1):
        if p.kind != "title" and p.section not in seen:
            seen[p.section] = (i, p.number)
    for section, (number, num) in seen.items():
        name = {"Appendix": "Appendix: run thumbnails"}.get(section, section)
        fig.text(x0, _y(y), num, fontsize=10, va="top")
        fig.text(x0 + 0.35 / PAGE_W, _y(y), name, fontsize=10, va="top")
        fig.text(1 - x0 - 0.05, _y(y), str(number), fontsize=10, va="top", ha="right")
        y += 0.27
    if day.hull is None:
        return
    text = "\n".join(textwrap.fill(p, 128) for p in METHOD_NOTE)
    fig.text(x0, _y(PAGE_H - 0.85), math_text(text), fontsize=7.2, color="#444444",
             va="bottom", linespacing=1.35)


#: The title page's note: conventions, the equations the report cites as "report eq. N" (as
#: towtank applies them, docs/method.md) and the report they come from.
SUT2_REPORT = ("B. Sadeghzadeh Parapari, M. S. Seif, H. Mahdigholi, \"Identification of Underwater "
               "Vehicle Hydrodynamic Coefficients Using Model Tests\", Marine Engineering "
               "Research Center, Sharif University of Technology (in Persian)")
METHOD_NOTE = (
    "Model-scale values are SI with SNAME signs (added mass and damping negative); prime values "
    "divide by ½ρL³ (added mass) or ½ρL² (damping). Intervals are 95 %.",
    "Equations: \"report eq. N\" is equation N of the SUT-2 model-test report [S], as towtank "
    "applies it (the method chapter of towtank's documentation, docs/method.md of its source, "
    "sets it out in full). Eqs. 7–8, added mass from accelerated and steady tows at the same "
    "speed U: X_udot = m − (D_a − D_s)/a at α = 0 and Y_vdot likewise at α = 90°, D_a the drag "
    "at the constant acceleration a, D_s the steady drag, m the model's mass. Eq. 13: C_D = "
    "D/(½ρAU²), A the frontal area. Eq. 14: C_D(α) = aα² + bα + c, α in rad. Eq. 15: "
    "X_u|u| = Y_uv = −½ρA·c, X_uv = −½ρA·b, X_v|v| = −½ρA·(a − c/2); and Y_v|v| = "
    "−½ρA_lat·C_D,90 from the transverse tows (α = 90°), A_lat the lateral area.",
    f"[S] {SUT2_REPORT}.",
)


def _table(fig: Figure, top_in: float, header: list[str], rows: list[list[str]],
           col_widths: list[float], *, fontsize: float = 7.5, row_in: float = 0.22,
           highlight: dict[tuple[int, int], str] | None = None,
           align: Sequence[Literal["left", "center", "right"]] | None = None) -> float:
    """A matplotlib table across the page; returns the inches used."""
    n = len(rows) + 1
    height = n * row_in
    x0 = MARGIN_IN / PAGE_W
    ax = fig.add_axes((x0, _y(top_in + height), 1 - 2 * x0, height / PAGE_H))
    ax.set_axis_off()
    total = sum(col_widths)
    tab = page_table(ax, rows, header, [w / total for w in col_widths], align)
    tab.auto_set_font_size(False)
    tab.set_fontsize(fontsize)
    for (r, c), cell in tab.get_celld().items():
        cell.set_linewidth(0.4)
        cell.set_edgecolor("#bbbbbb")
        cell.PAD = 0.04
        if r == 0:
            cell.set_facecolor("#" + style.XL_HEADER_FILL)
            cell.get_text().set_fontweight("bold")
        elif highlight and (r - 1, c) in highlight:
            cell.set_facecolor(highlight[(r - 1, c)])
        elif r % 2 == 0:
            cell.set_facecolor("#f7f7f7")
    return height


def _v(x: Any, fmt: str = ".4g", scale: float = 1.0) -> str:
    """A table number: format, true minus sign, '–' for missing."""
    try:
        v = float(x)
    except (TypeError, ValueError):
        return "–"
    if not math.isfinite(v):
        return "–"
    text = format(v * scale, fmt)
    if text.startswith("-") and not any(c in "123456789" for c in text.split("e")[0]):
        text = text[1:]  # −0.0000: a value that rounds to zero has no sign
    return text.replace("-", "\u2212")


def coefficient_rows(coef: pd.DataFrame) -> tuple[list[str], list[list[str]], list[str],
                                                  dict[tuple[int, int], str]]:
    """Header, rows, method footnotes and highlighted cells of the summary's table.

    A coefficient equal to another by the hull's symmetry shows that symbol as its method
    ("= Y_vdot") instead of a footnote.

    Parameters
    ----------
    coef : DataFrame
        coefficients.csv's table (``day.coefficients``, docs/formats.md).
    """
    header = ["coefficient", "value", "unit", "95 % interval", "prime·10³", "ref.·10³",
              "diff %", "prototype¹", "method"]
    methods: list[str] = []
    rows, hl = [], {}
    mirrors = mirrored(coef["symbol"])
    for i, r in enumerate(coef.to_dict("records")):
        m = str(r.get("method", ""))
        if r["symbol"] in mirrors:
            ref = "= " + math_symbol(mirrors[r["symbol"]])
        else:
            if m not in methods:
                methods.append(m)
            ref = f"[{methods.index(m) + 1}]"
        diff = r.get("diff_pct", math.nan)
        rows.append([
            math_symbol(r["symbol"]), _v(r["value"]), r["unit"],
            f"{_v(r['ci_low'])} … {_v(r['ci_high'])}", _v(r["prime"], ".4g", 1e3),
            _v(r.get("reference_prime"), ".4g", 1e3), _v(diff, "+.1f"),
            _v(r.get("prototype_value")), ref,
        ])
        try:
            if abs(float(diff)) > DIFF_HIGHLIGHT_PCT:
                hl[(i, 6)] = "#ffe699"
        except (TypeError, ValueError):
            pass
    return header, rows, methods, hl


def _text_block(fig: Figure, top_in: float, text: str, *, width: int = 112,
                fontsize: float = 7.5, color: str = "#333333", indent_in: float = 0.0) -> float:
    wrapped = textwrap.fill(text, width)
    x = (MARGIN_IN + indent_in) / PAGE_W
    fig.text(x, _y(top_in), math_text(wrapped), fontsize=fontsize, va="top",
             color=color, linespacing=1.3)
    return (wrapped.count("\n") + 1) * fontsize * 1.3 / 72 + 0.06


def _text_blocks(fig: Figure, top_in: float, texts: Sequence[str]) -> float:
    """Small paragraphs (footnotes) one under the other; returns the inches used."""
    used = 0.0
    for text in texts:
        used += _text_block(fig, top_in + used, text, width=125, fontsize=7)
    return used


def _heading(fig: Figure, top_in: float, text: str) -> float:
    fig.text(MARGIN_IN / PAGE_W, _y(top_in), text, fontsize=10.5, fontweight="bold", va="top")
    return 0.3


def _draw_summary(fig: Figure, day: DayResult) -> None:
    date, _ = report_date(day)
    y = 0.95
    has_model = day.protocol.model is not None
    proto = day.protocol
    facts = [("Campaign", proto.name),
             ("Model", _model_text(proto.model) if has_model else None),
             ("Fin", _fin_text(proto.fin, day.fins)),
             (_medium_label(proto.water), _water_text(proto.water, day.runs)),
             ("Test date", date or "not given"), ("Runs", _counts(day)),
             ("Reference", f"prime values of {reference_name(day.protocol.campaign.reference)}"
              if day.hull is not None else None)]
    for label, value in facts:
        if value is None:
            continue
        fig.text(MARGIN_IN / PAGE_W, _y(y + 0.12), label, fontsize=8.5, fontweight="bold",
                 va="baseline")
        fig.text((MARGIN_IN + 1.0) / PAGE_W, _y(y + 0.12), literal(value), fontsize=8.5,
                 va="baseline")
        y += 0.21
    geometry = geometry_text(day) if has_model else None
    if geometry is not None:
        fig.text(MARGIN_IN / PAGE_W, _y(y + 0.12), "Geometry", fontsize=8.5,
                 fontweight="bold", va="baseline")
        y += _text_block(fig, y + 0.01, geometry, width=90, fontsize=8.5, color="black",
                         indent_in=1.0) + 0.02
    y += 0.15
    if day.hull is not None and len(day.coefficients):
        y += _heading(fig, y, "Hull coefficients (model scale, SNAME signs)")
        header, rows, methods, hl = coefficient_rows(day.coefficients)
        y += _table(fig, y, header, rows, [0.85, 0.85, 0.45, 1.45, 0.75, 0.7, 0.55, 0.95, 0.6],
                    highlight=hl, align=("center",) + ("right",) * 7 + ("center",),
                    fontsize=7.8) + 0.1
        notes = [f"[{i}] {m}" for i, m in enumerate(methods, start=1)]
        notes.append(f"Shaded: |diff %| > {DIFF_HIGHLIGHT_PCT:g} against the reference. "
                     "\"report eq. N\": equation N of the SUT-2 report [S], written out on "
                     "page 1. "
                     "¹ Prototype, in the row's unit: prime × ½ρ_p·L_p³ (added mass, kg) or "
                     "× ½ρ_p·L_p² (kg/m).")
        y += _text_blocks(fig, y, notes)
        # an added mass's second estimate and its agreement are in its method's footnote
        # (towtank.analysis.hull.fit_added_mass)
        y += 0.2
    elif day.protocol.model is not None and day.captive_results:
        y += _heading(fig, y, "Hull coefficients")
        y += _text_block(fig, y, "No resistance coefficients: the day's runs are captive tests "
                         "(their derivatives are in the Captive section).", fontsize=8.5) + 0.2
    elif day.protocol.model is not None:
        y += _heading(fig, y, "Hull coefficients")
        y += _text_block(fig, y, "No hull coefficients: the day has no usable hull runs "
                         "(see the quality section).", fontsize=8.5) + 0.2
    fr, sr = day.fins, day.scaling
    if fr is not None and len(fr.curves):
        y += _heading(fig, y, "Fin: lift slope, stall and minimum drag per speed")
        y += _fin_table(fig, y, fr) + 0.2
    if fr is not None and len(fr.table):
        y += _fin_runs_table(fig, y, fr) + 0.2
    if sr is not None:
        y += _heading(fig, y, "Prototype resistance")
        y += _scaling_table(fig, y, sr, similarity_section=day.protocol.model is not None)
    if day.hull is None and day.fins is None and day.protocol.model is None:
        _text_block(fig, y, "The day gave no coefficients; the quality section says why.",
                    fontsize=9)


def captive_rows(fit: CaptiveFit) -> tuple[list[str], list[list[str]], list[str]]:
    """Header, rows and method footnotes of a captive page's derivative table.

    Parameters
    ----------
    fit : CaptiveFit
        A plane's captive result (``day.captive``, ``day.captive_vertical``).
    """
    lt = fit.draught_m is not None
    header = ["derivative", "value", "unit", "95 % interval", "prime·10³",
              *(["prime L·T·10³"] if lt else []), "runs", "method"]
    methods: list[str] = []
    rows = []
    for e in fit.estimates.values():
        if e.method not in methods:
            methods.append(e.method)
        rows.append([math_symbol(e.symbol), _v(e.value), e.unit.replace("*", "·"),
                     f"{_v(e.ci_low)} … {_v(e.ci_high)}", _v(e.prime, ".4g", 1e3),
                     *([_v(e.prime_lt, ".4g", 1e3)] if lt else []), str(e.n_runs),
                     f"[{methods.index(e.method) + 1}]"])
    return header, rows, methods


def captive_options_text(options: dict[str, Any]) -> str:
    """The reduction's options as ITTC 7.5-02-06-02 asks them stated (the provenance's
    ``captive`` section, :func:`towtank.report.provenance.captive_provenance`), one sentence."""
    inertia = options["inertia_removed"]
    parts = [f"{k.split('_')[0]} = {v:g} {UNIT_OF_KEY[k]}" for k, v in inertia.items()
             if v is not None]
    reference = ("about O (N_O = mz + balance_x_m·fy, balance_x_m = "
                 f"{options['balance_x_m']:g} m)" if options["moment_reference"] == "origin"
                 else "about the balance point, x = "
                 f"{options['balance_x_m'] or 0.0:g} m from O (the sway velocities and x_G "
                 "taken there too)")
    return (f"Moments {reference}; the model's inertia removed with {', '.join(parts)}; PMM: "
            f"{options['pmm_cycle_rule']} (the cycles each run kept: pmm.csv cycles_used).")


#: Units of the [model] keys in :func:`captive_options_text`.
UNIT_OF_KEY = {"mass_kg": "kg", "izz_kg_m2": "kg·m²", "iyy_kg_m2": "kg·m²", "xg_m": "m"}


def captive_fit_text(fit: CaptiveFit, options: dict[str, Any] | None = None) -> list[str]:
    """The paragraphs under a captive page's table: the reduction's options (``options``,
    the provenance's captive section), the runs by test, the fit's reduced chi^2 per
    equation and its notes (agreement over omega', terms left out)."""
    counts: dict[str, int] = {}
    for r in fit.runs:
        counts[r.test] = counts.get(r.test, 0) + 1
    tests = ", ".join(f"{n} {CAPTIVE_TEST_NAMES.get(t, t)}" for t, n in counts.items())
    out = [f"{len(fit.runs)} runs fitted jointly ({tests}); a run's steady mean or a PMM run's "
           "cycle-averaged mean and first harmonics are the units of information."]
    if options is not None:
        out.insert(0, captive_options_text(options))
    chi2 = "; ".join(f"{eq}: {_v(c, '.3g')}" for eq, c in fit.chi2_reduced.items())
    if chi2:
        out.append(f"Reduced chi^2 of the weighted fit per equation: {chi2}.")
    out += [n for n in fit.notes if n]
    return out


def _draw_captive(fig: Figure, fit: CaptiveFit, options: dict[str, Any] | None = None
                  ) -> None:
    """A captive page: the plane's derivatives with their intervals, primes and methods,
    then the fit's notes."""
    y = PAGE_HEADER_IN + 0.1
    plane = "vertical plane (Z, M)" if fit.plane == "vertical" else "horizontal plane (Y, N)"
    y += _heading(fig, y, f"Captive derivatives, {plane}: model scale, SI")
    header, rows, methods = captive_rows(fit)
    widths = [0.9, 0.85, 0.95, 1.5, 0.75, *([0.85] if fit.draught_m is not None else []),
              0.45, 0.6]
    y += _table(fig, y, header, rows, widths, fontsize=7.6, row_in=0.2,
                align=("center", "right", "center", "right", "right",
                       *(("right",) if fit.draught_m is not None else ()), "right",
                       "center")) + 0.1
    lt = (f"; prime L·T: value/(½ρ T L^(k−1)), T = {fit.draught_m:g} m"
          if fit.draught_m is not None else "")
    notes = [f"[{i}] {m}" for i, m in enumerate(methods, start=1)]
    notes.append(f"Prime: value/(½ρ L^k), L = {fit.length_m:g} m, ρ = {fit.rho:.2f} kg/m³, k "
                 "by the derivative (docs/formats.md)" + lt + ". The rotary and acceleration "
                 "derivatives are totals (the added-mass Coriolis and Munk parts included). "
                 "Intervals: 95 %, Student's t on the fit's degrees of freedom. Offsets _uu: "
                 "the asymmetry and zero residue, never used as derivatives.")
    y += _text_blocks(fig, y, notes) + 0.15
    y += _heading(fig, y, "The fit")
    _text_blocks(fig, y, captive_fit_text(fit, options))


def _fin_table(fig: Figure, y: float, fr: FinResult) -> float:
    c = fr.curves
    header = [r"$U$ group [m/s]", "Re", "runs", r"$dC_L/d\alpha$ [1/rad]", "95 % interval",
              "Sandia 2-D", "lifting line", "stall [deg]", r"$C_{L,max}$", r"$C_{D,min}$"]
    rows = []
    for r in c.to_dict("records"):
        stall = _v(r["stall_angle_deg"], ".3g")
        if r.get("stall_reached") is False:
            stall = f"> {stall}"
        lo, hi = _v(r["lift_slope_ci_low"], ".3f"), _v(r["lift_slope_ci_high"], ".3f")
        rows.append([_v(r["speed_group"], ".2f"), sci(r["re_mean"]), str(r["n_runs"]),
                     _v(r["lift_slope"], ".3f"), "–" if lo == hi == "–" else f"{lo} … {hi}",
                     _v(r["lift_slope_sandia_2d"], ".3f"), _v(r["lift_slope_3d"], ".3f"),
                     stall, _v(r["cl_max"], ".3f"), _v(r["cd_min"], ".4f")])
    used = _table(fig, y, header, rows, [1.0, 0.75, 0.45, 1.15, 1.1, 0.8, 0.8, 0.8, 0.65, 0.65])
    used += 0.08 + _text_block(fig, y + used + 0.08, (
        f"Effective aspect ratio {fr.aspect_ratio:.3g}, span efficiency "
        f"{fr.oswald_e:.3g}. "
        "Stall '> x': C_L still rising at the largest angle tested. "
        "Sandia 2-D and lifting line: the same straight-line fit through the 2-D section data "
        "and the finite-span expectation at the group's mean Re."), width=125, fontsize=7)
    ctrl = fr.control
    if ctrl is not None and len(ctrl):
        recs = ctrl.to_dict("records")
        text = "Control derivatives (pair of fins, Prestero 2001): " + "; ".join(
            f"{r.get('symbol', '')} = {_v(r.get('value'))} "
            f"{str(r.get('unit', '')).replace('*', '·')}".strip()
            for r in recs)
        if "lift_slope" in recs[0]:
            slope = _v(recs[0]["lift_slope"], ".4g")
            text += (f". They use the lift slope dC_L/dα = {slope} /rad: "
                     f"{recs[0].get('lift_slope_source', '')}.")
        used += _text_block(fig, y + used, text, width=125, fontsize=7)
    return used


def _fin_runs_table(fig: Figure, y: float, fr: FinResult) -> float:
    """fins.csv beside the 3-D expectation, when it fits on the page; else a pointer to the
    Fin runs pages (:func:`_draw_fin_runs`)."""
    t = fr.table
    used = _heading(fig, y, "Fin runs: measured against the Sandia section and finite span")
    if not fin_runs_fit(fr):  # the page plan's rule: the Fin runs pages hold it otherwise
        return used + _text_block(fig, y + used, f"{len(t)} fin runs: in the Fin runs "
                                  "section, fins.csv and the Fins sheet of report.xlsx.",
                                  fontsize=8)
    return used + _fin_rows(fig, y + used, t.to_dict("records"))


#: Where the summary page's fin-runs table starts [in from the top] and its row height [in].
FIN_TABLE_TOP_IN = 6.0
FIN_ROW_IN = 0.19


def fin_runs_fit(fins: FinResult, top_in: float = FIN_TABLE_TOP_IN) -> bool:
    """Whether the fin runs' table fits on the summary page below ``top_in``.

    Parameters
    ----------
    fins : FinResult
        The day's fin result (``day.fins``): one table row per fin run.
    top_in : float
        Where the table starts, from the top of the page [in].
    """
    room = PAGE_H - PAGE_FOOTER_IN - 0.5 - top_in
    return (len(fins.table) + 1) * FIN_ROW_IN <= room


def _draw_fin_runs(fig: Figure, fins: FinResult, runs: list[int]) -> None:
    t = fins.table
    recs = [r for r in t.to_dict("records") if int(r["run"]) in set(runs)]
    y = PAGE_HEADER_IN + 0.25
    used = _fin_rows(fig, y, recs)
    _text_block(fig, y + used + 0.12,
                "Steady means of the fin runs (zero, drift and tare removed): C_L and C_D on "
                "chord × span, beside the 2-D NACA 0015 section data (Sheldahl & Klimas) and "
                "the finite-span expectation (lifting line) at each run's Re.", fontsize=7.5)


def _fin_rows(fig: Figure, y: float, recs: list[dict[str, Any]]) -> float:
    header = ["run", "α [deg]", "U [m/s]", "Re", r"$C_L$", r"$C_D$", r"$C_L$ 2-D",
              r"$C_D$ 2-D", r"$C_L$ finite span", r"$C_D$ finite span"]
    rows = [[str(int(r["run"])), _v(r["angle_deg"], "g"), _v(r["speed_mean"], ".3f"),
             sci(r["re"], 3), _v(r["cl"], ".4f"), _v(r["cd"], ".4f"),
             _v(r["cl_sandia"], ".4f"), _v(r["cd_sandia"], ".4f"), _v(r.get("cl_3d"), ".4f"),
             _v(r.get("cd_3d"), ".4f")] for r in recs]
    return _table(fig, y, header, rows, [0.45, 0.55, 0.6, 0.75, 0.65, 0.65, 0.7, 0.7, 1.0, 1.0],
                  row_in=FIN_ROW_IN, fontsize=7.2)


def _scaling_table(fig: Figure, y: float, sr: ScalingResult, *,
                   similarity_section: bool) -> float:
    """The prototype resistance table: the recommended estimate named in its header and
    shaded, the Froude-scaled model resistance beside it for comparison; then the rule behind
    the recommendation, the form factor with its trend over Re, and what was used (with
    ``similarity_section``, a pointer to the Scaling section's figure)."""
    rec = getattr(sr, "recommendation", None)
    recommended = rec.column if rec is not None else "none"
    ittc_head = r"$R_p$ ITTC-57 [N]" + (", recommended" if recommended == "drag_ittc57" else "")
    froude_head = (r"$R_p$ Froude [N], comparison" if recommended == "drag_ittc57"
                   else r"$R_p$ Froude [N]")
    header = [r"$U_p$ [m/s]", r"$Re_p$", r"$Fn_p$", r"$U_m$ Froude [m/s]",
              r"$U_m$ Reynolds [m/s]", ittc_head, froude_head]
    rows, hl = [], {}
    for i, r in enumerate(sr.table.to_dict("records")):
        froude = _v(r["drag_froude"], ".4g")
        if not r.get("froude_in_tested_range", True):
            froude += " *"
        rows.append([_v(r["speed_prototype"], ".3g"), sci(r["re_prototype"], 3),
                     _v(r["fn_prototype"], ".3f"), _v(r["speed_model_froude"], ".3f"),
                     _v(r["speed_model_reynolds"], ".3f"), _v(r["drag_ittc57"], ".4g"), froude])
        if recommended == "drag_ittc57":
            hl[(i, 5)] = "#d9ead3"
    used = _table(fig, y, header, rows, [0.5, 0.65, 0.4, 0.9, 1.05, 1.75, 1.55], highlight=hl,
                  fontsize=7.0)
    ff = sr.form_factor
    area = (f"on the prototype's wetted area S_p = λ²·S_m = {fmt_num(sr.wetted_area_prototype)} m²"
            if sr.wetted_area_prototype is not None else "not computed: no wetted area known")
    dcf = f" + ΔC_F = {sr.delta_cf:g}" if sr.delta_cf else ""
    lo, hi = sr.tested_speed_range
    star = (f"* U_m Froude outside the tested {lo:.2f}–{hi:.2f} m/s: the model's resistance "
            "curve extrapolated. " if not sr.table["froude_in_tested_range"].all() else "")
    rule = rec.rule if rec is not None else ""
    trend = getattr(sr, "form_factor_trend_text", "")
    note = (rule + " " + star + f"ITTC-57: (1 + k)·C_F{dcf}, {area}. "
            + (f"Form factor 1 + k = {ff.one_plus_k:.3f} ± {ff.std:.3f}: mean and s.d. over "
               f"{ff.n} tested speeds ({ff.n_runs} runs, repeats averaged per speed). "
               if ff is not None else "") + trend)
    note += (" Similarity (Reynolds ranges, depth): the Scaling section."
             if similarity_section else "")
    return used + 0.08 + _text_block(fig, y + used + 0.08, note.strip(), width=125,
                                     fontsize=7)


def _draw_quality(fig: Figure, lines: list[tuple[str, str]]) -> None:
    y = 0.95
    x0 = MARGIN_IN / PAGE_W
    for kind, text in lines:
        if kind == "h":
            fig.text(x0, _y(y + 0.06), literal(text), fontsize=10.5,
                     fontweight="bold", va="top")
        elif kind == "mono":
            fig.text(x0, _y(y), true_minus(literal(text)), fontsize=6.8,
                     family="DejaVu Sans Mono", va="top", color="#222222")
        elif kind in ("p", "li"):
            fig.text(x0 + (0.1 / PAGE_W if kind == "li" else 0), _y(y), math_text(text),
                     fontsize=7.8, va="top", color="#222222")
        y += LINE_IN[kind]


def _thumb_title(row: dict[str, Any]) -> str:
    test = str(row.get("test") or "").strip()
    kind = f" {test}" if test in ("steady", "accel", *CAPTIVE_TESTS) else ""
    head = f"run {int(row['run'])} · {row['config']}{kind} · α = {fmt_num(row['angle_deg'], 3)}°"
    u = row.get("speed_mean")
    if u is not None and isinstance(u, float) and math.isfinite(u):
        head += f" · {u:.2f} m/s"
    return head


class ThumbGrid:
    """One A4 figure with the 3 × 4 thumbnail axes, drawn again for every appendix page.

    Making a matplotlib Axes (and its twin, and their ticks) is most of the time a thumbnail
    page takes; the appendix of a large campaign has dozens of such pages, so the axes are made
    once and each page only replaces what is drawn in them (lines, phase shades, titles, the
    page's header and footer).
    """

    def __init__(self) -> None:
        self.fig = _page()
        top = (PAGE_HEADER_IN + 0.45) / PAGE_H
        bottom = (PAGE_FOOTER_IN + 0.45) / PAGE_H
        gs = self.fig.add_gridspec(THUMB_ROWS, THUMB_COLS, left=0.085, right=0.91, top=1 - top,
                                   bottom=bottom, hspace=0.5, wspace=0.72)
        self.cells = []
        for k in range(THUMBS_PER_PAGE):
            ax = self.fig.add_subplot(gs[k // THUMB_COLS, k % THUMB_COLS])
            twin = figures.thumbnail_twin(ax)
            for a in (ax, twin):
                a.tick_params(labelsize=6, length=2, pad=1.5)
                a.yaxis.set_major_locator(MaxNLocator(4))
            ax.set_ylabel(figures.SPEED_LABEL_SHORT, fontsize=6.5, labelpad=1)
            twin.set_ylabel(figures.FORCE_LABEL_SHORT, fontsize=6.5, labelpad=1)
            ax.xaxis.set_major_locator(MaxNLocator(5, integer=True))
            self.cells.append((ax, twin))

    @staticmethod
    def _labels(ax: Any, twin: Any, *, captive: bool) -> None:
        """The cell's axis labels: a captive run's N (left) and X, Y (right), else U and
        D, L."""
        ax.set_ylabel(CAPTIVE_MOMENT_LABEL if captive else figures.SPEED_LABEL_SHORT,
                      fontsize=6.5, labelpad=1)
        twin.set_ylabel(CAPTIVE_LOADS_LABEL if captive else figures.FORCE_LABEL_SHORT,
                        fontsize=6.5, labelpad=1)

    def _clear(self) -> None:
        fig = self.fig
        for art in [*fig.texts, *fig.artists, *fig.legends]:
            art.remove()
        for ax, twin in self.cells:
            for a in (ax, twin):
                for art in [*a.lines, *a.patches, *a.texts, *a.child_axes]:
                    art.remove()
                a.set_title("")
            ax.set_xlabel("")
            ax.set_visible(True)
            ax.set_axis_on()
            twin.set_visible(True)

    def draw(self, day: DayResult, run_ids: list[int]) -> Figure:
        """The figure with the runs ``run_ids`` drawn (at most :data:`THUMBS_PER_PAGE`)."""
        self._clear()
        by_run = {int(r["run"]): r for r in day.runs.to_dict("records")}
        any_lift = any_captive = any_pmm = False
        any_hull = any_yaw = False
        for k, (ax, twin) in enumerate(self.cells):
            if k >= len(run_ids):
                ax.set_visible(False)
                twin.set_visible(False)
                continue
            run = run_ids[k]
            row = by_run[run]
            red = day.reductions.get(run)
            title = _thumb_title(row)
            if red is None or row["status"] != "ok":
                reason = run_reason(run, row.get("reason"), day.rejected)
                preview = day.previews.get(run) if row["status"] == "rejected" else None
                ax.set_title(literal(title), fontsize=7.5, loc="left", fontweight="normal")
                if preview is not None:  # read but not reduced: show what the file holds
                    figures.preview_thumbnail(ax, preview, twin=twin, linewidth=0.8)
                    self._labels(ax, twin, captive=False)
                    any_hull = True
                    ax.set_xlabel("t [s]", fontsize=6.5, labelpad=1)
                    where: dict[str, Any] = {"x": 0.5, "y": 0.97, "va": "top"}
                else:
                    ax.set_axis_off()
                    twin.set_visible(False)
                    where = {"x": 0.5, "y": 0.5, "va": "center"}
                small = preview is not None  # over a trace: keep the box small
                box = textwrap.fill(f"{row['status']}: {reason}", 44 if small else 38)
                ax.text(where["x"], where["y"], literal(box),
                        ha="center", va=where["va"], fontsize=6.2 if small else 7, zorder=10,
                        color="#7a0000" if row["status"] == "rejected" else "#555555",
                        transform=ax.transAxes,
                        bbox={"boxstyle": "round,pad=0.6", "fc": "#f6f6f6", "ec": "#cccccc",
                              "alpha": 0.92})
                continue
            captive = captive_trace(red)
            if captive is None:
                any_lift |= bool(red.has_lift)
                any_hull = True
            else:
                any_captive = True
                any_pmm |= captive.pmm
                any_yaw |= "yaw" in captive.motion
            figures.run_thumbnail(ax, red, labels=False, linewidth=0.8, twin=twin)
            self._labels(ax, twin, captive=captive is not None)
            ax.set_title(literal(title), fontsize=7.5, loc="left", fontweight="normal")
            ax.set_xlabel("t [s]", fontsize=6.5, labelpad=1)
        legend_y = 1 - (PAGE_HEADER_IN - 0.2) / PAGE_H
        handles = figures.thumbnail_legend_handles(any_lift) if any_hull or not any_captive \
            else []
        if any_captive:  # beside a hull run's entries, without their phase shades again
            handles += captive_legend_handles(any_pmm, any_yaw, phases=not handles)
        self.fig.legend(handles=handles, loc="upper center",
                        ncol=figures.legend_columns(len(handles)),
                        fontsize=6.8, frameon=False, columnspacing=1.2,
                        handlelength=1.6, bbox_to_anchor=(0.5, legend_y))
        return self.fig


# ---------------------------------------------------------------------------------- writer
#: Page groups of report.pdf drawn at once (fixed, so that the file is the same on any machine).
PDF_PARTS = 4

#: Reports this process has drawn. The group this process draws itself (the others are drawn
#: in forked processes) turns with each report, so a process that draws many reports (a watch
#: session, a notebook) lays out every kind of page's text itself in turn, and the processes
#: it forks start with those layouts in its text caches (:mod:`towtank.report.textcache`,
#: :mod:`towtank.report.mathcache`) instead of empty ones. Which process draws a group does
#: not change the file.
_REPORTS_DRAWN = itertools.count()

#: Rough drawing time of a page by kind, relative (to split the pages evenly between cores);
#: a thumbnail page costs in proportion to its runs.
PAGE_COST = {"title": 0.1, "summary": 0.7, "figure": 0.5, "runs": 0.4, "fin_runs": 0.4,
             "quality": 0.3, "thumbs": 1.0, "captive": 0.4}


def _page_cost(page: Page) -> float:
    cost = PAGE_COST.get(page.kind, 0.5)
    if page.kind == "thumbs":
        cost *= 0.1 + 0.9 * len(page.payload) / THUMBS_PER_PAGE
    return cost


def split_pages(plan: list[Page], parts: int) -> list[list[int]]:
    """Page indices in ``parts`` contiguous groups of about equal drawing time (none empty)."""
    parts = max(1, min(parts, len(plan)))
    ends = np.cumsum([_page_cost(p) for p in plan])
    cuts = [0]
    for k in range(1, parts):
        target = ends[-1] * k / parts
        c = int(np.searchsorted(ends, target))  # pages [0, b) before the cut: b = c or c + 1
        b = min((c, c + 1), key=lambda b: abs(ends[max(b - 1, 0)] - target) if b else math.inf)
        cuts.append(min(max(b, cuts[-1] + 1), len(plan) - (parts - k)))  # none empty
    cuts.append(len(plan))
    return [list(range(a, b)) for a, b in zip(cuts[:-1], cuts[1:], strict=True)]


def write_pdf(day: DayResult, folder: str | Path, *, parts: int = PDF_PARTS,
              beside: bool = True) -> Path:
    """Write ``folder/report.pdf``.

    The pages are drawn in ``parts`` groups at once (:func:`split_pages`, each group by
    matplotlib's ``PdfPages`` into a part file: one group in this process, a different one with
    each report it draws, the others each in a forked process of its own; or, without
    ``beside``, every group here one after another) and the parts joined in order with pypdf;
    the metadata (title, author, creation date from the report date) are set once on the
    whole. Neither the number of parts nor the processes that draw them depend on the machine
    or the jobs, so the same day gives the same bytes anywhere.

    Parameters
    ----------
    day : DayResult
        The processed day.
    folder : path
        The output folder (the report writers' temporary folder).
    parts : int
        Page groups drawn at once.
    beside : bool
        Draw the groups in processes of their own, beside this one (False: one job asked
        for; the same file).

    Returns
    -------
    Path
        The PDF written.
    """
    folder = Path(folder)
    path = folder / "report.pdf"
    plan = page_plan(day)
    groups = split_pages(plan, parts)
    part_files = [folder / f".report-part-{k}.pdf" for k in range(len(groups))]
    try:
        tasks = [
            (f"report.pdf pages {g[0] + 1}–{g[-1] + 1}", partial(_write_part, day, plan, g, part))
            for g, part in zip(groups, part_files, strict=True)
        ]
        here = next(_REPORTS_DRAWN) % len(tasks)
        run_beside(tasks[here:] + tasks[:here], fork=beside)  # the first is drawn here
        writer = PdfWriter()
        for part in part_files:
            writer.append(part)
        date, _ = report_date(day)
        created = creation_date(date)
        meta = {
            "/Title": f"{day.protocol.name}: towing-tank test report",
            "/Author": "towtank",
            "/Subject": "Hydrodynamic coefficients from towing-tank runs",
            "/Creator": f"towtank {__version__}",
            "/Producer": f"matplotlib {mpl.__version__}, pypdf",
        }
        if created is not None:
            meta["/CreationDate"] = created.strftime("D:%Y%m%d%H%M%SZ")
        writer.add_metadata(meta)
        with open(path, "wb") as fh:
            writer.write(fh)
    finally:
        for part in part_files:
            part.unlink(missing_ok=True)
    return path


def _write_part(day: DayResult, plan: list[Page], pages: list[int], path: Path) -> None:
    """Draw the pages ``pages`` (indices into ``plan``) into the PDF ``path``."""
    meta = {"CreationDate": None, "ModDate": None}  # set on the joined file
    grids: dict[str, ThumbGrid] = {}
    with mpl.rc_context(style.rc()), PdfPages(path, metadata=meta) as pdf:
        for i in pages:
            fig = _render(day, plan[i], plan, grids)
            _decorate(fig, day.protocol.name, plan[i], i + 1, len(plan))
            pdf.savefig(fig)


def _render(
    day: DayResult, page: Page, plan: list[Page], grids: dict[str, ThumbGrid] | None = None
) -> Figure:
    """The figure of one page; thumbnail pages reuse the ThumbGrid kept in ``grids``."""
    if page.kind == "thumbs":
        grids = {} if grids is None else grids
        if "thumbs" not in grids:
            grids["thumbs"] = ThumbGrid()
        return grids["thumbs"].draw(day, page.payload)
    if page.kind == "figure":
        _name, func = page.payload  # bound to the results it draws (available_figures)
        fig = func(page=True)
        if fig is None:  # available_figures said yes: a stage changed under us
            fig = _page()
            _text_block(fig, 1.2, "No data for this figure.", fontsize=10)
        return fig
    fig = _page()
    if page.kind == "title":
        _draw_title(fig, day, plan)
    elif page.kind == "summary":
        _draw_summary(fig, day)
    elif page.kind == "quality":
        _draw_quality(fig, page.payload)
    elif page.kind == "runs":
        _draw_runs(fig, day.runs, day.protocol, page.payload)
    elif page.kind == "fin_runs":
        _draw_fin_runs(fig, require(day.fins, "fin"), page.payload)
    elif page.kind == "captive":
        _draw_captive(fig, page.payload, captive_provenance(day))
    return fig


#: Rows of the per-run table on one page.
RUNS_PER_PAGE = 46

_STATUS_FILL = {"rejected": "#f4cccc", "void": "#e6e6e6"}


#: How the runs table names each run's reference area (runs.csv ``ref_area``).
REF_AREA_LABEL = {"frontal": "A", "lateral": "A_lat", "fin": "c·s"}


def _draw_runs(fig: Figure, table: pd.DataFrame, protocol: Protocol, run_ids: list[int]
               ) -> None:
    """The per-run table (runs.csv's main columns) for ``run_ids``: one row per run, the
    tare-corrected steady drag and its coefficient on the area its test uses (named in its own
    column); rejected and void runs shaded; a blank acceleration explained below."""
    if "captive_Y_N" in table.columns:
        ref_x = protocol_reference_x(protocol.captive, protocol.model)
        _draw_captive_runs(fig, table, run_ids, moment_point(ref_x))
        return
    runs = table.set_index("run", drop=False)
    y = PAGE_HEADER_IN + 0.25
    header = ["run", "config", "test", "α [deg]", "U [m/s]", "a [m/s²]", "drag [N]",
              r"$C_D$", r"$C_D$ area", "Re", "tare [N]", "status"]
    blank, accel_note = missing_accel_note(table, protocol.processing, run_ids)
    rows, fill = [], {}
    for i, run in enumerate(run_ids):
        r = runs.loc[run]
        ok = r["status"] == "ok"
        cd = r.get("cd_ref", r["cd"])
        area = str(r.get("ref_area") or "")
        rows.append([str(run), literal(r["config"]), literal(r.get("test") or ""),
                     _v(r["angle_deg"], "g"),
                     _v(r["speed_mean"], ".3f") if ok else "–",
                     ("– ¹" if run in blank else _v(r["accel_mean"], ".3f")) if ok else "–",
                     _v(r["drag_mean"], ".4g") if ok else "–",
                     _v(cd, ".4f") if ok else "–",
                     math_text(REF_AREA_LABEL.get(area, "–")) if ok else "–",
                     sci(r["re"], 3) if ok and math.isfinite(float(r["re"])) else "–",
                     _v(r["tare_drag"], ".3g") if ok else "–",
                     literal(r["status"])])
        if r["status"] in _STATUS_FILL:
            for c in range(len(header)):
                fill[(i, c)] = _STATUS_FILL[str(r["status"])]
    used = _table(fig, y, header, rows, [0.45, 0.55, 0.55, 0.6, 0.65, 0.65, 0.75, 0.65, 0.6,
                                        0.75, 0.65, 0.7], row_in=0.19, fontsize=7.2,
                  highlight=fill)
    used += 0.12 + _text_block(fig, y + used + 0.12,
                               "Steady means over the plateau window (drag tare-corrected; a is "
                               "the mean constant acceleration where the run has one). C_D on "
                               "the area its test uses, named in the next column (runs.csv "
                               "cd_ref, ref_area): A the frontal area (hull runs), A_lat the "
                               "lateral area (transverse tows at α = 90°, the C_D,90 of "
                               "Y_v|v|), c·s chord × span (fin); Re on the length or chord, at "
                               f"each run's {_medium_word(protocol.water)} temperature. "
                               "Rejected runs (red) and void runs (grey) with their reasons: "
                               "Quality page and runs.csv.",
                               fontsize=7.5)
    if accel_note:
        _text_block(fig, y + used, accel_note, fontsize=7.5)


def _draw_captive_runs(fig: Figure, table: pd.DataFrame, run_ids: list[int],
                      moment: str = "about O") -> None:
    """The per-run table of a day with captive runs: each run's test and setting (drift β,
    rudder δ, arm radius R, PMM frequency), its speed and loads (captive runs: X, Y [N] and
    N [N m] ``moment`` (:func:`towtank.reduce.captive.moment_point`), inertia removed; other
    runs: the drag and its C_D) and status."""
    runs = table.set_index("run", drop=False)
    y = PAGE_HEADER_IN + 0.25
    header = ["run", "test", "β [deg]", "δ [deg]", "R [m]", "f [Hz]", "U [m/s]",
              "X or drag [N]", "Y [N]", "N [N m]", r"$C_D$", "cycles", "status"]
    rows, fill = [], {}
    for i, run in enumerate(run_ids):
        r = runs.loc[run]
        ok = r["status"] == "ok"
        captive = ok and math.isfinite(float(r["captive_Y_N"]))

        def val(name: str, fmt: str, row: Any = r) -> str:
            return _v(row.get(name), fmt)

        rows.append([str(run), literal(r.get("test") or ""), val("drift_deg", "g"),
                     val("rudder_deg", "g"), val("radius_m", "g"), val("pmm_frequency_hz", "g"),
                     val("speed_mean", ".3f") if ok else "–",
                     (val("captive_X_N", ".4g") if captive else val("drag_mean", ".4g"))
                     if ok else "–",
                     val("captive_Y_N", ".4g") if captive else "–",
                     val("captive_N_Nm", ".4g") if captive else "–",
                     "–" if captive or not ok else val("cd_ref", ".4f"),
                     val("pmm_cycles", ".0f") if captive else "–",
                     literal(r["status"])])
        if r["status"] in _STATUS_FILL:
            for c in range(len(header)):
                fill[(i, c)] = _STATUS_FILL[str(r["status"])]
    used = _table(fig, y, header, rows, [0.45, 0.7, 0.55, 0.55, 0.55, 0.5, 0.6, 0.85, 0.7,
                                        0.7, 0.6, 0.5, 0.7], row_in=0.19, fontsize=7.2,
                  highlight=fill)
    _text_block(fig, y + used + 0.12,
                "Captive runs: the setting from the run sheet (drift β, rudder δ, arm radius R, "
                "PMM frequency f), the steady mean speed and the hydrodynamic loads X, Y and "
                f"the moment N {moment} with the model's inertia removed: steady means (static "
                "tests) or cycle means over the kept PMM cycles (runs.csv captive_X_N, "
                "captive_Y_N, captive_N_Nm, pmm_cycles). Other runs: the tare-corrected drag "
                "and its C_D. Rejected runs (red) and void runs (grey) with their reasons: "
                "Quality page and runs.csv.", fontsize=7.5)


__all__ = [
    "page_plan", "write_pdf",
]

