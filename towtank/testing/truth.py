"""Truth of the synthetic days: the SUT-2 hull, tare and fin truths and the true forces they
give along a carriage profile (the generator's physics, see :mod:`towtank.testing.synthetic`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from towtank.reference.sandia import section_coefficients

GENERATOR_VERSION = "1.0"
"""Version of the generator's numerics; bumped whenever a seed would give different numbers."""

SUT2_TABLE4_PRIME: dict[str, float] = {
    "X_udot": -0.000780,
    "Y_vdot": -0.031,
    "Z_wdot": -0.031,
    "X_u|u|": -0.00330,
    "Y_v|v|": -0.096,
    "Z_w|w|": -0.096,
    "X_uv": -0.00014,
    "X_uw": -0.00014,
    "X_v|v|": 0.00103,
    "X_w|w|": 0.00103,
    "Y_uv": -0.00330,
    "Z_uw": -0.00330,
}
"""SUT-2 column of the SUT-2 report's Table 4 (prime values; added mass / (0.5 rho L^3),
damping / (0.5 rho L^2)), as in towtank/reference/data/sut2_table4.csv."""

COEFFICIENT_SYMBOLS = (
    "X_udot",
    "Y_vdot",
    "Z_wdot",
    "X_u|u|",
    "X_uv",
    "X_uw",
    "X_v|v|",
    "X_w|w|",
    "Y_uv",
    "Z_uw",
    "Y_v|v|",
    "Z_w|w|",
)
ADDED_MASS_SYMBOLS = ("X_udot", "Y_vdot", "Z_wdot")

HULL_SAMPLE_SEED = 20240521
FIN_SAMPLE_SEED = 20240522
#: Test dates written in the sample days' run sheets (the report's test date).
HULL_SAMPLE_DATE = "2024-05-21"
FIN_SAMPLE_DATE = "2024-05-22"

Config = Literal["hull", "fin", "sting"]
ChannelStyle = Literal["canonical", "lab"]
FileFormat = Literal["csv", "csv.gz", "tdms", "tdms-waveform", "lvm", "txt-eu", "mat", "mat73",
                     "hdf5", "hdf5-rate-name", "two-cell", "matrix", "speed-log",
                     "position-log", "zero-file", "no-speed"]
SheetFormat = Literal["csv", "xlsx"]

REFERENCE_FS = 1000.0  # [Hz] sampling rate at which the white-noise sigmas of Noise are given



@dataclass(frozen=True)
class HullTruth:
    """The true hydrodynamics of a captive axisymmetric hull.

    Parameters
    ----------
    m : float
        Weighed model mass downstream of the balance [kg].
    X_udot, Y_vdot : float
        Axial and transverse added mass [kg], SNAME sign (negative).
    a2, b1, c0 : float
        C_D(alpha) = a2 alpha^2 + b1 |alpha| + c0 on the frontal area [-], alpha [rad],
        |alpha| <= 30 deg.
    cd90 : float
        Transverse-tow drag coefficient on the lateral area [-].
    cl_alpha : float, default 2.0
        Body-lift slope on the frontal area [1/rad].
    length, diameter : float
        Overall length L [m] and diameter D [m].
    lateral_area : float, default 0.0152
        Projected side area for transverse tows [m^2].

    Its ``frontal_area`` [m^2] is pi D^2 / 4 of its diameter.
    """

    m: float
    X_udot: float
    Y_vdot: float
    a2: float
    b1: float
    c0: float
    cd90: float
    cl_alpha: float = 2.0
    length: float = 0.353
    diameter: float = 0.05
    lateral_area: float = 0.0152

    @property
    def frontal_area(self) -> float:
        """The hull's frontal area π·D²/4 [m²]."""
        return math.pi * self.diameter**2 / 4.0

    def cd(self, alpha_deg: Any) -> np.ndarray:
        """C_D(alpha) on the frontal area [-] for |alpha| <= 30 deg (``alpha_deg`` [deg])."""
        al = np.radians(np.abs(np.asarray(alpha_deg, dtype=float)))
        return self.a2 * al**2 + self.b1 * al + self.c0

    def cl(self, alpha_deg: Any) -> np.ndarray:
        """Body-lift coefficient on the frontal area [-] (``alpha_deg`` [deg], |alpha| <= 30)."""
        return self.cl_alpha * np.radians(np.asarray(alpha_deg, dtype=float))

    def m_eff(self, alpha_deg: Any) -> np.ndarray:
        """Inertia along the tow, m - X_udot cos^2 alpha - Y_vdot sin^2 alpha [kg]."""
        al = np.radians(np.asarray(alpha_deg, dtype=float))
        return self.m - self.X_udot * np.cos(al) ** 2 - self.Y_vdot * np.sin(al) ** 2

    def coefficients(self, rho: float) -> dict[str, float]:
        """The twelve coefficients of docs/formats.md, model-scale SI (kg, kg/m), at ``rho``.

        Parameters
        ----------
        rho : float
            Water density [kg/m^3] used to turn C_D into dimensional damping.
        """
        q = 0.5 * rho * self.frontal_area
        q_lat = 0.5 * rho * self.lateral_area
        x_uu = -q * self.c0
        x_uv = -q * self.b1
        x_vv = -q * (self.a2 - self.c0 / 2.0)
        y_vv = -q_lat * self.cd90
        return {
            "X_udot": float(self.X_udot),
            "Y_vdot": float(self.Y_vdot),
            "Z_wdot": float(self.Y_vdot),
            "X_u|u|": float(x_uu),
            "X_uv": float(x_uv),
            "X_uw": float(x_uv),
            "X_v|v|": float(x_vv),
            "X_w|w|": float(x_vv),
            "Y_uv": float(x_uu),
            "Z_uw": float(x_uu),
            "Y_v|v|": float(y_vv),
            "Z_w|w|": float(y_vv),
        }

    def primes(self, rho: float) -> dict[str, float]:
        """The coefficients made non-dimensional: / (0.5 rho L^3) or / (0.5 rho L^2) [-].

        Parameters
        ----------
        rho : float
            Water density [kg/m^3].
        """
        out = {}
        for sym, value in self.coefficients(rho).items():
            k = 3 if sym in ADDED_MASS_SYMBOLS else 2
            out[sym] = value / (0.5 * rho * self.length**k)
        return out


