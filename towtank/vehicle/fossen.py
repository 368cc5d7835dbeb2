"""The terms every vehicle module shares: the coefficient symbols, model.json's required keys
and the mass matrices of the Fossen-form model.

A leaf of :mod:`towtank.vehicle` (it imports none of its modules): the checks
(:mod:`towtank.vehicle.schema`), the model (:mod:`towtank.vehicle.model`), the simulator and
the identification all take these from here.

``M = M_RB + M_A`` (Fossen 2011, eqs. 3.44 and 6.42), body axes x forward, y starboard, z
down, SNAME signs, SI units; the added-mass Coriolis and centripetal force is C_A(nu) nu
(Fossen 2011, eq. 6.43).

References
----------
.. [1] Fossen, T. I. (2011), Handbook of Marine Craft Hydrodynamics and Motion Control,
   Wiley.
"""

from __future__ import annotations

import re
from collections.abc import Callable

import numpy as np

__all__ = [
    "DOF",
    "VELOCITIES",
    "SYMBOL_RE",
    "REQUIRED_KEYS",
    "skew",
    "rigid_body_mass_matrix",
    "coriolis_rigid_body",
    "added_mass_matrix",
    "coriolis_added_mass",
    "quadratic_form",
    "restoring_matrix",
    "LUMPED",
    "ADDED_MASS_RE",
    "ca_bilinear",
]

#: The forces and moments of the six degrees of freedom, in the order of the state [-].
DOF = "XYZKMN"
#: The body velocities u, v, w [m/s] and p, q, r [rad/s], in the same order.
VELOCITIES = "uvwpqr"
#: A hydrodynamic coefficient's symbol: a force or moment and a product of velocities, their
#: magnitudes and the control angles (``Y_uv``, ``N_r|r|``, ``Y_uudr``).
SYMBOL_RE = re.compile(r"^[XYZKMN]_(\|[uvwpqr]\||[uvwpqr]|dr|ds)+$")
#: An added mass's symbol (``Y_vdot``).
ADDED_MASS_RE = re.compile(r"^[XYZKMN]_[uvwpqr]dot$")
#: The coefficients of a product of two velocities to which C_A(nu) nu contributes (or, for
#: Y_uv and Z_uw, could: their part is zero), with that pair of velocities: a measured total
#: (Prestero's lumped form) holds that part, the Fossen form does not.
LUMPED = {"Y_ur": ("u", "r"), "Z_uq": ("u", "q"), "N_uv": ("u", "v"), "M_uw": ("u", "w"),
          "N_ur": ("u", "r"), "M_uq": ("u", "q"), "Y_uv": ("u", "v"), "Z_uw": ("u", "w")}
#: The keys every model.json holds (docs/formats.md §6).
REQUIRED_KEYS = ("rho_kg_m3", "mass_kg", "weight_N", "buoyancy_N", "cg_m", "cb_m",
                 "inertia_kg_m2", "coefficients")


def restoring_matrix(weight: float, buoyancy: float, rg: np.ndarray,
                     rb: np.ndarray) -> np.ndarray:
    """G, the restoring forces and moments as a matrix: g(eta) = G [sin theta,
    cos theta sin phi, cos theta cos phi]^T (Fossen 2011, eq. 4.6; g(eta) is on the left-hand
    side of the equations of motion, so the force on the vehicle is -g(eta)).

    Parameters
    ----------
    weight : float
        W, the vehicle's weight [N].
    buoyancy : float
        B, its buoyancy [N].
    rg, rb : numpy.ndarray
        The centres of gravity and buoyancy in body axes from the origin [m].

    Returns
    -------
    numpy.ndarray
        G, 6 x 3 [N, N m]: rows X, Y, Z, K, M, N.
    """
    (xg, yg, zg), (xb, yb, zb) = np.asarray(rg, dtype=float), np.asarray(rb, dtype=float)
    w, b = float(weight), float(buoyancy)
    gx, gy, gz = xg * w - xb * b, yg * w - yb * b, zg * w - zb * b  # W r_g - B r_b
    return np.array([[w - b, 0.0, 0.0], [0.0, -(w - b), 0.0], [0.0, 0.0, -(w - b)],
                     [0.0, gz, -gy], [gz, 0.0, gx], [-gy, -gx, 0.0]])


def skew(a: np.ndarray) -> np.ndarray:
    """S(a), the skew-symmetric matrix of the cross product: S(a) b = a x b (Fossen 2011,
    eq. 2.10).

    Parameters
    ----------
    a : numpy.ndarray
        A 3-vector [any unit]
    """
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def rigid_body_mass_matrix(mass: float, rg: np.ndarray, inertia: np.ndarray) -> np.ndarray:
    """M_RB (6x6) about the reference point (Fossen 2011, eq. 3.44).

    ``M_RB = [[m I, -m S(r_g)], [m S(r_g), I_o]]``.

    Parameters
    ----------
    mass : float
        Mass m [kg]
    rg : numpy.ndarray
        Centre of gravity r_g from the reference point, body axes [m]
    inertia : numpy.ndarray
        Inertia matrix I_o (3x3) about the reference point [kg m^2]
    """
    m_rb = np.zeros((6, 6))
    m_rb[:3, :3] = mass * np.eye(3)
    m_rb[:3, 3:] = -mass * skew(rg)
    m_rb[3:, :3] = mass * skew(rg)
    m_rb[3:, 3:] = inertia
    return m_rb


