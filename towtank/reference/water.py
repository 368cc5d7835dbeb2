"""Density and viscosity of fresh and sea water from temperature.

Follows ITTC Recommended Procedure 7.5-02-01-03, *Fresh Water and Seawater Properties* (2011):

- fresh water: IAPWS-95 density (Wagner & Pruß 2002) and the IAPWS 2008 viscosity formulation
  (Huber et al. 2009), both at atmospheric pressure, through the ``iapws`` package;
- sea water: density from the IAPWS-2008 seawater formulation (Feistel 2008; the Gibbs function that
  TEOS-10 is built on), dynamic viscosity from Sharqawy, Lienhard & Zubair (2010), *Desalination and
  Water Treatment* 16, 354-380, eq. (22): the pure-water viscosity above multiplied by
  ``1 + A S + B S^2``.

``iapws`` solves an equation of state for every call, so the scalar evaluations are cached on the
temperature rounded to 1e-4 °C (and the salinity rounded to 1e-4 g/kg).

The procedure's check values (15 °C): fresh 999.10 kg/m³ and 1.1386e-6 m²/s, sea water of
S = 35.165 g/kg 1025.98 kg/m³ and 1.1893e-6 m²/s.
"""

from __future__ import annotations

import functools
import math
import warnings
from dataclasses import dataclass

import iapws
import numpy as np

from towtank.reference.air import (
    DEFAULT_RELATIVE_HUMIDITY_PCT,
    STANDARD_PRESSURE_PA,
    air_properties,
)

#: Atmospheric pressure [MPa], the pressure of the ITTC tables.
ATMOSPHERIC_PRESSURE_MPA = 0.101325

#: Reference-composition salinity of standard sea water [g/kg] (ITTC 7.5-02-01-03).
STANDARD_SALINITY_G_KG = 35.165

#: Temperature range of ITTC 7.5-02-01-03 and of the seawater correlations [°C].
TEMPERATURE_RANGE_C = (0.0, 40.0)

#: Salinity range over which the seawater correlations are used here [g/kg].
SALINITY_RANGE_G_KG = (0.0, 42.0)

WATER_TYPES = ("fresh", "sea")

_KELVIN = 273.15

#: Temperatures at which water is liquid at atmospheric pressure [°C]: from sea water's
#: freezing point (about -1.9 °C at 35 g/kg) to just below fresh water's boiling point. The
#: properties are computed (extrapolated) anywhere inside; outside it there is no water.
LIQUID_RANGE_C = (-2.0, 99.0)


def temperature_problem(
    temperature_C: float, span: tuple[float, float] = LIQUID_RANGE_C,
    what: str = "of liquid water at atmospheric pressure",
) -> str | None:
    """Why ``temperature_C`` [°C] cannot be a water temperature, with the likely slip, or None.

    A value inside ``span`` [°C] is accepted; outside it the sentence names the unit or the
    typo that would explain it (kelvin, degrees Fahrenheit, a lost decimal point).
    """
    t = float(temperature_C)
    lo, hi = span
    if math.isfinite(t) and lo <= t <= hi:
        return None
    if not math.isfinite(t) or abs(t) > 1e6:
        return f"{temperature_C:g} °C is not a water temperature"
    hints = []
    if t > 0 and lo <= t / 10.0 <= hi:
        hints.append(f"a typo for {t / 10.0:g}")
    if lo <= t - _KELVIN <= hi:
        hints.append(f"in kelvin ({t - _KELVIN:.1f} °C)")
    elif lo <= (t - 32.0) / 1.8 <= hi:
        hints.append(f"in °F ({(t - 32.0) / 1.8:.1f} °C)")
    hint = f" (was it {' or '.join(hints)}?)" if hints else ""
    return f"{t:g} °C is outside the {lo:g}–{hi:g} °C {what}{hint}"


class WaterPropertyWarning(UserWarning):
    """A water property was evaluated outside the range its formulation is validated for."""


@dataclass(frozen=True)
class WaterProperties:
    """Water properties at one temperature (or an array of them).

    Attributes
    ----------
    rho : float or numpy.ndarray
        Density [kg/m^3]
    nu : float or numpy.ndarray
        Kinematic viscosity [m^2/s]
    mu : float or numpy.ndarray
        Dynamic viscosity [Pa s]
    temperature_C : float or numpy.ndarray
        Water temperature [°C]
    water_type : str
        ``"fresh"`` or ``"sea"``
    salinity_g_kg : float
        Absolute salinity [g/kg]; 0 for fresh water
    """

    rho: float | np.ndarray
    nu: float | np.ndarray
    mu: float | np.ndarray
    temperature_C: float | np.ndarray
    water_type: str
    salinity_g_kg: float


