"""Gertler's (1950) Series 58 bodies of revolution: the sixth-degree polynomial.

Gertler, M. (1950), *Resistance experiments on a systematic series of streamlined bodies of
revolution - for application to the design of high-speed submarines*, DTMB Report C-297
(Report 789), David Taylor Model Basin, with the polynomial form of Landweber, L. and Gertler,
M. (1950), *Mathematical formulation of bodies of revolution*, DTMB Report 719. The profile
for prediction is :func:`towtank.vehicle.hull.series58_profile`.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["SERIES58_PARENT", "series58_coefficients", "series58_radius", "check_series58"]

_N_CHECK = 4001


#: The default Series 58 parameters [-] (Gertler 1950): position of the largest section
#: m = x_m/L = 0.4, nose radius r0 = R0 L/D^2 = 0.5, tail radius r1 = R1 L/D^2 = 0.1, prismatic
#: coefficient Cp = 0.65. Cp is the design tool's: its Table 6 Series 58 vehicle of 150 kg is
#: 2.41 m long and 0.344 m in diameter (L/D = 7.0), and at Cp = 0.65 it displaces 149.4 kg of
#: sea water (1025.85 kg/m^3), its printed 150 kg within 0.5 %. m, r0 and r1 are towtank's
#: choice of a member of the series, not checked against Gertler's table.
SERIES58_PARENT = {"m": 0.4, "r0": 0.5, "r1": 0.1, "cp": 0.65}


def series58_coefficients(m: float, r0: float, r1: float, cp: float) -> np.ndarray:
    """Gertler's (1950) sixth-degree polynomial of a Series 58 body.

    ``(r/D)^2 = a1 xi + a2 xi^2 + ... + a6 xi^6`` with ``xi = x/L`` from the nose. The six
    coefficients solve the six conditions of Landweber & Gertler (1950):

    - nose radius of curvature R0: ``(r/D)^2 -> 2 r0 xi`` at the nose, so ``a1 = 2 r0``;
    - closed tail: ``sum a_i = 0``;
    - tail radius of curvature R1: ``d(r/D)^2/dxi = -2 r1`` at ``xi = 1``,
      ``sum i a_i = -2 r1``;
    - largest section at ``xi = m``: ``sum a_i m^i = 1/4`` and ``sum i a_i m^(i-1) = 0``;
    - prismatic coefficient: ``integral of (r/D)^2 dxi = Cp/4``, ``sum a_i/(i+1) = Cp/4``.

    Parameters
    ----------
    m : float
        Position of the largest section over the length, x_m/L [-], 0 < m < 1
    r0 : float
        Nose radius of curvature R0 made non-dimensional, R0 L/D^2 [-], >= 0
    r1 : float
        Tail radius of curvature R1 made non-dimensional, R1 L/D^2 [-], >= 0
    cp : float
        Prismatic coefficient V/((pi/4) D^2 L) [-], 0 < Cp < 1

    Returns
    -------
    numpy.ndarray
        a1 ... a6 [-]

    Raises
    ------
    ValueError
        Parameters outside those ranges, in one sentence.
    """
    for name, value, ok, rng in (("m", m, 0.0 < m < 1.0, "more than 0 and less than 1"),
                                 ("r0", r0, r0 >= 0.0, "at least 0"),
                                 ("r1", r1, r1 >= 0.0, "at least 0"),
                                 ("cp", cp, 0.0 < cp < 1.0, "more than 0 and less than 1")):
        if not (math.isfinite(value) and ok):
            raise ValueError(f"The Series 58 parameter {name} must be finite and {rng}, "
                             f"not {value}.")
    i = np.arange(1, 7, dtype=float)
    lhs = np.array([[1.0, 0, 0, 0, 0, 0], np.ones(6), i, m**i, i * m ** (i - 1), 1.0 / (i + 1)])
    rhs = np.array([2.0 * r0, 0.0, -2.0 * r1, 0.25, 0.0, cp / 4.0])
    return np.linalg.solve(lhs, rhs)


def series58_radius(xi: np.ndarray, coefficients: np.ndarray) -> np.ndarray:
    """``r/D`` of a Series 58 body at ``xi = x/L`` (0 nose, 1 tail) [-].

    ``r/D = sqrt(sum a_i xi^i)``, the polynomial of :func:`series58_coefficients`; where round-off
    makes the square slightly negative at the ends the radius is 0.
    """
    xi = np.asarray(xi, dtype=float)
    square = np.polyval(np.r_[np.asarray(coefficients, float)[::-1], 0.0], xi)
    return np.sqrt(np.maximum(square, 0.0))


def check_series58(length_m: float, diameter_m: float, m: float, r0: float, r1: float,
                   cp: float) -> np.ndarray:
    """The coefficients of a Series 58 body that exists, else ValueError in one sentence.

    Parameters
    ----------
    length_m, diameter_m : float
        Overall length L and largest diameter D [m], positive
    m, r0, r1, cp : float
        Gertler's parameters [-] (:func:`series58_coefficients`)

    Raises
    ------
    ValueError
        A length or diameter that is not a positive number, parameters outside their ranges,
        or parameters whose polynomial is no body: ``(r/D)^2`` negative somewhere, or larger
        than 1/4 (the body fatter than D) away from ``m``.
    """
    for name, value in (("length_m", length_m), ("diameter_m", diameter_m)):
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"The Series 58 {name} must be a positive number [m], not {value}.")
    a = series58_coefficients(m, r0, r1, cp)
    xi = 0.5 * (1.0 - np.cos(np.linspace(0.0, np.pi, _N_CHECK)))
    square = np.polyval(np.r_[a[::-1], 0.0], xi)
    tol = 1e-9
    if square.min() < -tol or square.max() > 0.25 + tol:
        bad = xi[np.argmin(square)] if square.min() < -tol else xi[np.argmax(square)]
        what = "negative" if square.min() < -tol else "above (D/2)^2"
        raise ValueError(
            f"The Series 58 parameters m = {m:g}, r0 = {r0:g}, r1 = {r1:g}, cp = {cp:g} give "
            f"no body of revolution: the radius squared of Gertler's polynomial is {what} at "
            f"x/L = {bad:.3f}.")
    return a
