"""Hull libraries for prediction: a body of revolution as a radius profile ``r(x)``.

Four sources: Myring's parametric hull (:mod:`towtank.reference.geometry`), the DARPA SUBOFF
bare hull (AFF-1) of Groves, Huang & Chang (1989), Gertler's (1950) Series 58 polynomial
bodies, and a radius table (``x_m, r_m``, nose to tail) for any other hull. Every profile is
sampled on a dense grid; the integrals the prediction needs (volume, wetted area, centre of
buoyancy) are trapezoidal sums on that grid.

References
----------
.. [1] Groves, N. C., Huang, T. T. and Chang, M. S. (1989), Geometric characteristics of DARPA
   SUBOFF models, DTRC/SHD-1298-01, David Taylor Research Center: bare-hull equations of the
   forebody, parallel midbody, afterbody and afterbody cap (lengths in feet, L = 14.2917 ft,
   R_max = 0.8333 ft).
.. [2] Myring, D. F. (1976), Aeronautical Quarterly 27(3), 186-194; Prestero, T. (2001), MIT/WHOI
   thesis, chapter 2.
.. [3] Gertler, M. (1950), Resistance experiments on a systematic series of streamlined bodies
   of revolution - for application to the design of high-speed submarines, DTMB Report C-297
   (Report 789), David Taylor Model Basin; the polynomial form of Landweber, L. and Gertler, M.
   (1950), Mathematical formulation of bodies of revolution, DTMB Report 719.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.integrate import trapezoid

from towtank.reference import geometry
from towtank.reference.series58 import (
    SERIES58_PARENT,
    check_series58,
    series58_coefficients,
    series58_radius,
)
from towtank.vehicle.schema import check_hull, joined

__all__ = [
    "HullProfile",
    "SUBOFF_LENGTH_M",
    "SERIES58_PARENT",
    "myring_profile",
    "series58_coefficients",
    "series58_profile",
    "series58_radius",
    "suboff_profile",
    "table_profile",
    "spheroid_profile",
]

#: Length of the full-scale DARPA SUBOFF model, 14.2917 ft [m] (Groves et al. 1989).
SUBOFF_LENGTH_M = 14.291667 * 0.3048
_N_GRID = 4001


@dataclass(frozen=True)
class HullProfile:
    """A body of revolution: radius ``r_m`` at stations ``x_m`` aft of the nose tip.

    Attributes
    ----------
    x_m : numpy.ndarray
        Stations from the nose tip, increasing aft [m]
    r_m : numpy.ndarray
        Radius at each station [m]
    name : str
        Which hull ("myring", "suboff", "series58", "table", "spheroid")
    source : str
        Where the profile comes from (equation and reference, or the table's file)
    """

    x_m: np.ndarray
    r_m: np.ndarray
    name: str
    source: str

    @property
    def length(self) -> float:
        """Overall length L [m]."""
        return float(self.x_m[-1] - self.x_m[0])

    @property
    def max_diameter(self) -> float:
        """Largest diameter D [m]."""
        return float(2.0 * self.r_m.max())

    @property
    def volume(self) -> float:
        """Displaced volume ``integral of pi r^2 dx`` [m^3]."""
        return float(trapezoid(np.pi * self.r_m**2, self.x_m))

    @property
    def x_buoyancy(self) -> float:
        """Centre of buoyancy aft of the nose tip [m]."""
        area = np.pi * self.r_m**2
        return float(trapezoid(area * self.x_m, self.x_m) / trapezoid(area, self.x_m))

    @property
    def wetted_area(self) -> float:
        """Curved surface area ``integral of 2 pi r ds`` along the profile [m^2]."""
        ds = np.hypot(np.diff(self.x_m), np.diff(self.r_m))
        return float(np.sum(np.pi * (self.r_m[1:] + self.r_m[:-1]) * ds))

    @property
    def lateral_area(self) -> float:
        """Projected side area ``integral of 2 r dx`` [m^2]."""
        return float(trapezoid(2.0 * self.r_m, self.x_m))

    def scaled(self, factor: float) -> HullProfile:
        """The geometrically similar hull ``factor`` times as long."""
        return HullProfile(self.x_m * factor, self.r_m * factor, self.name,
                           f"{self.source}, scaled by {factor:g}")


def _grid(length: float, n: int = _N_GRID) -> np.ndarray:
    # cosine spacing: dense at both ends, where the radius changes fastest
    return 0.5 * length * (1.0 - np.cos(np.linspace(0.0, np.pi, n)))


def myring_profile(
    a: float, b: float, c: float, n: float, theta_deg: float, d: float,
    a_offset: float = 0.0, c_offset: float = 0.0,
) -> HullProfile:
    """The Myring hull of :func:`towtank.reference.geometry.myring_radius` as a profile.

    Parameters
    ----------
    a, b, c : float
        Full nose, midbody and tail lengths [m]
    n : float
        Nose shape exponent [-]
    theta_deg : float
        Tail semi-angle [°]
    d : float
        Midbody diameter [m]
    a_offset, c_offset : float
        Lengths cut off the nose tip and the tail end [m]

    Returns
    -------
    HullProfile
    """
    length = a + b + c - a_offset - c_offset
    x = _grid(length)
    r = np.asarray(geometry.myring_radius(x, a, b, c, n, theta_deg, d, a_offset, c_offset))
    return HullProfile(x, r, "myring", "Myring (1976) profile, Prestero (2001) truncation")


def suboff_radius(x_ft: np.ndarray) -> np.ndarray:
    """Radius of the DARPA SUBOFF bare hull (AFF-1) [ft] at ``x_ft`` aft of the nose [ft].

    Groves, Huang & Chang (1989) [1]_: forebody (0 <= x <= 3.333333),
    ``r = R [1.126395101 x (0.3x-1)^4 + 0.442874707 x^2 (0.3x-1)^3
    + 1 - (0.3x-1)^4 (1.2x+1)]^(1/2.1)``;
    midbody ``r = R`` to x = 10.645833; afterbody with ``xi = (13.979167 - x)/3.333333``,
    ``r = R [rh^2 + rh K0 xi^2 + (20 - 20 rh^2 - 4 rh K0 - K1/3) xi^3
    + (-45 + 45 rh^2 + 6 rh K0 + K1) xi^4 + (36 - 36 rh^2 - 4 rh K0 - K1) xi^5
    + (-10 + 10 rh^2 + rh K0 + K1/3) xi^6]^(1/2)``, rh = 0.1175, K0 = 10, K1 = 44.6244; cap to
    x = 14.291667, ``r = rh R [1 - (3.2 x - 44.733333)^2]^(1/2)``; R = 0.833333 ft.
    """
    x = np.asarray(x_ft, dtype=float)
    big_r, rh, k0, k1 = 0.833333, 0.1175, 10.0, 44.6244
    r = np.zeros_like(x)
    fore = (x >= 0) & (x <= 3.333333)
    t = 0.3 * x[fore] - 1.0
    xf = x[fore]
    inner = 1.126395101 * xf * t**4 + 0.442874707 * xf**2 * t**3 + 1.0 - t**4 * (1.2 * xf + 1.0)
    r[fore] = big_r * np.maximum(inner, 0.0) ** (1.0 / 2.1)
    r[(x > 3.333333) & (x <= 10.645833)] = big_r
    aft = (x > 10.645833) & (x <= 13.979167)
    xi = (13.979167 - x[aft]) / 3.333333
    poly = (rh**2 + rh * k0 * xi**2 + (20 - 20 * rh**2 - 4 * rh * k0 - k1 / 3) * xi**3
            + (-45 + 45 * rh**2 + 6 * rh * k0 + k1) * xi**4
            + (36 - 36 * rh**2 - 4 * rh * k0 - k1) * xi**5
            + (-10 + 10 * rh**2 + rh * k0 + k1 / 3) * xi**6)
    r[aft] = big_r * np.sqrt(np.maximum(poly, 0.0))
    cap = (x > 13.979167) & (x <= 14.291667)
    r[cap] = rh * big_r * np.sqrt(np.maximum(1.0 - (3.2 * x[cap] - 44.733333) ** 2, 0.0))
    return r


def suboff_profile(length_m: float = SUBOFF_LENGTH_M) -> HullProfile:
    """The DARPA SUBOFF bare hull (AFF-1), geometrically scaled to ``length_m`` [m] ([1]_)."""
    if not (math.isfinite(length_m) and length_m > 0):
        raise ValueError(f"The SUBOFF length must be > 0 m, not {length_m}.")
    x_ft = _grid(14.291667)
    scale = length_m / (14.291667 * 0.3048)
    x = x_ft * 0.3048 * scale
    r = suboff_radius(x_ft) * 0.3048 * scale
    return HullProfile(x, r, "suboff", "DARPA SUBOFF AFF-1 bare hull, Groves, Huang & Chang "
                       "(1989) DTRC/SHD-1298-01" + (f", scaled to L = {length_m:g} m"
                                                    if abs(scale - 1) > 1e-9 else ""))


def series58_profile(length_m: float, diameter_m: float, m: float = SERIES58_PARENT["m"],
                     r0: float = SERIES58_PARENT["r0"], r1: float = SERIES58_PARENT["r1"],
                     cp: float = SERIES58_PARENT["cp"]) -> HullProfile:
    """A Series 58 body (Gertler 1950 [3]_) of length ``length_m`` [m] and largest diameter
    ``diameter_m`` [m].

    ``r(x) = D sqrt(sum a_i (x/L)^i)`` with the coefficients of
    :func:`towtank.reference.series58.series58_coefficients` (Gertler's six conditions on m,
    r0, r1, Cp). Its volume is ``Cp (pi/4) D^2 L`` and its centre of buoyancy
    ``L sum(a_i/(i+2)) / sum(a_i/(i+1))`` aft of the nose (both exact integrals of the
    polynomial); the wetted area is the integral of ``2 pi r ds`` on the grid.

    Raises
    ------
    ValueError
        A length or diameter that is not a positive number, parameters outside their ranges,
        or parameters whose polynomial is no body
        (:func:`towtank.reference.series58.check_series58`), in one sentence.
    """
    a = check_series58(length_m, diameter_m, m, r0, r1, cp)
    xi = _grid(1.0)
    x = xi * length_m
    r = diameter_m * series58_radius(xi, a)
    return HullProfile(x, r, "series58",
                       f"Series 58 (Gertler 1950, DTMB Report 789) m = {m:g}, r0 = {r0:g}, "
                       f"r1 = {r1:g}, Cp = {cp:g}, L = {length_m:g} m, D = {diameter_m:g} m")


def spheroid_profile(length_m: float, diameter_m: float, n: int = _N_GRID) -> HullProfile:
    """A prolate spheroid ``r = (D/2) sqrt(1 - (2x/L - 1)^2)`` (for checks against Lamb)."""
    x = _grid(length_m, n)
    r = 0.5 * diameter_m * np.sqrt(np.maximum(1.0 - (2.0 * x / length_m - 1.0) ** 2, 0.0))
    return HullProfile(x, r, "spheroid",
                       f"prolate spheroid L = {length_m:g} m, D = {diameter_m:g} m")


def table_profile(path: str | Path) -> HullProfile:
    """A radius table: a CSV with the columns ``x_m`` and ``r_m``, nose to tail.

    The stations are shifted so that the first is at 0 and must increase strictly; radii must
    be finite and non-negative. Between stations the radius is linear (the integrals are the
    trapezoidal sums over the table's own stations).

    Raises
    ------
    ValueError
        A missing column, fewer than 3 stations, non-increasing stations, a negative radius,
        a length outside 0.01 to 1000 m or a fineness ratio L/D outside 0.5 to 500
        (:func:`towtank.vehicle.schema.check_hull`), with one sentence naming the file.
    """
    path = Path(path)
    try:
        df = pd.read_csv(path, comment="#")
    except (OSError, ValueError) as exc:
        raise ValueError(f"{path.name}: the hull table cannot be read ({exc}).") from None
    df.columns = [str(c).strip() for c in df.columns]
    for col in ("x_m", "r_m"):
        if col not in df.columns:
            raise ValueError(f"{path.name}: the hull table lacks the column '{col}'.")
    x = pd.to_numeric(df["x_m"], errors="coerce").to_numpy(float)
    r = pd.to_numeric(df["r_m"], errors="coerce").to_numpy(float)
    if len(x) < 3 or not (np.all(np.isfinite(x)) and np.all(np.isfinite(r))):
        raise ValueError(f"{path.name}: the hull table needs at least 3 rows of numbers x_m, r_m.")
    if np.any(np.diff(x) <= 0):
        raise ValueError(f"{path.name}: x_m must increase strictly from nose to tail.")
    if np.any(r < 0) or r.max() <= 0:
        raise ValueError(f"{path.name}: r_m must be >= 0 m with at least one positive radius.")
    problems = check_hull(x, r, path.name)  # a length or fineness no vehicle has
    if problems:
        raise ValueError(joined(problems))
    return HullProfile(x - x[0], r, "table", f"radius table {path.name}")
