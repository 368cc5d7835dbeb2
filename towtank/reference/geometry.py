"""Myring hull geometry: radius profile, areas and volume of a body of revolution.

The profile is Myring's (1976), *A theoretical study of body drag in subcritical axisymmetric
flow*, Aeronautical Quarterly 27(3), 186-194, in the truncated form used for REMUS by Prestero
(2001), *Verification of a six-degree of freedom simulation model for the REMUS autonomous
underwater vehicle*, MIT/WHOI Joint Program thesis, chapter 2 (hull profile equations and the
table of REMUS Myring parameters):

- ``a``, ``b``, ``c``: full lengths of the nose, the cylindrical midbody and the tail [m];
- ``n``: nose shape exponent, ``theta_deg``: tail semi-angle at the tip [°], ``d``: diameter [m];
- ``a_offset``, ``c_offset``: lengths cut off the full nose at its tip and the full tail at its
  end [m] (a truncated nose has a flat face of non-zero radius).

``x`` is measured aft from the truncated nose, so the nose ends at ``a - a_offset``, the tail begins
at ``l_f = a - a_offset + b`` and the hull ends at ``l = a + b + c - a_offset - c_offset``. The nose
and tail curves are those of the untruncated body. With Prestero's REMUS values (a = 0.191 m,
a_offset = 0.0165 m, b = 0.654 m, c = 0.541 m, c_offset = 0.0368 m) these give his
l_f = 0.828 m and l = 1.33 m.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike


@dataclass(frozen=True)
class HullGeometry:
    """Principal dimensions of a Myring hull (bare hull, no appendages).

    Attributes
    ----------
    length : float
        Overall length of the truncated hull, ``a + b + c - a_offset - c_offset`` [m]
    max_diameter : float
        Maximum diameter, that of the midbody [m]
    frontal_area : float
        Frontal (cross-section) area ``pi d^2 / 4`` [m^2]
    lateral_area : float
        Projected side area ``integral of 2 r dx`` [m^2]
    wetted_area : float
        Curved surface area ``integral of 2 pi r ds`` along the profile [m^2]; the flat faces of a
        truncated nose or tail are not included
    volume : float
        Displaced volume ``integral of pi r^2 dx`` [m^3]
    x_buoyancy : float
        Centre of buoyancy aft of the (truncated) nose [m]
    nose_radius : float
        Radius of the flat face at the truncated nose, 0 if untruncated [m]
    tail_radius : float
        Radius of the flat face at the truncated tail, 0 if untruncated [m]
    """

    length: float
    max_diameter: float
    frontal_area: float
    lateral_area: float
    wetted_area: float
    volume: float
    x_buoyancy: float
    nose_radius: float
    tail_radius: float


def _check_parameters(
    a: float,
    b: float,
    c: float,
    n: float,
    theta_deg: float,
    d: float,
    a_offset: float,
    c_offset: float,
) -> None:
    """Raise ValueError unless the parameters describe a Myring hull."""
    values = {"a": a, "b": b, "c": c, "n": n, "theta_deg": theta_deg, "d": d}
    values |= {"a_offset": a_offset, "c_offset": c_offset}
    for name, value in values.items():
        if not math.isfinite(value):
            raise ValueError(f"Myring parameter {name} must be finite, not {value}.")
    if d <= 0.0:
        raise ValueError(f"The diameter d must be > 0 m, not {d}.")
    if n <= 0.0:
        raise ValueError(f"The nose shape exponent n must be > 0, not {n}.")
    for name in ("a", "b", "c"):
        if values[name] < 0.0:
            raise ValueError(f"The length {name} must be >= 0 m, not {values[name]}.")
    if not 0.0 <= a_offset <= a:
        raise ValueError(f"a_offset must lie between 0 and a = {a} m, not {a_offset}.")
    if not 0.0 <= c_offset <= c:
        raise ValueError(f"c_offset must lie between 0 and c = {c} m, not {c_offset}.")
    if a + b + c - a_offset - c_offset <= 0.0:
        raise ValueError("The Myring parameters give a hull of zero length.")
    if c > 0.0:
        if not 0.0 <= theta_deg < 90.0:
            raise ValueError(f"The tail semi-angle must lie in [0, 90) degrees, not {theta_deg}.")
        # r'(eta) = eta (3 B eta - 2 A) with r'(c) = -tan(theta): the tail narrows all the way
        # exactly when A >= 0, i.e. tan(theta) <= 3 d / (2 c).
        theta_max = math.degrees(math.atan(1.5 * d / c))
        if theta_deg > theta_max:
            raise ValueError(
                f"A tail semi-angle of {theta_deg:g} degrees makes the tail bulge beyond the "
                f"midbody: with c = {c:g} m and d = {d:g} m it must not exceed "
                f"{theta_max:.4g} degrees."
            )


def _tail_coefficients(c: float, d: float, theta_deg: float) -> tuple[float, float]:
    """``A``, ``B`` of the tail ``r = d/2 - A eta^2 + B eta^3`` (Myring 1976; Prestero 2001)."""
    tan_theta = math.tan(math.radians(theta_deg))
    return 1.5 * d / c**2 - tan_theta / c, d / c**3 - tan_theta / c**2


def myring_radius(
    x: ArrayLike,
    a: float,
    b: float,
    c: float,
    n: float,
    theta_deg: float,
    d: float,
    a_offset: float = 0.0,
    c_offset: float = 0.0,
) -> float | np.ndarray:
    """Radius of a Myring hull at axial station ``x`` (Myring 1976; Prestero 2001).

    Nose, ``0 <= x < a - a_offset``:
    ``r = d/2 [1 - ((x + a_offset - a) / a)^2]^(1/n)``;
    midbody, up to ``l_f = a - a_offset + b``: ``r = d/2``;
    tail, up to ``l = l_f + c - c_offset``:
    ``r = d/2 - (3d/(2c^2) - tan(theta)/c)(x - l_f)^2 + (d/c^3 - tan(theta)/c^2)(x - l_f)^3``.
    ``a = 0`` means no nose and ``c = 0`` no tail (a flat end).

    Parameters
    ----------
    x : float or array_like
        Axial station aft of the truncated nose tip [m]
    a : float
        Full nose length [m]
    b : float
        Midbody length [m]
    c : float
        Full tail length [m]
    n : float
        Nose shape exponent [-] (2: elliptical nose)
    theta_deg : float
        Tail semi-angle at the tail tip [°]
    d : float
        Maximum (midbody) diameter [m]
    a_offset : float, default 0
        Length cut off the nose tip [m]
    c_offset : float, default 0
        Length cut off the tail end [m]

    Returns
    -------
    float or numpy.ndarray
        Radius [m]; 0 outside ``0 <= x <= l``.

    Raises
    ------
    ValueError
        Parameters that do not describe a Myring hull (see :func:`myring_geometry`).
    """
    _check_parameters(a, b, c, n, theta_deg, d, a_offset, c_offset)
    xs = np.asarray(x, dtype=float)
    half = 0.5 * d
    nose_end = a - a_offset
    l_f = nose_end + b
    length = l_f + c - c_offset
    r = np.zeros(xs.shape)
    nose = (xs >= 0.0) & (xs < nose_end)
    xi = (xs[nose] + a_offset - a) / a
    r[nose] = half * np.maximum(1.0 - xi**2, 0.0) ** (1.0 / n)
    r[(xs >= nose_end) & (xs <= l_f)] = half
    tail = (xs > l_f) & (xs <= length)
    if np.any(tail):
        coef_a, coef_b = _tail_coefficients(c, d, theta_deg)
        eta = xs[tail] - l_f
        r[tail] = np.maximum(half - coef_a * eta**2 + coef_b * eta**3, 0.0)
    return float(r) if r.ndim == 0 else r


_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(24)
_GL_BREAKS = np.concatenate(([0.0], 2.0 ** -np.arange(16.0, -1.0, -1.0)))  # graded to lo


def _quad(func, lo: float, hi: float) -> float:
    """Composite 24-point Gauss-Legendre on panels halving towards ``lo`` (where the nose
    integrands' derivatives may be unbounded); numpy only, so importing this module does not
    import scipy.integrate."""
    if hi <= lo:
        return 0.0
    span = hi - lo
    total = 0.0
    for p0, p1 in zip(_GL_BREAKS[:-1], _GL_BREAKS[1:], strict=True):
        half = 0.5 * (p1 - p0) * span
        mid = lo + 0.5 * (p0 + p1) * span
        total += half * sum(
            float(wt) * func(mid + half * float(x))
            for x, wt in zip(_GL_NODES, _GL_WEIGHTS, strict=True)
        )
    return float(total)


def myring_geometry(
    a: float,
    b: float,
    c: float,
    n: float,
    theta_deg: float,
    d: float,
    a_offset: float = 0.0,
    c_offset: float = 0.0,
) -> HullGeometry:
    """Length, areas, volume and centre of buoyancy of a Myring hull.

    Integrals of the profile of :func:`myring_radius` (Myring 1976; Prestero 2001):
    volume ``V = integral of pi r^2 dx``, projected side area ``integral of 2 r dx`` and wetted
    (curved) area ``integral of 2 pi r ds = integral of 2 pi sqrt(r^2 + (r r')^2) dx``, each by
    composite 24-point Gauss-Legendre quadrature per section on 17 panels halving in width
    towards the section's start (the midbody in closed form). The nose slope is infinite at an
    untruncated tip; the nose is therefore integrated in ``w`` with
    ``1 + (x + a_offset - a)/a = w^max(n, 1)``, which makes the integrands finite there.

    Parameters
    ----------
    a : float
        Full nose length [m]
    b : float
        Midbody length [m]
    c : float
        Full tail length [m]
    n : float
        Nose shape exponent [-]
    theta_deg : float
        Tail semi-angle at the tail tip [°]
    d : float
        Maximum (midbody) diameter [m]
    a_offset : float, default 0
        Length cut off the nose tip [m]
    c_offset : float, default 0
        Length cut off the tail end [m]

    Returns
    -------
    HullGeometry

    Raises
    ------
    ValueError
        Non-finite or negative lengths, ``d`` or ``n`` not positive, offsets longer than their
        section, or a tail semi-angle above ``atan(3 d / (2 c))`` (the tail would bulge).
    """
    a, b, c, n, theta_deg, d, a_offset, c_offset = (
        float(v) for v in (a, b, c, n, theta_deg, d, a_offset, c_offset)
    )
    _check_parameters(a, b, c, n, theta_deg, d, a_offset, c_offset)
    half = 0.5 * d
    nose_end = a - a_offset
    l_f = nose_end + b
    length = l_f + c - c_offset

    volume = math.pi * half**2 * b
    lateral = d * b
    wetted = 2.0 * math.pi * half * b
    moment = volume * (nose_end + 0.5 * b)

    if nose_end > 0.0:
        q = max(n, 1.0)

        def nose_terms(w: float) -> tuple[float, float, float, float]:
            tau = w**q
            xi = tau - 1.0
            s = tau * (2.0 - tau)
            r = half * s ** (1.0 / n)
            r_dr = half**2 / n * s ** (2.0 / n - 1.0) * (-2.0 * xi / a)
            jac = a * q * w ** (q - 1.0)
            return r, r_dr, jac, a * tau - a_offset

        def nose_volume(w: float) -> float:
            r, _, jac, _ = nose_terms(w)
            return math.pi * r**2 * jac

        def nose_moment(w: float) -> float:
            r, _, jac, x = nose_terms(w)
            return x * math.pi * r**2 * jac

        def nose_lateral(w: float) -> float:
            r, _, jac, _ = nose_terms(w)
            return 2.0 * r * jac

        def nose_wetted(w: float) -> float:
            r, r_dr, jac, _ = nose_terms(w)
            return 2.0 * math.pi * math.hypot(r, r_dr) * jac

        w0 = (a_offset / a) ** (1.0 / q)
        volume += _quad(nose_volume, w0, 1.0)
        moment += _quad(nose_moment, w0, 1.0)
        lateral += _quad(nose_lateral, w0, 1.0)
        wetted += _quad(nose_wetted, w0, 1.0)

    tail_length = c - c_offset
    if tail_length > 0.0:
        coef_a, coef_b = _tail_coefficients(c, d, theta_deg)

        def tail_r(eta: float) -> float:
            return max(half - coef_a * eta**2 + coef_b * eta**3, 0.0)

        def tail_slope(eta: float) -> float:
            return -2.0 * coef_a * eta + 3.0 * coef_b * eta**2

        volume += _quad(lambda e: math.pi * tail_r(e) ** 2, 0.0, tail_length)
        moment += _quad(lambda e: (l_f + e) * math.pi * tail_r(e) ** 2, 0.0, tail_length)
        lateral += _quad(lambda e: 2.0 * tail_r(e), 0.0, tail_length)
        wetted += _quad(
            lambda e: 2.0 * math.pi * tail_r(e) * math.sqrt(1.0 + tail_slope(e) ** 2),
            0.0,
            tail_length,
        )

    params = (a, b, c, n, theta_deg, d, a_offset, c_offset)
    return HullGeometry(
        length=length,
        max_diameter=d,
        frontal_area=math.pi * d**2 / 4.0,
        lateral_area=lateral,
        wetted_area=wetted,
        volume=volume,
        x_buoyancy=moment / volume,
        nose_radius=float(myring_radius(0.0, *params)),
        tail_radius=float(myring_radius(length, *params)),
    )


def displaced_volume(length_m: float, diameter_m: float | None,
                     volume_m3: float | None) -> float | None:
    """A hull's displaced volume [m³]: given (or from the Myring description), else estimated
    as 0.75 of the circumscribing cylinder π/4·D²·L (a prismatic coefficient typical of
    torpedo-shaped bodies); None without a diameter."""
    if volume_m3 is not None and volume_m3 > 0:
        return float(volume_m3)
    if diameter_m is None or diameter_m <= 0:
        return None
    return 0.75 * math.pi / 4.0 * diameter_m**2 * length_m
