"""The report writer's speed-ups keep matplotlib's output: the shared mathtext cache."""

from __future__ import annotations

import matplotlib as mpl
from matplotlib.font_manager import FontProperties
from matplotlib.ft2font import LoadFlags
from matplotlib.mathtext import MathTextParser

import towtank.report.figure_base  # noqa: F401  # installs the shared cache
from towtank.report import mathcache


def test_math_layout_shared_between_parsers_and_unchanged() -> None:
    """Two renderers' parsers (one per PDF page) lay out a string once, and the layout is
    the one matplotlib's own uncached parse makes."""
    installed = getattr(MathTextParser, mathcache._METHOD)
    assert installed is mathcache._parse_cached, "importing the report installs the cache"
    prop = FontProperties(family="DejaVu Sans", size=7.5)
    text = r"$X_{\dot u}$ = m − (D_a − D_s)/a, shared-cache probe"
    first = MathTextParser("path").parse(text, 72, prop)
    second = MathTextParser("path").parse(text, 72, prop)
    assert second is first, "a second page's parser reuses the first page's layout"
    assert mathcache._PARSE is not None
    fresh = mathcache._PARSE(MathTextParser("path"), text, 72, prop.copy(), True,
                             LoadFlags.NO_HINTING)
    assert (fresh.width, fresh.height, fresh.depth) == (first.width, first.height, first.depth)
    assert len(fresh.glyphs) == len(first.glyphs) and len(fresh.rects) == len(first.rects)


def test_math_layout_follows_mathtext_rc() -> None:
    """A changed ``mathtext.*`` setting lays the string out anew, as matplotlib would."""
    prop = FontProperties(family="DejaVu Sans", size=9)
    text = r"$x_{probe}$"
    with mpl.rc_context({"mathtext.default": "it"}):
        italic = MathTextParser("path").parse(text, 72, prop)
    with mpl.rc_context({"mathtext.default": "rm"}):
        upright = MathTextParser("path").parse(text, 72, prop)
    assert upright is not italic, "the rc setting is part of the cache key"
    fonts = {tuple(g[0].fname for g in parse.glyphs) for parse in (italic, upright)}
    assert len(fonts) == 2, "upright and italic letters come from different fonts"
