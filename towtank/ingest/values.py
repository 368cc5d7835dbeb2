"""Numbers as a protocol or a sheet gives them, and values as a message shows them.

:func:`finite_number` takes any parsed value (TOML, a sheet cell) to a finite float or None,
never raising: an integer of 310 digits is too large for a float, and ``float()`` of it raises
``OverflowError``. :func:`shown` writes a value into a sentence, shortened when it is long.
"""

from __future__ import annotations

import math
import sys
from typing import Any

__all__ = ["finite_number", "shown"]


def finite_number(value: Any) -> float | None:
    """A TOML number as a finite float; None for anything else (text, true/false, inf, nan, an
    integer too large for a float, such as one of 400 digits)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    try:
        out = float(value)
    except OverflowError:
        return None
    return out if math.isfinite(out) else None


def shown(value: Any) -> str:
    """``value`` for a message: its repr, shortened when long (an integer of more than 20
    digits as ``999999…, an integer of 310 digits``)."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10**20:
        try:
            digits = str(abs(value))
        except ValueError:  # more digits than Python converts to text
            return f"an integer of more than {sys.get_int_max_str_digits()} digits"
        return f"{'-' if value < 0 else ''}{digits[:6]}…, an integer of {len(digits)} digits"
    text = repr(value)
    return text if len(text) <= 80 else f"{text[:40]}… ({len(text)} characters)"
