"""Air density for the cycling model: the textbook exponential atmosphere (:func:`air_density`), moist air from a
weather reading by the ideal gas law (:func:`air_density_weather`, with Buck 1981's saturation vapour pressure), and
the International Standard Atmosphere's temperature and pressure (:func:`isa_temperature_c`,
:func:`isa_pressure_hpa`; U.S. Standard Atmosphere 1976).

All quantities are SI but for the weather's own units (°C, hPa); every function accepts numpy arrays and broadcasts
them.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kernels import _checks
from kernels.cycling._arrays import _broadcast, _finite

RHO_SEA_LEVEL = 1.225
"""Air density at sea level (kg/m³)."""
SCALE_HEIGHT_M = 8500.0
"""Scale height of the textbook exponential atmosphere (m)."""

AIR_DENSITY_ALTITUDE_M = (-10_000.0, 30_000.0)
"""Altitudes :func:`air_density` takes (m): from 10 km below sea level (the deepest a course may reach,
:data:`kernels.course.MIN_ELEVATION_M`; 3.97 kg/m³ there) to 30 km, where :data:`kernels.cycling.MODEL_DOMAIN` stops
(the exponential atmosphere is no air above). Beyond them it gave 157 573 kg/m³ at −100 km and inf at −10³⁰⁰ m."""


def air_density(altitude_m: ArrayLike) -> NDArray[np.float64]:
    """Air density of the textbook exponential atmosphere, 1.225·exp(−h/8500).

    Args:
        altitude_m: altitude above sea level (m, −10 000 to 30 000: :data:`AIR_DENSITY_ALTITUDE_M`), any shape.

    Returns:
        Density (kg/m³), same shape.

    Raises:
        ValueError: an altitude is not a finite number or outside its range; the message names ``altitude_m``.
    """
    h = _finite("altitude_m", altitude_m)
    low, high = AIR_DENSITY_ALTITUDE_M
    if np.any((h < low) | (h > high)):
        raise ValueError(f"altitude_m must be in [{low:g}, {high:g}] m, got {_checks.shown(altitude_m)}")
    return RHO_SEA_LEVEL * np.exp(-h / SCALE_HEIGHT_M)


# --------------------------------------------------------------------------------------------- weather air
# Real air, for the course mode: the ideal gas law for moist air, and the standard atmosphere.
R_DRY_AIR = 287.058
"""Specific gas constant of dry air (J/(kg·K)), R / 0.0289652 kg/mol (U.S. Standard Atmosphere 1976)."""
R_WATER_VAPOUR = 461.495
"""Specific gas constant of water vapour (J/(kg·K)), R / 0.018016 kg/mol."""
ISA_SEA_LEVEL_PRESSURE_HPA = 1013.25
"""Standard sea-level pressure (hPa)."""
ISA_SEA_LEVEL_TEMPERATURE_C = 15.0
"""Standard sea-level temperature (°C)."""
ISA_LAPSE_RATE_K_PER_M = 0.0065
"""Temperature lapse rate of the standard troposphere (K/m)."""
_ISA_TROPOPAUSE_M = 11_000.0
ISA_ALTITUDE_M = (-5_000.0, 20_000.0)
"""Geometric altitudes (m) the standard atmosphere functions take: from −5 km, where the U.S. Standard Atmosphere
1976 tables begin, to 20 km, the top of the isothermal layer above the tropopause that they model."""
_ISA_G0 = 9.80665
_ISA_MOLAR_MASS = 0.0289644  # kg/mol, U.S. Standard Atmosphere 1976
_ISA_R = 8.31432  # J/(mol·K), the constant the 1976 standard uses
_ISA_EXPONENT = _ISA_G0 * _ISA_MOLAR_MASS / (_ISA_R * ISA_LAPSE_RATE_K_PER_M)  # 5.25588
_KELVIN = 273.15


def saturation_vapour_pressure_hpa(temperature_c: ArrayLike) -> NDArray[np.float64]:
    """Saturation vapour pressure of water over liquid water, Buck (1981).

    e_s = 6.1121·exp(17.502·T / (240.97 + T)) hPa, T in °C: Buck, A. L. (1981), "New equations for computing
    vapor pressure and enhancement factor", J. Appl. Meteorol. 20, 1527–1532, eq. 8 (e_w, enhancement factor
    left out; within 0.05 % of the Wexler/Goff–Gratch values from −20 to +50 °C, as Buck's table 2 reports).

    Args:
        temperature_c: air temperature (°C, −60 to 60), any shape.

    Returns:
        Pressure (hPa), same shape.

    Raises:
        ValueError: a temperature is not finite or outside −60…60 °C.
    """
    t = _finite("temperature_c", temperature_c)
    if np.any((t < -60.0) | (t > 60.0)):
        raise ValueError(f"temperature_c must be in [-60, 60] °C, got {_checks.shown(temperature_c)}")
    return 6.1121 * np.exp(17.502 * t / (240.97 + t))


def air_density_weather(
    temperature_c: ArrayLike, pressure_hpa: ArrayLike, relative_humidity: ArrayLike = 0.0
) -> NDArray[np.float64]:
    """Density of moist air from a weather reading, by the ideal gas law for dry air plus water vapour.

    ρ = (p − e)/(R_d·T) + e/(R_v·T), e = RH·e_s(T), with e_s from :func:`saturation_vapour_pressure_hpa`
    (Buck 1981). Humid air is lighter than dry air at the same pressure and temperature (water's molar mass is
    18 g/mol against air's 29). The non-ideality of air (compressibility Z ≈ 0.9996 near sea level, CIPM-2007,
    Picard et al. 2008, Metrologia 45:149) is left out: 0.04 %.

    Args:
        temperature_c: air temperature (°C, −60 to 60).
        pressure_hpa: station (not sea-level-reduced) pressure (hPa, 10 to 1100).
        relative_humidity: relative humidity as a fraction in [0, 1] (0.5 is 50 %).

    Returns:
        Density (kg/m³) with the broadcast shape of the inputs.

    Raises:
        ValueError: an argument is not finite or out of its range; the message names it.
    """
    e_s = saturation_vapour_pressure_hpa(temperature_c)
    t_k = _finite("temperature_c", temperature_c) + _KELVIN
    p = _finite("pressure_hpa", pressure_hpa)
    if np.any((p < 10.0) | (p > 1100.0)):
        raise ValueError(f"pressure_hpa must be in [10, 1100] hPa, got {_checks.shown(pressure_hpa)}")
    rh = _finite("relative_humidity", relative_humidity)
    if np.any((rh < 0.0) | (rh > 1.0)):
        raise ValueError(f"relative_humidity must be a fraction in [0, 1], got {_checks.shown(relative_humidity)}")
    _broadcast(temperature_c=t_k, pressure_hpa=p, relative_humidity=rh)
    e = rh * e_s
    if np.any(e >= p):
        raise ValueError("relative_humidity: the vapour pressure would reach the total pressure")
    return 100.0 * ((p - e) / (R_DRY_AIR * t_k) + e / (R_WATER_VAPOUR * t_k))


_EARTH_RADIUS_ISA_M = 6_356_766.0  # r₀ of the geopotential conversion, U.S. Standard Atmosphere 1976


def _isa_altitude(altitude_m: ArrayLike) -> NDArray[np.float64]:
    """Geopotential altitude H = r₀·h/(r₀ + h) of the geometric altitude h (what a map or a GPS gives)."""
    h = _finite("altitude_m", altitude_m)
    low, high = ISA_ALTITUDE_M
    if np.any((h < low) | (h > high)):
        raise ValueError(f"altitude_m must be in [{low:g}, {high:g}] m, got {_checks.shown(altitude_m)}")
    return _EARTH_RADIUS_ISA_M * h / (_EARTH_RADIUS_ISA_M + h)


def isa_temperature_c(altitude_m: ArrayLike) -> NDArray[np.float64]:
    """Temperature of the International Standard Atmosphere (°C): 15 − 6.5 K/km up to 11 km, −56.5 °C above.

    Args:
        altitude_m: geometric altitude above mean sea level (m, −5000 to 20 000: :data:`ISA_ALTITUDE_M`), any shape;
            converted to geopotential altitude H = r₀·h/(r₀ + h), r₀ = 6 356 766 m, as the standard's tables are.

    Returns:
        Temperature (°C), same shape.
    """
    h = _isa_altitude(altitude_m)
    return ISA_SEA_LEVEL_TEMPERATURE_C - ISA_LAPSE_RATE_K_PER_M * np.minimum(h, _ISA_TROPOPAUSE_M)


def isa_pressure_hpa(altitude_m: ArrayLike) -> NDArray[np.float64]:
    """Pressure of the International Standard Atmosphere (ISO 2533:1975; U.S. Standard Atmosphere 1976).

    Troposphere (H ≤ 11 km): p = 1013.25·(1 − L·H/T₀)^(g₀M/(R·L)) hPa, L = 6.5 K/km, T₀ = 288.15 K, exponent
    5.25588; above, the isothermal layer at 216.65 K: p = p₁₁·exp(−g₀M·(H − 11 000)/(R·216.65)).

    Args:
        altitude_m: geometric altitude above mean sea level (m, −5000 to 20 000: :data:`ISA_ALTITUDE_M`), any shape;
            converted to geopotential altitude H = r₀·h/(r₀ + h), r₀ = 6 356 766 m, as the standard's tables are.

    Returns:
        Pressure (hPa), same shape.

    Raises:
        ValueError: an altitude is not finite or outside −5000…20 000 m.
    """
    h = _isa_altitude(altitude_m)
    t0 = ISA_SEA_LEVEL_TEMPERATURE_C + _KELVIN
    low = np.minimum(h, _ISA_TROPOPAUSE_M)
    p = ISA_SEA_LEVEL_PRESSURE_HPA * (1.0 - ISA_LAPSE_RATE_K_PER_M * low / t0) ** _ISA_EXPONENT
    t_tropopause = t0 - ISA_LAPSE_RATE_K_PER_M * _ISA_TROPOPAUSE_M
    above = np.maximum(h - _ISA_TROPOPAUSE_M, 0.0)
    return p * np.exp(-_ISA_G0 * _ISA_MOLAR_MASS * above / (_ISA_R * t_tropopause))
