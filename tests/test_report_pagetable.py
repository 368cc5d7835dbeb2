"""The report's tables (towtank.report.pagetable): drawn as matplotlib's Table draws them, the
same pixels, without measuring every cell's window extent."""

from __future__ import annotations

from typing import Literal

import numpy as np
import pytest
from matplotlib.axes import Axes
from matplotlib.backend_bases import RendererBase
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.table import Cell, Table
from matplotlib.transforms import Bbox

from towtank.report import pdf
from towtank.report.pagetable import page_table

HEADER = ["run", "U [m/s]", "status"]
ROWS = [[str(k), f"{0.25 * k:.3f}", "ok" if k % 3 else "rejected"] for k in range(1, 12)]
WIDTHS = [0.2, 0.5, 0.3]


def _figure() -> tuple[Figure, Axes]:
    fig = Figure(figsize=(5, 3), dpi=80)
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0.1, 0.1, 0.8, 0.8))
    ax.set_axis_off()
    return fig, ax


def _pixels(fig: Figure) -> np.ndarray:
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba()).copy()


def _style(*tables: Table) -> None:
    """The report's look on each table: 7.5 pt text, thin lines, a grey bold header."""
    for tab in tables:
        tab.auto_set_font_size(False)
        tab.set_fontsize(7.5)
        for (r, _c), cell in tab.get_celld().items():
            cell.set_linewidth(0.4)
            cell.PAD = 0.04
            if r == 0:
                cell.set_facecolor("#dddddd")
                cell.get_text().set_fontweight("bold")


@pytest.mark.parametrize("align", [None, ["left", "center", "right"]])
def test_page_table_draws_matplotlibs_table_pixels(
        align: list[Literal["left", "center", "right"]] | None) -> None:
    """The same rows drawn by matplotlib's ``ax.table`` and by page_table: the same pixels,
    the same text anchors."""
    fig_mpl, ax_mpl = _figure()
    ref = ax_mpl.table(cellText=ROWS, colLabels=HEADER, colWidths=WIDTHS,
                       bbox=Bbox.from_bounds(0, 0, 1, 1), cellLoc="right")
    if align is not None:
        for (_r, c), cell in ref.get_celld().items():
            cell.get_text().set_horizontalalignment(align[c])
    fig_ours, ax_ours = _figure()
    ours = page_table(ax_ours, ROWS, HEADER, WIDTHS, align)
    _style(ref, ours)
    assert np.array_equal(_pixels(fig_mpl), _pixels(fig_ours))
    for key, cell in ref.get_celld().items():
        np.testing.assert_allclose(ours[key].get_text().get_position(),
                                   cell.get_text().get_position(), rtol=0, atol=1e-9)
        assert ours[key].get_bbox().bounds == pytest.approx(cell.get_bbox().bounds, abs=1e-12)


@pytest.fixture
def measured_cells(monkeypatch: pytest.MonkeyPatch) -> list[Cell]:
    """The cells whose window extent is measured from now on, in the order measured."""
    calls: list[Cell] = []
    extent = Cell.get_window_extent

    def counting(self: Cell, renderer: RendererBase | None = None) -> Bbox:
        calls.append(self)
        return extent(self, renderer)

    monkeypatch.setattr(Cell, "get_window_extent", counting)
    return calls


def test_report_table_draws_without_measuring_cells(measured_cells: list[Cell]) -> None:
    """A report table (pdf._table) is drawn without a window-extent measurement per cell."""
    fig = Figure(figsize=pdf.style.PAGE_SIZE, dpi=80)
    FigureCanvasAgg(fig)
    used = pdf._table(fig, 1.0, HEADER, ROWS, [0.45, 0.55, 0.6])
    fig.canvas.draw()
    assert used == pytest.approx((len(ROWS) + 1) * 0.22)
    assert measured_cells == []


def test_row_height_is_matplotlibs() -> None:
    """page_table's rows are as high as matplotlib's ``table()`` makes them."""
    from towtank.report.pagetable import row_height

    fig, ax = _figure()
    tab = Table(ax, None, Bbox.from_bounds(0, 0, 1, 1))
    private = getattr(tab, "_approx_text_height", None)
    if private is None:
        pytest.skip("this matplotlib's Table has no _approx_text_height to compare with")
    assert row_height(tab, ax) == private()


@pytest.mark.parametrize("align", [None, ["left", "center", "right"]])
def test_without_matplotlibs_private_methods_the_table_is_matplotlibs_own(
        monkeypatch: pytest.MonkeyPatch, request: pytest.FixtureRequest,
        align: list[Literal["left", "center", "right"]] | None) -> None:
    """A matplotlib whose Table lacks a private method the shortcut uses (planted: a name it
    does not have): page_table's table is drawn by Table.draw itself, with the same pixels as
    the shortcut's and matplotlib's ``ax.table``."""
    from towtank.report import pagetable

    assert pagetable.fast_placement()  # this matplotlib: the shortcut
    fig_fast, ax_fast = _figure()
    fast = page_table(ax_fast, ROWS, HEADER, WIDTHS, align)
    monkeypatch.setattr(pagetable, "PRIVATE_METHODS",
                        (*pagetable.PRIVATE_METHODS, "_a_method_no_matplotlib_has"))
    assert not pagetable.fast_placement()
    fig_slow, ax_slow = _figure()
    slow = page_table(ax_slow, ROWS, HEADER, WIDTHS, align)
    _style(fast, slow)
    measured = request.getfixturevalue("measured_cells")  # from here on
    slow_pixels = _pixels(fig_slow)
    assert measured, "Table.draw measures its cells: it was not the one drawing"
    monkeypatch.setattr(pagetable, "PRIVATE_METHODS", pagetable.PRIVATE_METHODS[:-1])
    assert np.array_equal(_pixels(fig_fast), slow_pixels)
