"""The basics every report figure shares: page margins, the figure and caption layout, the
one rc style (:func:`styled`), and the text helpers that typeset symbols and numbers
(``X_udot`` as X with a dotted u, ``2.67e+05`` as 2.67×10⁵, a true minus sign)."""

from __future__ import annotations

import functools
import math
import re
import textwrap
from collections.abc import Callable
from typing import Any

import matplotlib as mpl
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import PathCollection
from matplotlib.figure import Figure

import towtank.report.style as style
from towtank.report.mathcache import install as _share_math_cache
from towtank.report.safetext import clean_text
from towtank.report.textcache import install as _share_text_cache

_share_math_cache()  # one mathtext layout cache for every page and figure (same layouts)
_share_text_cache()  # one text metrics and glyph layout cache for every PDF page (same results)

PAGE_HEADER_IN = 0.95  # room kept free at the top of a PDF page for the section title [in]
PAGE_FOOTER_IN = 0.45  # room kept free at the bottom for the page footer [in]
CAPTION_CHARS = 118  # wrap width of captions on a page-wide figure
CAPTION_LINE_IN = 7.8 * 1.35 / 72  # height of one caption line [in]
_SUPERSCRIPT = str.maketrans("0123456789-", "⁰¹²³⁴⁵⁶⁷⁸⁹⁻")  # exponents of ×10ⁿ