def sut2_hull_truth(
    rho: float,
    length: float = 0.353,
    diameter: float = 0.05,
    mass: float = 0.552,
    lateral_area: float = 0.0152,
    cl_alpha: float = 2.0,
) -> HullTruth:
    """The SUT-2 quarter-scale hull of the SUT-2 report, from its Table 4 (SUT-2 column).

    Prime values are made dimensional with 0.5 rho L^3 (added mass) and 0.5 rho L^2 (damping)
    and inverted through docs/method.md's mappings: c0 = -X_u|u|/(0.5 rho A),
    b1 = -X_uv/(0.5 rho A),
    a2 = -X_v|v|/(0.5 rho A) + c0/2, cd90 = -Y_v|v|/(0.5 rho A_lat).

    Parameters
    ----------
    rho : float
        Tank water density [kg/m^3].
    length : float, default 0.353
        Model length L [m].
    diameter : float, default 0.05
        Model diameter D [m].
    mass : float, default 0.552
        Weighed model mass [kg].
    lateral_area : float, default 0.0152
        Projected side area [m^2].
    cl_alpha : float, default 2.0
        Body-lift slope on the frontal area [1/rad] (not in Table 4).

    Returns
    -------
    HullTruth
    """
    p = SUT2_TABLE4_PRIME
    mass_scale = 0.5 * rho * length**3
    damp_scale = 0.5 * rho * length**2
    frontal = math.pi * diameter**2 / 4.0
    q = 0.5 * rho * frontal
    c0 = -p["X_u|u|"] * damp_scale / q
    b1 = -p["X_uv"] * damp_scale / q
    a2 = -p["X_v|v|"] * damp_scale / q + c0 / 2.0
    cd90 = -p["Y_v|v|"] * damp_scale / (0.5 * rho * lateral_area)
    return HullTruth(
        m=mass,
        X_udot=p["X_udot"] * mass_scale,
        Y_vdot=p["Y_vdot"] * mass_scale,
        a2=a2,
        b1=b1,
        c0=c0,
        cd90=cd90,
        cl_alpha=cl_alpha,
        length=length,
        diameter=diameter,
        lateral_area=lateral_area,
    )