def coriolis_rigid_body(mass: float, rg: np.ndarray, inertia: np.ndarray,
                        nu: np.ndarray) -> np.ndarray:
    """C_RB(nu) nu about the reference point (Fossen 2011, eq. 3.56) [N, N m].

    Parameters
    ----------
    mass : float
        [kg]
    rg : numpy.ndarray
        Centre of gravity from the reference point [m]
    inertia : numpy.ndarray
        I_o (3x3) [kg m^2]
    nu : numpy.ndarray
        Body velocities u, v, w [m/s], p, q, r [rad/s]
    """
    nu1, nu2 = nu[:3], nu[3:]
    s2 = skew(nu2)
    top = mass * s2 @ nu1 - mass * s2 @ skew(rg) @ nu2
    bottom = mass * skew(rg) @ s2 @ nu1 - skew(inertia @ nu2) @ nu2
    return np.concatenate((top, bottom))


def added_mass_matrix(coefficients: dict[str, float]) -> np.ndarray:
    """M_A (6x6, symmetric) from the ``<F>_<v>dot`` coefficients: M_A[i, j] = -F_i,vdot_j
    (Fossen 2011, eq. 6.42) [kg, kg m, kg m^2].

    A missing coefficient is zero; where only one of a symmetric pair is given (Y_rdot,
    N_vdot) it stands for both.
    """
    ma = np.zeros((6, 6))
    for i, f in enumerate(DOF):
        for j, v in enumerate(VELOCITIES):
            a = coefficients.get(f"{f}_{v}dot")
            b = coefficients.get(f"{DOF[j]}_{VELOCITIES[i]}dot")
            val = a if a is not None else b
            if val is not None:
                ma[i, j] = -float(val)
    return 0.5 * (ma + ma.T)


def coriolis_added_mass(ma: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """C_A(nu) nu of Fossen (2011) eq. 6.43, the force the added mass exerts is its negative
    [N, N m].

    ``C_A = [[0, -S(A11 nu1 + A12 nu2)], [-S(A11 nu1 + A12 nu2), -S(A21 nu1 + A22 nu2)]]``.

    Parameters
    ----------
    ma : numpy.ndarray
        M_A (6x6) [kg, kg m, kg m^2]
    nu : numpy.ndarray
        Body velocities u, v, w [m/s], p, q, r [rad/s]
    """
    nu1, nu2 = nu[:3], nu[3:]
    a = ma[:3, :3] @ nu1 + ma[:3, 3:] @ nu2
    b = ma[3:, :3] @ nu1 + ma[3:, 3:] @ nu2
    return np.concatenate((-skew(a) @ nu2, -skew(a) @ nu1 - skew(b) @ nu2))


def quadratic_form(f: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
    """The coefficients (36, 6) of a quadratic function ``f`` of the 6-vector ``nu``:
    ``f(nu) = (nu nu^T).ravel() @ form`` (the product ``nu_a nu_b`` in row ``6 a + b``, those
    with ``a > b`` zero)."""
    eye = np.eye(6)
    form = np.zeros((6, 6, 6))
    for a in range(6):
        form[a, a] = f(eye[a])
        for b in range(a + 1, 6):
            form[a, b] = f(eye[a] + eye[b]) - f(eye[a]) - f(eye[b])
    return form.reshape(36, 6)


def ca_bilinear(ma: np.ndarray, symbol: str) -> float:
    """The coefficient of the product of two velocities in the force -C_A(nu) nu (Fossen
    2011, eq. 6.43): the added-mass part of the :data:`LUMPED` coefficient ``symbol``
    [its SI unit], e.g. Y_vdot - X_udot for N_uv (the Munk moment), X_udot for Y_ur.

    Linear in ``ma``.

    Parameters
    ----------
    ma : numpy.ndarray
        M_A (6x6) [kg, kg m, kg m^2]
    symbol : str
        A key of :data:`LUMPED`
    """
    dof = DOF.index(symbol[0])
    i, j = (VELOCITIES.index(c) for c in LUMPED[symbol])

    def force(x: float, y: float) -> float:
        nu = np.zeros(6)
        nu[i] += x
        nu[j] += y
        return float(-coriolis_added_mass(ma, nu)[dof])

    return force(1.0, 1.0) - force(1.0, 0.0) - force(0.0, 1.0)
