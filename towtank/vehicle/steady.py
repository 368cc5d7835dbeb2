"""Steady values of a simulated manoeuvre: the steadiness test, the plan-track circle fit and
angle wrapping (docs/formats.md §6, metrics.csv; docs/method.md, "Steady metrics").

A "steady" metric is the mean of its quantity over the last :data:`STEADY_FRACTION` of the
run, and is given only when that part of the run is steady: the range (largest minus smallest
value) of the quantity over it is at most its threshold (:data:`THRESHOLDS`). Otherwise the
value is NaN and a note says why: ``looping`` (the pitch passed +-90 deg during the run),
``oscillating`` (the quantity turns back at least twice in that part), ``not yet settled``
(it is still drifting one way) or ``not turning`` (a turn radius without a yaw rate).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["STEADY_FRACTION", "THRESHOLDS", "LABELS", "MIN_YAW_RATE_DEG_S", "wrap_deg",
           "circle_fit", "steady_mask", "steadiness", "looped", "speed_magnitude"]

#: The steady part of a run: its last fifth [-].
STEADY_FRACTION = 0.2
#: Largest range of each quantity over the steady part; ``rel`` ones are fractions of the
#: mean's magnitude [-], the others absolute in the quantity's unit.
THRESHOLDS = {
    "pitch_deg": ("abs", 0.5),          # [deg]
    "drift_deg": ("abs", 0.5),          # [deg]
    "angle_of_attack_deg": ("abs", 0.5),  # [deg]
    "depth_rate_m_s": ("abs", 0.01),    # [m/s]
    "speed_m_s": ("rel", 0.01),         # 1 % of the mean speed
    "yaw_rate_deg_s": ("rel", 0.02),    # 2 % of the mean yaw rate
}
#: The quantities' names in the notes.
LABELS = {"pitch_deg": "pitch", "drift_deg": "drift angle",
          "angle_of_attack_deg": "angle of attack", "depth_rate_m_s": "depth rate",
          "speed_m_s": "speed", "yaw_rate_deg_s": "yaw rate"}
#: Smallest mean |yaw rate| over the steady part for a turn radius [deg/s].
MIN_YAW_RATE_DEG_S = 0.1


def speed_magnitude(u: np.ndarray, v: np.ndarray, w: np.ndarray) -> np.ndarray:
    """The speed through the water ``|V| = sqrt(u^2 + v^2 + w^2)`` [m/s] of the body-axis
    velocities ``u``, ``v``, ``w`` [m/s], as ``hypot(hypot(u, v), w)``: no component's square
    underflows to 0 or overflows, so a speed of 1e-300 m/s is 1e-300 m/s, not 0."""
    return np.hypot(np.hypot(np.asarray(u, dtype=float), np.asarray(v, dtype=float)),
                    np.asarray(w, dtype=float))


def wrap_deg(angle_deg: float | np.ndarray) -> float | np.ndarray:
    """An angle [deg] wrapped to [-180, 180)."""
    return (np.asarray(angle_deg) + 180.0) % 360.0 - 180.0


def circle_fit(x_m: np.ndarray, y_m: np.ndarray) -> tuple[float, float, float]:
    """Least-squares circle through plan-track points: centre x, y and radius [m].

    Kasa's algebraic fit (Kasa 1976, "A circle fitting procedure and its error analysis",
    IEEE Trans. Instrum. Meas. IM-25(1), 8-14): ``x^2 + y^2 + D x + E y + F = 0`` in the
    least-squares sense (linear in D, E, F), centre ``(-D/2, -E/2)``, radius
    ``sqrt(D^2/4 + E^2/4 - F)``. The points are centred first (numerically better); exact for
    points on a circle, and for an arc of a steady turn.

    Parameters
    ----------
    x_m, y_m : numpy.ndarray
        Earth-axis positions [m], at least 3 not on one line
    """
    x = np.asarray(x_m, dtype=float)
    y = np.asarray(y_m, dtype=float)
    x0, y0 = float(x.mean()), float(y.mean())
    xc, yc = x - x0, y - y0
    a = np.column_stack((xc, yc, np.ones_like(xc)))
    (d, e, f), *_ = np.linalg.lstsq(a, -(xc**2 + yc**2), rcond=None)
    r2 = d * d / 4.0 + e * e / 4.0 - f
    radius = math.sqrt(r2) if r2 > 0 else float("nan")
    return x0 - d / 2.0, y0 - e / 2.0, radius


def steady_mask(t_s: np.ndarray, fraction: float = STEADY_FRACTION) -> np.ndarray:
    """The samples of the last ``fraction`` [-] of the run (times ``t_s`` [s])."""
    t = np.asarray(t_s, dtype=float)
    return t >= t[-1] - fraction * (t[-1] - t[0])


def steadiness(values: np.ndarray, name: str) -> str:
    """The steadiness test of a quantity over the steady part: "" when steady, else the note.

    ``values`` are the quantity's samples over the steady part (angles unwrapped), ``name`` a
    key of :data:`THRESHOLDS`. Steady: range ``max - min`` at most the threshold. Otherwise
    ``oscillating`` when it turns back at least twice (two or more sign changes of its
    differences, ignoring changes below a thousandth of the range), else ``not yet settled``.
    """
    v = np.asarray(values, dtype=float)
    if len(v) < 3 or not np.all(np.isfinite(v)):
        return "not steady: too few samples"
    kind, limit = THRESHOLDS[name]
    span = float(v.max() - v.min())
    allowed = limit * abs(float(v.mean())) if kind == "rel" else limit
    if span <= allowed:
        return ""
    unit = "deg/s" if name.endswith("deg_s") else ("m/s" if name.endswith("m_s") else "deg")
    dv = np.diff(v)
    dv = dv[np.abs(dv) > 1e-3 * span / len(v)]
    turns = int(np.count_nonzero(np.diff(np.sign(dv)) != 0))
    what = "oscillating" if turns >= 2 else "not yet settled"
    return (f"{what}: ranges over {span:.3g} {unit} in the last {STEADY_FRACTION:.0%} of the run "
            f"(steady: at most {allowed:.3g} {unit})")


def looped(theta_deg: np.ndarray, u_m_s: np.ndarray) -> str:
    """"" or the note of a run whose pitch passed +-90 deg (it went over the vertical):
    its later values are no steady state of the manoeuvre asked for."""
    theta = np.asarray(theta_deg, dtype=float)
    if not np.any(np.abs(theta) >= 90.0):
        return ""
    i = int(np.argmax(np.abs(theta)))
    return (f"looping: the pitch passed +-90 deg (it reached {theta[i]:.0f} deg unwrapped) and "
            f"u fell to {float(np.min(u_m_s)):.2f} m/s")
