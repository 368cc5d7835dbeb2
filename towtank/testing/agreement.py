"""How far a day in another lab's layout lies from the same day as plain CSV.

The same synthetic day (same seed, same runs) written in any file layout of
:mod:`towtank.testing.layouts` and with any run sheet must give the plain day's results:

- a hull day's coefficients within :data:`LAYOUT_RTOL` of the plain day's (relative) or a
  tenth (:data:`INTERVAL_FRACTION`) of their 95 % half-width, whichever is larger: a layout's
  own reading (a 100 Hz carriage log on another clock, an encoder's steps) moves a coefficient
  known to ±7 % (X_uv) or not at all (an added mass in air) by more than 0.1 % of its value,
  but by nothing that matters against its uncertainty;
- ``zero-file`` and ``no-speed``: each coefficient within the mean of the two days' 95 %
  half-widths (a zeros file is another recording of the zero, with its own noise; without a
  speed channel the set speed, the sheet's steady windows and no added mass, as no
  acceleration is measured);
- a fin day's C_L and C_D of every run within :data:`LAYOUT_RTOL` of the largest |C_L|,
  |C_D| of the plain day.

:func:`layout_gaps` gives each result's distance in units of what is allowed: the day agrees
when every gap is at most 1.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

__all__ = ["INTERVAL_FRACTION", "LAYOUT_RTOL", "layout_gaps"]

#: Relative tolerance of a layout's results against the plain CSV day's.
LAYOUT_RTOL = 1e-3
#: The part of a coefficient's 95 % half-width a layout's reading may move it by.
INTERVAL_FRACTION = 0.1

#: The coefficients a day without a measured speed cannot give.
_ADDED_MASSES = ("X_udot", "Y_vdot", "Z_wdot")


def _half_width(table: pd.DataFrame) -> pd.Series:
    return (table["ci_high"] - table["ci_low"]) / 2.0


def layout_gaps(layout: str, got: pd.DataFrame, ref: pd.DataFrame, *,
                fins: bool = False) -> dict[str, float]:
    """Each result's distance from the plain day's, as a fraction of what ``layout`` allows.

    Parameters
    ----------
    layout : str
        The file layout (``csv``, ``tdms``, ``zero-file``, ``no-speed``, ...).
    got, ref : DataFrame
        coefficients.csv (``symbol, value, ci_low, ci_high``) of the layout's day and of the
        plain day, or with ``fins`` their fins.csv (``run, cl, cd``).
    fins : bool
        Compare fin days (C_L, C_D per run) rather than hull coefficients.

    Returns
    -------
    dict
        ``{symbol: gap}`` (fins: ``{"cl run N": gap, ...}``); a result the plain day has and the
        layout's day lacks (or has and should not) is ``inf``.
    """
    if fins:
        a, b = got.set_index("run"), ref.set_index("run")
        out: dict[str, float] = {}
        for col in ("cl", "cd"):
            scale = LAYOUT_RTOL * float(b[col].abs().max())
            diff = (a[col].reindex(b.index) - b[col]).abs() / scale
            out |= {f"{col} run {r}": float(v) if math.isfinite(v) else math.inf
                    for r, v in diff.items()}
        return out
    mine, table = got.set_index("symbol"), ref.set_index("symbol")
    expected = [s for s in table.index if not (layout == "no-speed" and s in _ADDED_MASSES)]
    out = {s: math.inf for s in set(expected) ^ set(mine.index)}
    common = [s for s in expected if s in mine.index]
    diff = (mine.loc[common, "value"] - table.loc[common, "value"]).abs()
    half = _half_width(table.loc[common])
    if layout in ("no-speed", "zero-file"):
        allowed = (half + _half_width(mine.loc[common])) / 2.0
    else:
        allowed = np.maximum(LAYOUT_RTOL * table.loc[common, "value"].abs(),
                             INTERVAL_FRACTION * half)
    return out | {s: float(v) for s, v in (diff / allowed).items()}
