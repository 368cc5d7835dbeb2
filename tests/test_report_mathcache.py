"""The report writer's speed-ups keep matplotlib's output: the shared mathtext cache."""

from __future__ import annotations

import multiprocessing as mp

import matplotlib as mpl
from matplotlib.font_manager import FontProperties, get_font
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


def _child_layout(text: str, prop: FontProperties, send) -> None:  # noqa: ANN001
    """In a forked process: the layout of ``text`` from the shared cache, whether each of its
    glyphs is drawn from this process's own font object, and the glyphs' numbers."""
    parse = MathTextParser("path").parse(text, 72, prop)
    send.send(([g[0] is get_font(g[0].fname) for g in parse.glyphs],
               [tuple(g[1:]) for g in parse.glyphs], (parse.width, parse.height, parse.depth)))
    send.close()


def test_a_forked_process_draws_an_inherited_layout_with_its_own_fonts() -> None:
    """FreeType reads a font file lazily through its font object's file position, which a
    forked process shares with its parent: a layout the parent made (its glyphs name the
    parent's font objects) is given the child's own font objects, the same layout otherwise.
    Two processes reading through one position read each other's bytes: a report whose
    forked writers drew math the parent had laid out failed with "invalid outline"."""
    prop = FontProperties(family="DejaVu Sans", size=8)
    text = r"$C_{D}(\alpha)$ and $X_{\dot u}$, fork probe"
    here = MathTextParser("path").parse(text, 72, prop)  # laid out (and cached) here
    assert all(g[0] is get_font(g[0].fname) for g in here.glyphs)
    ctx = mp.get_context("fork")
    recv, send = ctx.Pipe(duplex=False)
    child = ctx.Process(target=_child_layout, args=(text, prop, send))
    child.start()
    send.close()
    own, glyphs, size = recv.recv()
    child.join()
    assert own and all(own), "the child drew with the parent's font objects"
    assert glyphs == [tuple(g[1:]) for g in here.glyphs]
    assert size == (here.width, here.height, here.depth)
    again = MathTextParser("path").parse(text, 72, prop)
    assert again is here, "the parent's own layouts stay cached"
