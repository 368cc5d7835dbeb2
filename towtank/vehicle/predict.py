"""Semi-empirical prediction of the manoeuvring coefficients of a finned body of revolution.

The hull is a radius profile (:mod:`towtank.vehicle.hull`), the fins are pairs (rudders or stern
planes) of rectangular fins. Body axes x forward, y starboard, z down, origin at the reference
point (``x_origin_m`` aft of the nose); SNAME symbols. Every term is the one of Prestero (2001)
[1]_, chapter 3, except where the method column says otherwise:

- added mass: slender-body strip theory, the section added mass ``rho pi r^2`` of a circle and
  ``rho pi (a^2 - r^2 + r^4/a^2)`` of a circle with a pair of fins (a = r + span; Blevins [2]_),
  integrated along the body; the axial term from the spheroid of the same length and diameter
  (Lamb's k1 [3]_). Strip theory ignores the flow round the ends and overestimates the
  transverse added mass of the hull (by 1/k2 - 1 = 9 % for a 6:1 spheroid): the hull's strip
  integrals are multiplied by Lamb's k2 of the spheroid of the same volume and maximum diameter
  (the "equivalent spheroid"), the fins' are not;
- axial drag: ITTC-57 friction line on the wetted area with Hoerner's form factor of a body of
  revolution ``1 + 1.5 (D/L)^1.5 + 7 (D/L)^3`` [4]_, plus the fins' section drag
  ``2 C_F (1 + 2 t/c + 60 (t/c)^4)`` on their planform area;
- cross-flow drag: ``-1/2 rho c_dc integral of 2 r x^k |x|^m dx`` with c_dc = 1.1 (circular
  cylinder, Hoerner) and the fins' ``c_df = 0.1 + 0.7 taper`` (Whicker & Fehlner [5]_) at their
  ``x_drag_m``; ``damping = "prestero"`` gives instead the reading of Prestero's equations that
  reproduces his printed REMUS table (:func:`prestero_cross_flow`, hull-alone axial drag);
- body lift ``-1/2 rho D^2 c_ydb`` with c_ydb = 1.2 at 0.65 L aft of the nose (Hoerner [4]_,
  Prestero [1]_); the Munk moment and the other added-mass Coriolis terms are NOT folded into
  Y_uv, N_uv, Y_ur, N_ur (the Fossen-form model computes them from the added masses, see
  :func:`towtank.vehicle.model.lumped_to_fossen`);
- fin lift: lifting line ``c_La = a0 / (1 + a0/(pi AR_e))`` with the section slope
  a0 = 0.9 * 2 pi and the hull-mirrored aspect ratio AR_e = 2 span/chord
  (:func:`towtank.analysis.fins.finite_span_slope`), giving Y_uvf, Y_urf, N_uvf, N_urf and the
  control derivatives (:func:`towtank.analysis.fins.control_derivatives`), the lift
  ``rho c_La S_fin`` of both fins of a pair; ``fin_lift = "prestero"`` counts one fin per pair,
  ``1/2 rho c_La S_fin``, the reading of Prestero's printed REMUS fin terms (Y_uudr = 9.64).

References
----------
.. [1] Prestero, T. (2001), Verification of a six-degree of freedom simulation model for the
   REMUS autonomous underwater vehicle, MSc thesis, MIT/WHOI, chapter 3.
.. [2] Blevins, R. D. (1979), Formulas for natural frequency and mode shape, Van Nostrand,
   table 14-1 (added mass of a circle with fins).
.. [3] Lamb, H. (1932), Hydrodynamics, 6th ed., section 373 (prolate spheroid: alpha0, beta0,
   k1 = alpha0/(2 - alpha0), k2 = beta0/(2 - beta0), k').
.. [4] Hoerner, S. F. (1965), Fluid-dynamic drag, chapters 3 and 6; ITTC (1957) friction line.
.. [5] Whicker, L. F. and Fehlner, L. F. (1958), Free-stream characteristics of a family of
   low-aspect-ratio control surfaces, DTMB report 933.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.integrate import trapezoid

from towtank.analysis import fins as fin_analysis
from towtank.vehicle.hull import HullProfile

__all__ = [
    "PREDICTED_COLUMNS",
    "FinPair",
    "axial_drag",
    "fin_rolling_drag",
    "hull_axial_drag_coefficient",
    "lamb_k_factors",
    "ittc57_cf",
    "prime_exponent",
    "predict_coefficients",
    "prestero_cross_flow",
]

PREDICTED_COLUMNS = ("symbol", "value", "unit", "prime", "method", "reference")
C_DC = 1.1  # cross-flow drag coefficient of a circular cylinder (Hoerner)
C_YDB = 1.2  # body lift coefficient (Hoerner; Prestero 2001)
X_CP_FRACTION = 0.65  # body lift centre of pressure, fraction of L aft of the nose
SECTION_EFFICIENCY = 0.9  # a0 = 0.9 * 2 pi (Prestero 2001, after Hoerner)
PRESTERO = "Prestero (2001) ch. 3"


@dataclass(frozen=True)
class FinPair:
    """A pair of rectangular fins on the hull (both sides).

    Attributes
    ----------
    plane : str
        "rudder" (vertical fins: sway and yaw) or "sternplane" (horizontal: heave and pitch)
    x_m : float
        Quarter-chord position from the reference point, negative aft [m]
    span_m : float
        Span of one fin, root (hull) to tip [m]
    chord_m : float
        Chord [m]
    section : str
        NACA 4-digit section (its thickness ratio is used for the section drag)
    taper : float
        Tip chord / root chord [-]
    x_drag_m : float, optional
        Position of the centre of the fin's cross-flow drag from the reference point, negative
        aft [m] (Prestero's x_fin of his cross-flow terms); default the quarter chord ``x_m``
    """

    plane: str
    x_m: float
    span_m: float
    chord_m: float
    section: str = "NACA0012"
    taper: float = 1.0
    x_drag_m: float | None = None

    @property
    def x_drag(self) -> float:
        """Moment arm of the fin's cross-flow drag [m]: ``x_drag_m``, else ``x_m``."""
        return self.x_m if self.x_drag_m is None else float(self.x_drag_m)

    @property
    def c_df(self) -> float:
        """Fin cross-flow drag coefficient ``0.1 + 0.7 taper`` (Whicker & Fehlner 1958) [-]."""
        return 0.1 + 0.7 * self.taper

    @property
    def area(self) -> float:
        """Planform area of one fin [m^2]."""
        return self.span_m * self.chord_m

    @property
    def thickness_ratio(self) -> float:
        """t/c from the last two digits of a NACA 4-digit name, 0.12 if not given."""
        m = re.fullmatch(r"NACA\s*\d\d(\d\d)", self.section.strip().upper())
        return int(m.group(1)) / 100.0 if m else 0.12


def lamb_k_factors(length_m: float, diameter_m: float) -> tuple[float, float, float]:
    """Lamb's added-mass coefficients of a prolate spheroid, k1 (axial), k2 (transverse), k'.

    With e = sqrt(1 - (D/L)^2): alpha0 = 2(1-e^2)/e^3 (ln((1+e)/(1-e))/2 - e),
    beta0 = 1/e^2 - (1-e^2)/(2e^3) ln((1+e)/(1-e)), k1 = alpha0/(2-alpha0),
    k2 = beta0/(2-beta0), k' = e^4 (beta0-alpha0) / ((2-e^2)(2e^2 - (2-e^2)(beta0-alpha0)))
    (Lamb 1932, section 373). The added masses are k1 rho V, k2 rho V and k' rho I_fluid.

    Parameters
    ----------
    length_m, diameter_m : float
        Length and diameter of the spheroid [m], length > diameter

    Returns
    -------
    tuple of float
        (k1, k2, k_rot) [-]
    """
    e = math.sqrt(1.0 - (diameter_m / length_m) ** 2)
    log = math.log((1.0 + e) / (1.0 - e))
    alpha0 = 2.0 * (1.0 - e * e) / e**3 * (0.5 * log - e)
    beta0 = 1.0 / (e * e) - (1.0 - e * e) / (2.0 * e**3) * log
    k1 = alpha0 / (2.0 - alpha0)
    k2 = beta0 / (2.0 - beta0)
    d = beta0 - alpha0
    k_rot = e**4 * d / ((2.0 - e * e) * (2.0 * e * e - (2.0 - e * e) * d))
    return k1, k2, k_rot


def ittc57_cf(reynolds: float) -> float:
    """ITTC-1957 model-ship correlation line ``C_F = 0.075 / (log10 Re - 2)^2``."""
    return 0.075 / (math.log10(reynolds) - 2.0) ** 2


def prime_exponent(symbol: str) -> int:
    """The power of L in the SNAME prime ``value / (1/2 rho L^k)`` of a coefficient symbol.

    Forces (X, Y, Z) 2, moments (K, M, N) 3; +1 for each angular rate (p, q, r) among the
    motion variables and +1 for an acceleration (``dot``); a control angle (``dr``, ``ds``)
    counts nothing: Y_uv 2, Y_ur 3, N_uv 3, N_r|r| 5, X_udot 3, N_rdot 5, N_uudr 3.
    """
    head, _, sub = symbol.partition("_")
    k = 2 if head in ("X", "Y", "Z") else 3
    sub = sub.replace("|", "")
    if sub.endswith("dot"):
        k += 1
        sub = sub[:-3]
    if sub.endswith(("dr", "ds")):
        sub = sub[:-2]
    return k + sum(ch in "pqr" for ch in sub)


def coefficient_unit(symbol: str) -> str:
    """The SI unit of a coefficient as predicted.csv writes it (``kg*m/rad`` for N_ur)."""
    k = prime_exponent(symbol)
    # 1/2 rho L^k has units kg m^(k-3); an angular variable adds /rad
    sub = symbol.partition("_")[2].replace("|", "")
    n_rad = sum(ch in "pqr" for ch in sub.removesuffix("dot").removesuffix("dr").removesuffix("ds"))
    n_rad += symbol.endswith(("dr", "ds"))
    power = k - 3
    rad = "" if n_rad == 0 else ("rad" if n_rad == 1 else f"rad^{n_rad}")
    if power == -1:
        return f"kg/(m*{rad})" if rad else "kg/m"
    base = "kg" if power == 0 else ("kg*m" if power == 1 else f"kg*m^{power}")
    return base + (f"/{rad}" if rad else "")


def axial_drag(profile: HullProfile, fins: Sequence[FinPair], rho: float, nu: float,
               speed_m_s: float) -> float:
    """X_u|u| [kg/m]: friction-line axial drag of the hull and the fins at one speed.

    ``X_u|u| = -1/2 rho [S_w C_F (1 + k) + sum 2 S_fin 2 C_F,fin (1 + 2 t/c + 60 (t/c)^4)]``
    with the ITTC-57 line at ``Re = U L / nu`` (fins: ``U c / nu``) and Hoerner's form factor
    of a body of revolution ``1 + k = 1 + 1.5 (D/L)^1.5 + 7 (D/L)^3`` (Hoerner 1965, ch. 6).

    Parameters
    ----------
    profile : HullProfile
    fins : sequence of FinPair
    rho : float
        Water density [kg/m^3]
    nu : float
        Kinematic viscosity [m^2/s]
    speed_m_s : float
        Speed U of the Reynolds numbers [m/s]
    """
    frontal = math.pi * profile.max_diameter**2 / 4.0
    drag_area = hull_axial_drag_coefficient(profile, nu, speed_m_s) * frontal
    for pair in fins:
        cf_fin = ittc57_cf(max(speed_m_s * pair.chord_m / nu, 1.0e3))
        tc = pair.thickness_ratio
        drag_area += 2.0 * pair.area * 2.0 * cf_fin * (1 + 2 * tc + 60 * tc**4)
    return -0.5 * rho * drag_area


def hull_axial_drag_coefficient(profile: HullProfile, nu: float, speed_m_s: float) -> float:
    """The bare hull's axial drag coefficient on its frontal area, c_d [-].

    ``c_d = S_w C_F (1 + k) / A_f`` with the ITTC-57 line at ``Re = U L / nu``, Hoerner's form
    factor ``1 + k = 1 + 1.5 (D/L)^1.5 + 7 (D/L)^3`` (Hoerner 1965, ch. 6) and
    ``A_f = pi D^2 / 4``: the c_d of Prestero's (2001) eq. 3.8, ``X_u|u| = -1/2 rho c_d A_f``,
    for the hull alone (no fins).

    Parameters
    ----------
    profile : HullProfile
    nu : float
        Kinematic viscosity [m^2/s]
    speed_m_s : float
        Speed U of the Reynolds number [m/s]
    """
    length, diameter = profile.length, profile.max_diameter
    cf = ittc57_cf(speed_m_s * length / nu)
    form = 1.0 + 1.5 * (diameter / length) ** 1.5 + 7.0 * (diameter / length) ** 3
    return profile.wetted_area * cf * form / (math.pi * diameter**2 / 4.0)


def prestero_cross_flow(profile: HullProfile, fins: Sequence[FinPair], x_origin: float,
                        rho: float) -> dict[str, float]:
    """Prestero's (2001) cross-flow damping terms as his printed REMUS table has them.

    With the hull's cross-flow integrals ``I_k = integral from x_t to x_b of 2R(x) g_k(x) dx``
    (x from the tail end x_t to the nose x_b, origin at the reference point), c_dc = 1.1, and
    for each fin pair its fins' cross-flow ``F = 1/2 rho S_fin c_df`` counted once (S_fin the
    area of one fin, c_df = 0.1 + 0.7 taper) at ``x_f`` (``FinPair.x_drag``)::

        Y_v|v| = Z_w|w| = -1/2 rho c_dc I(1)        - sum F                  (eq. 3.9)
        M_w|w| = -N_v|v| = -1/2 rho c_dc I(x)       - sum F x_f              (eq. 3.10)
        Y_r|r| = -Z_q|q| = -1/2 rho c_dc I(x|x|)    + sum F x_f|x_f|         (eq. 3.11)
        M_q|q| = N_r|r|  = -1/2 rho c_dc I(x^2|x|)  - sum F |x_f|^3          (eq. 3.12)
        K_p|p|           = sum over the pairs of -F r_mean^3                 (eq. 3.14)

    (r_mean = D/2 + span/2, the mean height of the fin above the axis of the hull's maximum
    diameter D; the Y and N terms use the rudders, the Z and M terms the stern planes).

    This is the reading of his eqs. 3.9-3.14 that reproduces his printed REMUS values on his
    geometry (x_f = -0.6827 m, c_df = 0.558): the fins counted once per pair; his M_w|w| and
    N_v|v| with the signs of +x Z and -x Y (SNAME's cross-flow moment is N = x Y, M = -x Z,
    which gives N_v|v| > 0 with the fins aft); in his Y_r|r| the fins' term with the sign
    opposite to the hull's. towtank's default keeps the SNAME signs and both fins of a pair
    (:func:`predict_coefficients`).

    Parameters
    ----------
    profile : HullProfile
        The hull
    fins : sequence of FinPair
        The fin pairs
    x_origin : float
        Reference point aft of the nose tip [m]
    rho : float
        Water density [kg/m^3]

    Returns
    -------
    dict
        symbol -> value [SI] for Y_v|v|, Z_w|w|, M_w|w|, N_v|v|, Y_r|r|, Z_q|q|, M_q|q|,
        N_r|r|, K_p|p|
    """
    xb = x_origin - profile.x_m[::-1]
    w = 2.0 * profile.r_m[::-1]
    hq = 0.5 * rho * C_DC

    def fsum(plane: str, fx) -> float:
        return sum(0.5 * rho * p.c_df * p.area * fx(p.x_drag) for p in fins if p.plane == plane)

    out: dict[str, float] = {}
    for plane, (force, moment, vel, rate, s) in {
        "rudder": ("Y", "N", "v", "r", 1.0), "sternplane": ("Z", "M", "w", "q", -1.0)
    }.items():
        out[f"{force}_{vel}|{vel}|"] = -hq * float(trapezoid(w, xb)) - fsum(plane, lambda x: 1.0)
        m_ww = -hq * float(trapezoid(w * xb, xb)) - fsum(plane, lambda x: x)
        out[f"{moment}_{vel}|{vel}|"] = -s * m_ww
        y_rr = -hq * float(trapezoid(w * xb * np.abs(xb), xb)) + fsum(plane, lambda x: x * abs(x))
        out[f"{force}_{rate}|{rate}|"] = s * y_rr
        out[f"{moment}_{rate}|{rate}|"] = (-hq * float(trapezoid(w * xb**2 * np.abs(xb), xb))
                                           - fsum(plane, lambda x: abs(x) ** 3))
    r_hull = 0.5 * profile.max_diameter
    out["K_p|p|"] = -sum(0.5 * rho * p.c_df * p.area * (r_hull + 0.5 * p.span_m) ** 3
                         for p in fins)
    return out


def _fin_strip(profile: HullProfile, pair: FinPair, x_origin: float) -> tuple[np.ndarray, ...]:
    """Stations (body x) over the fin's chord, hull radius there and the fin-tip radius."""
    x_le = pair.x_m + 0.25 * pair.chord_m
    x_te = pair.x_m - 0.75 * pair.chord_m
    xb = np.linspace(x_te, x_le, 201)
    r = np.interp(x_origin - xb, profile.x_m, profile.r_m, left=0.0, right=0.0)
    return xb, r, r + pair.span_m


def fin_rolling_drag(profile: HullProfile, pair: FinPair, x_origin: float, rho: float) -> float:
    """Roll damping K_p|p| of one pair of fins by cross-flow drag [kg*m^2/rad^2].

    A fin strip at radius s moves sideways at ``p s`` and carries the cross-flow drag
    ``1/2 rho c_df c (p s)|p s|``; its moment arm is s, so per fin
    ``K_p|p| = -1/2 rho c_df integral over the chord of (a^4 - r^4)/4 dx`` with r the hull
    radius and a = r + span the tip radius at each station x. This is Prestero's (2001)
    eq. 3.14, ``K_p|p| = Y_v|v|f r_mean^3``, with the mean of s^3 over the span instead of
    the cube of the mean radius (which undercounts the tip by a factor of about 1.6 on REMUS).
    ``c_df = 0.1 + 0.7 taper`` (Whicker & Fehlner 1958).

    Parameters
    ----------
    profile : HullProfile
        The hull (its radius under the fin's root)
    pair : FinPair
        The fin pair (two fins)
    x_origin : float
        Reference point aft of the nose tip [m]
    rho : float
        Water density [kg/m^3]

    Returns
    -------
    float
        The pair's K_p|p| [kg*m^2/rad^2], negative
    """
    xs, r, a = _fin_strip(profile, pair, x_origin)
    c_df = pair.c_df
    per_fin = 0.5 * rho * c_df * float(trapezoid((a**4 - r**4) / 4.0, xs))
    return -2.0 * per_fin


def _added_mass_strips(
    profile: HullProfile, pairs: Sequence[FinPair], plane: str, x_origin: float, rho: float,
    hull_factor: float,
) -> tuple[np.ndarray, np.ndarray, list[np.ndarray], list[np.ndarray]]:
    """Sectional transverse added mass m(x) [kg/m] at body stations x for one plane: the hull's
    stations and strips, then each fin pair's stations and its strips' excess over the hull."""
    xb = x_origin - profile.x_m[::-1]
    m = hull_factor * rho * np.pi * profile.r_m[::-1] ** 2
    extra_x: list[np.ndarray] = []
    extra_m: list[np.ndarray] = []
    for pair in pairs:
        if pair.plane != plane:
            continue
        xs, r, a = _fin_strip(profile, pair, x_origin)
        extra_x.append(xs)
        # the fins' section replaces the bare circle: add (finned - circle) there
        extra_m.append(rho * np.pi * (a**2 - r**2 + r**4 / a**2) - hull_factor * rho * np.pi * r**2)
    return xb, m, extra_x, extra_m


def _moments(xb: np.ndarray, m: np.ndarray, extra_x: list[np.ndarray],
             extra_m: list[np.ndarray], power: int) -> float:
    total = float(trapezoid(m * xb**power, xb))
    for xs, ms in zip(extra_x, extra_m, strict=True):
        total += float(trapezoid(ms * xs**power, xs))
    return total


#: A predicted value smaller than this fraction of the table's largest is round-off of a
#: term that vanishes by symmetry (e.g. Y_rdot of a fore-aft symmetric hull), written as 0.
ROUND_OFF = 1e-12


def predict_coefficients(
    profile: HullProfile,
    fins: Sequence[FinPair] = (),
    rho: float = 1000.0,
    nu: float = 1.0e-6,
    speed_m_s: float = 1.5,
    x_origin_m: float | None = None,
    added_mass: str = "towtank",
    damping: str = "towtank",
    fin_lift: str = "towtank",
) -> pd.DataFrame:
    """The predicted coefficient set of a finned body of revolution (module docstring).

    Parameters
    ----------
    profile : HullProfile
        The bare hull
    fins : sequence of FinPair
        Fin pairs (rudders, stern planes); none for a bare hull
    rho : float
        Water density [kg/m^3]
    nu : float
        Kinematic viscosity [m^2/s]
    speed_m_s : float
        Speed of the Reynolds number of the axial drag [m/s]
    x_origin_m : float, optional
        Reference point aft of the nose tip [m]; default the centre of buoyancy
    added_mass : {"towtank", "prestero"}
        "towtank": the hull's strips times Lamb's k2 of the equivalent spheroid (the method
        column then also gives the uncorrected value); "prestero": plain strip theory as in
        Prestero (2001) eqs. 3.18-3.24, which reproduces his printed added masses
    damping : {"towtank", "prestero"}
        "towtank": SNAME-signed cross-flow drag of the hull and of both fins of each pair, and
        the friction-line axial drag of hull and fins (the method column also gives Prestero's
        value where it differs); "prestero": the hull's axial drag alone,
        ``-1/2 rho c_d A_f`` (:func:`hull_axial_drag_coefficient`), and the cross-flow terms of
        :func:`prestero_cross_flow`, which reproduce his printed REMUS table
    fin_lift : {"towtank", "prestero"}
        "towtank": the lift of both fins of a pair, ``F = rho c_La S_fin`` (two fins, each
        ``1/2 rho c_La S_fin u^2 delta``); "prestero": one fin per pair,
        ``F = 1/2 rho c_La S_fin``, which reads Prestero's printed REMUS fin terms (his
        Y_uudr = 9.64 kg/(m rad) against 21.3 for the pair). Either way Y_uudr = F,
        N_uudr = F x_fin, Z_uuds = -F, M_uuds = F x_fin and the fins' parts of Y_uv, Z_uw
        (-F), N_uv (-F x_fin), M_uw (F x_fin), Y_ur (-F x_fin), Z_uq (F x_fin), N_ur, M_uq
        (-F x_fin^2) (Prestero 2001 eqs. 3.29-3.44)

    Returns
    -------
    pandas.DataFrame
        predicted.csv: symbol, value, unit, prime, method, reference
    """
    if added_mass not in ("towtank", "prestero"):
        raise ValueError(f"added_mass must be 'towtank' or 'prestero', not {added_mass!r}.")
    if damping not in ("towtank", "prestero"):
        raise ValueError(f"damping must be 'towtank' or 'prestero', not {damping!r}.")
    if fin_lift not in ("towtank", "prestero"):
        raise ValueError(f"fin_lift must be 'towtank' or 'prestero', not {fin_lift!r}.")
    length = profile.length
    diameter = profile.max_diameter
    x0 = profile.x_buoyancy if x_origin_m is None else float(x_origin_m)
    rows: list[tuple[str, float, str, str]] = []

    def add(symbol: str, value: float, method: str, reference: str = PRESTERO) -> None:
        rows.append((symbol, float(value), method, reference))

    # ---- added mass
    k1, _, _ = lamb_k_factors(length, diameter)
    volume_ld = math.pi / 6.0 * length * diameter**2
    add("X_udot", -k1 * rho * volume_ld,
        f"-k1 rho V of the spheroid of the same L and D (Lamb k1 = {k1:.4f})",
        "Lamb (1932) s. 373; Prestero (2001) eq. 3.17")
    # the spheroid of the same volume and maximum diameter: a parallel midbody acts as a longer
    # body, whose ends (where strip theory fails) are those of a fuller spheroid
    l_eq = 6.0 * profile.volume / (math.pi * diameter**2)
    _, k2_eq, _ = lamb_k_factors(max(l_eq, 1.0001 * diameter), diameter)
    corr = (f"strip theory, hull strips x Lamb k2 = {k2_eq:.4f} of the equivalent spheroid "
            f"(same volume and max diameter, L/D = {l_eq / diameter:.2f}); fins by Blevins")
    if added_mass == "prestero":
        corr = "plain strip theory as Prestero (2001): hull rho pi r^2, fins by Blevins"
    ref_am = "Lamb (1932); Blevins (1979); Prestero (2001) eqs. 3.18-3.24"
    factor = k2_eq if added_mass == "towtank" else 1.0
    for plane, (force, moment, sgn) in {"rudder": ("Y", "N", -1.0),
                                         "sternplane": ("Z", "M", 1.0)}.items():
        strips = _added_mass_strips(profile, fins, plane, x0, rho, factor)
        plain = _added_mass_strips(profile, fins, plane, x0, rho, 1.0)
        vel, rate = ("v", "r") if plane == "rudder" else ("w", "q")
        for sym, power, sign in ((f"{force}_{vel}dot", 0, -1.0), (f"{force}_{rate}dot", 1, sgn),
                                 (f"{moment}_{vel}dot", 1, sgn), (f"{moment}_{rate}dot", 2, -1.0)):
            text = corr
            if added_mass == "towtank":
                text += (f" (uncorrected, Prestero's method: "
                         f"{sign * _moments(*plain, power):.4g})")
            add(sym, sign * _moments(*strips, power), text, ref_am)
    k_pdot = 0.0
    stations: dict[tuple[float, float], float] = {}  # a cruciform station counts once
    for pair in fins:
        key = (round(pair.x_m, 6), round(pair.chord_m, 6))
        stations[key] = max(stations.get(key, 0.0), pair.span_m)
    for (x_m, chord), span in stations.items():
        xs, r, a = _fin_strip(profile, FinPair("rudder", x_m, span, chord), x0)
        k_pdot -= float(trapezoid(2.0 / math.pi * rho * a**4, xs))
    add("K_pdot", k_pdot,
        "fins only: -integral of (2/pi) rho a^4 dx over each fin station (a = r + span)",
        "Blevins (1979); Prestero (2001) eq. 3.25")

    # ---- axial drag
    reynolds = speed_m_s * length / nu
    cf = ittc57_cf(reynolds)
    form = 1.0 + 1.5 * (diameter / length) ** 1.5 + 7.0 * (diameter / length) ** 3
    fin_text = "; fins 2 C_F (1 + 2t/c + 60(t/c)^4) S" if fins else ""
    c_d = hull_axial_drag_coefficient(profile, nu, speed_m_s)
    a_f = math.pi * diameter**2 / 4.0
    x_uu_hull = -0.5 * rho * c_d * a_f
    hull_text = (f"-1/2 rho c_d A_f of the hull alone, c_d = S_w C_F (1 + k)/A_f = {c_d:.4f} "
                 f"(ITTC-57 C_F = {cf:.5f} at Re = {reynolds:.3g}, {speed_m_s:g} m/s, form factor "
                 f"{form:.3f}) on A_f = {a_f:.4g} m^2")
    if damping == "prestero":
        add("X_u|u|", x_uu_hull, hull_text + " (Prestero's eq. 3.8)",
            "Prestero (2001) eq. 3.8; ITTC (1957); Hoerner (1965) ch. 6")
    else:
        add("X_u|u|", axial_drag(profile, fins, rho, nu, speed_m_s),
            f"ITTC-57 C_F = {cf:.5f} at Re = {reynolds:.3g} ({speed_m_s:g} m/s) x form factor "
            f"{form:.3f} on S_w = {profile.wetted_area:.4g} m^2{fin_text} (Prestero's method, "
            f"hull alone: {x_uu_hull:.4g})",
            "ITTC (1957); Hoerner (1965) ch. 6")

    # ---- cross-flow drag
    xb = x0 - profile.x_m[::-1]
    w = 2.0 * profile.r_m[::-1]
    hq = 0.5 * rho * C_DC

    def fin_cd(plane: str, fx) -> float:
        return sum(0.5 * rho * p.c_df * 2.0 * p.area * fx(p.x_drag)
                   for p in fins if p.plane == plane)

    pre = prestero_cross_flow(profile, fins, x0, rho)
    ref_xf = "Hoerner (1965); Whicker & Fehlner (1958); Prestero (2001) eqs. 3.9-3.13"
    if damping == "prestero":
        xflow = (f"Prestero's cross-flow terms as printed: hull c_dc = {C_DC}, one fin's "
                 "1/2 rho S_fin c_df per pair at x_drag, his signs (prestero_cross_flow)")
        for sym in ("Y_v|v|", "Y_r|r|", "N_v|v|", "N_r|r|", "Z_w|w|", "Z_q|q|", "M_w|w|",
                    "M_q|q|"):
            add(sym, pre[sym], xflow, ref_xf)
        add("K_p|p|", pre["K_p|p|"],
            "Prestero's Y_v|v|f r_mean^3 per fin pair, r_mean = D/2 + span/2",
            "Prestero (2001) eq. 3.14; Whicker & Fehlner (1958)")
    else:
        xflow = f"cross-flow drag, hull c_dc = {C_DC} (Hoerner), fins c_df = 0.1 + 0.7 taper"

        def differs(sym: str, why: str) -> str:
            if not any(p.plane == ("rudder" if sym[0] in "YN" else "sternplane") for p in fins):
                return ""
            return (f"; differs on purpose from Prestero's printed value, which his method "
                    f"(damping = prestero) gives as {pre[sym]:.4g} ({why})")

        rate_why = "one fin per pair, the fins' term with the sign opposite to the hull's"
        moment_why = "one fin per pair, signs of +x Z and -x Y; SNAME N = x Y, M = -x Z here"
        for plane, (force, moment, vel, rate, s) in {
            "rudder": ("Y", "N", "v", "r", 1.0), "sternplane": ("Z", "M", "w", "q", -1.0)
        }.items():
            add(f"{force}_{vel}|{vel}|", -hq * trapezoid(w, xb) - fin_cd(plane, lambda x: 1.0),
                xflow, ref_xf)
            add(f"{force}_{rate}|{rate}|",
                s * (-hq * trapezoid(w * xb * np.abs(xb), xb)
                     - fin_cd(plane, lambda x: x * abs(x))),
                xflow + differs(f"{force}_{rate}|{rate}|", rate_why), ref_xf)
            add(f"{moment}_{vel}|{vel}|",
                s * (-hq * trapezoid(w * xb, xb) - fin_cd(plane, lambda x: x)),
                xflow + differs(f"{moment}_{vel}|{vel}|", moment_why), ref_xf)
            add(f"{moment}_{rate}|{rate}|",
                -hq * trapezoid(w * xb**2 * np.abs(xb), xb)
                - fin_cd(plane, lambda x: x**2 * abs(x)),
                xflow, ref_xf)
        k_pp = sum(fin_rolling_drag(profile, pair, x0, rho) for pair in fins)
        add("K_p|p|", k_pp,
            "fins' cross-flow drag integrated over the span, -sum 1/2 rho c_df c (a^4 - r^4)/4 "
            "per fin (Prestero's Y_v|v|f r_mean^3 with r^3 averaged over the span, not "
            "r_mean^3)", "Prestero (2001) eq. 3.14; Whicker & Fehlner (1958)")

    # ---- body lift (no Munk moment here: C_A(v) of the model carries it)
    x_cp = x0 - X_CP_FRACTION * length
    lift = 0.5 * rho * diameter**2 * C_YDB
    body = f"body lift c_ydb = {C_YDB} on D^2 at x_cp = {x_cp:+.4f} m (0.65 L aft of the nose)"
    fins_y = [p for p in fins if p.plane == "rudder"]
    fins_z = [p for p in fins if p.plane == "sternplane"]

    def fin_slope(pair: FinPair) -> float:
        a0 = SECTION_EFFICIENCY * 2.0 * math.pi
        ar = fin_analysis.effective_aspect_ratio(pair.span_m, pair.chord_m, "wall")
        return float(fin_analysis.finite_span_slope(a0, ar))

    # F = rho c_La S_fin: the lift of both fins of a pair (each 1/2 rho c_La S_fin u^2 delta);
    # fin_lift = "prestero" counts one fin per pair, as his printed REMUS terms read
    per_pair = 1.0 if fin_lift == "towtank" else 0.5

    def fsum(pairs, fx) -> float:
        return sum(per_pair * rho * fin_slope(p) * p.area * fx(p.x_m) for p in pairs)

    fin_count = ("both fins of a pair, rho c_La S_fin" if fin_lift == "towtank" else
                 "one fin per pair, 1/2 rho c_La S_fin (fin_lift = prestero: his printed REMUS "
                 "reading)")
    lift_txt = (body + "; fins: lifting line c_La = a0/(1 + a0/(pi 2 span/chord)), a0 = 0.9 2 pi, "
                + fin_count)
    ref_lift = "Hoerner (1965); Prestero (2001) eqs. 3.29-3.40; Anderson s. 5.3"
    add("Y_uv", -lift - fsum(fins_y, lambda x: 1.0), lift_txt, ref_lift)
    add("Z_uw", -lift - fsum(fins_z, lambda x: 1.0), lift_txt, ref_lift)
    add("N_uv", -lift * x_cp - fsum(fins_y, lambda x: x), lift_txt, ref_lift)
    add("M_uw", lift * x_cp + fsum(fins_z, lambda x: x), lift_txt, ref_lift)
    rate_txt = f"fin lift (lifting line, {fin_count}); added-mass part in C_A(v)"
    add("Y_ur", -fsum(fins_y, lambda x: x), rate_txt, ref_lift)
    add("Z_uq", fsum(fins_z, lambda x: x), rate_txt, ref_lift)
    add("N_ur", -fsum(fins_y, lambda x: x * x), rate_txt, ref_lift)
    add("M_uq", -fsum(fins_z, lambda x: x * x), rate_txt, ref_lift)
    ctrl = f"control derivative, lift of {fin_count} (lifting line)"
    ref_ctrl = "Prestero (2001) eqs. 3.41-3.44"
    if fins_y:
        add("Y_uudr", fsum(fins_y, lambda x: 1.0), ctrl, ref_ctrl)
        add("N_uudr", fsum(fins_y, lambda x: x), ctrl, ref_ctrl)
    if fins_z:
        add("Z_uuds", -fsum(fins_z, lambda x: 1.0), ctrl, ref_ctrl)
        add("M_uuds", fsum(fins_z, lambda x: x), ctrl, ref_ctrl)

    out = pd.DataFrame(rows, columns=["symbol", "value", "method", "reference"])
    # a term that is zero by symmetry comes out of the quadratures as round-off (1e-17 kg m
    # beside 35 kg): written as the 0 it is
    scale = float(np.nanmax(np.abs(out["value"]))) if len(out) else 0.0
    out.loc[np.abs(out["value"]) <= ROUND_OFF * scale, "value"] = 0.0
    out["unit"] = [coefficient_unit(s) for s in out["symbol"]]
    out["prime"] = [v / (0.5 * rho * length ** prime_exponent(s))
                    for s, v in zip(out["symbol"], out["value"], strict=True)]
    return out[list(PREDICTED_COLUMNS)]
