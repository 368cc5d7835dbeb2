"""Powering: effective power and a Wageningen B-series propeller matched to the thrust.

The resistance at the prototype is ``R = -X_u|u| U^2`` from the predicted axial drag (ITTC-57
friction line with Hoerner's form factor, :func:`towtank.vehicle.predict.axial_drag`, at each
speed's Reynolds number). The propeller works behind the hull with the thrust deduction t and
the wake fraction w of the protocol: it must deliver ``T = R / (1 - t)`` at the advance speed
``V_A = U (1 - w)`` (Harvald 1983, ch. 6). Its open-water thrust and torque coefficients are the
Wageningen B-series polynomials of Oosterveld & van Oossanen (1975) [1]_ at Re = 2e6,

    K_T = sum_i C_i J^s_i (P/D)^t_i (A_E/A_0)^u_i Z^v_i   (39 terms, their Table 1)
    K_Q = sum_i C_i J^s_i (P/D)^t_i (A_E/A_0)^u_i Z^v_i   (47 terms, their Table 1)

with ``J = V_A / (n D)``, ``K_T = T / (rho n^2 D^4)``, ``K_Q = Q / (rho n^2 D^5)`` and the
open-water efficiency ``eta_0 = J K_T / (2 pi K_Q)``. The advance ratio is the root of
``K_T(J) / J^2 = T / (rho D^2 V_A^2)``; the delivered power is ``P_D = 2 pi n Q`` (relative
rotative efficiency 1). The design tool's eqs. 10-13 are the same polynomials.

References
----------
.. [1] Oosterveld, M. W. C. and van Oossanen, P. (1975), Further computer-analyzed data of the
   Wageningen B-screw series, International Shipbuilding Progress 22(251), 251-262, Table 1.
.. [2] Harvald, S. A. (1983), Resistance and propulsion of ships, Wiley, ch. 6.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from scipy.optimize import brentq

__all__ = [
    "KT_TERMS",
    "KQ_TERMS",
    "POWERING_COLUMNS",
    "PROPELLER_FIELDS",
    "Propeller",
    "bseries_kt_kq",
    "effective_power",
    "kt_polynomial",
    "match_thrust",
    "powering_table",
    "propeller_from",
    "propeller_thrust",
    "self_propulsion_rps",
]

#: (C, s, t, u, v): C J^s (P/D)^t (A_E/A_0)^u Z^v, K_T at Re = 2e6 ([1]_, Table 1, 39 terms).
KT_TERMS: tuple[tuple[float, int, int, int, int], ...] = (
    (0.00880496, 0, 0, 0, 0), (-0.204554, 1, 0, 0, 0), (0.166351, 0, 1, 0, 0),
    (0.158114, 0, 2, 0, 0), (-0.147581, 2, 0, 1, 0), (-0.481497, 1, 1, 1, 0),
    (0.415437, 0, 2, 1, 0), (0.0144043, 0, 0, 0, 1), (-0.0530054, 2, 0, 0, 1),
    (0.0143481, 0, 1, 0, 1), (0.0606826, 1, 1, 0, 1), (-0.0125894, 0, 0, 1, 1),
    (0.0109689, 1, 0, 1, 1), (-0.133698, 0, 3, 0, 0), (0.00638407, 0, 6, 0, 0),
    (-0.00132718, 2, 6, 0, 0), (0.168496, 3, 0, 1, 0), (-0.0507214, 0, 0, 2, 0),
    (0.0854559, 2, 0, 2, 0), (-0.0504475, 3, 0, 2, 0), (0.010465, 1, 6, 2, 0),
    (-0.00648272, 2, 6, 2, 0), (-0.00841728, 0, 3, 0, 1), (0.0168424, 1, 3, 0, 1),
    (-0.00102296, 3, 3, 0, 1), (-0.0317791, 0, 3, 1, 1), (0.018604, 1, 0, 2, 1),
    (-0.00410798, 0, 2, 2, 1), (-0.000606848, 0, 0, 0, 2), (-0.0049819, 1, 0, 0, 2),
    (0.0025983, 2, 0, 0, 2), (-0.000560528, 3, 0, 0, 2), (-0.00163652, 1, 2, 0, 2),
    (-0.000328787, 1, 6, 0, 2), (0.000116502, 2, 6, 0, 2), (0.000690904, 0, 0, 1, 2),
    (0.00421749, 0, 3, 1, 2), (5.65229e-05, 3, 6, 1, 2), (-0.00146564, 0, 3, 2, 2),
)
#: (C, s, t, u, v) of K_Q at Re = 2e6 ([1]_, Table 1, 47 terms).
KQ_TERMS: tuple[tuple[float, int, int, int, int], ...] = (
    (0.00379368, 0, 0, 0, 0), (0.00886523, 2, 0, 0, 0), (-0.032241, 1, 1, 0, 0),
    (0.00344778, 0, 2, 0, 0), (-0.0408811, 0, 1, 1, 0), (-0.108009, 1, 1, 1, 0),
    (-0.0885381, 2, 1, 1, 0), (0.188561, 0, 2, 1, 0), (-0.00370871, 1, 0, 0, 1),
    (0.00513696, 0, 1, 0, 1), (0.0209449, 1, 1, 0, 1), (0.00474319, 2, 1, 0, 1),
    (-0.00723408, 2, 0, 1, 1), (0.00438388, 1, 1, 1, 1), (-0.0269403, 0, 2, 1, 1),
    (0.0558082, 3, 0, 1, 0), (0.0161886, 0, 3, 1, 0), (0.00318086, 1, 3, 1, 0),
    (0.015896, 0, 0, 2, 0), (0.0471729, 1, 0, 2, 0), (0.0196283, 3, 0, 2, 0),
    (-0.0502782, 0, 1, 2, 0), (-0.030055, 3, 1, 2, 0), (0.0417122, 2, 2, 2, 0),
    (-0.0397722, 0, 3, 2, 0), (-0.00350024, 0, 6, 2, 0), (-0.0106854, 3, 0, 0, 1),
    (0.00110903, 3, 3, 0, 1), (-0.000313912, 0, 6, 0, 1), (0.0035985, 3, 0, 1, 1),
    (-0.00142121, 0, 6, 1, 1), (-0.00383637, 1, 0, 2, 1), (0.0126803, 0, 2, 2, 1),
    (-0.00318278, 2, 3, 2, 1), (0.00334268, 0, 6, 2, 1), (-0.00183491, 1, 1, 0, 2),
    (0.000112451, 3, 2, 0, 2), (-2.97228e-05, 3, 6, 0, 2), (0.000269551, 1, 0, 1, 2),
    (0.00083265, 2, 0, 1, 2), (0.00155334, 0, 2, 1, 2), (0.000302683, 0, 6, 1, 2),
    (-0.0001843, 0, 0, 2, 2), (-0.000425399, 0, 3, 2, 2), (8.69243e-05, 3, 3, 2, 2),
    (-0.0004659, 0, 6, 2, 2), (5.54194e-05, 1, 6, 2, 2),
)

POWERING_COLUMNS = ("speed_m_s", "resistance_N", "effective_power_W", "thrust_N",
                    "advance_speed_m_s", "J", "K_T", "K_Q", "rps", "torque_N_m",
                    "eta_open_water", "delivered_power_W")


@dataclass(frozen=True)
class Propeller:
    """A Wageningen B-series propeller behind the hull ([vehicle.propeller]).

    Attributes
    ----------
    diameter_m : float
        Diameter D [m]
    pitch_ratio : float
        P/D [-], 0.5 to 1.4 in the series
    blade_area_ratio : float
        Expanded blade area ratio A_E/A_0 [-], 0.30 to 1.05 in the series
    blades : int
        Number of blades Z, 2 to 7 in the series
    thrust_deduction : float
        t [-]: T (1 - t) = R
    wake_fraction : float
        w [-]: V_A = U (1 - w)
    """

    diameter_m: float
    pitch_ratio: float
    blade_area_ratio: float
    blades: int = 3
    thrust_deduction: float = 0.0
    wake_fraction: float = 0.0


#: The keys of a propeller's block (``[vehicle.propeller]``, model.json ``propeller``).
PROPELLER_FIELDS = ("diameter_m", "pitch_ratio", "blade_area_ratio", "blades",
                    "thrust_deduction", "wake_fraction")


def propeller_from(block: dict[str, Any]) -> Propeller:
    """The :class:`Propeller` of a checked ``[vehicle.propeller]`` or model.json
    ``propeller`` block (keys :data:`PROPELLER_FIELDS`; t and w default 0, Z 3)."""
    return Propeller(**{k: block[k] for k in PROPELLER_FIELDS if block.get(k) is not None})


def _poly(terms, j, pd_ratio, ear, z):
    j = np.asarray(j, dtype=float)
    return sum(c * j**s * pd_ratio**t * ear**u * z**v for c, s, t, u, v in terms)


def bseries_kt_kq(j, pitch_ratio: float, blade_area_ratio: float,
                  blades: int) -> tuple[np.ndarray, np.ndarray]:
    """Open-water K_T and K_Q of a Wageningen B-series propeller at Re = 2e6 ([1]_, Table 1).

    Parameters
    ----------
    j : array_like
        Advance ratio J = V_A / (n D) [-]
    pitch_ratio : float
        P/D [-]
    blade_area_ratio : float
        A_E/A_0 [-]
    blades : int
        Z [-]

    Returns
    -------
    tuple of numpy.ndarray
        (K_T, K_Q) [-]
    """
    return (_poly(KT_TERMS, j, pitch_ratio, blade_area_ratio, blades),
            _poly(KQ_TERMS, j, pitch_ratio, blade_area_ratio, blades))


def effective_power(resistance_n, speed_m_s):
    """Effective (towing) power ``P_E = R U`` [W] of the resistance R [N] at speed U [m/s]."""
    return np.asarray(resistance_n, dtype=float) * np.asarray(speed_m_s, dtype=float)


def match_thrust(thrust_n: float, advance_speed_m_s: float, prop: Propeller,
                 rho: float) -> dict[str, float]:
    """The operating point of ``prop`` delivering ``thrust_n`` at ``advance_speed_m_s``.

    Solves ``K_T(J) / J^2 = T / (rho D^2 V_A^2)`` for J between 0.01 and the zero-thrust
    advance ratio, then ``n = V_A / (J D)``, ``Q = K_Q rho n^2 D^5``,
    ``eta_0 = J K_T / (2 pi K_Q)``, ``P_D = 2 pi n Q`` ([1]_; module docstring).

    Parameters
    ----------
    thrust_n : float
        Required thrust T [N], > 0
    advance_speed_m_s : float
        V_A [m/s], > 0
    prop : Propeller
    rho : float
        Water density [kg/m^3]

    Returns
    -------
    dict
        J, K_T, K_Q, rps [1/s], torque_N_m, eta_open_water, delivered_power_W

    Raises
    ------
    ValueError
        No advance ratio gives the thrust (the propeller is too small for it).
    """
    d, va = prop.diameter_m, advance_speed_m_s
    target = thrust_n / (rho * d**2 * va**2)
    js = np.linspace(0.01, 2.0, 400)
    kt, _ = bseries_kt_kq(js, prop.pitch_ratio, prop.blade_area_ratio, prop.blades)
    positive = np.nonzero(kt <= 0)[0]
    j_max = js[positive[0]] if positive.size else js[-1]

    def f(j: float) -> float:
        k, _ = bseries_kt_kq(j, prop.pitch_ratio, prop.blade_area_ratio, prop.blades)
        return float(k) / j**2 - target

    if f(0.01) < 0:
        raise ValueError(f"a B-series propeller of D = {d:g} m cannot deliver {thrust_n:.4g} N "
                         f"at V_A = {va:.4g} m/s.")
    j = brentq(f, 0.01, float(j_max), xtol=1e-12)
    kt_j, kq_j = (float(x) for x in bseries_kt_kq(j, prop.pitch_ratio,
                                                   prop.blade_area_ratio, prop.blades))
    n = va / (j * d)
    torque = kq_j * rho * n**2 * d**5
    return {"J": j, "K_T": kt_j, "K_Q": kq_j, "rps": n, "torque_N_m": torque,
            "eta_open_water": j * kt_j / (2.0 * math.pi * kq_j),
            "delivered_power_W": 2.0 * math.pi * n * torque}


def powering_table(speeds_m_s: Sequence[float], resistance_n: Sequence[float],
                   prop: Propeller, rho: float) -> pd.DataFrame:
    """powering.csv: the effective power and the propeller's operating point at each speed.

    Parameters
    ----------
    speeds_m_s : sequence of float
        Speeds U [m/s]
    resistance_n : sequence of float
        Resistance R at each speed [N]
    prop : Propeller
    rho : float
        Water density [kg/m^3]

    Returns
    -------
    pandas.DataFrame
        Columns :data:`POWERING_COLUMNS`
    """
    rows = [{"speed_m_s": u, "resistance_N": r, "effective_power_W": float(effective_power(r, u)),
             **_self_propulsion(r, u, prop, rho)}
            for u, r in zip(speeds_m_s, resistance_n, strict=True)]
    return pd.DataFrame(rows, columns=list(POWERING_COLUMNS))


def _self_propulsion(resistance_n: float, speed_m_s: float, prop: Propeller,
                     rho: float) -> dict[str, float]:
    """The thrust ``T = R / (1 - t)``, the advance speed ``V_A = U (1 - w)`` and the operating
    point (:func:`match_thrust`) that gives it."""
    thrust = resistance_n / (1.0 - prop.thrust_deduction)
    va = speed_m_s * (1.0 - prop.wake_fraction)
    return {"thrust_N": thrust, "advance_speed_m_s": va, **match_thrust(thrust, va, prop, rho)}


def self_propulsion_rps(resistance_n: float, speed_m_s: float, prop: Propeller,
                        rho: float) -> float:
    """The propeller's rate n [1/s] at the self-propulsion point: ``T (1 - t) = R`` at the
    speed U, the advance speed ``V_A = U (1 - w)`` ([2]_; :func:`match_thrust`).

    ``resistance_n`` is R [N] and ``speed_m_s`` U [m/s], both > 0; ``rho`` the water's density
    [kg/m^3]. A ValueError when the propeller cannot deliver the thrust (:func:`match_thrust`).
    """
    return float(_self_propulsion(resistance_n, speed_m_s, prop, rho)["rps"])


def kt_polynomial(prop: Propeller) -> np.ndarray:
    """K_T of ``prop`` as a polynomial in J: the coefficients of J^0 .. J^3 ([1]_, Table 1,
    with P/D, A_E/A_0 and Z fixed; the terms' J exponents are 0 to 3)."""
    coef = np.zeros(4)
    for c, s, t, u, v in KT_TERMS:
        coef[s] += c * prop.pitch_ratio**t * prop.blade_area_ratio**u * prop.blades**v
    return coef


def propeller_thrust(u_m_s: float, rps: float, prop: Propeller, rho: float,
                     kt: np.ndarray | None = None) -> float:
    """The thrust ``T = rho n^2 D^4 K_T(J)`` [N] at the rate n and the surge speed u, with
    ``J = u (1 - w) / (n D)`` ([1]_); an advance speed below 0 is taken as 0 (the series
    holds for J >= 0).

    Parameters
    ----------
    u_m_s : float
        Surge speed u [m/s]
    rps : float
        n [1/s], > 0
    prop : Propeller
    rho : float
        Water density [kg/m^3]
    kt : numpy.ndarray, optional
        :func:`kt_polynomial` of ``prop`` (computed when not given)
    """
    coef = kt_polynomial(prop) if kt is None else kt
    d = prop.diameter_m
    j = max(u_m_s, 0.0) * (1.0 - prop.wake_fraction) / (rps * d)
    k_t = coef[0] + j * (coef[1] + j * (coef[2] + j * coef[3]))
    return float(rho * rps**2 * d**4 * k_t)
