"""Density and viscosity of moist air, for wind tunnels and other rigs in air.

- Density: the CIPM-2007 equation for the density of moist air, A. Picard, R. S. Davis,
  M. Gläser and K. Fujii (2008), *Revised formula for the density of moist air (CIPM-2007)*,
  Metrologia 45, 149-155, eqs. (A1.1)-(A1.5), with the mole fraction of carbon dioxide 0.0004
  (the formula's reference value). It is the ideal-gas law for a mixture of dry air and water
  vapour, ``rho = p M_a / (Z R T) [1 - x_v (1 - M_v / M_a)]``, with the compressibility factor
  ``Z`` and the enhancement factor ``f`` of the vapour; its stated range is 600-1100 hPa and
  15-27 °C (outside it the equation is extrapolated; the protocol warns of a pressure outside
  60-110 kPa). Check values: 20 °C, 101325 Pa and 50 % relative
  humidity give 1.1993 kg/m³ (tabulated 1.1992 kg/m³); dry air at 15 °C and 101325 Pa gives
  1.2255 kg/m³ (the ISO 2533 standard atmosphere: 1.2250 kg/m³).
- Dynamic viscosity: Sutherland's law, ``mu = mu_0 (T/T_0)^(3/2) (T_0 + S)/(T + S)``, with
  ``mu_0 = 1.716e-5 Pa s``, ``T_0 = 273.15 K``, ``S = 110.4 K`` (F. M. White, *Viscous Fluid
  Flow*, 3rd ed., McGraw-Hill 2006, eq. (1-36) and Table 1-2: within 2 % over 170-1900 K). It is
  the viscosity of dry air; water vapour changes it by less than 0.5 % at room temperature
  (P. T. Tsilingiris 2008, Energy Conversion and Management 49, 1098-1110), which is neglected.
  Check value: 20 °C gives 1.813e-5 Pa s.
- Kinematic viscosity ``nu = mu / rho``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Standard atmospheric pressure [Pa], the default of [water] pressure_Pa for air.
STANDARD_PRESSURE_PA = 101325.0

#: Default relative humidity of air [%] when the protocol gives none.
DEFAULT_RELATIVE_HUMIDITY_PCT = 50.0

#: Mole fraction of carbon dioxide in the air [mol/mol] (CIPM-2007's reference value).
X_CO2 = 0.0004

#: Range of the CIPM-2007 formula: temperature [°C] and pressure [Pa] (Picard et al. 2008).
CIPM_TEMPERATURE_RANGE_C = (15.0, 27.0)
CIPM_PRESSURE_RANGE_PA = (60.0e3, 110.0e3)

#: Air temperatures accepted at all [°C]: outside, a value is a unit slip (kelvin, °F).
AIR_TEMPERATURE_RANGE_C = (-60.0, 150.0)

#: Pressures accepted at all [Pa]: below, the value is in hPa, kPa or bar; above, a unit slip.
AIR_PRESSURE_RANGE_PA = (10.0e3, 1.0e7)

_KELVIN = 273.15
_R = 8.314472  # molar gas constant [J/(mol K)] (CIPM-2007)
_M_V = 18.01528e-3  # molar mass of water [kg/mol]
# saturation vapour pressure, CIPM-2007 eq. (A1.2) [K^-2, K^-1, -, K]
_A, _B, _C, _D = 1.2378847e-5, -1.9121316e-2, 33.93711047, -6.3431645e3
# enhancement factor, eq. (A1.3) [-, Pa^-1, K^-2]
_ALPHA, _BETA, _GAMMA = 1.00062, 3.14e-8, 5.6e-7
# compressibility factor, eq. (A1.4)
_A0, _A1, _A2 = 1.58123e-6, -2.9331e-8, 1.1043e-10  # [K/Pa, 1/Pa, 1/(K Pa)]
_B0, _B1 = 5.707e-6, -2.051e-8  # [K/Pa, 1/Pa]
_C0, _C1 = 1.9898e-4, -2.376e-6  # [K/Pa, 1/Pa]
_DD, _E = 1.83e-11, -0.765e-8  # [K^2/Pa^2, K^2/Pa^2]

#: Sutherland's law for air (White 2006, Table 1-2): mu_0 [Pa s], T_0 [K], S [K].
SUTHERLAND_MU0 = 1.716e-5
SUTHERLAND_T0 = 273.15
SUTHERLAND_S = 110.4


@dataclass(frozen=True)
class AirProperties:
    """Properties of moist air at one state (or an array of temperatures).

    Attributes
    ----------
    rho : float or numpy.ndarray
        Density [kg/m^3]
    nu : float or numpy.ndarray
        Kinematic viscosity [m^2/s]
    mu : float or numpy.ndarray
        Dynamic viscosity [Pa s]
    temperature_C : float or numpy.ndarray
        Air temperature [°C]
    pressure_Pa : float
        Absolute pressure [Pa]
    relative_humidity_pct : float
        Relative humidity [%]
    """

    rho: float | np.ndarray
    nu: float | np.ndarray
    mu: float | np.ndarray
    temperature_C: float | np.ndarray
    pressure_Pa: float
    relative_humidity_pct: float


def _check(temperature_C: np.ndarray, pressure_Pa: float, relative_humidity_pct: float) -> None:
    if not np.all(np.isfinite(temperature_C)):
        raise ValueError("Air temperature must be finite (got NaN or infinity).")
    if np.any(temperature_C <= -_KELVIN):
        raise ValueError("Air temperature must lie above absolute zero (-273.15 °C).")
    if not math.isfinite(pressure_Pa) or pressure_Pa <= 0.0:
        raise ValueError(f"Air pressure must be a finite value > 0 Pa, not {pressure_Pa}.")
    if not math.isfinite(relative_humidity_pct) or not 0.0 <= relative_humidity_pct <= 100.0:
        raise ValueError(
            f"Relative humidity must lie in 0-100 %, not {relative_humidity_pct}.")


def saturation_vapour_pressure(temperature_C: float | np.ndarray) -> float | np.ndarray:
    """Saturation vapour pressure of water over a plane liquid surface (CIPM-2007, eq. A1.2).

    ``p_sv = exp(A T^2 + B T + C + D/T)`` Pa, T in kelvin (Picard et al. 2008).

    Parameters
    ----------
    temperature_C : float or array_like
        Temperature [°C]

    Returns
    -------
    float or numpy.ndarray
        Saturation vapour pressure [Pa]
    """
    t = np.asarray(temperature_C, dtype=float) + _KELVIN
    out = np.exp(_A * t**2 + _B * t + _C + _D / t)
    return float(out) if out.ndim == 0 else out


def air_density(
    temperature_C: float | np.ndarray,
    pressure_Pa: float = STANDARD_PRESSURE_PA,
    relative_humidity_pct: float = DEFAULT_RELATIVE_HUMIDITY_PCT,
) -> float | np.ndarray:
    """Density of moist air by the CIPM-2007 equation (Picard et al. 2008, Metrologia 45, 149).

    ``rho = p M_a / (Z R T) [1 - x_v (1 - M_v/M_a)]`` (eq. A1.1), with
    ``x_v = h f(p, t) p_sv(T) / p`` the mole fraction of water vapour (h the relative humidity
    as a fraction, f the enhancement factor, eq. A1.3, p_sv eq. A1.2), ``Z`` the
    compressibility factor (eq. A1.4), ``M_a`` the molar mass of dry air with 0.0004 mol/mol
    of CO2 (eq. A1.5), ``M_v`` that of water and ``R`` the molar gas constant.

    Parameters
    ----------
    temperature_C : float or array_like
        Air temperature [°C]
    pressure_Pa : float, default 101325
        Absolute pressure [Pa]
    relative_humidity_pct : float, default 50
        Relative humidity [%]

    Returns
    -------
    float or numpy.ndarray
        Density [kg/m^3]

    Raises
    ------
    ValueError
        A non-finite temperature or one below absolute zero, a pressure not > 0, a relative
        humidity outside 0-100 %.

    Examples
    --------
    >>> round(air_density(20.0, 101325.0, 50.0), 4)
    1.1993
    """
    t = np.asarray(temperature_C, dtype=float)
    p = float(pressure_Pa)
    _check(t, p, float(relative_humidity_pct))
    big_t = t + _KELVIN
    h = float(relative_humidity_pct) / 100.0
    f = _ALPHA + _BETA * p + _GAMMA * t**2
    x_v = h * f * saturation_vapour_pressure(t) / p
    z = (1.0 - p / big_t * (_A0 + _A1 * t + _A2 * t**2 + (_B0 + _B1 * t) * x_v
                            + (_C0 + _C1 * t) * x_v**2)
         + (p / big_t) ** 2 * (_DD + _E * x_v**2))
    m_a = (28.96546 + 12.011 * (X_CO2 - 0.0004)) * 1e-3
    rho = p * m_a / (z * _R * big_t) * (1.0 - x_v * (1.0 - _M_V / m_a))
    return float(rho) if np.ndim(rho) == 0 else rho


def air_viscosity(temperature_C: float | np.ndarray) -> float | np.ndarray:
    """Dynamic viscosity of air by Sutherland's law (White 2006, *Viscous Fluid Flow*, eq. 1-36).

    ``mu = mu_0 (T/T_0)^(3/2) (T_0 + S)/(T + S)``, mu_0 = 1.716e-5 Pa s, T_0 = 273.15 K,
    S = 110.4 K (White's Table 1-2).

    Parameters
    ----------
    temperature_C : float or array_like
        Air temperature [°C]

    Returns
    -------
    float or numpy.ndarray
        Dynamic viscosity [Pa s]

    Examples
    --------
    >>> f"{air_viscosity(20.0):.4g}"
    '1.813e-05'
    """
    t = np.asarray(temperature_C, dtype=float) + _KELVIN
    mu = (SUTHERLAND_MU0 * (t / SUTHERLAND_T0) ** 1.5
          * (SUTHERLAND_T0 + SUTHERLAND_S) / (t + SUTHERLAND_S))
    return float(mu) if mu.ndim == 0 else mu


def air_properties(
    temperature_C: float | np.ndarray,
    pressure_Pa: float = STANDARD_PRESSURE_PA,
    relative_humidity_pct: float = DEFAULT_RELATIVE_HUMIDITY_PCT,
) -> AirProperties:
    """Density (CIPM-2007), viscosity (Sutherland) and ``nu = mu / rho`` of moist air.

    Parameters
    ----------
    temperature_C : float or array_like
        Air temperature [°C]
    pressure_Pa : float, default 101325
        Absolute pressure [Pa]
    relative_humidity_pct : float, default 50
        Relative humidity [%]

    Returns
    -------
    AirProperties
        ``rho`` [kg/m^3], ``nu`` [m^2/s], ``mu`` [Pa s].

    Raises
    ------
    ValueError
        As :func:`air_density`.
    """
    rho = air_density(temperature_C, pressure_Pa, relative_humidity_pct)
    mu = air_viscosity(temperature_C)
    t = np.asarray(temperature_C, dtype=float)
    return AirProperties(
        rho=rho, nu=mu / rho, mu=mu,
        temperature_C=float(t) if t.ndim == 0 else t.copy(),
        pressure_Pa=float(pressure_Pa), relative_humidity_pct=float(relative_humidity_pct),
    )
