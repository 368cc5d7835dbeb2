"""The report writer's shared text caches keep matplotlib's results: metrics and glyph layouts
computed once for every PDF page (renderer), the same as matplotlib's own."""

from __future__ import annotations

import io
from typing import Any

import matplotlib.text as mtext
import pytest
from matplotlib import _text_helpers
from matplotlib.backends import backend_pdf
from matplotlib.font_manager import FontProperties

import towtank.report.figure_base  # noqa: F401  # installs the shared caches
from towtank.report import textcache


def _renderer() -> Any:
    """A PDF page's renderer, as ``savefig`` makes one per page."""
    return backend_pdf.RendererPdf(backend_pdf.PdfFile(io.BytesIO()), 72, 600, 800)


def test_text_metrics_measured_once_for_all_pdf_pages(monkeypatch: pytest.MonkeyPatch) -> None:
    """Two pages' renderers measure a string once, and the size is matplotlib's own."""
    assert textcache.install(), "importing the report installs the caches"
    calls: list[str] = []
    measure = backend_pdf.RendererPdf.get_text_width_height_descent

    def counting(self: Any, s: str, prop: Any, ismath: Any) -> Any:
        calls.append(s)
        return measure(self, s, prop, ismath)

    monkeypatch.setattr(backend_pdf.RendererPdf, "get_text_width_height_descent", counting)
    prop = FontProperties(family="DejaVu Sans", size=7.3)
    text = "Run 12 · U = 1.25 m/s, metrics probe"
    metrics = getattr(mtext, textcache._METRICS_NAME)  # private to matplotlib
    first = metrics(_renderer(), text, prop, False, 72)
    second = metrics(_renderer(), text, prop, False, 72)
    assert calls == [text], "the second page reuses the first page's measurement"
    assert second == first == measure(_renderer(), text, prop, False)
    bigger = FontProperties(family="DejaVu Sans", size=9.1)
    wider = metrics(_renderer(), text, bigger, False, 72)
    assert wider[0] > first[0], "the font size is part of the key"


def test_glyph_layout_shaped_once_and_unchanged() -> None:
    """The PDF backend's layout of a string is shaped once per font and size, with the glyphs
    and positions matplotlib's own layout gives."""
    prop = FontProperties(family="DejaVu Sans", size=7.7)
    text = "Fr = 0.31 − AVg layout probe"
    font = _renderer()._get_font_ttf(prop)
    shaped: Any = backend_pdf._text_helpers.layout(text, font)
    again = backend_pdf._text_helpers.layout(text, _renderer()._get_font_ttf(prop))
    assert again is shaped, "a second page reuses the first page's layout"
    fresh = list(_text_helpers.layout(text, _renderer()._get_font_ttf(prop)))
    assert [(i.char, i.glyph_index, i.x, i.y, i.prev_kern) for i in shaped] == [
        (i.char, i.glyph_index, i.x, i.y, i.prev_kern) for i in fresh]
    larger: Any = backend_pdf._text_helpers.layout(
        text, _renderer()._get_font_ttf(FontProperties(family="DejaVu Sans", size=11)))
    assert list(larger)[-1].x > list(shaped)[-1].x, "the font size is part of the key"
