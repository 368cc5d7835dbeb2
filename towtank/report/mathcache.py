"""One mathtext layout cache for the whole process, shared by every page of every report.

matplotlib lays out a ``$...$`` string with :class:`matplotlib.mathtext.MathTextParser`, whose
cache is an ``lru_cache`` of 50 entries keyed on the parser instance. Every page saved to a PDF
gets a new renderer and so a new parser: a symbol such as ``$X_{\\dot u}$`` is parsed again
on every page, and a report's few hundred math strings overflow the 50 entries within a page.
:func:`install` gives the parsers one larger cache keyed on what a layout depends on (the
parser's output type, the string, dpi, font properties, antialiasing, glyph-loading flags and
the ``mathtext.*`` rc settings), not on the parser instance. The layouts are the same as
matplotlib's (the same function computes them), so the report's pixels do not change.

A layout names the font objects its glyphs are drawn from, and FreeType reads a font's file
lazily, through the file position of the object's open file. A forked process shares that
position with its parent, so the two must never read through one object: two processes seeking
and reading one file position read each other's bytes ("invalid outline", "too many hints", or
a wrong glyph). matplotlib's own font cache is emptied in a forked process for that reason; the
layouts this process inherits are likewise set aside at a fork and, when asked for again, given
the child's own font objects (:func:`_own_fonts`): the same layout, no new parse.
"""

from __future__ import annotations

import inspect
import os
from typing import Any

import matplotlib as mpl
from matplotlib.font_manager import get_font
from matplotlib.mathtext import MathTextParser

__all__ = ["install", "rc_value", "MATH_CACHE_SIZE"]

#: Math strings kept laid out (a sample-hull report has ≈ 200 distinct ones).
MATH_CACHE_SIZE = 2048

#: The private method of matplotlib's parser that lays a string out through its small cache.
_METHOD = "_parse_cached"
_PARSE = getattr(getattr(MathTextParser, _METHOD, None), "__wrapped__", None)
_RC_KEYS = tuple(sorted(k for k in mpl.rcParams if k.startswith("mathtext.")))
_PARSERS: dict[str, MathTextParser] = {}
_EXPECTED = ("self", "s", "dpi", "prop", "antialiased", "load_glyph_flags")

#: Layouts made in this process (or given its font objects), by what they depend on.
_LAYOUTS: dict[tuple[Any, ...], Any] = {}
#: Layouts a parent process made before it forked this one: their glyphs name the parent's
#: font objects (see the module's text).
_INHERITED: dict[tuple[Any, ...], Any] = {}


def _set_aside_at_fork() -> None:
    """In a forked process: every layout so far is the parent's."""
    _INHERITED.update(_LAYOUTS)
    _LAYOUTS.clear()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_set_aside_at_fork)


def _parameters(func: Any) -> tuple[str, ...]:
    return tuple(inspect.signature(func).parameters)


def _parse_new(output_type: str, s: str, dpi: float, prop: Any, antialiased: bool,
               load_glyph_flags: Any) -> Any:
    """matplotlib's own uncached parse, run by one parser of ``output_type``."""
    assert _PARSE is not None
    parser = _PARSERS.setdefault(output_type, MathTextParser("agg" if output_type == "raster"
                                                             else "path"))
    return _PARSE(parser, s, dpi, prop, antialiased, load_glyph_flags)


def _own_fonts(parse: Any) -> Any:
    """An inherited layout with each glyph's font object this process's own: the one
    matplotlib's font cache gives for the same file, as the parse itself would have loaded it
    (a raster layout is an image and names no font)."""
    glyphs = getattr(parse, "glyphs", None)
    if not glyphs:
        return parse
    return parse._replace(glyphs=[(get_font(g[0].fname), *g[1:]) for g in glyphs])


def _parse_cached(self: MathTextParser, s: str, dpi: float, prop: Any, antialiased: bool,
                  load_glyph_flags: Any) -> Any:
    output_type = getattr(self, "_output_type")  # noqa: B009
    rc = tuple(rc_value(mpl.rcParams[k]) for k in _RC_KEYS)  # the mathtext.* settings read
    key = (output_type, s, dpi, prop, antialiased, load_glyph_flags, rc)
    found = _LAYOUTS.get(key)
    if found is None:
        inherited = _INHERITED.pop(key, None)
        found = (_own_fonts(inherited) if inherited is not None
                 else _parse_new(output_type, s, dpi, prop, antialiased, load_glyph_flags))
        if len(_LAYOUTS) >= MATH_CACHE_SIZE:
            _LAYOUTS.clear()
        _LAYOUTS[key] = found
    return found


def rc_value(value: Any) -> Any:
    """An rc value as a hashable key part (a list as a tuple)."""
    return tuple(value) if isinstance(value, list) else value


def install() -> bool:
    """Make every :class:`~matplotlib.mathtext.MathTextParser` use the shared cache (once;
    later calls do nothing). Returns whether the shared cache is in use: not with a
    matplotlib whose parser is not built as expected, which then keeps its own cache."""
    if getattr(MathTextParser, _METHOD, None) is _parse_cached:
        return True
    if _PARSE is None or _parameters(_PARSE) != _EXPECTED:
        return False
    setattr(MathTextParser, _METHOD, _parse_cached)
    return True
