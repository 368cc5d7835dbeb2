"""A matplotlib table drawn without measuring each cell twice.

:class:`matplotlib.table.Table` positions its cells on every draw: it measures the window extent
of every cell to find the grid's bounding box, scales and moves the cells into the table's box,
then, drawing each cell, measures the cell's window extent again to place its text. Each
measurement composes the cell's patch transform and pushes the cell's path through it. The
cells of a table are axis-aligned rectangles whose corners are known in axes coordinates, so
:class:`PageTable` reads the grid's box from the corners and transforms the corners of all the
cells at once to place the texts. The cells, their order, their rectangles and their texts are
matplotlib's; the numbers are the same to rounding, so the page's pixels do not change.

The shortcut leans on two private methods of matplotlib's Table (``_update_positions`` places
the cells, ``_get_grid_bbox`` is what it measures). A matplotlib without them draws the
report's tables with :meth:`Table.draw` itself: the same cells, measured as matplotlib
measures them, only slower (:func:`fast_placement` says which).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib.patches import Rectangle
from matplotlib.table import Cell, Table
from matplotlib.transforms import Bbox

__all__ = ["PageTable", "page_table", "fast_placement", "row_height", "PRIVATE_METHODS"]

#: matplotlib's private Table methods the shortcut uses (there since matplotlib 2.x).
PRIVATE_METHODS = ("_update_positions", "_get_grid_bbox")


def fast_placement() -> bool:
    """Whether this matplotlib's Table has the private methods :class:`PageTable`'s shortcut
    uses (:data:`PRIVATE_METHODS`); without them its tables are drawn by :meth:`Table.draw`."""
    return all(callable(getattr(Table, name, None)) for name in PRIVATE_METHODS)


def _corners(cells: Sequence[Cell]) -> np.ndarray:
    """Lower-left and upper-right corner (x0, y0, x1, y1) of each cell [axes fraction]."""
    return np.array([(c.get_x(), c.get_y(), c.get_x() + c.get_width(),
                      c.get_y() + c.get_height()) for c in cells], dtype=float).reshape(-1, 4)


class PageTable(Table):
    """A :class:`~matplotlib.table.Table` placing its cells from their corners.

    Only what :meth:`Table.draw` measures changes: the grid's box (:meth:`_get_grid_bbox`) is
    the union of the cells' corners, and each cell's text is placed from its corners transformed
    with the rest of the table's at once. Cells keep matplotlib's drawing (rectangle, then text).
    """

    def _get_grid_bbox(self, renderer: Any) -> Bbox:
        """The cells' bounding box (rows and columns ≥ 0) [axes fraction]."""
        xy = _corners([c for (row, col), c in self.get_celld().items() if row >= 0 and col >= 0])
        return Bbox.from_extents(xy[:, 0].min(), xy[:, 1].min(), xy[:, 2].max(), xy[:, 3].max())

    def draw(self, renderer: Any) -> None:
        """Position the cells (as matplotlib does), then draw each rectangle and its text;
        matplotlib's own drawing where its Table lacks the private methods used."""
        if not fast_placement():
            super().draw(renderer)
            return
        if not self.get_visible():
            return
        renderer.open_group("table", gid=self.get_gid())
        # matplotlib's placement; private, not in its stubs
        self._update_positions(renderer)  # type: ignore[attr-defined]
        celld = self.get_celld()
        cells = [celld[k] for k in sorted(celld)]
        xy = _corners(cells)
        trans = self.get_transform()
        lo = trans.transform(xy[:, :2])
        hi = trans.transform(xy[:, 2:])
        for cell, (x0, y0), (x1, y1) in zip(cells, lo, hi, strict=True):
            if not cell.get_visible():
                continue
            Rectangle.draw(cell, renderer)
            text = cell.get_text()
            text.set_position((_text_x(x0, x1, text.get_horizontalalignment(), cell.PAD),
                               y0 + (y1 - y0) / 2))
            text.draw(renderer)
            cell.stale = False
        renderer.close_group("table")
        self.stale = False


def _text_x(x0: float, x1: float, loc: str, pad: float) -> float:
    """Anchor of a cell's text between the cell's edges ``x0``, ``x1`` [px], as Cell places it."""
    width = x1 - x0
    if loc == "center":
        return x0 + width / 2
    if loc == "left":
        return x0 + width * pad
    return x0 + width * (1 - pad)


def row_height(tab: Table, ax: Any) -> float:
    """The row height [axes fraction] matplotlib's ``table()`` gives its cells: 1.2 lines of
    the table's font size (``Table.FONTSIZE`` [pt]) at the figure's dpi over the axes' height
    (matplotlib's ``Table._approx_text_height``, computed from public values)."""
    return tab.FONTSIZE / 72.0 * ax.figure.dpi / ax.bbox.height * 1.2


def page_table(ax: Any, rows: Sequence[Sequence[str]], header: Sequence[str],
               col_widths: Sequence[float],
               align: Sequence[str] | None = None) -> PageTable:
    """A :class:`PageTable` filling ``ax``: a header row over ``rows``.

    Built cell by cell as :func:`matplotlib.table.table` builds it (``bbox`` the whole axes,
    ``colWidths`` ``col_widths`` [axes fraction], white cells); each column's text is placed
    ``align[c]`` ("left", "center", "right"), or without ``align`` the body's right and the
    header's centred as matplotlib's table places them.
    """
    tab = PageTable(ax, None, Bbox.from_bounds(0, 0, 1, 1))
    tab.edges = "closed"
    height = row_height(tab, ax)
    for r, row in enumerate(rows):
        for c, text in enumerate(row):
            tab.add_cell(r + 1, c, width=col_widths[c], height=height, text=text,
                         facecolor="w", loc="right" if align is None else align[c])
    for c, text in enumerate(header):
        tab.add_cell(0, c, width=col_widths[c], height=height, text=text, facecolor="w",
                     loc="center" if align is None else align[c])
    ax.add_table(tab)
    return tab