@functools.lru_cache(maxsize=4096)
def _fresh_rho_mu(temperature_C: float) -> tuple[float, float]:
    """IAPWS-95 density [kg/m^3] and IAPWS 2008 viscosity [Pa s] at 1 atm (cached)."""
    with warnings.catch_warnings():
        # iapws warns about extrapolation itself; the caller issues WaterPropertyWarning instead
        warnings.simplefilter("ignore")
        state = iapws.IAPWS95(T=temperature_C + _KELVIN, P=ATMOSPHERIC_PRESSURE_MPA)
    if state.phase != "Liquid" or not math.isfinite(state.rho):
        raise ValueError(
            f"Water at {temperature_C:g} °C and atmospheric pressure is not liquid "
            f"(IAPWS-95 gives phase {state.phase!r})."
        )
    return float(state.rho), float(state.mu)


def _sharqawy_viscosity_factor(temperature_C: float, salinity_g_kg: float) -> float:
    """Ratio mu_sw / mu_w of Sharqawy et al. (2010), eq. (22) [-].

    ``1 + A S + B S^2`` with S in kg/kg and
    A = 1.541 + 1.998e-2 t - 9.52e-5 t^2, B = 7.974 - 7.561e-2 t + 4.724e-4 t^2 (t in °C);
    stated accuracy ±1.5 %.
    """
    t = temperature_C
    s = salinity_g_kg / 1000.0
    a = 1.541 + 1.998e-2 * t - 9.52e-5 * t**2
    b = 7.974 - 7.561e-2 * t + 4.724e-4 * t**2
    return 1.0 + a * s + b * s**2


