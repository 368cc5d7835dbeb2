"""Synthetic towing-tank runs whose truth is exactly known.

The generator behind the shipped sample days and every physics test. A run is built in four
small, vectorised steps (no per-sample Python loops)::

    plan_profile / carriage_profile        carriage speed U(t) and acceleration a(t)
    hull_forces / fin_forces / tare_forces true forces on the model and on the mounting
    simulate_run                           + zero offset, drift, noise, vibration, mains hum
    write_run_file / write_run_sheet       CSV, CSV.gz or TDMS files and a run sheet

and whole days are made by :func:`make_hull_day` and :func:`make_fin_day`, which also write a
``truth.json`` holding everything needed to check a reduction: the truth dataclasses, the twelve
coefficients at the tank water's density, and per-run truth (plateau forces, tare, phases).

Conventions are those of FORMATS.md and METHOD.md: SI units, angles in degrees at the interface,
SNAME signs (added mass and damping negative). ``drag`` is the balance force along the tow
direction, positive when it pulls the model forward, so that at constant acceleration ``a``

    D_model = R(U, alpha) + (m - X_udot cos^2 alpha - Y_vdot sin^2 alpha) a.

Randomness comes only from the :class:`numpy.random.Generator` passed in (or derived from a
seed), so a seed gives identical numbers and, through the writers, identical file bytes.
"""

from __future__ import annotations

import datetime as _dt
import gzip
import io
import json
import math
import re
import shutil
import zipfile
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any, Literal

import numpy as np
import pandas as pd

from towtank import __version__ as _TOWTANK_VERSION

__all__ = [
    "GENERATOR_VERSION",
    "SUT2_TABLE4_PRIME",
    "CarriagePlan",
    "plan_profile",
    "carriage_profile",
    "HullTruth",
    "sut2_hull_truth",
    "TareTruth",
    "FinTruth",
    "Noise",
    "hull_forces",
    "fin_forces",
    "tare_forces",
    "simulate_run",
    "LabChannels",
    "to_file_frame",
    "write_run_file",
    "write_run_sheet",
    "RunSpec",
    "DayTruth",
    "hull_day_plan",
    "fin_day_plan",
    "make_hull_day",
    "make_fin_day",
    "write_truth",
    "load_truth",
    "write_protocol",
    "hull_protocol_sections",
    "fin_protocol_sections",
    "write_sample_protocols",
    "write_sample_days",
]

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
damping / (0.5 rho L^2)), as in shared/reference/sut2_table4.csv."""

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
FileFormat = Literal["csv", "csv.gz", "tdms"]
SheetFormat = Literal["csv", "xlsx"]

_REFERENCE_FS = 1000.0  # [Hz] sampling rate at which the white-noise sigmas of Noise are given


# ========================================================================== carriage profile
@dataclass(frozen=True)
class CarriagePlan:
    """A jerk-limited carriage run, in continuous time.

    Phases: still until ``t_accel_start``; S-curve ramp (jerk-limited rise of the acceleration
    to ``accel``, constant-acceleration stretch ``t_const_accel_start`` to
    ``t_const_accel_end``, jerk-limited fall to zero acceleration at exactly ``speed`` at
    ``t_plateau_start``); plateau at exactly ``speed`` until ``t_plateau_end``; mirrored
    deceleration at ``decel`` (constant stretch ``t_decel_const_start`` to
    ``t_decel_const_end``) until ``t_decel_end``; still until ``duration``.

    All times [s] from the start of the file; ``speed`` [m/s], ``accel``, ``decel`` [m/s^2],
    ``jerk_up``, ``jerk_down`` [m/s^3], ``distance`` [m] travelled.
    """

    speed: float
    accel: float
    decel: float
    jerk_up: float
    jerk_down: float
    t_accel_start: float
    t_const_accel_start: float
    t_const_accel_end: float
    t_plateau_start: float
    t_plateau_end: float
    t_decel_const_start: float
    t_decel_const_end: float
    t_decel_end: float
    duration: float
    distance: float

    @property
    def plateau_s(self) -> float:
        """Length of the steady plateau [s]."""
        return self.t_plateau_end - self.t_plateau_start

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Carriage speed and acceleration at times ``t``.

        Parameters
        ----------
        t : numpy.ndarray
            Sample times [s].

        Returns
        -------
        speed : numpy.ndarray
            Carriage speed U(t) [m/s]; exactly ``self.speed`` on the plateau, >= 0.
        accel : numpy.ndarray
            Carriage acceleration a(t) [m/s^2]; exactly ``self.accel`` on the constant stretch.
        """
        t = np.asarray(t, dtype=float)
        v, acc, dec, ju, jd = self.speed, self.accel, self.decel, self.jerk_up, self.jerk_down
        t0, t1, t2, t3 = (
            self.t_accel_start,
            self.t_const_accel_start,
            self.t_const_accel_end,
            self.t_plateau_start,
        )
        t4, t5, t6, t7 = (
            self.t_plateau_end,
            self.t_decel_const_start,
            self.t_decel_const_end,
            self.t_decel_end,
        )
        conds = [t < t0, t < t1, t < t2, t < t3, t < t4, t < t5, t < t6, t < t7]
        zero = np.zeros_like(t)
        tau_up = t - t0
        tau_top = t3 - t
        tau_dn = t - t4
        tau_end = t7 - t
        u1 = 0.5 * acc * (t1 - t0)  # speed at the start of the constant-acceleration stretch
        u5 = v - 0.5 * dec * (t5 - t4)  # speed at the start of the constant-deceleration stretch
        speed = np.select(
            conds,
            [
                zero,
                0.5 * ju * tau_up**2,
                u1 + acc * (t - t1),
                v - 0.5 * ju * tau_top**2,
                np.full_like(t, v),
                v - 0.5 * jd * tau_dn**2,
                u5 - dec * (t - t5),
                0.5 * jd * tau_end**2,
            ],
            default=0.0,
        )
        accel = np.select(
            conds,
            [
                zero,
                ju * tau_up,
                np.full_like(t, acc),
                ju * tau_top,
                zero,
                -jd * tau_dn,
                np.full_like(t, -dec),
                -jd * tau_end,
            ],
            default=0.0,
        )
        return np.maximum(speed, 0.0), accel

    def phases(self) -> dict[str, float]:
        """Phase boundaries [s], keyed as in the per-run truth of :func:`simulate_run`."""
        return {
            "t_still_end": self.t_accel_start,
            "t_accel_start": self.t_accel_start,
            "t_const_accel_start": self.t_const_accel_start,
            "t_const_accel_end": self.t_const_accel_end,
            "t_accel_end": self.t_plateau_start,
            "t_plateau_start": self.t_plateau_start,
            "t_plateau_end": self.t_plateau_end,
            "t_decel_start": self.t_plateau_end,
            "t_decel_const_start": self.t_decel_const_start,
            "t_decel_const_end": self.t_decel_const_end,
            "t_decel_end": self.t_decel_end,
            "t_end": self.duration,
        }


def _ramp_jerk(speed: float, accel: float, jerk: float, min_const_fraction: float) -> float:
    """Jerk of an S-curve ramp, raised where needed so a constant-acceleration stretch remains.

    The stretch gains ``speed - accel**2/jerk`` of the speed; the jerk is raised so that this is
    at least ``min_const_fraction`` of ``speed``.
    """
    return max(jerk, accel**2 / (speed * (1.0 - min_const_fraction)))


