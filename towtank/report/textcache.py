"""Text metrics and glyph layouts shared by every page of every PDF report.

matplotlib measures a string (width, height, descent) through a cache kept per renderer, and
the PDF backend shapes a string into positioned glyphs (``_text_helpers.layout``) anew for
every string drawn. Every page saved to a PDF gets a new renderer, so the same tick label,
table header or caption word is measured and shaped again on every page. :func:`install`
gives PDF renderers one process-wide cache of each, keyed on what the result depends on:

- metrics: the string, the font properties, math or not, dpi and the rc settings the PDF
  renderer's measurement reads (``pdf.use14corefonts``, ``mathtext.*``);
- glyph layouts: the font object (its file, face and fallbacks), its size, the string, font
  features and language.

The results are the ones matplotlib computes (the same functions compute them), so the
report's pixels and text do not change. Rasterised drawing (a renderer other than the PDF
one) and usetex strings keep matplotlib's own path.
"""

from __future__ import annotations

import functools
import inspect
from types import SimpleNamespace
from typing import Any

import matplotlib as mpl
import matplotlib.text as mtext
from matplotlib import _text_helpers  # the PDF backend's text shaper
from matplotlib.backends import backend_pdf
from matplotlib.backends.backend_pdf import RendererPdf

from towtank.report.mathcache import rc_value

__all__ = ["install", "METRICS_CACHE_SIZE", "LAYOUT_CACHE_SIZE"]

#: Strings kept measured (a sample-hull report measures ≈ 1,000 distinct ones).
METRICS_CACHE_SIZE = 8192
#: Strings kept shaped (font, size and string).
LAYOUT_CACHE_SIZE = 8192

_METRICS_NAME = "_get_text_metrics_with_cache"  # private to matplotlib.text
_ORIGINAL_METRICS = getattr(mtext, _METRICS_NAME)
_ORIGINAL_LAYOUT = _text_helpers.layout
_ORIGINAL_FONT_TTF = RendererPdf._get_font_ttf
_RC_KEYS = ("pdf.use14corefonts", "text.usetex",
            *sorted(k for k in mpl.rcParams if k.startswith("mathtext.")))
#: The size [pt] each font object was last set to by a PDF renderer.
_FONT_SIZE: dict[int, float] = {}
_EXPECTED = {
    "metrics": ("renderer", "text", "fontprop", "ismath", "dpi"),
    "layout": ("string", "font", "features", "language"),
    "font": ("self", "prop"),
}


#: (string, font properties, math, dpi, rc) -> (width, height, descent) [pt].
_METRICS: dict[tuple[Any, ...], tuple[float, float, float]] = {}


def _metrics(renderer: Any, text: str, fontprop: Any, ismath: Any, dpi: float) -> Any:
    """:func:`matplotlib.text._get_text_metrics_with_cache`, shared between PDF renderers."""
    base = getattr(renderer, "_renderer", renderer)  # a MixedModeRenderer draws through it
    if type(base) is not RendererPdf or ismath == "TeX":
        return _ORIGINAL_METRICS(renderer, text, fontprop, ismath, dpi)
    prop = fontprop.copy()  # FontProperties hashes on its (mutable) state
    key = (text, prop, ismath, dpi, tuple(rc_value(mpl.rcParams[k]) for k in _RC_KEYS))
    found = _METRICS.get(key)
    if found is None:
        found = base.get_text_width_height_descent(text, prop, ismath=ismath)
        if len(_METRICS) >= METRICS_CACHE_SIZE:
            _METRICS.clear()
        _METRICS[key] = found
    return found


def _font_ttf(self: Any, prop: Any) -> Any:
    """The PDF renderer's font for ``prop``, its size noted for :func:`_layout`."""
    font = _ORIGINAL_FONT_TTF(self, prop)
    _FONT_SIZE[id(font)] = float(prop.get_size_in_points())
    return font


@functools.lru_cache(LAYOUT_CACHE_SIZE)
def _layout_shared(string: str, font: Any, size: float, features: Any, language: Any
                   ) -> tuple[Any, ...]:
    """matplotlib's glyph layout of ``string`` at ``size`` [pt] (in the key only; the font
    is set to it)."""
    return tuple(_ORIGINAL_LAYOUT(string, font, features=features, language=language))


def _layout(string: str, font: Any, *, features: Any = None, language: Any = None) -> Any:
    """The PDF backend's glyph layout, shared between pages. The PDF backend reads only the
    items (not the glyph last loaded into the font)."""
    size = _FONT_SIZE.get(id(font))
    if size is None:
        return _ORIGINAL_LAYOUT(string, font, features=features, language=language)
    key_features = tuple(features) if isinstance(features, list) else features
    key_language = tuple(language) if isinstance(language, list) else language
    return _layout_shared(string, font, size, key_features, key_language)


def _parameters(func: Any) -> tuple[str, ...]:
    return tuple(inspect.signature(func).parameters)


def install() -> bool:
    """Make PDF renderers share the metrics and layout caches (once; later calls do
    nothing). Returns whether the caches are in use: not with a matplotlib whose functions
    are not built as expected, which then keeps its own behaviour."""
    if getattr(mtext, _METRICS_NAME) is _metrics:
        return True
    if (_parameters(_ORIGINAL_METRICS) != _EXPECTED["metrics"]
            or _parameters(_ORIGINAL_LAYOUT) != _EXPECTED["layout"]
            or _parameters(_ORIGINAL_FONT_TTF) != _EXPECTED["font"]
            or getattr(backend_pdf, "_text_helpers", None) is not _text_helpers):
        return False
    setattr(mtext, _METRICS_NAME, _metrics)
    setattr(RendererPdf, "_get_font_ttf", _font_ttf)  # noqa: B010
    # the PDF backend alone shapes through the cache (text paths read the loaded glyph)
    helpers = {k: getattr(_text_helpers, k) for k in dir(_text_helpers) if not k.startswith("__")}
    helpers["layout"] = _layout
    setattr(backend_pdf, "_text_helpers", SimpleNamespace(**helpers))  # noqa: B010
    return True