@functools.lru_cache(maxsize=4096)
def _sea_rho_mu(temperature_C: float, salinity_g_kg: float) -> tuple[float, float]:
    """IAPWS-2008 seawater density [kg/m^3] and Sharqawy (2010) viscosity [Pa s] (cached)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        state = iapws.SeaWater(
            T=temperature_C + _KELVIN, P=ATMOSPHERIC_PRESSURE_MPA, S=salinity_g_kg / 1000.0
        )
    rho = float(state.rho)
    if not math.isfinite(rho) or rho <= 0.0:
        raise ValueError(
            f"The IAPWS-2008 seawater formulation has no liquid state at {temperature_C:g} °C "
            f"and S = {salinity_g_kg:g} g/kg."
        )
    _, mu_water = _fresh_rho_mu(temperature_C)
    return rho, mu_water * _sharqawy_viscosity_factor(temperature_C, salinity_g_kg)


def _resolve(water_type: str, salinity_g_kg: float | None) -> tuple[str, float]:
    """Normalised water type and the salinity [g/kg] to use with it."""
    kind = str(water_type).strip().lower()
    if kind not in WATER_TYPES:
        raise ValueError(
            f"Unknown water_type {water_type!r}: use one of {', '.join(map(repr, WATER_TYPES))}."
        )
    if kind == "fresh":
        if salinity_g_kg not in (None, 0, 0.0):
            raise ValueError(
                f"A salinity of {salinity_g_kg} g/kg was given for fresh water: "
                "use water_type='sea' for saline water."
            )
        return kind, 0.0
    salinity = STANDARD_SALINITY_G_KG if salinity_g_kg is None else float(salinity_g_kg)
    if not math.isfinite(salinity) or salinity < 0.0:
        raise ValueError(f"Salinity must be a finite value >= 0 g/kg, not {salinity_g_kg}.")
    return kind, salinity


def _check_ranges(temperature_C: np.ndarray, kind: str, salinity_g_kg: float) -> None:
    """Raise on non-finite temperatures; warn outside the validated ranges."""
    if not np.all(np.isfinite(temperature_C)):
        raise ValueError("Water temperature must be finite (got NaN or infinity).")
    lo, hi = TEMPERATURE_RANGE_C
    t_min, t_max = float(np.min(temperature_C)), float(np.max(temperature_C))
    if t_min < lo or t_max > hi:
        warnings.warn(
            f"Water temperature {t_min:g}..{t_max:g} °C lies outside {lo:g}-{hi:g} °C, the range "
            "of ITTC 7.5-02-01-03; the properties are extrapolated.",
            WaterPropertyWarning,
            stacklevel=3,
        )
    s_lo, s_hi = SALINITY_RANGE_G_KG
    if kind == "sea" and not s_lo <= salinity_g_kg <= s_hi:
        warnings.warn(
            f"Salinity {salinity_g_kg:g} g/kg lies outside {s_lo:g}-{s_hi:g} g/kg; the seawater "
            "properties are extrapolated.",
            WaterPropertyWarning,
            stacklevel=3,
        )


def _rho_mu(
    temperature_C: float | np.ndarray, kind: str, salinity_g_kg: float
) -> tuple[float | np.ndarray, float | np.ndarray]:
    """Density [kg/m^3] and dynamic viscosity [Pa s], scalar or elementwise."""

    def scalar(t: float) -> tuple[float, float]:
        t_key = round(float(t), 4)
        if kind == "fresh":
            return _fresh_rho_mu(t_key)
        return _sea_rho_mu(t_key, round(salinity_g_kg, 4))

    t = np.asarray(temperature_C, dtype=float)
    if t.ndim == 0:
        return scalar(float(t))
    rho, mu = np.vectorize(scalar, otypes=[float, float])(t)
    return rho, mu


def water_properties(
    temperature_C: float | np.ndarray,
    water_type: str = "fresh",
    salinity_g_kg: float | None = None,
) -> WaterProperties:
    """Density and viscosity of water at atmospheric pressure (ITTC 7.5-02-01-03, 2011).

    Fresh water uses IAPWS-95 for the density and the IAPWS 2008 viscosity formulation.
    Sea water uses the IAPWS-2008 seawater Gibbs function for the density and Sharqawy et al.
    (2010), eq. (22), ``mu_sw = mu_w (1 + A S + B S^2)`` for the viscosity. In both cases
    ``nu = mu / rho``.

    Parameters
    ----------
    temperature_C : float or array_like
        Water temperature [°C]
    water_type : str, default "fresh"
        ``"fresh"`` or ``"sea"``
    salinity_g_kg : float, optional
        Absolute salinity [g/kg], sea water only; default 35.165 g/kg (standard sea water).

    Returns
    -------
    WaterProperties
        ``rho`` [kg/m^3], ``nu`` [m^2/s], ``mu`` [Pa s]; arrays when ``temperature_C`` is one.

    Raises
    ------
    ValueError
        Unknown ``water_type``, a salinity given for fresh water, a negative salinity, a
        non-finite temperature, or a temperature at which water is not liquid.

    Warns
    -----
    WaterPropertyWarning
        Temperature outside 0-40 °C, or salinity outside 0-42 g/kg for sea water.

    Examples
    --------
    >>> round(water_properties(15.0).rho, 2)
    999.1
    """
    kind, salinity = _resolve(water_type, salinity_g_kg)
    t = np.asarray(temperature_C, dtype=float)
    _check_ranges(t, kind, salinity)
    rho, mu = _rho_mu(t, kind, salinity)
    temperature = float(t) if t.ndim == 0 else t.copy()
    return WaterProperties(
        rho=rho,
        nu=mu / rho,
        mu=mu,
        temperature_C=temperature,
        water_type=kind,
        salinity_g_kg=salinity,
    )


def density(
    temperature_C: float | np.ndarray,
    water_type: str = "fresh",
    salinity_g_kg: float | None = None,
) -> float | np.ndarray:
    """Water density at atmospheric pressure (ITTC 7.5-02-01-03; see :func:`water_properties`).

    Parameters
    ----------
    temperature_C : float or array_like
        Water temperature [°C]
    water_type : str, default "fresh"
        ``"fresh"`` or ``"sea"``
    salinity_g_kg : float, optional
        Absolute salinity [g/kg], sea water only; default 35.165 g/kg.

    Returns
    -------
    float or numpy.ndarray
        Density [kg/m^3]
    """
    return water_properties(temperature_C, water_type, salinity_g_kg).rho


def kinematic_viscosity(
    temperature_C: float | np.ndarray,
    water_type: str = "fresh",
    salinity_g_kg: float | None = None,
) -> float | np.ndarray:
    """Kinematic viscosity of water (ITTC 7.5-02-01-03; see :func:`water_properties`).

    Parameters
    ----------
    temperature_C : float or array_like
        Water temperature [°C]
    water_type : str, default "fresh"
        ``"fresh"`` or ``"sea"``
    salinity_g_kg : float, optional
        Absolute salinity [g/kg], sea water only; default 35.165 g/kg.

    Returns
    -------
    float or numpy.ndarray
        Kinematic viscosity [m^2/s]
    """
    return water_properties(temperature_C, water_type, salinity_g_kg).nu


def water_at(temperature_C: float, water_type: str, salinity_g_kg: float | None,
             pressure_Pa: float | None = None,
             relative_humidity_pct: float | None = None) -> tuple[float, float]:
    """(rho [kg/m^3], nu [m^2/s]) of the tank's or the prototype's medium.

    Water (``fresh``, ``sea``): ITTC 7.5-02-01-03 (:func:`water_properties`). Air
    (``air``): CIPM-2007 density and Sutherland viscosity
    (:func:`towtank.reference.air.air_properties`).

    Out-of-range warnings (WaterPropertyWarning) are silenced here: the protocol's unit checks
    already put a temperature or salinity outside the ITTC range of [water] and
    [prototype.water] into the day's warnings, and each run's temperature is checked when the
    day is processed.

    Parameters
    ----------
    temperature_C : float
        Temperature of the medium [°C]
    water_type : str
        ``"fresh"``, ``"sea"`` or ``"air"``
    salinity_g_kg : float or None
        Absolute salinity [g/kg], sea water only; None for standard sea water (35.165 g/kg)
    pressure_Pa : float, optional
        Absolute pressure of air [Pa]; default 101325 Pa
    relative_humidity_pct : float, optional
        Relative humidity of air [%]; default 50 %
    """
    if water_type == "air":
        a = air_properties(
            temperature_C,
            STANDARD_PRESSURE_PA if pressure_Pa is None else pressure_Pa,
            DEFAULT_RELATIVE_HUMIDITY_PCT if relative_humidity_pct is None
            else relative_humidity_pct)
        return float(a.rho), float(a.nu)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        w = water_properties(temperature_C, water_type, salinity_g_kg)
    return float(w.rho), float(w.nu)
