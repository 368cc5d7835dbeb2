"""NACA 0015 section lift and drag from Sheldahl & Klimas (1981), SAND80-2114.

The table shipped in ``towtank/reference/data/naca0015_sandia.csv`` gives the two-dimensional
(infinite
aspect ratio) lift and drag coefficients of the NACA 0015 section from 0 to 180 deg angle of
attack at 11 Reynolds numbers from 1e4 to 1e7 [1]_. It is read once and cached.

Interpolation (docs/method.md, "Fins"): linear in the angle of attack at each of the two tabulated
Reynolds numbers that bracket the requested one, then linear in log10(Re) between those two. The
section is symmetric, so negative angles use C_L(-alpha) = -C_L(alpha), C_D(-alpha) = C_D(alpha).

Out-of-range policy
-------------------
- ``|alpha| > 180 deg`` is not an angle of attack the table can describe: ``ValueError`` naming the
  offending value. (Wrap angles into [-180, 180] before calling.)
- Reynolds numbers outside [1e4, 1e7] are, by default (``out_of_range="clamp"``), *clamped* to the
  nearest tabulated Reynolds number and a :class:`SandiaRangeWarning` names the Re and the limit
  used. Clamping rather than extrapolating in log10(Re) is deliberate: below 1e5 the section data
  change fast and non-monotonically with Re, so a straight-line extrapolation could give values
  that no section has. ``out_of_range="nan"`` returns NaN there instead (no warning) and
  ``out_of_range="raise"`` raises ``ValueError``.
- A Reynolds number that is zero or negative is always a ``ValueError``.
- NaN in either input gives NaN in both outputs (never an error, never a warning).

References
----------
.. [1] Sheldahl, R. E. and Klimas, P. C. (1981), Aerodynamic Characteristics of Seven Symmetrical
   Airfoil Sections Through 180-Degree Angle of Attack for Use in Aerodynamic Analysis of Vertical
   Axis Wind Turbines, SAND80-2114, Sandia National Laboratories, Albuquerque NM.
"""

from __future__ import annotations

import functools
import io
import warnings
from importlib import resources
from pathlib import Path
from typing import Literal

import numpy as np
import numpy.typing as npt
import pandas as pd

__all__ = [
    "SandiaRangeWarning",
    "reynolds_numbers",
    "section_coefficients",
    "source",
    "table",
]

_DATA_FILE = "naca0015_sandia.csv"


class SandiaRangeWarning(UserWarning):
    """A Reynolds number lies outside the Sandia table and was clamped to its nearest limit."""


def _read_data_text(name: str) -> str:
    """Text of ``towtank/reference/data/<name>``, through importlib.resources.

    Python 3.11's ``importlib.resources`` cannot open a package that is imported as a namespace
    package through a setuptools editable-install finder ("MultiplexedPath only supports
    directories"); the file is then read from beside this module, where the package ships it.
    """
    try:
        return (resources.files("towtank.reference") / "data" / name).read_text(encoding="utf-8")
    except (NotADirectoryError, FileNotFoundError, TypeError):
        return (Path(__file__).resolve().parent / "data" / name).read_text(encoding="utf-8")


@functools.lru_cache(maxsize=1)
def _load() -> tuple[pd.DataFrame, str]:
    """Read the packaged CSV once: (table sorted by Re and alpha, source comment text)."""
    text = _read_data_text(_DATA_FILE)
    comments = [
        line[1:].strip() for line in text.splitlines() if line.lstrip().startswith("#")
    ]
    frame = pd.read_csv(io.StringIO(text), comment="#")
    frame = frame.astype(
        {"reynolds": float, "alpha_deg": float, "cl": float, "cd": float}
    ).sort_values(["reynolds", "alpha_deg"], ignore_index=True)
    return frame, "\n".join(comments)


@functools.lru_cache(maxsize=1)
def _grid() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The table as a grid: (log10 Re (n,), alpha [deg] (m,), C_L (n, m), C_D (n, m))."""
    frame, _ = _load()
    cl = frame.pivot(index="reynolds", columns="alpha_deg", values="cl")
    cd = frame.pivot(index="reynolds", columns="alpha_deg", values="cd")
    if cl.isna().to_numpy().any() or cd.isna().to_numpy().any():
        raise ValueError(
            f"The Sandia table {_DATA_FILE} is not a complete (Re, alpha) grid."
        )  # pragma: no cover - guards the shipped data file
    log_re = np.log10(cl.index.to_numpy(dtype=float))
    alpha = cl.columns.to_numpy(dtype=float)
    return log_re, alpha, cl.to_numpy(dtype=float), cd.to_numpy(dtype=float)


def table() -> pd.DataFrame:
    """The Sheldahl & Klimas (1981) NACA 0015 table [1]_ as shipped.

    Returns
    -------
    pandas.DataFrame
        Columns ``reynolds`` [-], ``alpha_deg`` [deg] (0 ... 180), ``cl`` [-], ``cd`` [-], sorted
        by Reynolds number then angle. A copy: changing it does not change the cached table.
    """
    frame, _ = _load()
    return frame.copy()


def source() -> str:
    """The source note of the shipped table: its ``#`` comment lines, without the ``#``."""
    _, text = _load()
    return text


def reynolds_numbers() -> np.ndarray:
    """The tabulated Reynolds numbers [-], ascending (1e4 ... 1e7, 11 values)."""
    frame, _ = _load()
    return np.unique(frame["reynolds"].to_numpy(dtype=float))


def _fmt(x: float) -> str:
    """A Reynolds number for a message: two significant digits, compact exponent (8.1e4)."""
    mantissa, _, exponent = f"{x:.1e}".partition("e")
    return f"{mantissa}e{int(exponent)}"