@dataclass(frozen=True)
class TareTruth:
    """Force on the mounting (sting or fin post) alone: F = t2 U|U| + t1 U + m_t a.

    Parameters
    ----------
    t2 : float, default 0.08
        Quadratic drag term [N s^2/m^2].
    t1 : float, default 0.01
        Linear drag term [N s/m].
    m_t : float, default 0.08
        Inertia of the mounting downstream of the balance, with its added mass [kg].
    lift_t2, lift_t1, lift_m_t : float
        The same for the lift channel [N s^2/m^2], [N s/m], [kg]; small.
    """

    t2: float = 0.08
    t1: float = 0.01
    m_t: float = 0.08
    lift_t2: float = 0.005
    lift_t1: float = -0.002
    lift_m_t: float = 0.004

    @classmethod
    def none(cls) -> TareTruth:
        """No mounting force at all."""
        return cls(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


@dataclass(frozen=True)
class FinTruth:
    """A fin tested on its own (NACA 0015 section, 2-D Sandia data at each sample's Re).

    Parameters
    ----------
    chord : float, default 0.12
        Chord c [m].
    span : float, default 0.15
        Span [m]; planform area S = chord * span.
    m_fin : float, default 0.25
        Inertia of the fin downstream of the balance, with its added mass [kg].
    section : str, default "NACA0015"
    """

    chord: float = 0.12
    span: float = 0.15
    m_fin: float = 0.25
    section: str = "NACA0015"

    @property
    def area(self) -> float:
        """Planform area S = chord * span [m^2]."""
        return self.chord * self.span



def hull_forces(
    speed: np.ndarray,
    accel: np.ndarray,
    angle_deg: float,
    hull: HullTruth,
    rho: float,
) -> tuple[np.ndarray, np.ndarray]:
    """True drag and lift on a captive hull (mounting excluded).

    Parameters
    ----------
    speed : numpy.ndarray
        Tow speed U [m/s].
    accel : numpy.ndarray
        Tow acceleration a [m/s^2].
    angle_deg : float
        Angle of the hull to the tow [deg]: |angle| <= 30 or |angle| = 90 (transverse tow).
    hull : HullTruth
    rho : float
        Water density [kg/m^3].

    Returns
    -------
    drag : numpy.ndarray
        R(U, alpha) + M_eff(alpha) a [N], positive pulling the model forward.
    lift : numpy.ndarray
        0.5 rho A C_L_alpha alpha U|U| [N]; zero at 0 and 90 deg.
    """
    u = np.asarray(speed, dtype=float)
    a = np.asarray(accel, dtype=float)
    ang = abs(float(angle_deg))
    uu = u * np.abs(u)
    if ang == 90.0:
        drag = 0.5 * rho * hull.lateral_area * hull.cd90 * uu
        lift = np.zeros_like(u)
    elif ang <= 30.0:
        assert hull.frontal_area is not None  # set by HullTruth.__post_init__
        drag = 0.5 * rho * hull.frontal_area * hull.cd(angle_deg) * uu
        lift = 0.5 * rho * hull.frontal_area * hull.cl(angle_deg) * uu
    else:
        raise ValueError(
            f"The synthetic hull covers |angle| <= 30 deg and 90 deg, not {angle_deg:g} deg."
        )
    return drag + hull.m_eff(angle_deg) * a, lift


def fin_forces(
    speed: np.ndarray,
    accel: np.ndarray,
    angle_deg: float,
    fin: FinTruth,
    rho: float,
    nu: float,
) -> tuple[np.ndarray, np.ndarray]:
    """True drag and lift on a fin from the 2-D Sandia NACA 0015 data (mounting excluded).

    Re = |U| c / nu per sample, clipped to the table's range [1e4, 1e7] (where it matters only
    at speeds so low that the force is negligible).

    Parameters
    ----------
    speed : numpy.ndarray
        Tow speed U [m/s].
    accel : numpy.ndarray
        Tow acceleration a [m/s^2].
    angle_deg : float
        Angle of attack [deg].
    fin : FinTruth
    rho : float
        Water density [kg/m^3].
    nu : float
        Kinematic viscosity [m^2/s].

    Returns
    -------
    drag : numpy.ndarray
        0.5 rho S C_D U|U| + m_fin a [N].
    lift : numpy.ndarray
        0.5 rho S C_L U|U| [N].
    """
    u = np.asarray(speed, dtype=float)
    a = np.asarray(accel, dtype=float)
    re = np.clip(np.abs(u) * fin.chord / nu, 1e4, 1e7)
    cl, cd = section_coefficients(np.full(u.shape, float(angle_deg)), re)
    q = 0.5 * rho * fin.area * (u * np.abs(u))
    return q * cd + fin.m_fin * a, q * cl


def tare_forces(
    speed: np.ndarray, accel: np.ndarray, tare: TareTruth
) -> tuple[np.ndarray, np.ndarray]:
    """Drag and lift on the mounting alone: t2 U|U| + t1 U + m_t a per channel.

    Parameters
    ----------
    speed : numpy.ndarray
        Tow speed U [m/s].
    accel : numpy.ndarray
        Tow acceleration a [m/s^2].
    tare : TareTruth

    Returns
    -------
    drag, lift : numpy.ndarray
        Tare forces [N].
    """
    u = np.asarray(speed, dtype=float)
    a = np.asarray(accel, dtype=float)
    uu = u * np.abs(u)
    drag = tare.t2 * uu + tare.t1 * u + tare.m_t * a
    lift = tare.lift_t2 * uu + tare.lift_t1 * u + tare.lift_m_t * a
    return drag, lift


def model_forces(
    config: str,
    angle_deg: float,
    u: np.ndarray,
    a: np.ndarray,
    *,
    hull: HullTruth | None,
    fin: FinTruth | None,
    rho: float,
    nu: float,
) -> tuple[np.ndarray, np.ndarray]:
    """The model's true drag and lift [N] in a run of ``config`` (``"hull"``, ``"fin"``; the
    sting alone otherwise: zero) at ``angle_deg`` [deg], speed ``u`` [m/s] and acceleration
    ``a`` [m/s²], in water of density ``rho`` [kg/m³] and kinematic viscosity ``nu`` [m²/s]."""
    if config == "hull":
        assert hull is not None
        return hull_forces(u, a, angle_deg, hull, rho)
    if config == "fin":
        assert fin is not None
        return fin_forces(u, a, angle_deg, fin, rho, nu)
    return np.zeros_like(u), np.zeros_like(u)


# ================================================================================= simulate
