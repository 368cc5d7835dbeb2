"""Carriage profiles of the synthetic runs: planned speed, acceleration and jerk limits, and
the sampled speed U(t) and acceleration a(t)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


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


def sample_times(duration: float, fs: float) -> np.ndarray:
    """Sample times ``k / fs`` [s], k = 0 … floor(duration·fs), of a recording ``duration``
    [s] long at ``fs`` [Hz] (ValueError for a rate that is not a positive number)."""
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
    t = sample_times(plan.duration, fs)
    u, a = plan.evaluate(t)
    return t, u, a


# ===================================================================================== truth
