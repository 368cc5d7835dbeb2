"""One mathtext layout cache for the whole process, shared by every page of every report.

matplotlib lays out a ``$...$`` string with :class:`matplotlib.mathtext.MathTextParser`, whose
cache is an ``lru_cache`` of 50 entries keyed on the parser instance. Every page saved to a PDF
gets a new renderer and so a new parser: a symbol such as ``$X_{\\dot u}$`` is parsed again
on every page, and a report's few hundred math strings overflow the 50 entries within a page.
:func:`install` gives the parsers one larger cache keyed on what a layout depends on (the
parser's output type, the string, dpi, font properties, antialiasing, glyph-loading flags and
the ``mathtext.*`` rc settings), not on the parser instance. The layouts are the same as
matplotlib's (the same function computes them), so the report's pixels do not change.
"""

from __future__ import annotations

import functools
import inspect
from typing import Any

import matplotlib as mpl
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


def _parameters(func: Any) -> tuple[str, ...]:
    return tuple(inspect.signature(func).parameters)


@functools.lru_cache(MATH_CACHE_SIZE)
def _parse_shared(output_type: str, s: str, dpi: float, prop: Any, antialiased: bool,
                  load_glyph_flags: Any, rc: tuple[Any, ...]) -> Any:
    """matplotlib's own uncached parse, run by one parser of ``output_type``; ``rc`` is in
    the key only (the ``mathtext.*`` settings the parse reads)."""
    assert _PARSE is not None
    parser = _PARSERS.setdefault(output_type, MathTextParser("agg" if output_type == "raster"
                                                             else "path"))
    return _PARSE(parser, s, dpi, prop, antialiased, load_glyph_flags)


def _parse_cached(self: MathTextParser, s: str, dpi: float, prop: Any, antialiased: bool,
                  load_glyph_flags: Any) -> Any:
    rc = tuple(rc_value(mpl.rcParams[k]) for k in _RC_KEYS)
    return _parse_shared(getattr(self, "_output_type"), s, dpi, prop, antialiased,  # noqa: B009
                         load_glyph_flags, rc)


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