def section_coefficients(
    alpha_deg: npt.ArrayLike,
    reynolds: npt.ArrayLike,
    *,
    out_of_range: Literal["clamp", "nan", "raise"] = "clamp",
) -> tuple[np.ndarray, np.ndarray]:
    """Two-dimensional NACA 0015 lift and drag coefficients from the Sandia table.

    Bilinear interpolation of Sheldahl & Klimas (1981) [1]_ as docs/method.md prescribes ("Fins"):
    at each of the two tabulated Reynolds numbers Re_i <= Re <= Re_(i+1),

        C(alpha, Re_i) = C_ij + (C_i(j+1) - C_ij) (|alpha| - alpha_j) / (alpha_(j+1) - alpha_j),

    then, with w = (log10 Re - log10 Re_i) / (log10 Re_(i+1) - log10 Re_i),

        C(alpha, Re) = (1 - w) C(alpha, Re_i) + w C(alpha, Re_(i+1)),

    and the section's symmetry C_L(-alpha) = -C_L(alpha), C_D(-alpha) = C_D(alpha). Tabulated
    points are reproduced exactly.

    Parameters
    ----------
    alpha_deg : array_like
        Angle of attack [deg], -180 <= alpha <= 180. Broadcast against ``reynolds``.
    reynolds : array_like
        Reynolds number on the chord, U c / nu [-]. Must be positive.
    out_of_range : {"clamp", "nan", "raise"}, default "clamp"
        What to do with a Reynolds number outside the tabulated range [1e4, 1e7]: clamp it to
        the nearest limit with a :class:`SandiaRangeWarning`, return NaN, or raise ValueError.

    Returns
    -------
    cl : numpy.ndarray
        Section lift coefficient [-], shape of the broadcast inputs.
    cd : numpy.ndarray
        Section drag coefficient [-], shape of the broadcast inputs.

    Raises
    ------
    ValueError
        If any ``|alpha_deg| > 180``, any ``reynolds <= 0``, an unknown ``out_of_range``, or a
        Reynolds number out of range with ``out_of_range="raise"``.

    Warns
    -----
    SandiaRangeWarning
        With ``out_of_range="clamp"``, once per violated limit, naming the Re and the limit.
    """
    if out_of_range not in ("clamp", "nan", "raise"):
        raise ValueError(
            f"out_of_range must be 'clamp', 'nan' or 'raise', not {out_of_range!r}."
        )
    alpha, re = np.broadcast_arrays(
        np.asarray(alpha_deg, dtype=float), np.asarray(reynolds, dtype=float)
    )
    alpha = alpha.copy()
    re = re.copy()
    valid = ~(np.isnan(alpha) | np.isnan(re))

    too_big = valid & (np.abs(alpha) > 180.0)
    if too_big.any():
        bad = alpha[too_big].flat[0]
        raise ValueError(
            f"Angle of attack {bad:g} deg is outside [-180, 180] deg, the range of the "
            "Sandia NACA 0015 table; wrap it into that range first."
        )
    non_positive = valid & (re <= 0.0)
    if non_positive.any():
        bad = re[non_positive].flat[0]
        raise ValueError(f"Reynolds number {bad:g} is not positive.")

    log_re, alpha_grid, cl_grid, cd_grid = _grid()
    re_lo, re_hi = 10.0 ** log_re[0], 10.0 ** log_re[-1]
    below = valid & (re < re_lo)
    above = valid & (re > re_hi)
    if below.any() or above.any():
        if out_of_range == "raise":
            bad = re[below | above].flat[0]
            raise ValueError(
                f"Reynolds number {_fmt(bad)} is outside the Sandia NACA 0015 table's range "
                f"[{_fmt(re_lo)}, {_fmt(re_hi)}]."
            )
        if out_of_range == "nan":
            valid = valid & ~below & ~above
        else:
            for mask, limit, word in ((below, re_lo, "below"), (above, re_hi, "above")):
                if mask.any():
                    values = np.unique(re[mask])
                    shown = ", ".join(_fmt(v) for v in values[:5])
                    more = f" and {values.size - 5} more" if values.size > 5 else ""
                    warnings.warn(
                        f"Reynolds number {shown}{more} is {word} the Sandia NACA 0015 table's "
                        f"{'lowest' if word == 'below' else 'highest'} Re = {_fmt(limit)}; "
                        f"the section data at Re = {_fmt(limit)} are used instead.",
                        SandiaRangeWarning,
                        stacklevel=2,
                    )
            re = np.clip(re, re_lo, re_hi)

    a = np.where(valid, np.abs(alpha), 0.0)
    lr = np.where(valid, np.log10(np.where(valid, re, re_lo)), log_re[0])

    i = np.clip(np.searchsorted(log_re, lr, side="right") - 1, 0, log_re.size - 2)
    w = (lr - log_re[i]) / (log_re[i + 1] - log_re[i])
    j = np.clip(np.searchsorted(alpha_grid, a, side="right") - 1, 0, alpha_grid.size - 2)
    t = (a - alpha_grid[j]) / (alpha_grid[j + 1] - alpha_grid[j])

    def _interp(grid: np.ndarray) -> np.ndarray:
        at_lo = (1.0 - t) * grid[i, j] + t * grid[i, j + 1]
        at_hi = (1.0 - t) * grid[i + 1, j] + t * grid[i + 1, j + 1]
        return (1.0 - w) * at_lo + w * at_hi

    sign = np.where(alpha < 0.0, -1.0, 1.0)
    cl = np.where(valid, sign * _interp(cl_grid), np.nan)
    cd = np.where(valid, _interp(cd_grid), np.nan)
    return cl, cd
