"""A glider's wings: lift and drag valid from 0 to 90 deg angle of attack (docs/method.md,
"Wings to 90 deg").

Below stall the wing follows the lifting line: ``C_L = a alpha`` with the slope of a swept
wing ``a = a0 cos L / (1 + a0 cos L / (pi AR))`` (a0 = 0.9 2 pi, as the fins of
:mod:`towtank.vehicle.predict`; Helmbold's low-aspect-ratio form, e.g. Hoerner & Borst 1975,
*Fluid-dynamic lift*, ch. 3) and ``C_D = C_D0 + C_L^2 / (pi AR)`` (induced drag). Beyond
stall it is a flat plate whose normal force ``C_N = C_Dmax sin alpha`` gives
``C_L = C_N cos alpha``, ``C_D = C_D0 + C_N sin alpha`` with ``C_Dmax = 1.11 + 0.018 AR``
(Viterna & Corrigan 1982, "Fixed pitch rotor performance of large horizontal axis wind
turbines", NASA CP-2230, 69-85; flat plates of small aspect ratio: Ortiz, Rival & Wood 2015,
Energies 8, 2438-2453, the reference of the parametric glider study). The two are joined by
the sigmoid of Beard & McLain (2012, *Small unmanned aircraft: theory and practice*, eq. 4.10)
``sigma(alpha) = (1 + e^(-M(alpha - a_s)) + e^(M(alpha + a_s))) /
((1 + e^(-M(alpha - a_s))) (1 + e^(M(alpha + a_s))))``, ``C = (1 - sigma) C_attached +
sigma C_plate``, stall ``a_s`` = :data:`STALL_DEG`, sharpness M = :data:`BLEND_RATE`.

Each half wing acts at its area's centroid, ``(x_w, +-b/4, 0)`` for a rectangular planform,
with the local velocity ``nu1 + omega x r`` (so the wings damp roll and pitch); its angle of
attack is ``atan2(w_l, u_l)``, the span-wise component ``v_l`` sheds no lift.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["STALL_DEG", "BLEND_RATE", "A0", "lift_slope", "wing_coefficients", "Wings"]

#: Stall angle of the blend [deg].
STALL_DEG = 15.0
#: Sharpness M of the blend [1/rad].
BLEND_RATE = 25.0
#: Section lift slope [1/rad] (0.9 2 pi, as towtank's fins).
A0 = 0.9 * 2.0 * math.pi
#: Zero-lift drag coefficient of the wings without ``wing_cd0`` [-].
CD0 = 0.01


def lift_slope(aspect_ratio: float, sweep_deg: float = 0.0) -> float:
    """The wing's lift slope a [1/rad] of aspect ratio ``aspect_ratio`` [-] and quarter-chord
    sweep ``sweep_deg`` [deg] (module docstring)."""
    a0 = A0 * math.cos(math.radians(sweep_deg))
    return a0 / (1.0 + a0 / (math.pi * aspect_ratio))


def wing_coefficients(alpha_rad: float | np.ndarray, aspect_ratio: float,
                      sweep_deg: float = 0.0, cd0: float = CD0
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Lift and drag coefficients C_L, C_D [-] at ``alpha_rad`` [rad] (any angle; blended
    lifting line and flat plate, module docstring)."""
    a = np.asarray(alpha_rad, dtype=float)
    slope = lift_slope(aspect_ratio, sweep_deg)
    stall = math.radians(STALL_DEG)
    m = BLEND_RATE
    with np.errstate(over="ignore"):
        e1 = np.exp(np.clip(-m * (a - stall), -700, 700))
        e2 = np.exp(np.clip(m * (a + stall), -700, 700))
        sigma = (1.0 + e1 + e2) / ((1.0 + e1) * (1.0 + e2))
    sigma = np.where(np.isfinite(sigma), sigma, 1.0)
    cl_att = slope * a
    cd_att = cd0 + cl_att**2 / (math.pi * aspect_ratio)
    cn = (1.11 + 0.018 * aspect_ratio) * np.sin(a)
    cl = (1.0 - sigma) * cl_att + sigma * cn * np.cos(a)
    cd = (1.0 - sigma) * cd_att + sigma * (cd0 + cn * np.sin(a))
    return cl, cd


class Wings:
    """The wings of a model.json ``glider`` block (area [m^2], span [m], sweep [deg], x [m])."""

    def __init__(self, glider: dict[str, Any], rho: float):
        self.area = float(glider["wing_area_m2"])
        self.span = float(glider["wing_span_m"])
        self.sweep = float(glider.get("wing_sweep_deg", 0.0))
        self.x = float(glider["wing_x_m"])
        self.cd0 = float(glider.get("wing_cd0", CD0))
        self.rho = float(rho)
        self.ar = self.span**2 / self.area

    def force(self, nu: np.ndarray) -> np.ndarray:
        """The wings' force and moment [N, N m] in body axes at velocities ``nu``
        (u, v, w [m/s], p, q, r [rad/s])."""
        tau = np.zeros(6)
        u, _, w, p, q, r = (float(x) for x in nu[:6])  # the sections see u and w only
        for side in (1.0, -1.0):
            # a wing's point (x, y, 0), y = ±span/4: its velocity nu[:3] + omega × (x, y, 0)
            y = side * self.span / 4.0
            ul = u - r * y
            wl = w + p * y - q * self.x
            q2 = ul * ul + wl * wl
            if q2 == 0.0:
                continue
            alpha = math.atan2(wl, ul)
            cl, cd = wing_coefficients(alpha, self.ar, self.sweep, self.cd0)
            half = 0.5 * self.rho * q2 * 0.5 * self.area
            ca, sa = math.cos(alpha), math.sin(alpha)
            fx = half * (float(cl) * sa - float(cd) * ca)
            fz = half * (-float(cl) * ca - float(cd) * sa)
            # force (fx, 0, fz) at (x, y, 0): moment (x, y, 0) × (fx, 0, fz)
            tau[0] += fx
            tau[2] += fz
            tau[3] += y * fz
            tau[4] -= self.x * fz
            tau[5] -= y * fx
        return tau