# ------------------------------------------------------------------------------------ helpers
def styled(func: Callable[..., Any]) -> Callable[..., Any]:
    """Run ``func`` inside the report's rc style."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with mpl.rc_context(style.rc()):
            return func(*args, **kwargs)

    return wrapper


def math_symbol(symbol: str) -> str:
    """A coefficient's ASCII symbol in mathtext: ``X_udot`` → ``$X_{\\dot u}$``.

    Parameters
    ----------
    symbol : str
        docs/formats.md symbol such as ``X_udot``, ``X_u|u|`` or ``Y_uv``.
    """
    head, _, sub = symbol.partition("_")
    if not sub:
        return symbol
    if sub.endswith("dot"):
        sub = r"\dot " + sub[:-3]
    return f"${head}_{{{sub}}}$"


#: Plain-text symbols of the program's messages and their mathtext (no spaces inside, so that
#: wrapping never splits one), longest first.
_MATH_TOKENS: tuple[tuple[str, str], ...] = tuple(
    sorted(
        {
            **{s: f"${s[0]}_{{\\dot{{{s[2]}}}}}$" for s in ("X_udot", "Y_vdot", "Z_wdot")},
            **{s: f"${s[0]}_{{{s[2:]}}}$" for s in (
                "X_u|u|", "X_uv", "X_uw", "X_v|v|", "X_w|w|", "Y_uv", "Z_uw", "Y_v|v|",
                "Z_w|w|")},
            **{s: f"${s[0]}_{{uu\\delta_{s[-1]}}}$" for s in (
                "Y_uudr", "Z_uuds", "M_uuds", "N_uudr")},
            "C_D(α)": r"$C_D(\alpha)$", "C_D,90": r"$C_{D,90}$", "C_D,min": r"$C_{D,min}$",
            "C_L,max": r"$C_{L,max}$", "C_D": r"$C_D$", "C_L": r"$C_L$", "C_F": r"$C_F$",
            "A_lat": r"$A_{lat}$", "ρ_p": r"$\rho_p$", "ρ_m": r"$\rho_m$", "L_p": r"$L_p$",
            "U_p": r"$U_p$", "U_m": r"$U_m$", "R_p": r"$R_p$", "S_p": r"$S_p$", "S_m": r"$S_m$",
            "D_a": r"$D_a$",
            "D_s": r"$D_s$", "k2": r"$k_2$", "k1": r"$k_1$", "q2": r"$q_2$", "q1": r"$q_1$",
        }.items(),
        key=lambda kv: -len(kv[0]),
    )
)
_MATH_RE = re.compile(
    r"(?<![A-Za-z0-9_$\\])("
    + "|".join(re.escape(k) for k, _ in _MATH_TOKENS)
    + r")(?![A-Za-z0-9_])"
)


_E_NUMBER = re.compile(r"(?<![\w.])(-?\d+(?:\.\d+)?)e([+-]?\d+)(?!\w|\.\d)")  # "…e+06." too
_HYPHEN_MINUS = re.compile(r"(?<![\w.)\]])-(?=\d)")


def literal(text: object) -> str:
    """Text from the inputs (names, file names, reasons) drawn as it is: a ``$`` in it is
    escaped, so that matplotlib never parses it as mathtext (which could fail the report)."""
    return clean_text(str(text)).replace("$", r"\$")


def true_minus(text: str) -> str:
    """``text`` with a true minus sign (U+2212) for the hyphen before a number."""
    return _HYPHEN_MINUS.sub("\u2212", text)


def math_text(text: str) -> str:
    """Prose as the report prints it: plain symbols in mathtext (``X_udot`` → X with a dotted
    u), numbers like ``2.67e+05`` as 2.67×10⁵, and a true minus sign before a number.

    A ``$`` already in the text (a run's remarks, say) is escaped first, so that no text
    from the inputs is ever parsed as mathtext.
    """
    table = dict(_MATH_TOKENS)
    text = _E_NUMBER.sub(
        lambda m: f"{m.group(1)}×10" + str(int(m.group(2))).translate(_SUPERSCRIPT), text
    )
    text = true_minus(text)
    return _MATH_RE.sub(lambda m: table[m.group(1)], literal(text))


def new_figure(page: bool, size: tuple[float, float] = style.FIGURE_SIZE) -> Figure:
    """An empty report figure: an A4 page (:data:`towtank.report.style.PAGE_SIZE`) or ``size``.

    Parameters
    ----------
    page : bool
        Make it an A4 report page.
    size : tuple of float
        (width, height) of a figure that is not a page [in].
    """
    return Figure(figsize=style.PAGE_SIZE if page else size)


def figure_grid(fig: Figure, nrows: int, ncols: int, *, page: bool, title: str, text: str,
            top_in: float = 0.8, xlabel_in: float = 0.5, left: float = 0.1,
            right: float = 0.95, **kw: Any) -> Any:
    """Title, caption and a GridSpec between them, with margins in inches.

    A page figure keeps room for the PDF page's header and footer; the caption's height is
    known from its wrapped line count, so the axes end just above it.

    Parameters
    ----------
    fig : Figure
        The figure (from :func:`new_figure`).
    nrows, ncols : int
        The grid's rows and columns.
    page : bool
        Keep room for the PDF page's header (:data:`PAGE_HEADER_IN`) and footer
        (:data:`PAGE_FOOTER_IN`).
    title : str
        Bold title at the top.
    text : str
        Caption under the axes (wrapped by :func:`wrap_caption`).
    top_in : float
        Room between the top (below the page header) and the axes [in].
    xlabel_in : float
        Room between the caption and the axes for the x labels [in].
    left, right : float
        The grid's left and right edges [figure fraction].
    **kw
        Passed on to :meth:`~matplotlib.figure.Figure.add_gridspec` (``hspace``, ...).

    Returns
    -------
    GridSpec
    """
    h = fig.get_size_inches()[1]
    header = PAGE_HEADER_IN if page else 0.0
    footer = PAGE_FOOTER_IN if page else 0.0
    fig.text(0.5, 1 - (header + 0.22) / h, title, ha="center", va="top", fontsize=10.5,
             fontweight="bold")
    wrapped = wrap_caption(text)
    n_lines = wrapped.count("\n") + 1
    cap_top = footer + 0.25 + n_lines * CAPTION_LINE_IN
    fig.text(0.08, cap_top / h, wrapped, ha="left", va="top", fontsize=7.8, linespacing=1.35,
             color="#333333")
    bottom = cap_top + 0.2 + xlabel_in
    return fig.add_gridspec(nrows, ncols, left=left, right=right, top=1 - (header + top_in) / h,
                            bottom=bottom / h, **kw)


def wrap_caption(text: str, width: int = CAPTION_CHARS) -> str:
    """``text`` wrapped to ``width`` characters; paragraphs (blank-line separated) kept apart."""
    paras = [textwrap.fill(" ".join(p.split()), width) for p in text.split("\n\n") if p.strip()]
    return math_text("\n".join(paras))


def fmt_number(x: float, digits: int = 4) -> str:
    """A number for a label: ``digits`` significant digits, a true minus sign, '–' for NaN.

    Parameters
    ----------
    x : float
        The number (None or not finite gives '–').
    digits : int
        Significant digits.
    """
    if x is None or not math.isfinite(float(x)):
        return "–"
    return f"{float(x):.{digits}g}".replace("-", "\u2212")


def sci(x: float, digits: int = 2) -> str:
    """A positive number in scientific notation with Unicode superscripts: 2.7e5 → 2.7×10⁵.

    Plain text, not mathtext: cheap to lay out and found by a PDF text search.

    Parameters
    ----------
    x : float
        The number.
    digits : int
        Significant digits.
    """
    x = float(x)
    if not math.isfinite(x) or x <= 0:
        return fmt_number(x)
    m, _, e = f"{x:.{digits}g}".partition("e")
    if not e:
        return m
    return f"{m}×10" + str(int(e)).translate(_SUPERSCRIPT)


# ------------------------------------------------------------------------- legends and axes
def _renderer(fig: Figure) -> Any:
    """A renderer of ``fig`` to measure text and legend boxes (an Agg canvas if it has none)."""
    canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
    return canvas.get_renderer()


def data_under_legend(ax: Any, legend: Any = None, renderer: Any = None) -> int:
    """How many data artists of ``ax`` its legend covers, counted as matplotlib's ``loc="best"``
    counts them: a line whose segments cross the legend's box, a marker or scatter point inside
    it, a filled band (``fill_between``) under it. Shaded spans (``axvspan``) are background
    and not counted.

    Parameters
    ----------
    ax : Axes
        The axes.
    legend : Legend, optional
        The legend to test (default: the axes' own).
    renderer : optional
        A renderer of the axes' figure (made when not given).
    """
    leg = legend if legend is not None else ax.get_legend()
    if leg is None:
        return 0
    renderer = renderer if renderer is not None else _renderer(ax.figure)
    box = leg.get_window_extent(renderer).padded(2.0)  # [display px]: a marker's half width
    n = 0
    for line in ax.lines:
        if not line.get_visible() or len(line.get_xdata()) == 0:
            continue
        path = line.get_transform().transform_path(line.get_path())
        if line.get_linestyle() in ("None", "", " "):  # markers only
            n += int(box.count_contains(path.vertices))
        else:
            n += int(path.intersects_bbox(box, filled=False))
    for coll in ax.collections:
        if not coll.get_visible():
            continue
        if isinstance(coll, PathCollection):  # scatter points
            offsets = coll.get_offset_transform().transform(coll.get_offsets())
            n += int(box.count_contains(offsets))
        else:  # bands
            trans = coll.get_transform()
            n += sum(int(trans.transform_path(p).intersects_bbox(box, filled=True))
                     for p in coll.get_paths())
    return n


def place_legend(ax: Any, handles: list[Any] | None = None,
                 headroom: tuple[float, ...] = (0.0, 0.12, 0.25, 0.4, 0.6),
                 **kw: Any) -> Any:
    """A legend of ``ax`` that covers none of its data (:func:`data_under_legend`).

    matplotlib's ``loc="best"`` is tried first; while the legend still covers data, the
    y axis is grown above the data (by the fractions ``headroom`` of its span, in the axis'
    own scale) so that a clear place opens above the curves. Call it after everything is
    drawn: it fixes the y limits.

    Parameters
    ----------
    ax : Axes
        The axes.
    handles : list, optional
        Legend entries (default: the labelled artists).
    headroom : tuple of float
        Growths of the y span tried in turn [-].
    **kw
        Passed on to :meth:`~matplotlib.axes.Axes.legend` (``loc`` defaults to "best").
    """
    kw.setdefault("loc", "best")
    renderer = _renderer(ax.figure)
    y0, y1 = ax.get_ylim()
    ax.set_xlim(ax.get_xlim())  # no autoscale after this: the data's place is known
    scale = ax.yaxis.get_transform()
    s0, s1 = scale.transform([y0, y1])
    best: tuple[int, float] | None = None
    for extra in headroom:
        top = float(scale.inverted().transform([s1 + extra * (s1 - s0)])[0])
        ax.set_ylim(y0, top)
        leg = ax.legend(handles=handles, **kw) if handles is not None else ax.legend(**kw)
        n = data_under_legend(ax, leg, renderer)
        if n == 0:
            return leg
        if best is None or n < best[0]:
            best = (n, extra)
    assert best is not None
    top = float(scale.inverted().transform([s1 + best[1] * (s1 - s0)])[0])
    ax.set_ylim(y0, top)
    return ax.legend(handles=handles, **kw) if handles is not None else ax.legend(**kw)


def zero_fraction(ax: Any) -> float:
    """Where y = 0 lies on ``ax``: 0 at the bottom, 1 at the top [-]."""
    y0, y1 = ax.get_ylim()
    return -y0 / (y1 - y0)


def align_zero(ax: Any, twin: Any) -> None:
    """Lower the bottom of one of two linear y axes (both holding 0) so that y = 0 lies at the
    same height on both: a twin axis' zero line is then the other's."""
    (a0, a1), (b0, b1) = ax.get_ylim(), twin.get_ylim()
    if not (a0 <= 0 < a1 and b0 <= 0 < b1):
        return
    fa, fb = zero_fraction(ax), zero_fraction(twin)
    if fa < fb < 1:
        ax.set_ylim(-fb * a1 / (1 - fb), a1)
    elif fb < fa < 1:
        twin.set_ylim(-fa * b1 / (1 - fa), b1)
