"""One look for every figure and page of the report: rc settings, colours, page geometry.

Everything here is constant data (no matplotlib import), so the workbook writer can use the
colours too without pulling in matplotlib.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from cycler import cycler

if TYPE_CHECKING:  # the rc key names as matplotlib's stubs list them; no import at run time
    from matplotlib.typing import RcKeyType

#: A4 portrait [in].
PAGE_SIZE: tuple[float, float] = (8.27, 11.69)
#: Size of a stand-alone figure (PNG) and of a figure page's drawing area [in].
FIGURE_SIZE: tuple[float, float] = (8.27, 9.6)
#: Resolution of the PNG figures [dpi].
PNG_DPI = 150

#: matplotlib rc settings applied with ``plt.rc_context`` around every drawing.
RC: dict[RcKeyType, Any] = {
    "font.family": "DejaVu Sans",
    "font.size": 8.5,
    "axes.titlesize": 9.5,
    "axes.titleweight": "bold",
    "axes.titley": 1.0,  # fixed title position: skips a costly automatic placement
    "axes.titlepad": 5.0,
    "axes.labelsize": 8.5,
    "axes.grid": True,
    "axes.axisbelow": True,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "axes.prop_cycle": None,  # set below from PALETTE
    "grid.color": "#b0b0b0",
    "grid.alpha": 0.35,
    "grid.linewidth": 0.5,
    "legend.fontsize": 7.5,
    "legend.frameon": True,
    "legend.framealpha": 0.85,
    "legend.edgecolor": "#cccccc",
    "xtick.labelsize": 7.5,
    "ytick.labelsize": 7.5,
    "lines.linewidth": 1.3,
    "lines.markersize": 4.5,
    "mathtext.fontset": "dejavusans",
    "pdf.fonttype": 3,  # subset Type 3 fonts: searchable text, fast to embed
    "svg.fonttype": "none",
    "savefig.dpi": PNG_DPI,
    "figure.dpi": 100,
    "path.simplify": True,
}

#: Qualitative colours (colour-blind safe, Okabe-Ito) for series.
PALETTE: tuple[str, ...] = (
    "#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000", "#F0E442",
)
SPEED_COLOR = "#222222"
DRAG_COLOR = "#0072B2"
LIFT_COLOR = "#D55E00"
FIT_COLOR = "#0072B2"
BAND_COLOR = "#9ecae1"
OUTLIER_COLOR = "#C00000"
STEADY_SAMPLE_COLOR = "#9a9a9a"

#: Phase shading of a run thumbnail: window name -> (colour, label).
PHASE_SHADES: dict[str, tuple[str, str]] = {
    "still_pre": ("#d9d9d9", "zero (still)"),
    "accel": ("#fdd0a2", "acceleration"),
    "steady": ("#c7e9c0", "steady"),
    "decel": ("#dadaeb", "deceleration"),
    "still_post": ("#d9d9d9", "still after"),
}

# workbook fills (ARGB without alpha) ----------------------------------------------------------
XL_HEADER_FILL = "DDEBF7"
XL_REJECTED_FILL = "F8CBAD"
XL_VOID_FILL = "E7E6E6"
XL_DIFF_FILL = "FFE699"
XL_NOTE_FONT_COLOR = "7F7F7F"


def rc() -> dict[RcKeyType, Any]:
    """The rc dict, with the colour cycle made from :data:`PALETTE`."""
    out = dict(RC)
    out["axes.prop_cycle"] = cycler(color=list(PALETTE))
    return out
