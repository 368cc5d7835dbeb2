"""Similarity laws, model-to-prototype scaling and resistance extrapolation.

Conventions follow docs/method.md, "Similarity and scaling" (the SUT-2 report, section 3): the scale
ratio is ``lambda = L_p / L_m`` (prototype over model), ``Fn = U / sqrt(g L)``, ``Re = U L / nu``.
Resistance is extrapolated with the ITTC 1957 model-ship correlation line and a form factor
(ITTC Recommended Procedure 7.5-02-02-02, *1978 ITTC Performance Prediction Method*, with the
wave-making term dropped for a deeply submerged body).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from towtank.analysis.form_factor_trend import (  # noqa: F401  (re-exported)
    FormFactorTrend,
    form_factor_trend,
    form_factor_trend_statement,
)

#: Standard acceleration of gravity [m/s^2].
from towtank.errors import ProtocolError
from towtank.ingest.protocol_types import Protocol, Water
from towtank.reference.constants import STANDARD_GRAVITY
from towtank.reference.water import water_at
from towtank.stats.grouping import speed_groups  # noqa: F401  (re-exported)

#: Depth-to-diameter ratio beyond which a submerged body of revolution makes no significant waves.
DEEP_SUBMERGENCE_DEPTH_RATIO = 3.0

#: Reynolds number below which a model's boundary layer may still be laminar: the default of
#: [processing] laminar_re, used alike by the form factor and the similarity statement.
TURBULENT_RE_MODEL = 2.0e5

#: Smallest prototype Reynolds number scaled: far below it the ITTC-57 line means nothing (its
#: pole is at Re = 100) and a speed there is a unit mistake.
MIN_PROTOTYPE_REYNOLDS = 1.0e3

PRIME_KINDS = {"added_mass": 3, "damping": 2}

SCALING_COLUMNS = (
    "speed_prototype",
    "re_prototype",
    "fn_prototype",
    "speed_model_froude",
    "speed_model_reynolds",
    "drag_froude",
    "drag_ittc57",
    "froude_in_tested_range",
    "reynolds_in_tested_range",
    "re_model_froude",
)

#: scaling.csv's columns after :data:`SCALING_COLUMNS`, added by the day's pipeline: the
#: prototype resistance the report recommends [N] and the column it is taken from (or "none").
SCALING_RECOMMENDED_COLUMNS = ("drag_recommended", "recommended")


def medium_at(water: Water, temperature_C: float | None = None) -> tuple[float, float]:
    """(rho [kg/m^3], nu [m^2/s]) of a protocol's [water] or [prototype.water] medium
    (:func:`towtank.reference.water.water_at`: ITTC 7.5-02-01-03 for water, CIPM-2007 and
    Sutherland for air).

    Parameters
    ----------
    water : towtank.ingest.protocol_types.Water
        The section: type, temperature [°C], salinity [g/kg], pressure [Pa] and relative
        humidity [%] of air
    temperature_C : float, optional
        A run's temperature [°C]; default the section's own
    """
    t = water.temperature_C if temperature_C is None else temperature_C
    return water_at(t, water.type, water.salinity_g_kg, water.pressure_Pa,
                    water.relative_humidity_pct)


def froude_number(
    speed: ArrayLike, length: ArrayLike, g: float = STANDARD_GRAVITY
) -> float | np.ndarray:
    """Length Froude number, ``Fn = U / sqrt(g L)``.

    Parameters
    ----------
    speed : float or array_like
        Speed through the water [m/s]
    length : float or array_like
        Reference length [m]
    g : float, default 9.80665
        Acceleration of gravity [m/s^2]

    Returns
    -------
    float or numpy.ndarray
        Froude number [-]
    """
    return np.asarray(speed, dtype=float) / np.sqrt(g * np.asarray(length, dtype=float))


def reynolds_number(speed: ArrayLike, length: ArrayLike, nu: ArrayLike) -> float | np.ndarray:
    """Length Reynolds number, ``Re = U L / nu``.

    Parameters
    ----------
    speed : float or array_like
        Speed through the water [m/s]
    length : float or array_like
        Reference length [m]
    nu : float or array_like
        Kinematic viscosity of the water [m^2/s]

    Returns
    -------
    float or numpy.ndarray
        Reynolds number [-]
    """
    return np.asarray(speed, dtype=float) * np.asarray(length, dtype=float) / np.asarray(nu)


def ittc57_cf(reynolds: ArrayLike) -> float | np.ndarray:
    """Frictional resistance coefficient of the ITTC 1957 model-ship correlation line.

    ``C_F = 0.075 / (log10 Re - 2)^2`` (ITTC 1957; ITTC 7.5-02-02-02).

    Parameters
    ----------
    reynolds : float or array_like
        Reynolds number based on length [-], > 100

    Returns
    -------
    float or numpy.ndarray
        Frictional resistance coefficient on the wetted area [-]

    Raises
    ------
    ValueError
        A Reynolds number is not above 100, where the line has its pole.
    """
    re = np.asarray(reynolds, dtype=float)
    if np.any(~(re > 100.0)):
        raise ValueError("The ITTC-57 line is defined only for Reynolds numbers above 100.")
    return 0.075 / (np.log10(re) - 2.0) ** 2


def froude_speed_model(speed_prototype: ArrayLike, scale: float) -> float | np.ndarray:
    """Model speed under Froude similarity, ``U_m = U_p / sqrt(lambda)``.

    Parameters
    ----------
    speed_prototype : float or array_like
        Prototype speed [m/s]
    scale : float
        Scale ratio ``lambda = L_p / L_m`` [-]

    Returns
    -------
    float or numpy.ndarray
        Model speed [m/s]
    """
    return np.asarray(speed_prototype, dtype=float) / math.sqrt(_positive(scale, "scale"))


def froude_speed_prototype(speed_model: ArrayLike, scale: float) -> float | np.ndarray:
    """Prototype speed under Froude similarity, ``U_p = U_m sqrt(lambda)``.

    Parameters
    ----------
    speed_model : float or array_like
        Model speed [m/s]
    scale : float
        Scale ratio ``lambda = L_p / L_m`` [-]

    Returns
    -------
    float or numpy.ndarray
        Prototype speed [m/s]
    """
    return np.asarray(speed_model, dtype=float) * math.sqrt(_positive(scale, "scale"))


def reynolds_speed_model(
    speed_prototype: ArrayLike, scale: float, nu_model: float, nu_prototype: float
) -> float | np.ndarray:
    """Model speed under Reynolds similarity, ``U_m = U_p lambda nu_m / nu_p``.

    Parameters
    ----------
    speed_prototype : float or array_like
        Prototype speed [m/s]
    scale : float
        Scale ratio ``lambda = L_p / L_m`` [-]
    nu_model : float
        Kinematic viscosity of the tank water [m^2/s]
    nu_prototype : float
        Kinematic viscosity of the prototype's water [m^2/s]

    Returns
    -------
    float or numpy.ndarray
        Model speed [m/s]
    """
    return (
        np.asarray(speed_prototype, dtype=float)
        * _positive(scale, "scale")
        * _positive(nu_model, "nu_model")
        / _positive(nu_prototype, "nu_prototype")
    )


def reynolds_speed_prototype(
    speed_model: ArrayLike, scale: float, nu_model: float, nu_prototype: float
) -> float | np.ndarray:
    """Prototype speed under Reynolds similarity, ``U_p = U_m (nu_p / nu_m) / lambda``.

    Parameters
    ----------
    speed_model : float or array_like
        Model speed [m/s]
    scale : float
        Scale ratio ``lambda = L_p / L_m`` [-]
    nu_model : float
        Kinematic viscosity of the tank water [m^2/s]
    nu_prototype : float
        Kinematic viscosity of the prototype's water [m^2/s]

    Returns
    -------
    float or numpy.ndarray
        Prototype speed [m/s]
    """
    return (
        np.asarray(speed_model, dtype=float)
        * _positive(nu_prototype, "nu_prototype")
        / _positive(nu_model, "nu_model")
        / _positive(scale, "scale")
    )


def froude_force_ratio(scale: float, rho_model: float, rho_prototype: float) -> float:
    """Prototype-to-model force ratio under Froude similarity, ``lambda^3 rho_p / rho_m``.

    Parameters
    ----------
    scale : float
        Scale ratio ``lambda = L_p / L_m`` [-]
    rho_model : float
        Density of the tank water [kg/m^3]
    rho_prototype : float
        Density of the prototype's water [kg/m^3]

    Returns
    -------
    float
        ``F_p / F_m`` [-]
    """
    return (
        _positive(scale, "scale") ** 3
        * _positive(rho_prototype, "rho_prototype")
        / _positive(rho_model, "rho_model")
    )


def reynolds_force_ratio(
    rho_model: float, rho_prototype: float, nu_model: float, nu_prototype: float
) -> float:
    """Prototype-to-model force ratio under Reynolds similarity, ``(rho_p/rho_m)(nu_p/nu_m)^2``.

    Equal Reynolds numbers give ``U_p L_p = U_m L_m nu_p / nu_m``, and so
    ``F = C (1/2) rho U^2 L^2`` scales with ``rho nu^2``, independently of the scale ratio.

    Parameters
    ----------
    rho_model : float
        Density of the tank water [kg/m^3]
    rho_prototype : float
        Density of the prototype's water [kg/m^3]
    nu_model : float
        Kinematic viscosity of the tank water [m^2/s]
    nu_prototype : float
        Kinematic viscosity of the prototype's water [m^2/s]

    Returns
    -------
    float
        ``F_p / F_m`` [-]
    """
    return (
        _positive(rho_prototype, "rho_prototype")
        / _positive(rho_model, "rho_model")
        * (_positive(nu_prototype, "nu_prototype") / _positive(nu_model, "nu_model")) ** 2
    )


@dataclass(frozen=True, eq=False)
class FormFactor:
    """Form factor ``1 + k`` from model resistance (ITTC 7.5-02-02-02 with the ITTC-57 line).

    Attributes
    ----------
    one_plus_k : float
        Mean over the tested speeds of the per-speed ``C_T / C_F`` [-]
    std : float
        Sample standard deviation (ddof = 1) of the per-speed values [-]; NaN for one speed
    n : int
        Number of tested speeds used (repeats at one speed count once)
    n_runs : int
        Number of points (runs) used
    values : numpy.ndarray
        ``(1 + k)_i = C_T,i / C_F,i`` for every input point [-] (NaN where ``Re`` <= 100)
    reynolds : numpy.ndarray
        Reynolds number of every input point [-]
    used : numpy.ndarray
        Boolean mask of the points with ``Re >= re_min`` that enter the mean
    re_range : tuple of float
        Smallest and largest Reynolds number of the points used [-]
    speeds : numpy.ndarray
        Mean speed of each tested speed used, ascending [m/s]
    speed_values : numpy.ndarray
        ``1 + k`` of each tested speed, the mean over its repeats [-]
    speed_runs : numpy.ndarray
        Number of points (runs) at each tested speed
    speed_reynolds : numpy.ndarray
        Mean Reynolds number of each tested speed [-]
    """

    one_plus_k: float
    std: float
    n: int
    n_runs: int
    values: np.ndarray
    reynolds: np.ndarray
    used: np.ndarray
    re_range: tuple[float, float]
    speeds: np.ndarray
    speed_values: np.ndarray
    speed_runs: np.ndarray
    speed_reynolds: np.ndarray = field(default_factory=lambda: np.zeros(0))


def form_factor(
    drag: ArrayLike,
    speed: ArrayLike,
    wetted_area: float,
    rho: float | ArrayLike,
    nu: float | ArrayLike,
    length: float,
    re_min: float = 2e5,
    rel_tol: float = 0.02,
) -> FormFactor:
    """Form factor ``1 + k = C_T / C_F`` from steady zero-angle model resistance.

    For each point ``C_T = R / (1/2 rho S U^2)`` and ``C_F`` is the ITTC-57 line at
    ``Re = U L / nu``; ``(1 + k)_i = C_T / C_F`` (ITTC 7.5-02-02-02, with no wave resistance for a
    deeply submerged body). Only the points with ``Re >= re_min`` are used, so that the laminar
    and transitional range is left out. Their repeats at one tested speed (speeds within
    ``rel_tol``, :func:`speed_groups`) are averaged first; ``1 + k`` is then the mean over the
    tested speeds and its spread the sample standard deviation over them, so that a speed run
    five times weighs no more than a speed run once.

    Parameters
    ----------
    drag : array_like
        Steady resistance of the model at zero incidence, tare removed [N]
    speed : array_like
        Model speed of each point [m/s]
    wetted_area : float
        Wetted surface area of the model [m^2]
    rho : float or array_like
        Density of the tank water [kg/m^3]: one value, or each point's (its run's water)
    nu : float or array_like
        Kinematic viscosity of the tank water [m^2/s]: one value, or each point's
    length : float
        Model length [m]
    re_min : float, default 2e5
        Smallest Reynolds number used [-]
    rel_tol : float, default 0.02
        Relative speed difference within which points are repeats of one tested speed [-]

    Returns
    -------
    FormFactor

    Raises
    ------
    ValueError
        ``drag`` and ``speed`` differ in length, or no point reaches ``re_min``.
    """
    r = np.atleast_1d(np.asarray(drag, dtype=float))
    u = np.abs(np.atleast_1d(np.asarray(speed, dtype=float)))
    if r.shape != u.shape:
        raise ValueError(
            f"drag and speed must have the same length ({r.size} and {u.size} points given)."
        )
    area = _positive(wetted_area, "wetted_area")
    rho_i, nu_i = (_positive_each(x, name, r.shape) for x, name in ((rho, "rho"), (nu, "nu")))
    re = np.asarray(reynolds_number(u, _positive(length, "length"), nu_i))
    values = np.full(r.shape, np.nan)
    valid = np.isfinite(re) & (re > 100.0) & np.isfinite(r)
    ct = r[valid] / (0.5 * rho_i[valid] * area * u[valid] ** 2)
    values[valid] = ct / ittc57_cf(re[valid])
    used = valid & (re >= re_min)
    n_runs = int(np.count_nonzero(used))
    if n_runs == 0:
        top = f"{np.nanmax(re):.3g}" if np.any(np.isfinite(re)) else "undefined"
        raise ValueError(
            f"No steady point reaches Re = {re_min:.3g} (highest Re = {top}), so the form factor "
            "cannot be taken outside the laminar range."
        )
    groups = speed_groups(np.abs(u[used]), rel_tol)
    count = np.bincount(groups)
    speeds = np.bincount(groups, weights=u[used]) / count
    speed_values = np.bincount(groups, weights=values[used]) / count
    n = int(speeds.size)
    std = float(np.std(speed_values, ddof=1)) if n > 1 else float("nan")
    return FormFactor(
        one_plus_k=float(np.mean(speed_values)),
        std=std,
        n=n,
        n_runs=n_runs,
        values=values,
        reynolds=re,
        used=used,
        re_range=(float(np.min(re[used])), float(np.max(re[used]))),
        speeds=speeds,
        speed_values=speed_values,
        speed_runs=count,
        speed_reynolds=np.bincount(groups, weights=re[used]) / count,
    )


@dataclass(frozen=True)
class ResistanceRecommendation:
    """Which prototype resistance of scaling.csv the report recommends, and why.

    Attributes
    ----------
    column : str
        ``"drag_ittc57"``, or ``"none"`` when no column is the prototype resistance
    rule : str
        The rule, in sentences for the report
    """

    column: str
    rule: str


def recommend_resistance(
    depth_ratio: float | None, ittc57_available: bool, free_surface: bool = True
) -> ResistanceRecommendation:
    """The prototype resistance to use: ITTC-57 with the form factor for a body without waves.

    A body of revolution deeper than :data:`DEEP_SUBMERGENCE_DEPTH_RATIO` diameters makes no
    significant waves, so its resistance is viscous and scales with Reynolds number: the
    ITTC-57 line with the form factor (1978 ITTC method without the wave term,
    ``R_p = 1/2 rho_p S_p U_p^2 [(1 + k) C_F(Re_p) + Delta C_F]``) is the prototype
    resistance. Froude scaling of the total resistance (``lambda^3 rho_p / rho_m`` at equal
    Fn) is right for wave-making resistance only; it keeps the model's friction coefficient,
    which is larger than the prototype's, and is shown for comparison. Near the surface (depth
    not more than 3 D) the resistance holds a wave part that neither column gives alone, so
    none is recommended.

    Parameters
    ----------
    depth_ratio : float or None
        Submergence of the model's axis over its diameter, depth/D [-]; None when not known
    ittc57_available : bool
        Whether ``drag_ittc57`` was computed (wetted area and form factor known)
    free_surface : bool, default True
        False for a model tested in air (a wind tunnel): there is no free surface, so no
        waves whatever ``depth_ratio`` says, and the rule says so.

    Returns
    -------
    ResistanceRecommendation
    """
    froude = ("R_p Froude scales the model's total resistance by λ³ρ_p/ρ_m at equal Froude "
              "number, which holds for wave-making resistance only (it keeps the model's "
              "larger friction coefficient): shown for comparison, it is not a prototype "
              "resistance.")
    formula = ("R_p ITTC-57 = ½ρ_p·S_p·U_p²·[(1 + k)·C_F + ΔC_F], C_F at the prototype's "
               "Reynolds number")
    deep = DEEP_SUBMERGENCE_DEPTH_RATIO
    if not free_surface:
        if not ittc57_available:
            return ResistanceRecommendation("none", (
                "No prototype resistance is recommended: R_p ITTC-57 needs the model's wetted "
                "area and a form factor, which the day does not give. " + froude))
        return ResistanceRecommendation("drag_ittc57", (
            f"Recommended: {formula}. Rule: the model was tested in air, with no free surface, "
            "so it made no waves: its resistance is viscous and scales with Reynolds number "
            "(1978 ITTC method without wave resistance). " + froude))
    if depth_ratio is not None and not depth_ratio > deep:
        return ResistanceRecommendation("none", (
            f"No prototype resistance is recommended: the model ran at {depth_ratio:.3g} D, not "
            f"deeper than {deep:g} D, so its resistance holds wave-making as well as viscous "
            "resistance; R_p ITTC-57 leaves the waves out and R_p Froude scales the viscous "
            "part as if it were wave-making."))
    if not ittc57_available:
        return ResistanceRecommendation("none", (
            "No prototype resistance is recommended: R_p ITTC-57 needs the model's wetted area "
            "and a form factor, which the day does not give. " + froude))
    if depth_ratio is None:
        return ResistanceRecommendation("drag_ittc57", (
            f"Recommended: {formula}, assuming the model made no waves ([model] depth_m not "
            f"given; a body deeper than {deep:g} D makes none), so that its resistance is "
            "viscous and scales with Reynolds number. " + froude))
    return ResistanceRecommendation("drag_ittc57", (
        f"Recommended: {formula}. Rule: the model ran at {depth_ratio:.3g} D, deeper than "
        f"{deep:g} D, so it made no waves: its resistance is viscous and scales with Reynolds "
        "number (1978 ITTC method without wave resistance). " + froude))


def ittc57_drag(
    speed_prototype: ArrayLike,
    length_prototype: float,
    wetted_area_prototype: float,
    rho_p: float,
    nu_p: float,
    one_plus_k: float,
    delta_cf: float = 0.0,
) -> float | np.ndarray:
    """Prototype resistance from the ITTC-57 line and a form factor.

    ``R_p = 1/2 rho_p S_p U_p^2 [(1 + k) C_F(Re_p) + Delta C_F]`` (ITTC 7.5-02-02-02, 1978 ITTC
    method without wave resistance; ``C_F`` from the ITTC 1957 line).

    Parameters
    ----------
    speed_prototype : float or array_like
        Prototype speed [m/s], > 0
    length_prototype : float
        Prototype length [m]
    wetted_area_prototype : float
        Prototype wetted surface area [m^2]
    rho_p : float
        Density of the prototype's water [kg/m^3]
    nu_p : float
        Kinematic viscosity of the prototype's water [m^2/s]
    one_plus_k : float
        Form factor ``1 + k`` [-]
    delta_cf : float, default 0
        Roughness allowance ``Delta C_F`` [-]

    Returns
    -------
    float or numpy.ndarray
        Prototype resistance [N]
    """
    u = np.asarray(speed_prototype, dtype=float)
    re = reynolds_number(np.abs(u), _positive(length_prototype, "length_prototype"), nu_p)
    ct = one_plus_k * ittc57_cf(re) + delta_cf
    return 0.5 * rho_p * _positive(wetted_area_prototype, "wetted_area_prototype") * u**2 * ct


def _prime_factor(rho: float, length: float, kind: str) -> float:
    """``1/2 rho L^3`` for added mass, ``1/2 rho L^2`` for quadratic damping."""
    if kind not in PRIME_KINDS:
        raise ValueError(
            f"Unknown coefficient kind {kind!r}: use one of {', '.join(map(repr, PRIME_KINDS))}."
        )
    return 0.5 * _positive(rho, "rho") * _positive(length, "length") ** PRIME_KINDS[kind]


def prototype_value(
    prime: ArrayLike, rho_prototype: float, length_prototype: float, kind: str
) -> float | np.ndarray:
    """Dimensional prototype coefficient from its prime (non-dimensional) value.

    Added mass: ``prime * 1/2 rho L^3`` [kg]; quadratic damping: ``prime * 1/2 rho L^2`` [kg/m]
    (SNAME 1950 prime system, as in docs/method.md "Conventions").

    Parameters
    ----------
    prime : float or array_like
        Prime coefficient [-]
    rho_prototype : float
        Density of the prototype's water [kg/m^3]
    length_prototype : float
        Prototype length [m]
    kind : str
        ``"added_mass"`` or ``"damping"``

    Returns
    -------
    float or numpy.ndarray
        Dimensional coefficient [kg] or [kg/m]
    """
    return np.asarray(prime, dtype=float) * _prime_factor(rho_prototype, length_prototype, kind)


def prime_value(value: ArrayLike, rho: float, length: float, kind: str) -> float | np.ndarray:
    """Prime (non-dimensional) coefficient from a dimensional one; inverse of `prototype_value`.

    Added mass: ``value / (1/2 rho L^3)``; quadratic damping: ``value / (1/2 rho L^2)``.

    Parameters
    ----------
    value : float or array_like
        Dimensional coefficient [kg] (added mass) or [kg/m] (quadratic damping)
    rho : float
        Water density [kg/m^3]
    length : float
        Body length [m]
    kind : str
        ``"added_mass"`` or ``"damping"``

    Returns
    -------
    float or numpy.ndarray
        Prime coefficient [-]
    """
    return np.asarray(value, dtype=float) / _prime_factor(rho, length, kind)


def check_protocol_speeds(protocol: Protocol) -> None:
    """Raise ProtocolError unless every [prototype] speed of ``protocol`` is finite, > 0 and
    gives Re_p >= 1e3 (:func:`check_prototype_speeds`); nothing without a [model] and a
    [prototype].

    Needs the prototype water's viscosity, so it runs once the analysis libraries are loaded
    (after the reductions), not in :func:`towtank.ingest.protocol.load_protocol`.
    """
    proto = protocol.prototype
    if protocol.model is None or proto is None:
        return
    _, nu_p = medium_at(proto.water)
    try:
        check_prototype_speeds(proto.speeds_m_s, proto.length_m, nu_p)
    except ValueError as exc:
        raise ProtocolError(
            f"{protocol.path.name}: 'speeds_m_s' in [prototype] cannot be scaled: {exc}"
        ) from None


def check_prototype_speeds(
    speeds: ArrayLike,
    length: float,
    nu: float,
    re_min: float = MIN_PROTOTYPE_REYNOLDS,
) -> np.ndarray:
    """Prototype speeds as a 1-D array, checked to be usable for scaling.

    Each speed must be finite, > 0 and give ``Re = U L / nu >= re_min``: the ITTC-57 line
    ``C_F = 0.075 / (log10 Re - 2)^2`` has its pole at Re = 100 and describes turbulent
    friction only, so a prototype speed far below ``re_min`` is a unit or typing mistake.

    Parameters
    ----------
    speeds : float or array_like
        Prototype speeds [m/s]
    length : float
        Prototype length [m]
    nu : float
        Kinematic viscosity of the prototype's water [m^2/s]
    re_min : float, default 1e3
        Smallest Reynolds number accepted [-]

    Returns
    -------
    numpy.ndarray
        The speeds [m/s]

    Raises
    ------
    ValueError
        One sentence naming the first unusable speed and why.
    """
    u = np.atleast_1d(np.asarray(speeds, dtype=float)).ravel()
    if u.size == 0:
        raise ValueError("no prototype speed was given.")
    l_p, nu_p = _positive(length, "length"), _positive(nu, "nu")
    for v in u:
        if not math.isfinite(v) or v <= 0.0:
            raise ValueError(f"the prototype speed {v:g} m/s is not a finite speed > 0.")
        re = v * l_p / nu_p
        if re < re_min:
            raise ValueError(
                f"the prototype speed {v:g} m/s gives Re = {re:.3g} (L = {l_p:g} m, "
                f"nu = {nu_p:.4g} m²/s), below {re_min:.3g}, where the ITTC-57 friction line "
                f"means nothing; give speeds of at least {re_min * nu_p / l_p:.2g} m/s."
            )
    return u


def scaling_table(
    speeds_prototype: ArrayLike,
    *,
    scale: float,
    length_model: float,
    length_prototype: float,
    rho_m: float,
    nu_m: float,
    rho_p: float,
    nu_p: float,
    resistance_model: Callable[[float], float],
    tested_speed_range: tuple[float, float],
    wetted_area_model: float | None,
    one_plus_k: float,
    delta_cf: float = 0.0,
) -> pd.DataFrame:
    """Prototype resistance at given speeds, by Froude scaling and by the ITTC-57 method.

    For each prototype speed ``U_p``:

    - ``re_prototype = U_p L_p / nu_p``, ``fn_prototype = U_p / sqrt(g L_p)``;
    - ``speed_model_froude = U_p / sqrt(lambda)``,
      ``speed_model_reynolds = U_p lambda nu_m / nu_p``;
    - ``drag_froude = R_m(speed_model_froude) lambda^3 rho_p / rho_m``: the model's resistance
      curve Froude-scaled, which is what it is labelled (a deeply submerged hull's resistance does
      not follow Froude scaling);
    - ``drag_ittc57 = 1/2 rho_p S_p U_p^2 [(1 + k) C_F(Re_p) + Delta C_F]`` with
      ``S_p = S_m lambda^2`` (:func:`ittc57_drag`); NaN when the wetted area is unknown
      (``wetted_area_model`` None) or ``one_plus_k`` is NaN;
    - ``froude_in_tested_range`` / ``reynolds_in_tested_range``: whether the corresponding model
      speed lies inside ``tested_speed_range`` (``drag_froude`` is extrapolated where it does not);
    - ``re_model_froude = speed_model_froude L_m / nu_m``.

    ``scale`` is the ``lambda`` used for speeds, forces and areas; ``length_prototype`` and
    ``length_model`` give the Reynolds and Froude numbers. They must agree,
    ``length_prototype / length_model`` within 1 % of ``scale``.

    Parameters
    ----------
    speeds_prototype : float or array_like
        Prototype speeds [m/s], > 0, each with ``Re_p >= 1e3`` (:func:`check_prototype_speeds`)
    scale : float
        Scale ratio ``lambda = L_p / L_m`` [-]
    length_model : float
        Model length [m]
    length_prototype : float
        Prototype length [m]
    rho_m : float
        Density of the tank water [kg/m^3]
    nu_m : float
        Kinematic viscosity of the tank water [m^2/s]
    rho_p : float
        Density of the prototype's water [kg/m^3]
    nu_p : float
        Kinematic viscosity of the prototype's water [m^2/s]
    resistance_model : callable
        Steady model resistance [N] as a function of model speed [m/s]
    tested_speed_range : tuple of float
        Lowest and highest model speed tested [m/s]
    wetted_area_model : float or None
        Wetted surface area of the model [m^2]; None when it is not known
    one_plus_k : float
        Form factor ``1 + k`` [-], e.g. from :func:`form_factor`; NaN when it is not known
    delta_cf : float, default 0
        Roughness allowance ``Delta C_F`` [-]

    Returns
    -------
    pandas.DataFrame
        One row per prototype speed, columns as listed in ``SCALING_COLUMNS``.

    Raises
    ------
    ValueError
        Lengths inconsistent with ``scale``, an invalid tested speed range, or an unusable
        prototype speed.
    """
    lam = _positive(scale, "scale")
    l_m = _positive(length_model, "length_model")
    l_p = _positive(length_prototype, "length_prototype")
    if abs(l_p / l_m - lam) > 0.01 * lam:
        raise ValueError(
            f"length_prototype / length_model = {l_p / l_m:.4g} does not match scale = {lam:.4g}."
        )
    lo, hi = (float(v) for v in tested_speed_range)
    if not lo <= hi:
        raise ValueError(f"tested_speed_range must be (lowest, highest), not ({lo}, {hi}).")
    u_p = check_prototype_speeds(speeds_prototype, l_p, nu_p)
    u_m_froude = np.asarray(froude_speed_model(u_p, lam))
    u_m_reynolds = reynolds_speed_model(u_p, lam, nu_m, nu_p)
    r_m = np.array([float(resistance_model(float(u))) for u in u_m_froude], dtype=float)
    if wetted_area_model is None or not math.isfinite(one_plus_k):
        drag_ittc57 = np.full(u_p.shape, np.nan)
    else:
        wetted_area_prototype = _positive(wetted_area_model, "wetted_area_model") * lam**2
        drag_ittc57 = np.asarray(ittc57_drag(
            u_p, l_p, wetted_area_prototype, rho_p, nu_p, one_plus_k, delta_cf
        ))
    table = pd.DataFrame(
        {
            "speed_prototype": u_p,
            "re_prototype": reynolds_number(u_p, l_p, nu_p),
            "fn_prototype": froude_number(u_p, l_p),
            "speed_model_froude": u_m_froude,
            "speed_model_reynolds": u_m_reynolds,
            "drag_froude": r_m * froude_force_ratio(lam, rho_m, rho_p),
            "drag_ittc57": drag_ittc57,
            "froude_in_tested_range": (u_m_froude >= lo) & (u_m_froude <= hi),
            "reynolds_in_tested_range": (u_m_reynolds >= lo) & (u_m_reynolds <= hi),
            "re_model_froude": reynolds_number(u_m_froude, l_m, nu_m),
        },
        columns=list(SCALING_COLUMNS),
    )
    return table


def similarity_statement(
    re_model_range: tuple[float, float],
    re_prototype_range: tuple[float, float],
    depth_m: float | None = None,
    diameter_m: float | None = None,
    turbulent_re: float = TURBULENT_RE_MODEL,
    free_surface: bool = True,
) -> str:
    """Plain-English account of which similarity the model tests met.

    States the model and prototype Reynolds ranges and their ratio, whether they overlap
    (Reynolds similarity), whether the model range lies above ``turbulent_re`` (the threshold
    below which :func:`form_factor` leaves points out, [processing] laminar_re; the SUT-2
    report asked for Re > 1e5) and, when the depth and diameter are given, whether the depth exceeds
    3 D so that the body makes no waves and Froude similarity is not needed (the SUT-2 tests ran at
    5 D).

    Parameters
    ----------
    re_model_range : tuple of float
        Lowest and highest Reynolds number of the model tests [-]
    re_prototype_range : tuple of float
        Lowest and highest Reynolds number of the prototype's operation [-]
    depth_m : float, optional
        Submergence of the model's axis during the tests [m]
    diameter_m : float, optional
        Maximum diameter of the model [m]
    turbulent_re : float, default 2e5
        Model Reynolds number below which the boundary layer may be laminar [-]
    free_surface : bool, default True
        False for tests in air: no free surface, so Froude similarity does not apply (said in
        place of the depth sentence; ``depth_m`` is then not used).

    Returns
    -------
    str
        Sentences separated by single spaces.

    Raises
    ------
    ValueError
        Non-positive Reynolds numbers, or only one of ``depth_m`` and ``diameter_m`` given.
    """
    m_lo, m_hi = _re_range(re_model_range, "re_model_range")
    p_lo, p_hi = _re_range(re_prototype_range, "re_prototype_range")
    sentences = [
        f"The model tests covered Re = {m_lo:.3g} to {m_hi:.3g}; the prototype operates at "
        f"Re = {p_lo:.3g} to {p_hi:.3g}."
    ]
    overlap_lo, overlap_hi = max(m_lo, p_lo), min(m_hi, p_hi)
    if overlap_lo <= overlap_hi:
        sentences.append(
            f"Reynolds similarity was met for Re = {overlap_lo:.3g} to {overlap_hi:.3g}, "
            "where the two ranges overlap."
        )
    else:
        ratio_lo, ratio_hi = sorted((p_lo / m_lo, p_hi / m_hi))
        side = "above" if p_lo > m_hi else "below"
        sentences.append(
            f"Reynolds similarity was not met: the prototype's Reynolds numbers lie {side} the "
            f"model's, by a factor of {_ratio_text(ratio_lo, ratio_hi)}, so the resistance is "
            "extrapolated with the ITTC-57 line and a form factor."
        )
    re_t = _positive(turbulent_re, "turbulent_re")
    if m_lo >= re_t:
        sentences.append(f"All model tests were above Re = {re_t:.3g}, in turbulent flow.")
    elif m_hi >= re_t:
        sentences.append(
            f"Part of the model range lies below Re = {re_t:.3g}, where the boundary layer may "
            "be laminar; those tests do not scale to the prototype and are left out of the "
            "form factor."
        )
    else:
        sentences.append(
            f"All model tests were below Re = {re_t:.3g}, where the boundary layer may be "
            "laminar; they do not scale to a turbulent prototype."
        )
    if (depth_m is None) != (diameter_m is None):
        raise ValueError("Give both depth_m and diameter_m, or neither.")
    if not free_surface:
        sentences.append("The model was tested in air, with no free surface: it made no waves, "
                         "Froude similarity does not apply and its resistance scales with "
                         "Reynolds number.")
    elif depth_m is not None and diameter_m is not None:
        ratio = _positive(depth_m, "depth_m") / _positive(diameter_m, "diameter_m")
        if ratio > DEEP_SUBMERGENCE_DEPTH_RATIO:
            sentences.append(
                f"The model ran at a depth of {depth_m:g} m = {ratio:.3g} D, more than "
                f"{DEEP_SUBMERGENCE_DEPTH_RATIO:g} D, so it made no significant waves and Froude "
                "similarity was not needed; its resistance scales with Reynolds number."
            )
        else:
            sentences.append(
                f"The model ran at a depth of {depth_m:g} m = {ratio:.3g} D, not more than "
                f"{DEEP_SUBMERGENCE_DEPTH_RATIO:g} D, so free-surface waves may have added to its "
                "resistance and Froude similarity would also be needed."
            )
    return " ".join(sentences)


def _ratio_text(lo: float, hi: float) -> str:
    if math.isclose(lo, hi, rel_tol=0.005):
        return f"{lo:.3g}"
    return f"{lo:.3g} to {hi:.3g}"


def _re_range(values: tuple[float, float], name: str) -> tuple[float, float]:
    lo, hi = sorted(float(v) for v in values)
    if not (math.isfinite(lo) and math.isfinite(hi) and lo > 0.0):
        raise ValueError(f"{name} must hold two finite Reynolds numbers > 0, not {values}.")
    return lo, hi


def _positive_each(value: float | ArrayLike, name: str, shape: tuple[int, ...]) -> np.ndarray:
    """``value`` (one value or one per point) as an array of ``shape``; ValueError unless
    every value is finite and > 0, or the sizes differ."""
    v = np.asarray(value, dtype=float)
    if v.ndim and v.shape != shape:
        raise ValueError(f"{name} must be one value or one per point ({v.size} given for "
                         f"{int(np.prod(shape))} points).")
    if not (np.all(np.isfinite(v)) and np.all(v > 0.0)):
        raise ValueError(f"{name} must be finite values > 0.")
    return np.broadcast_to(v, shape)


def _positive(value: float, name: str) -> float:
    """``value`` as a float; raise ValueError unless it is finite and > 0."""
    v = float(value)
    if not (math.isfinite(v) and v > 0.0):
        raise ValueError(f"{name} must be a finite value > 0, not {value}.")
    return v
