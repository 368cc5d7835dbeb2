"""Pressure hull: the wall thickness a cylindrical hull needs at a design depth.

The design tool's section on structure (its eqs. 5-7): a thin-walled cylinder (h < R/10) of
radius R under the hydrostatic pressure ``p = rho g depth`` carries the membrane stresses

    sigma_x = p R / (2 h)        (eq. 5, axial)
    sigma_theta = p R / h        (eq. 6, hoop: the larger, which sets yield)

and buckles between frames a length l apart in n circumferential lobes at von Mises' pressure
(eq. 7; Ross 2011, eq. 2.1 with lambda = pi R / l)

    q_c = (E h / R) / (n^2 - 1 + lambda^2 / 2)
          [ 1 / (n^2 / lambda^2 + 1)^2 + h^2 / (12 R^2 (1 - nu^2)) (n^2 - 1 + lambda^2)^2 ],

minimised over n >= 2. The required thickness is the larger of the yield thickness
``h_y = SF p R / sigma_y`` (eq. 6) and the thickness whose q_c equals ``SF p`` (eq. 7).

References
----------
.. [1] von Mises, R. (1914), Der kritische Aussendruck zylindrischer Rohre, VDI Zeitschrift 58,
   750-755; Ross, C. T. F. (2011), Pressure vessels: external pressure technology, 2nd ed.,
   Woodhead, ch. 2.
"""

from __future__ import annotations

import math

import pandas as pd
from scipy.optimize import brentq

from towtank.reference.constants import STANDARD_GRAVITY

__all__ = [
    "G",
    "axial_stress",
    "hoop_stress",
    "von_mises_pressure",
    "yield_thickness",
    "buckling_thickness",
    "pressure_hull_table",
]

G = STANDARD_GRAVITY  # [m/s²]


def axial_stress(pressure_pa, radius_m, thickness_m):
    """Axial membrane stress ``sigma_x = p R / (2 h)`` [Pa] (design tool eq. 5)."""
    return pressure_pa * radius_m / (2.0 * thickness_m)


def hoop_stress(pressure_pa, radius_m, thickness_m):
    """Hoop membrane stress ``sigma_theta = p R / h`` [Pa] (design tool eq. 6)."""
    return pressure_pa * radius_m / thickness_m


def von_mises_pressure(thickness_m: float, radius_m: float, frame_spacing_m: float,
                       e_pa: float, poisson: float, max_lobes: int = 40) -> tuple[float, int]:
    """Von Mises' lobar buckling pressure of a cylinder between frames (eq. 7; [1]_).

    Parameters
    ----------
    thickness_m : float
        Wall thickness h [m]
    radius_m : float
        Mean radius R [m]
    frame_spacing_m : float
        Unsupported length l between frames (or end closures) [m]
    e_pa : float
        Young's modulus E [Pa]
    poisson : float
        Poisson's ratio nu [-]
    max_lobes : int
        Largest lobe number n tried

    Returns
    -------
    tuple
        (q_c [Pa], n): the smallest pressure over n = 2 .. max_lobes and its lobe number
    """
    h, r = thickness_m, radius_m
    lam = math.pi * r / frame_spacing_m
    best = (math.inf, 2)
    for n in range(2, max_lobes + 1):
        q = (e_pa * h / r) / (n * n - 1 + 0.5 * lam**2) * (
            1.0 / (n * n / lam**2 + 1.0) ** 2
            + h * h / (12.0 * r * r * (1.0 - poisson**2)) * (n * n - 1 + lam**2) ** 2)
        best = min(best, (q, n))
    return best


def yield_thickness(pressure_pa: float, radius_m: float, yield_pa: float,
                    safety_factor: float = 1.0) -> float:
    """Thickness ``h = SF p R / sigma_y`` [m] at which the hoop stress (eq. 6) reaches yield."""
    return safety_factor * pressure_pa * radius_m / yield_pa


def buckling_thickness(pressure_pa: float, radius_m: float, frame_spacing_m: float,
                       e_pa: float, poisson: float, safety_factor: float = 1.0) -> float:
    """The thickness [m] whose von Mises pressure (eq. 7) is ``SF p`` (root in h)."""
    target = safety_factor * pressure_pa

    def f(h: float) -> float:
        return von_mises_pressure(h, radius_m, frame_spacing_m, e_pa, poisson)[0] - target

    return brentq(f, 1e-7 * radius_m, radius_m, xtol=1e-12)


def pressure_hull_table(depth_m: float, radius_m: float, frame_spacing_m: float,
                        yield_pa: float, e_pa: float, poisson: float, safety_factor: float,
                        rho: float) -> pd.DataFrame:
    """pressure_hull.csv: pressure, both thicknesses, the required one and its stresses.

    Parameters
    ----------
    depth_m : float
        Design depth [m]
    radius_m : float
        Hull radius R [m]
    frame_spacing_m : float
        Unsupported length l [m]
    yield_pa : float
        Yield stress of the material sigma_y [Pa]
    e_pa : float
        Young's modulus E [Pa]
    poisson : float
        Poisson's ratio [-]
    safety_factor : float
        SF on the pressure [-]
    rho : float
        Sea-water density [kg/m^3]

    Returns
    -------
    pandas.DataFrame
        quantity, value, unit, equation
    """
    p = rho * G * depth_m
    h_y = yield_thickness(p, radius_m, yield_pa, safety_factor)
    h_b = buckling_thickness(p, radius_m, frame_spacing_m, e_pa, poisson, safety_factor)
    h = max(h_y, h_b)
    q_c, n = von_mises_pressure(h, radius_m, frame_spacing_m, e_pa, poisson)
    ref = "design tool eqs. 5-7; von Mises (1914), Ross (2011) ch. 2"
    rows = [
        ("pressure", p, "Pa", "p = rho g depth"),
        ("thickness_yield", h_y, "m", "eq. 6: h = SF p R / sigma_y"),
        ("thickness_buckling", h_b, "m", "eq. 7: von Mises q_c(h) = SF p, min over n"),
        ("thickness_required", h, "m", "max of eqs. 6 and 7"),
        ("governed_by", 0.0 if h_y >= h_b else 1.0, "-", "0 yield (eq. 6), 1 buckling (eq. 7)"),
        ("hoop_stress", hoop_stress(p, radius_m, h), "Pa", "eq. 6: sigma_theta = p R / h"),
        ("axial_stress", axial_stress(p, radius_m, h), "Pa", "eq. 5: sigma_x = p R / (2 h)"),
        ("buckling_pressure", q_c, "Pa", "eq. 7 at the required thickness"),
        ("buckling_lobes", float(n), "-", "eq. 7: the lobe number n of the minimum"),
        ("thin_wall_ok", float(h < radius_m / 10.0), "-", "1 if h < R/10 (eqs. 5-7 apply)"),
    ]
    out = pd.DataFrame(rows, columns=["quantity", "value", "unit", "equation"])
    out["reference"] = ref
    return out