def plan_profile(
    speed: float,
    accel: float,
    *,
    jerk: float = 4.0,
    pre_still_s: float = 3.0,
    post_still_s: float = 3.0,
    plateau_s: float | None = None,
    decel: float | None = None,
    tank_length_m: float = 100.0,
    min_const_fraction: float = 0.5,
) -> CarriagePlan:
    """Plan a jerk-limited carriage run that fits the tank.

    Parameters
    ----------
    speed : float
        Set (plateau) speed [m/s], > 0.
    accel : float
        Set acceleration of the constant-acceleration stretch [m/s^2], > 0.
    jerk : float, default 4.0
        Jerk of the S-curve transitions [m/s^3]. Raised for the run where needed so that the
        constant-acceleration stretch gains at least ``min_const_fraction`` of the speed (low
        speeds, high accelerations).
    pre_still_s, post_still_s : float, default 3.0
        Carriage at rest before and after the run [s] (the zero windows).
    plateau_s : float, optional
        Length of the steady plateau [s]. Default: as long as the rest of the tank allows, at
        most 8 s; at least 2 s, else ValueError.
    decel : float, optional
        Deceleration [m/s^2], > 0. Default ``max(accel, 0.5)`` clipped to at most 2.0.
    tank_length_m : float, default 100.0
        Usable length of the tank [m].
    min_const_fraction : float, default 0.5
        Least fraction of the speed gained at constant acceleration [-], in [0, 1).

    Returns
    -------
    CarriagePlan

    Raises
    ------
    ValueError
        If an argument is out of range or the run does not fit the tank.
    """
    for label, value in (("speed", speed), ("accel", accel), ("jerk", jerk)):
        if not (math.isfinite(value) and value > 0.0):
            raise ValueError(f"{label} must be a positive number, not {value!r}.")
    if not (0.0 <= min_const_fraction < 1.0):
        raise ValueError("min_const_fraction must be in [0, 1).")
    if pre_still_s < 0.0 or post_still_s < 0.0:
        raise ValueError("pre_still_s and post_still_s must not be negative.")
    if decel is None:
        decel = min(max(accel, 0.5), 2.0)
    if not (math.isfinite(decel) and decel > 0.0):
        raise ValueError(f"decel must be a positive number, not {decel!r}.")
    if plateau_s is not None and not (math.isfinite(plateau_s) and plateau_s > 0.0):
        raise ValueError(f"plateau_s must be a positive number, not {plateau_s!r}.")

    ju = _ramp_jerk(speed, accel, jerk, min_const_fraction)
    jd = _ramp_jerk(speed, decel, jerk, min_const_fraction)
    tju, tjd = accel / ju, decel / jd
    t_up = speed / accel + tju  # S-curve ramp time; its speed is point-symmetric about the middle
    t_dn = speed / decel + tjd
    ramps_m = 0.5 * speed * (t_up + t_dn)
    if plateau_s is None:
        room_s = (tank_length_m - ramps_m) / speed
        if room_s < 2.0:
            raise ValueError(
                f"A run to {speed:g} m/s at {accel:g} m/s^2 does not fit the {tank_length_m:g} m "
                f"tank with a plateau of at least 2 s (ramps need {ramps_m:.1f} m)."
            )
        plateau_s = min(8.0, room_s)
    distance = ramps_m + speed * plateau_s
    if distance > tank_length_m * (1.0 + 1e-12):
        raise ValueError(
            f"A run to {speed:g} m/s at {accel:g} m/s^2 with a {plateau_s:g} s plateau needs "
            f"{distance:.1f} m, more than the {tank_length_m:g} m tank."
        )

    t0 = float(pre_still_s)
    t3 = t0 + t_up
    t4 = t3 + plateau_s
    t7 = t4 + t_dn
    return CarriagePlan(
        speed=float(speed),
        accel=float(accel),
        decel=float(decel),
        jerk_up=float(ju),
        jerk_down=float(jd),
        t_accel_start=t0,
        t_const_accel_start=t0 + tju,
        t_const_accel_end=t3 - tju,
        t_plateau_start=t3,
        t_plateau_end=t4,
        t_decel_const_start=t4 + tjd,
        t_decel_const_end=t7 - tjd,
        t_decel_end=t7,
        duration=t7 + post_still_s,
        distance=float(distance),
    )


def _sample_times(duration: float, fs: float) -> np.ndarray:
    if not (math.isfinite(fs) and fs > 0.0):
        raise ValueError(f"fs must be a positive number, not {fs!r}.")
    n = int(math.floor(duration * fs + 1e-9)) + 1
    return np.arange(n) / fs


def carriage_profile(
    speed: float,
    accel: float,
    *,
    fs: float,
    jerk: float = 4.0,
    pre_still_s: float = 3.0,
    post_still_s: float = 3.0,
    plateau_s: float | None = None,
    decel: float | None = None,
    tank_length_m: float = 100.0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sampled carriage profile: still, S-curve ramp, plateau, S-curve stop, still.

    Parameters
    ----------
    speed : float
        Set speed [m/s].
    accel : float
        Set acceleration [m/s^2].
    fs : float
        Sampling rate [Hz].
    jerk, pre_still_s, post_still_s, plateau_s, decel, tank_length_m
        As in :func:`plan_profile` ([m/s^3], [s], [s], [s], [m/s^2], [m]).

    Returns
    -------
    t : numpy.ndarray
        Sample times [s], ``arange(n) / fs``.
    U : numpy.ndarray
        Carriage speed [m/s].
    a : numpy.ndarray
        Carriage acceleration [m/s^2].
    """
    plan = plan_profile(
        speed,
        accel,
        jerk=jerk,
        pre_still_s=pre_still_s,
        post_still_s=post_still_s,
        plateau_s=plateau_s,
        decel=decel,
        tank_length_m=tank_length_m,
    )
    t = _sample_times(plan.duration, fs)
    u, a = plan.evaluate(t)
    return t, u, a


# ===================================================================================== truth
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
    frontal_area : float, optional
        Frontal area A [m^2]; default pi D^2 / 4.
    lateral_area : float, default 0.0152
        Projected side area for transverse tows [m^2].
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
    frontal_area: float | None = None
    lateral_area: float = 0.0152

    def __post_init__(self) -> None:
        if self.frontal_area is None:
            object.__setattr__(self, "frontal_area", math.pi * self.diameter**2 / 4.0)

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
        """The twelve FORMATS coefficients, model-scale SI (kg, kg/m), at density ``rho``.

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
    and inverted through METHOD.md's mappings: c0 = -X_u|u|/(0.5 rho A), b1 = -X_uv/(0.5 rho A),
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
        frontal_area=frontal,
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


@dataclass(frozen=True)
class Noise:
    """Imperfections of the recorded channels. White-noise sigmas are given at 1 kHz and scaled
    by sqrt(fs / 1000), so that the noise density is the same at any sampling rate.

    Parameters
    ----------
    zero_offset : float, default 0.3
        Balance zero offset drawn uniformly in [-zero_offset, zero_offset] per run and channel [N].
    drift : float, default 0.005
        Linear drift over the whole run, total uniformly in [-drift, drift] [N].
    balance_sigma : float, default 0.005
        White balance noise at 1 kHz [N].
    vibration_per_speed : float, default 0.0015
        Carriage vibration amplitude per unit speed [N per m/s] (3 mN at 2 m/s).
    vibration_hz : tuple of float, default (8.0, 15.0)
        Range of the vibration frequency drawn per run [Hz].
    hum_amplitude : float, default 0.002
        Mains hum amplitude [N].
    hum_hz : float, default 50.0
        Mains frequency [Hz].
    speed_sigma : float, default 0.001
        White noise of the recorded speed at 1 kHz [m/s].
    speed_quantum : float, default 1e-4
        Resolution of the recorded speed [m/s]; 0 for none.
    accel_sigma : float, default 0.02
        White noise of the optional accel channel at 1 kHz [m/s^2].
    """

    zero_offset: float = 0.3
    drift: float = 0.005
    balance_sigma: float = 0.005
    vibration_per_speed: float = 0.0015
    vibration_hz: tuple[float, float] = (8.0, 15.0)
    hum_amplitude: float = 0.002
    hum_hz: float = 50.0
    speed_sigma: float = 0.001
    speed_quantum: float = 1e-4
    accel_sigma: float = 0.02

    @classmethod
    def quiet(cls) -> Noise:
        """No noise, no zero offset, no drift: recorded channels equal the truth."""
        return cls(
            zero_offset=0.0,
            drift=0.0,
            balance_sigma=0.0,
            vibration_per_speed=0.0,
            hum_amplitude=0.0,
            speed_sigma=0.0,
            speed_quantum=0.0,
            accel_sigma=0.0,
        )


# ==================================================================================== forces
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
    from towtank.sandia import section_coefficients

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


def _model_forces(
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
    if config == "hull":
        assert hull is not None
        return hull_forces(u, a, angle_deg, hull, rho)
    if config == "fin":
        assert fin is not None
        return fin_forces(u, a, angle_deg, fin, rho, nu)
    return np.zeros_like(u), np.zeros_like(u)


# ================================================================================= simulate
def _as_rng(rng: np.random.Generator | int | None) -> np.random.Generator:
    if isinstance(rng, np.random.Generator):
        return rng
    return np.random.default_rng(0 if rng is None else rng)


def _water(temperature_C: float, water_type: str) -> Any:
    from towtank.water import water_properties

    return water_properties(temperature_C, water_type)


def simulate_run(
    config: Config,
    angle_deg: float,
    speed: float,
    accel: float,
    *,
    hull: HullTruth | None = None,
    tare: TareTruth | None = None,
    fin: FinTruth | None = None,
    noise: Noise | None = None,
    water: Any = None,
    fs: float = 1000.0,
    rng: np.random.Generator | int | None = None,
    jerk: float = 4.0,
    decel: float | None = None,
    plateau_s: float | None = None,
    pre_still_s: float = 3.0,
    post_still_s: float = 3.0,
    tank_length_m: float = 100.0,
    accel_channel: bool = False,
    temperature_C: float = 18.0,
    water_type: str = "fresh",
) -> tuple[pd.DataFrame, dict[str, Any]]:
    """Simulate one run: the recorded channels and the run's exact truth.

    drag_raw = D_model + F_tare + zero + drift(t) + vibration + hum + white noise, the same for
    lift with its own offset, drift and phases; speed = U + white noise, quantised; the optional
    accel channel = a + white noise.

    Parameters
    ----------
    config : {"hull", "fin", "sting"}
        What is mounted; ``"sting"`` records the mounting (tare) force alone.
    angle_deg : float
        Angle to the tow [deg].
    speed : float
        Set speed [m/s].
    accel : float
        Set acceleration [m/s^2].
    hull : HullTruth, optional
        Default :func:`sut2_hull_truth` at the run's density (hull runs).
    tare : TareTruth, optional
        Mounting force; default none (sting runs then record only zero, drift and noise).
    fin : FinTruth, optional
        Default :class:`FinTruth` (fin runs).
    noise : Noise, optional
        Default ``Noise()`` (realistic); ``Noise.quiet()`` for exact channels.
    water : object with ``rho`` [kg/m^3] and ``nu`` [m^2/s], optional
        Default ``towtank.water.water_properties(temperature_C, water_type)``.
    fs : float, default 1000.0
        Sampling rate [Hz].
    rng : numpy.random.Generator or int, optional
        Random source, or a seed for one (default seed 0).
    jerk, decel, plateau_s, pre_still_s, post_still_s, tank_length_m
        Carriage profile, see :func:`plan_profile` ([m/s^3], [m/s^2], [s], [s], [s], [m]).
    accel_channel : bool, default False
        Record an ``accel`` channel.
    temperature_C : float, default 18.0
        Water temperature [degC], used only when ``water`` is not given.
    water_type : str, default "fresh"
        ``fresh`` or ``sea``, used only when ``water`` is not given.

    Returns
    -------
    frame : pandas.DataFrame
        Columns ``time`` [s], ``speed`` [m/s], (``accel`` [m/s^2],) ``drag`` [N], ``lift`` [N].
    truth : dict
        Per-run truth: set speed and acceleration, phase boundaries [s], plateau model drag and
        lift (zero, drift, tare removed) [N], plateau tare [N], inertia along the tow [kg],
        plateau coefficients and Reynolds number, water, realised offsets and drifts [N].
    """
    if config not in ("hull", "fin", "sting"):
        raise ValueError(f"config must be 'hull', 'fin' or 'sting', not {config!r}.")
    rng = _as_rng(rng)
    noise = Noise() if noise is None else noise
    if water is None:
        water = _water(temperature_C, water_type)
    rho, nu = float(water.rho), float(water.nu)
    if config == "hull" and hull is None:
        hull = sut2_hull_truth(rho)
    if config == "fin" and fin is None:
        fin = FinTruth()
    tare = TareTruth.none() if tare is None else tare

    plan = plan_profile(
        speed,
        accel,
        jerk=jerk,
        pre_still_s=pre_still_s,
        post_still_s=post_still_s,
        plateau_s=plateau_s,
        decel=decel,
        tank_length_m=tank_length_m,
    )
    t = _sample_times(plan.duration, fs)
    u, a = plan.evaluate(t)
    n = t.size

    d_model, l_model = _model_forces(config, angle_deg, u, a, hull=hull, fin=fin, rho=rho, nu=nu)
    d_tare, l_tare = tare_forces(u, a, tare)

    # random draws, always in this order (so a seed gives the same run whatever the amplitudes)
    zero = noise.zero_offset * rng.uniform(-1.0, 1.0, size=2)
    drift = noise.drift * rng.uniform(-1.0, 1.0, size=2)
    vib_hz = float(rng.uniform(*noise.vibration_hz))
    phases = rng.uniform(0.0, 2.0 * np.pi, size=4)
    white = rng.standard_normal((3, n))
    accel_white = rng.standard_normal(n) if accel_channel else None

    scale = math.sqrt(fs / _REFERENCE_FS)
    ramp = t / t[-1] if n > 1 else np.zeros_like(t)
    w_vib = 2.0 * np.pi * vib_hz * t
    w_hum = 2.0 * np.pi * noise.hum_hz * t
    vib_amp = noise.vibration_per_speed * np.abs(u)

    def disturbance(k: int) -> np.ndarray:
        return (
            zero[k]
            + drift[k] * ramp
            + vib_amp * np.sin(w_vib + phases[k])
            + noise.hum_amplitude * np.sin(w_hum + phases[2 + k])
            + noise.balance_sigma * scale * white[k]
        )

    drag_rec = d_model + d_tare + disturbance(0)
    lift_rec = l_model + l_tare + disturbance(1)
    speed_rec = u + noise.speed_sigma * scale * white[2]
    if noise.speed_quantum > 0.0:
        speed_rec = np.round(speed_rec / noise.speed_quantum) * noise.speed_quantum

    columns: dict[str, np.ndarray] = {"time": t, "speed": speed_rec}
    if accel_white is not None:
        columns["accel"] = a + noise.accel_sigma * scale * accel_white
    columns["drag"] = drag_rec
    columns["lift"] = lift_rec
    frame = pd.DataFrame(columns)

    # plateau truth through the very same functions, so it equals the plateau samples bit for bit
    v_arr, zero_arr = np.array([plan.speed]), np.array([0.0])
    d_plat, l_plat = _model_forces(
        config, angle_deg, v_arr, zero_arr, hull=hull, fin=fin, rho=rho, nu=nu
    )
    td_plat, tl_plat = tare_forces(v_arr, zero_arr, tare)
    q = 0.5 * rho * plan.speed**2
    truth: dict[str, Any] = {
        "config": config,
        "angle_deg": float(angle_deg),
        "speed": plan.speed,
        "accel": plan.accel,
        "decel": plan.decel,
        "jerk": plan.jerk_up,
        "jerk_decel": plan.jerk_down,
        "fs": float(fs),
        "n_samples": int(n),
        "duration_s": float(t[-1]),
        "distance_m": plan.distance,
        **plan.phases(),
        "rho": rho,
        "nu": nu,
        "drag_model": float(d_plat[0]),
        "lift_model": float(l_plat[0]),
        "tare_drag": float(td_plat[0]),
        "tare_lift": float(tl_plat[0]),
        "m_eff": 0.0,
        "cd": None,
        "cl": None,
        "reynolds": None,
        "zero_drag": float(zero[0]),
        "zero_lift": float(zero[1]),
        "drift_drag": float(drift[0]),
        "drift_lift": float(drift[1]),
        "vibration_hz": vib_hz,
    }
    if config == "hull":
        assert hull is not None
        truth["m_eff"] = float(hull.m_eff(angle_deg))
        truth["cd"] = float(d_plat[0] / (q * hull.frontal_area))
        truth["cl"] = float(l_plat[0] / (q * hull.frontal_area))
        truth["reynolds"] = plan.speed * hull.length / nu
        if abs(angle_deg) == 90.0:
            truth["cd_lateral"] = float(hull.cd90)
    elif config == "fin":
        assert fin is not None
        truth["m_eff"] = float(fin.m_fin)
        truth["cd"] = float(d_plat[0] / (q * fin.area))
        truth["cl"] = float(l_plat[0] / (q * fin.area))
        truth["reynolds"] = plan.speed * fin.chord / nu
    truth["inertia_drag"] = truth["m_eff"] * plan.accel
    truth["tare_m_t"] = float(tare.m_t)
    return frame, truth


# =================================================================================== writers
_DECIMALS = {"time": 6, "speed": 6, "accel": 5, "drag": 6, "lift": 6}
_VOLT_DECIMALS = 8
_UNITS = {"time": "s", "speed": "m/s", "accel": "m/s^2", "drag": "N", "lift": "N"}


@dataclass(frozen=True)
class LabChannels:
    """A lab's column names and load-cell calibrations (value = gain * (raw - offset)).

    Parameters
    ----------
    time, speed, accel : str
        Column names of the time [s], carriage speed [m/s] and acceleration [m/s^2] channels.
    drag, lift : str
        Column names of the load cells, recorded in volts.
    drag_gain, lift_gain : float
        Calibrations [N/V]; the lift cell is mounted reversed (negative gain).
    drag_offset, lift_offset : float
        Electrical offsets [V].
    """

    time: str = "Time (s)"
    speed: str = "Carriage speed (m/s)"
    accel: str = "Carriage accel (m/s^2)"
    drag: str = "Fx load cell (V)"
    lift: str = "Fy load cell (V)"
    drag_gain: float = 20.0
    drag_offset: float = 0.0
    lift_gain: float = -25.0
    lift_offset: float = 0.0

    def protocol_section(self, accel: bool = False) -> dict[str, dict[str, Any]]:
        """The protocol's ``[channels]`` table for files written in this style."""
        out: dict[str, dict[str, Any]] = {
            "time": {"column": self.time},
            "speed": {"column": self.speed},
        }
        if accel:
            out["accel"] = {"column": self.accel}
        out["drag"] = {"column": self.drag, "gain": self.drag_gain, "offset": self.drag_offset}
        out["lift"] = {"column": self.lift, "gain": self.lift_gain, "offset": self.lift_offset}
        return out


def _clean(x: np.ndarray, decimals: int) -> np.ndarray:
    return np.round(np.asarray(x, dtype=float), decimals) + 0.0  # + 0.0 turns -0.0 into 0.0


def to_file_frame(
    frame: pd.DataFrame,
    channel_style: ChannelStyle = "canonical",
    channels: LabChannels | None = None,
) -> pd.DataFrame:
    """The columns as written to a run file: renamed, converted to volts, rounded.

    Rounding: time and speed to 1e-6, accel to 1e-5, forces to 1e-6 N, volts to 1e-8 V (far
    below the noise).

    Parameters
    ----------
    frame : pandas.DataFrame
        Canonical channels from :func:`simulate_run` [SI].
    channel_style : {"canonical", "lab"}
        Canonical names and units, or the lab's names with forces in volts.
    channels : LabChannels, optional
        The lab's names and calibrations (default ``LabChannels()``).
    """
    if channel_style not in ("canonical", "lab"):
        raise ValueError(f"channel_style must be 'canonical' or 'lab', not {channel_style!r}.")
    out = {}
    lab = channels or LabChannels()
    for col in frame.columns:
        values = frame[col].to_numpy(dtype=float)
        if channel_style == "canonical":
            out[col] = _clean(values, _DECIMALS[col])
        elif col in ("drag", "lift"):
            gain = lab.drag_gain if col == "drag" else lab.lift_gain
            offset = lab.drag_offset if col == "drag" else lab.lift_offset
            out[getattr(lab, col)] = _clean(values / gain + offset, _VOLT_DECIMALS)
        else:
            out[getattr(lab, col)] = _clean(values, _DECIMALS[col])
    return pd.DataFrame(out)


def _csv_bytes(frame: pd.DataFrame) -> bytes:
    return frame.to_csv(index=False, lineterminator="\n").encode("utf-8")


def write_run_file(
    frame: pd.DataFrame,
    path: str | Path,
    *,
    channel_style: ChannelStyle = "canonical",
    channels: LabChannels | None = None,
    tdms_dtype: Literal["float64", "float32"] = "float64",
) -> Path:
    """Write one run file; the format follows the name: ``.csv``, ``.csv.gz`` or ``.tdms``.

    CSV has a header row; ``.csv.gz`` is gzip with a zero timestamp (same bytes for the same
    data); TDMS has one group ``data`` with one channel per column, time included (time always
    as float64, the other channels as ``tdms_dtype``).

    Parameters
    ----------
    frame : pandas.DataFrame
        Canonical channels from :func:`simulate_run` [SI].
    path : str or pathlib.Path
        Where to write.
    channel_style : {"canonical", "lab"}
    channels : LabChannels, optional
    tdms_dtype : {"float64", "float32"}, default "float64"
        Storage of the non-time TDMS channels; float32 (LabVIEW SGL) halves the file and keeps
        ~7 significant digits, far below the noise.

    Returns
    -------
    pathlib.Path
    """
    if tdms_dtype not in ("float64", "float32"):
        raise ValueError(f"tdms_dtype must be 'float64' or 'float32', not {tdms_dtype!r}.")
    path = Path(path)
    out = to_file_frame(frame, channel_style, channels)
    name = path.name.lower()
    path.parent.mkdir(parents=True, exist_ok=True)
    if name.endswith(".csv.gz"):
        path.write_bytes(gzip.compress(_csv_bytes(out), compresslevel=6, mtime=0))
    elif name.endswith(".csv"):
        path.write_bytes(_csv_bytes(out))
    elif name.endswith(".tdms"):
        from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

        lab = channels or LabChannels()
        units = {}
        for canon in frame.columns:
            col = canon if channel_style == "canonical" else getattr(lab, canon)
            lab_force = channel_style == "lab" and canon in ("drag", "lift")
            units[col] = "V" if lab_force else _UNITS[canon]
        objects = [
            RootObject(properties={"name": path.stem, "generator": "towtank.synthetic"}),
            GroupObject("data"),
        ]
        time_col = "time" if channel_style == "canonical" else lab.time
        for col in out.columns:
            dtype = np.float64 if col == time_col else np.dtype(tdms_dtype)
            objects.append(
                ChannelObject(
                    "data",
                    col,
                    out[col].to_numpy(dtype=np.float64).astype(dtype),
                    properties={"unit_string": units[col]},
                )
            )
        with TdmsWriter(str(path)) as writer:
            writer.write_segment(objects)
    else:
        raise ValueError(f"{path.name}: a run file must be .csv, .csv.gz or .tdms.")
    return path


SHEET_COLUMNS = (
    "run",
    "file",
    "config",
    "test",
    "angle_deg",
    "speed_nominal",
    "accel_nominal",
    "tare_group",
    "water_temp_C",
    "status",
    "remarks",
)

_FIXED_TIME = _dt.datetime(2024, 5, 21, 9, 0, 0)


def _xlsx_bytes(rows: list[dict[str, Any]], columns: Sequence[str]) -> bytes:
    """An .xlsx workbook with one sheet ``runs``, byte-for-byte reproducible."""
    import openpyxl

    wb = openpyxl.Workbook()
    ws = wb.active
    ws.title = "runs"
    ws.append(list(columns))
    for row in rows:
        ws.append([None if row.get(c) in ("", None) else row.get(c) for c in columns])
    wb.properties.creator = "towtank.synthetic"
    wb.properties.created = _FIXED_TIME
    buf = io.BytesIO()
    wb.save(buf)
    # openpyxl stamps the save time and the zip entries' dates: pin both
    stamp = _FIXED_TIME.strftime("%Y-%m-%dT%H:%M:%SZ").encode()
    out = io.BytesIO()
    with zipfile.ZipFile(buf) as src, zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as dst:
        for info in src.infolist():
            data = src.read(info.filename)
            if info.filename == "docProps/core.xml":
                data = re.sub(
                    rb"(<dcterms:modified[^>]*>)[^<]*(</dcterms:modified>)",
                    rb"\g<1>" + stamp + rb"\g<2>",
                    data,
                )
            zi = zipfile.ZipInfo(info.filename, date_time=(1980, 1, 1, 0, 0, 0))
            zi.compress_type = zipfile.ZIP_DEFLATED
            zi.external_attr = info.external_attr
            dst.writestr(zi, data)
    return out.getvalue()


def write_run_sheet(
    rows: Iterable[Mapping[str, Any]], path: str | Path, columns: Sequence[str] = SHEET_COLUMNS
) -> Path:
    """Write a run sheet (FORMATS §2) as ``.csv`` or ``.xlsx``, one row per run.

    Parameters
    ----------
    rows : iterable of mapping
        One mapping per run with (at least) the keys of ``columns``; missing ones are left blank.
    path : str or pathlib.Path
        ``.csv`` or ``.xlsx``.
    columns : sequence of str
        Column order; default the FORMATS §2 columns.

    Returns
    -------
    pathlib.Path
    """
    path = Path(path)
    rows = [dict(r) for r in rows]
    path.parent.mkdir(parents=True, exist_ok=True)
    suffix = path.suffix.lower()
    if suffix == ".xlsx":
        path.write_bytes(_xlsx_bytes(rows, columns))
    elif suffix == ".csv":
        frame = pd.DataFrame([{c: r.get(c, "") for c in columns} for r in rows], columns=columns)
        path.write_bytes(_csv_bytes(frame))
    else:
        raise ValueError(f"{path.name}: a run sheet must be .csv or .xlsx.")
    return path


# ============================================================================== day builders
@dataclass(frozen=True)
class RunSpec:
    """One planned run of a day.

    Parameters
    ----------
    config : {"hull", "fin", "sting"}
    angle_deg : float
        Angle to the tow [deg].
    speed : float
        Set speed [m/s].
    accel : float
        Set acceleration [m/s^2].
    test : {"steady", "accel"}, default "steady"
    tare_group : str, default "A"
    status : {"ok", "void"}, default "ok"
    remarks : str, default ""
    plateau_s : float, optional
        Plateau length [s]; default as long as the tank allows (at most 8 s).
    decel : float, optional
        Deceleration [m/s^2].
    water_temp_C : float, optional
        Water temperature of the run [degC]; default drawn around the day's temperature.
    run : int, optional
        Run number; default the position in the plan, from 1.
    """

    config: Config
    angle_deg: float
    speed: float
    accel: float
    test: str = "steady"
    tare_group: str = "A"
    status: str = "ok"
    remarks: str = ""
    plateau_s: float | None = None
    decel: float | None = None
    water_temp_C: float | None = None
    run: int | None = None


def hull_day_plan() -> list[RunSpec]:
    """The SUT-2-style hull day: sting tares, hull at 0-15 deg, accelerated and transverse runs.

    Run count per config: sting 12 (7 steady, 5 accelerated), hull 30 (19 steady at 0-15 deg
    including 3 repeats, 1 voided run, 3 accelerated at 0 deg, 5 steady and 2 accelerated
    transverse tows at 90 deg); 42 in all.
    """
    low = 0.15  # [m/s^2] set acceleration of the low-speed steady runs
    high = 0.5  # [m/s^2] set acceleration of the steady runs at 0.8 m/s and above
    plan: list[RunSpec] = []
    for v in (0.1, 0.2, 0.3):
        plan.append(RunSpec("sting", 0.0, v, low))
    for v in (0.8, 1.2, 1.6, 2.0):
        plan.append(RunSpec("sting", 0.0, v, high))
    for acc in (0.25, 0.5, 1.0):
        plan.append(RunSpec("sting", 0.0, 2.0, acc, test="accel"))
    for acc in (0.1, 0.2):
        plan.append(RunSpec("sting", 0.0, 0.3, acc, test="accel"))
    speeds = (0.8, 1.2, 1.6, 2.0)
    for v in speeds:
        plan.append(RunSpec("hull", 0.0, v, high))
    for acc in (0.25, 0.5, 1.0):
        plan.append(RunSpec("hull", 0.0, 2.0, acc, test="accel"))
    plan.append(
        RunSpec(
            "hull",
            5.0,
            1.6,
            high,
            status="void",
            remarks="carriage stopped early",
            plateau_s=0.6,
        )
    )
    for ang in (5.0, 10.0, 15.0):
        for v in speeds:
            plan.append(RunSpec("hull", ang, v, high))
    plan.append(RunSpec("hull", 0.0, 1.2, high, remarks="repeat"))
    plan.append(RunSpec("hull", 0.0, 2.0, high, remarks="repeat"))
    plan.append(RunSpec("hull", 10.0, 1.6, high, remarks="repeat"))
    for v in (0.10, 0.15, 0.20, 0.25, 0.30):
        plan.append(RunSpec("hull", 90.0, v, low, remarks="transverse tow"))
    for acc in (0.1, 0.2):
        plan.append(RunSpec("hull", 90.0, 0.3, acc, test="accel", remarks="transverse tow"))
    return plan


def fin_day_plan() -> list[RunSpec]:
    """The NACA 0015 fin day: post tares, then the fin at 0-35 deg at four speeds.

    Angles 0, 2.5, 5 and 7.5 deg (the zero-lift check and points in the linear range, so that
    every speed keeps three or more distinct angles below its stall, which is 7.5-10 deg at
    these Re, for a lift slope with an intercept and residual degrees of freedom), then 10-35
    deg in 5 deg steps into and past stall. Run count per config: sting (the fin's post) 5
    (4 steady, 1 accelerated), fin 40 (10 angles x 4 speeds, steady); 45 in all. All in tare
    group "post".
    """
    acc = 0.5
    plan = [RunSpec("sting", 0.0, v, acc, tare_group="post") for v in (0.8, 1.5, 2.0, 2.7)]
    plan.append(RunSpec("sting", 0.0, 2.0, 1.0, test="accel", tare_group="post"))
    for ang in (0.0, 2.5, 5.0, 7.5, 10.0, 15.0, 20.0, 25.0, 30.0, 35.0):
        for v in (1.0, 1.5, 2.0, 2.5):
            plan.append(RunSpec("fin", ang, v, acc, tare_group="post"))
    return plan


@dataclass
class DayTruth:
    """Everything a synthetic day was made from, as written to ``truth.json``.

    ``coefficients`` and ``primes`` are the hull's at the day's nominal water (``water``);
    ``runs`` maps run number to the per-run truth of :func:`simulate_run` plus sheet fields.
    """

    name: str
    seed: int
    generator_version: str
    fs: float
    file_format: str
    channel_style: str
    tdms_dtype: str | None
    water: dict[str, Any]
    noise: Noise
    tares: dict[str, TareTruth]
    hull: HullTruth | None = None
    fin: FinTruth | None = None
    channels: LabChannels | None = None
    coefficients: dict[str, float] | None = None
    primes: dict[str, float] | None = None
    runs: dict[int, dict[str, Any]] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict (run numbers as string keys)."""
        out: dict[str, Any] = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name == "runs":
                value = {str(k): v for k, v in value.items()}
            elif f.name == "tares":
                value = {k: asdict(v) for k, v in value.items()}
            elif dataclass_instance(value):
                value = asdict(value)
            out[f.name] = value
        out["towtank_version"] = _TOWTANK_VERSION
        return out


def dataclass_instance(value: Any) -> bool:
    """True for a dataclass instance (not a class)."""
    return hasattr(value, "__dataclass_fields__") and not isinstance(value, type)


def _json_default(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


def write_truth(truth: DayTruth | Mapping[str, Any], path: str | Path) -> Path:
    """Write a day's truth as JSON (``truth.json``).

    Parameters
    ----------
    truth : DayTruth or mapping
    path : str or pathlib.Path
    """
    path = Path(path)
    data = truth.to_dict() if isinstance(truth, DayTruth) else dict(truth)
    text = json.dumps(data, indent=2, default=_json_default, allow_nan=False)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text + "\n", encoding="utf-8")
    return path


def load_truth(path: str | Path) -> dict[str, Any]:
    """Read ``truth.json`` back (a plain dict; run numbers are string keys of ``runs``).

    Parameters
    ----------
    path : str or pathlib.Path
        The file, or the day's directory holding it.
    """
    path = Path(path)
    if path.is_dir():
        path = path / "truth.json"
    return json.loads(path.read_text(encoding="utf-8"))


def _run_temperatures(
    plan: Sequence[RunSpec],
    temperature_C: float,
    spread_C: tuple[float, float] | None,
    rng: np.random.Generator,
) -> list[float]:
    """Water temperature per run [degC]: a slow warming across the day, to 0.1 degC."""
    n = len(plan)
    jitter = rng.normal(0.0, 0.03, size=n)
    if spread_C is None:
        drawn = np.full(n, float(temperature_C))
    else:
        lo, hi = spread_C
        frac = np.arange(n) / max(n - 1, 1)
        drawn = np.clip(
            temperature_C + lo + (hi - lo) * frac + jitter, temperature_C + lo, temperature_C + hi
        )
        drawn = np.round(drawn, 1)
    return [
        float(spec.water_temp_C) if spec.water_temp_C is not None else float(x)
        for spec, x in zip(plan, drawn, strict=True)
    ]


def _make_day(
    out_dir: str | Path,
    plan: Sequence[RunSpec],
    *,
    name: str,
    seed: int,
    fs: float,
    file_format: FileFormat,
    sheet_format: SheetFormat,
    channel_style: ChannelStyle,
    channels: LabChannels | None,
    noise: Noise,
    temperature_C: float,
    temperature_spread_C: tuple[float, float] | None,
    water_type: str,
    hull: HullTruth | None,
    fin: FinTruth | None,
    tares: Mapping[str, TareTruth],
    accel_channel: bool,
    tank_length_m: float,
    tdms_dtype: Literal["float64", "float32"] = "float64",
    date: str | _dt.date | None = None,
) -> DayTruth:
    if file_format not in ("csv", "csv.gz", "tdms"):
        raise ValueError(f"file_format must be 'csv', 'csv.gz' or 'tdms', not {file_format!r}.")
    if sheet_format not in ("csv", "xlsx"):
        raise ValueError(f"sheet_format must be 'csv' or 'xlsx', not {sheet_format!r}.")
    out_dir = Path(out_dir)
    data_dir = out_dir / "data"
    data_dir.mkdir(parents=True, exist_ok=True)
    if channel_style == "lab" and channels is None:
        channels = LabChannels()

    test_date = _iso_date(date)
    numbers = [spec.run if spec.run is not None else i + 1 for i, spec in enumerate(plan)]
    if len(set(numbers)) != len(numbers):
        raise ValueError("Run numbers of the plan must be unique.")

    streams = np.random.SeedSequence(seed).spawn(len(plan) + 1)
    day_rng = np.random.default_rng(streams[0])
    temps = _run_temperatures(plan, temperature_C, temperature_spread_C, day_rng)

    nominal = _water(temperature_C, water_type)
    rho0, nu0 = float(nominal.rho), float(nominal.nu)
    water_cache: dict[float, Any] = {}
    truth = DayTruth(
        name=name,
        seed=int(seed),
        generator_version=GENERATOR_VERSION,
        fs=float(fs),
        file_format=file_format,
        channel_style=channel_style,
        tdms_dtype=tdms_dtype if file_format == "tdms" else None,
        water={"type": water_type, "temperature_C": float(temperature_C), "rho": rho0, "nu": nu0},
        noise=noise,
        tares=dict(tares),
        hull=hull,
        fin=fin,
        channels=channels if channel_style == "lab" else None,
    )
    if hull is not None:
        truth.coefficients = hull.coefficients(rho0)
        truth.primes = hull.primes(rho0)

    rows = []
    for spec, number, temp, stream in zip(plan, numbers, temps, streams[1:], strict=True):
        if temp not in water_cache:
            water_cache[temp] = _water(temp, water_type)
        tare = tares.get(spec.tare_group, TareTruth.none())
        frame, run_truth = simulate_run(
            spec.config,
            spec.angle_deg,
            spec.speed,
            spec.accel,
            hull=hull,
            tare=tare,
            fin=fin,
            noise=noise,
            water=water_cache[temp],
            fs=fs,
            rng=np.random.default_rng(stream),
            decel=spec.decel,
            plateau_s=spec.plateau_s,
            tank_length_m=tank_length_m,
            accel_channel=accel_channel,
        )
        file_name = f"run_{number:03d}.{file_format}"
        write_run_file(
            frame,
            data_dir / file_name,
            channel_style=channel_style,
            channels=channels,
            tdms_dtype=tdms_dtype,
        )
        row = {
            "run": int(number),
            "file": file_name,
            "config": spec.config,
            "test": spec.test,
            "angle_deg": float(spec.angle_deg),
            "speed_nominal": float(spec.speed),
            "accel_nominal": float(spec.accel),
            "tare_group": spec.tare_group,
            "water_temp_C": temp,
            "status": spec.status,
            "remarks": spec.remarks,
        }
        rows.append(row)
        truth.runs[int(number)] = {**row, "water_temp_C": temp, **run_truth}

    columns: tuple[str, ...] = SHEET_COLUMNS
    if test_date is not None:  # the sheet only: truth.json is the same with or without it
        columns += ("date",)
        rows = [{**row, "date": test_date} for row in rows]
    write_run_sheet(rows, out_dir / f"run_sheet.{sheet_format}", columns)
    write_truth(truth, out_dir / "truth.json")
    return truth


def _iso_date(date: str | _dt.date | None) -> str | None:
    """A test date as ISO text, YYYY-MM-DD (None stays None)."""
    if date is None:
        return None
    if isinstance(date, _dt.datetime):
        return date.date().isoformat()
    if isinstance(date, _dt.date):
        return date.isoformat()
    try:
        return _dt.date.fromisoformat(str(date).strip()).isoformat()
    except ValueError:
        raise ValueError(f"date must be an ISO date, YYYY-MM-DD, not {date!r}.") from None


def make_hull_day(
    out_dir: str | Path,
    *,
    seed: int = HULL_SAMPLE_SEED,
    fs: float = 200.0,
    file_format: FileFormat = "csv.gz",
    sheet_format: SheetFormat = "xlsx",
    channel_style: ChannelStyle = "lab",
    noise: Noise | None = None,
    temperature_C: float = 18.0,
    runs: Sequence[RunSpec] | None = None,
    hull: HullTruth | None = None,
    tares: Mapping[str, TareTruth] | None = None,
    channels: LabChannels | None = None,
    accel_channel: bool = False,
    temperature_spread_C: tuple[float, float] | None = (-0.2, 0.3),
    water_type: str = "fresh",
    tank_length_m: float = 100.0,
    date: str | _dt.date | None = None,
) -> DayTruth:
    """Write a synthetic SUT-2 hull day: ``data/run_NNN.*``, ``run_sheet.*``, ``truth.json``.

    Parameters
    ----------
    out_dir : str or pathlib.Path
        The day's directory (created).
    seed : int
        Seed of the day; each run gets its own stream from it.
    fs : float, default 200.0
        Sampling rate [Hz].
    file_format : {"csv", "csv.gz", "tdms"}, default "csv.gz"
    sheet_format : {"csv", "xlsx"}, default "xlsx"
    channel_style : {"canonical", "lab"}, default "lab"
        Lab style writes the load cells in volts under the names of :class:`LabChannels`.
    noise : Noise, optional
        Default ``Noise()``.
    temperature_C : float, default 18.0
        Nominal water temperature [degC]; the truth coefficients are at this density.
    runs : sequence of RunSpec, optional
        The run plan; default :func:`hull_day_plan`.
    hull : HullTruth, optional
        Default :func:`sut2_hull_truth` at the nominal density.
    tares : mapping of str to TareTruth, optional
        Mounting force per tare group; default ``{"A": TareTruth()}``. Groups not listed
        have no mounting force.
    channels : LabChannels, optional
        Lab names and calibrations (lab style).
    accel_channel : bool, default False
        Record an accel channel.
    temperature_spread_C : (float, float) or None, default (-0.2, 0.3)
        Run temperatures rise across the day from ``temperature_C + lo`` to ``+ hi`` [degC]
        (rounded to 0.1 degC); None keeps every run at ``temperature_C``.
    water_type : str, default "fresh"
    tank_length_m : float, default 100.0
        Tank length [m].
    date : str or datetime.date, optional
        Test date; if given, the run sheet gets a ``date`` column (ISO ``YYYY-MM-DD``, FORMATS
        §2: other columns are kept), from which the report takes its test date. Default: no
        such column.

    Returns
    -------
    DayTruth
    """
    nominal = _water(temperature_C, water_type)
    hull = sut2_hull_truth(float(nominal.rho)) if hull is None else hull
    return _make_day(
        out_dir,
        hull_day_plan() if runs is None else list(runs),
        name="SUT-2 quarter-scale hull, synthetic day",
        seed=seed,
        fs=fs,
        file_format=file_format,
        sheet_format=sheet_format,
        channel_style=channel_style,
        channels=channels,
        noise=Noise() if noise is None else noise,
        temperature_C=temperature_C,
        temperature_spread_C=temperature_spread_C,
        water_type=water_type,
        hull=hull,
        fin=None,
        tares={"A": TareTruth()} if tares is None else tares,
        accel_channel=accel_channel,
        tank_length_m=tank_length_m,
        date=date,
    )


POST_TARE = TareTruth(t2=0.12, t1=0.015, m_t=0.12, lift_t2=0.004, lift_t1=0.001, lift_m_t=0.003)
"""Default tare of the fin day's post (a stiffer, thicker mounting than the hull's sting)."""


def make_fin_day(
    out_dir: str | Path,
    *,
    seed: int = FIN_SAMPLE_SEED,
    fs: float = 200.0,
    file_format: FileFormat = "tdms",
    sheet_format: SheetFormat = "csv",
    channel_style: ChannelStyle = "canonical",
    noise: Noise | None = None,
    temperature_C: float = 18.0,
    runs: Sequence[RunSpec] | None = None,
    fin: FinTruth | None = None,
    tares: Mapping[str, TareTruth] | None = None,
    channels: LabChannels | None = None,
    accel_channel: bool = False,
    temperature_spread_C: tuple[float, float] | None = (-0.2, 0.3),
    water_type: str = "fresh",
    tank_length_m: float = 100.0,
    tdms_dtype: Literal["float64", "float32"] = "float32",
    date: str | _dt.date | None = None,
) -> DayTruth:
    """Write a synthetic NACA 0015 fin day: ``data/run_NNN.*``, ``run_sheet.*``, ``truth.json``.

    Parameters are those of :func:`make_hull_day`, except: ``fin`` (default ``FinTruth()``,
    chord 0.12 m, span 0.15 m), ``tares`` (default ``{"post": POST_TARE}``), ``runs`` (default
    :func:`fin_day_plan`), ``tdms_dtype`` (storage of the non-time TDMS channels, default
    float32 as LabVIEW's SGL, to keep the day small), and the defaults TDMS files, CSV sheet
    and canonical channel names. ``date`` as in :func:`make_hull_day` (a ``date`` column of the
    run sheet only if given).

    Returns
    -------
    DayTruth
    """
    return _make_day(
        out_dir,
        fin_day_plan() if runs is None else list(runs),
        name="NACA 0015 fin, synthetic day",
        seed=seed,
        fs=fs,
        file_format=file_format,
        sheet_format=sheet_format,
        channel_style=channel_style,
        channels=channels,
        noise=Noise() if noise is None else noise,
        temperature_C=temperature_C,
        temperature_spread_C=temperature_spread_C,
        water_type=water_type,
        hull=None,
        fin=FinTruth() if fin is None else fin,
        tares={"post": POST_TARE} if tares is None else tares,
        accel_channel=accel_channel,
        tank_length_m=tank_length_m,
        tdms_dtype=tdms_dtype,
        date=date,
    )


# ================================================================================= protocols
_BARE_KEY = set("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_-")


def _toml_key(key: str) -> str:
    if key and set(key) <= _BARE_KEY:
        return key
    return _toml_value(key)


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | np.integer):
        return str(int(value))
    if isinstance(value, float | np.floating):
        x = float(value)
        if math.isnan(x):
            return "nan"
        if math.isinf(x):
            return "inf" if x > 0 else "-inf"
        return repr(x)
    if isinstance(value, str | Path):
        text = str(value)
        text = text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
        text = text.replace("\t", "\\t")
        return f'"{text}"'
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, Mapping):
        inner = ", ".join(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in value.items())
        return "{ " + inner + " }" if inner else "{}"
    raise TypeError(f"{type(value).__name__} cannot be written to TOML")


def _toml_table(lines: list[str], dotted: str, table: Mapping[str, Any], inline: set[str]) -> None:
    lines.append(f"[{dotted}]")
    subtables = []
    for key, value in table.items():
        if isinstance(value, Mapping) and dotted not in inline:
            subtables.append((key, value))
        else:
            lines.append(f"{_toml_key(key)} = {_toml_value(value)}")
    for key, value in subtables:
        _toml_table(lines, f"{dotted}.{_toml_key(key)}", value, inline)


def write_protocol(
    path: str | Path,
    *,
    header: str | None = None,
    inline_tables: Iterable[str] = ("channels",),
    **sections: Mapping[str, Any],
) -> Path:
    """Write a protocol TOML (FORMATS §1) from nested dicts.

    Values may be str, float, int, bool, lists of those, and dicts. A dict inside a section is
    written as a sub-table (``[prototype.water]``), except in the sections named by
    ``inline_tables`` where it becomes an inline table (``drag = { column = "...", gain = 20.0 }``).

    Parameters
    ----------
    path : str or pathlib.Path
        The TOML file to write.
    header : str, optional
        Comment lines written at the top.
    inline_tables : iterable of str, default ("channels",)
    **sections : mapping
        One mapping per section, in order: ``campaign={...}, water={...}, ...``.

    Returns
    -------
    pathlib.Path
    """
    path = Path(path)
    lines: list[str] = []
    if header:
        lines.extend(f"# {line}".rstrip() for line in header.splitlines())
        lines.append("")
    inline = set(inline_tables)
    for name, table in sections.items():
        if not isinstance(table, Mapping):
            raise TypeError(f"section {name!r} must be a mapping")
        _toml_table(lines, _toml_key(name), table, inline)
        lines.append("")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines).rstrip("\n") + "\n", encoding="utf-8")
    return path


def hull_protocol_sections(
    day_dir: str = "../sample_runs/sut2_hull",
    output_dir: str = "../reports/sut2_hull",
    *,
    sheet_format: SheetFormat = "xlsx",
    channel_style: ChannelStyle = "lab",
    channels: LabChannels | None = None,
    temperature_C: float = 18.0,
) -> dict[str, dict[str, Any]]:
    """The sections of the SUT-2 hull day's protocol (paths relative to the protocol file).

    Parameters
    ----------
    day_dir, output_dir : str
        The day's directory and the output directory, relative to the protocol file.
    sheet_format : {"csv", "xlsx"}
    channel_style : {"canonical", "lab"}
        Lab style adds the ``[channels]`` mapping.
    channels : LabChannels, optional
    temperature_C : float, default 18.0
        Tank water temperature [degC].
    """
    sections: dict[str, dict[str, Any]] = {
        "campaign": {
            "name": "SUT-2 quarter-scale hull, synthetic day",
            "run_sheet": f"{day_dir}/run_sheet.{sheet_format}",
            "data_dir": f"{day_dir}/data",
            "output_dir": output_dir,
            "reference": "remus",
        },
        "water": {"type": "fresh", "temperature_C": float(temperature_C)},
        "model": {
            "name": "SUT-2 1/4 model",
            "length_m": 0.353,
            "diameter_m": 0.050,
            "mass_kg": 0.552,
            "lateral_area_m2": 0.0152,
            "wetted_area_m2": 0.0472,
            "scale": 4.0,
            "depth_m": 0.25,
            "myring": {
                "a": 0.05875,
                "b": 0.1765,
                "c": 0.11775,
                "n": 2.0,
                "theta_deg": 25.0,
                "d": 0.05,
            },
        },
        "prototype": {
            "length_m": 1.412,
            "speeds_m_s": [1.0, 1.5, 2.0, 2.5],
            "water": {"type": "sea", "temperature_C": 15.0},
        },
    }
    if channel_style == "lab":
        sections["channels"] = (channels or LabChannels()).protocol_section()
    sections["processing"] = {}
    return sections


def fin_protocol_sections(
    day_dir: str = "../sample_runs/naca0015_fin",
    output_dir: str = "../reports/naca0015_fin",
    *,
    sheet_format: SheetFormat = "csv",
    fin: FinTruth | None = None,
    temperature_C: float = 18.0,
) -> dict[str, dict[str, Any]]:
    """The sections of the NACA 0015 fin day's protocol (canonical channels, no [model]).

    Parameters
    ----------
    day_dir, output_dir : str
        Relative to the protocol file.
    sheet_format : {"csv", "xlsx"}
    fin : FinTruth, optional
    temperature_C : float, default 18.0
        Tank water temperature [degC].
    """
    fin = fin or FinTruth()
    return {
        "campaign": {
            "name": "NACA 0015 fin, synthetic day",
            "run_sheet": f"{day_dir}/run_sheet.{sheet_format}",
            "data_dir": f"{day_dir}/data",
            "output_dir": output_dir,
        },
        "water": {"type": "fresh", "temperature_C": float(temperature_C)},
        "fin": {
            "chord_m": fin.chord,
            "span_m": fin.span,
            "section": fin.section,
            "x_m": -0.61,
            "linear_max_deg": 10.0,
        },
        "processing": {},
    }


def write_sample_protocols(protocols_dir: str | Path) -> list[Path]:
    """Write ``sut2_hull.toml`` and ``naca0015_fin.toml`` for the sample days.

    Parameters
    ----------
    protocols_dir : str or pathlib.Path
        Directory of the protocols; the sample days are expected in ``../sample_runs``.
    """
    protocols_dir = Path(protocols_dir)
    note = "Generated by towtank.synthetic.write_sample_protocols; data: write_sample_days."
    return [
        write_protocol(
            protocols_dir / "sut2_hull.toml",
            header="Synthetic SUT-2 quarter-scale hull day (sample_runs/sut2_hull).\n" + note,
            **hull_protocol_sections(),
        ),
        write_protocol(
            protocols_dir / "naca0015_fin.toml",
            header="Synthetic NACA 0015 fin day (sample_runs/naca0015_fin).\n" + note,
            **fin_protocol_sections(),
        ),
    ]


_SAMPLE_README = """\
# Sample runs (synthetic)

Generated by `towtank.synthetic.write_sample_days` (generator version {version}); do not edit by
hand, regenerate. Each day holds `data/` (one file per run), a run sheet (with the test date in its
`date` column) and `truth.json` with the exact truth the data were made from (coefficients, per-run
plateau forces, tares, phases).

- `sut2_hull/`: SUT-2 quarter-scale hull, {hull_n} runs at {hull_fs:g} Hz, gzipped CSV in the lab's
  channel names (load cells in volts), run sheet .xlsx; protocol `protocols/sut2_hull.toml`.
- `naca0015_fin/`: NACA 0015 fin (chord 0.12 m, span 0.15 m), {fin_n} runs at {fin_fs:g} Hz,
  TDMS with canonical channel names, run sheet .csv; protocol `protocols/naca0015_fin.toml`.
"""


def write_sample_days(
    root: str | Path, *, protocols_dir: str | Path | None = None
) -> dict[str, DayTruth]:
    """Regenerate the shipped sample days ``root/sut2_hull`` and ``root/naca0015_fin``.

    Both directories are replaced as a whole; seeds are fixed, so the files are reproducible.
    Each run sheet carries its day's test date in a ``date`` column (:data:`HULL_SAMPLE_DATE`,
    :data:`FIN_SAMPLE_DATE`), which the report prints.

    Parameters
    ----------
    root : str or pathlib.Path
        The ``sample_runs`` directory.
    protocols_dir : str or pathlib.Path, optional
        If given, also write the two protocols there.

    Returns
    -------
    dict
        ``{"sut2_hull": DayTruth, "naca0015_fin": DayTruth}``.
    """
    root = Path(root)
    root.mkdir(parents=True, exist_ok=True)
    for name in ("sut2_hull", "naca0015_fin"):
        if (root / name).exists():
            shutil.rmtree(root / name)
    hull = make_hull_day(root / "sut2_hull", date=HULL_SAMPLE_DATE)
    fin = make_fin_day(root / "naca0015_fin", date=FIN_SAMPLE_DATE)
    (root / "README.md").write_text(
        _SAMPLE_README.format(
            version=GENERATOR_VERSION,
            hull_n=len(hull.runs),
            hull_fs=hull.fs,
            fin_n=len(fin.runs),
            fin_fs=fin.fs,
        ),
        encoding="utf-8",
    )
    if protocols_dir is not None:
        write_sample_protocols(protocols_dir)
    return {"sut2_hull": hull, "naca0015_fin": fin}
