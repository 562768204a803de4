"""The International Standard Atmosphere (ISO 2533:1975, the ICAO standard atmosphere below 20 km): temperature,
pressure and density against altitude above mean sea level (geometric, as a scene's heights are: converted to the
standard's geopotential altitude with the Earth's radius 6,356,766 m), for a standard day or a day hotter or colder
by a constant offset.

Two layers are modelled: the troposphere (-2 km to 11 km, temperature falling 6.5 K per km from 288.15 K at sea
level) and the lower stratosphere (11 km to 20 km, isothermal at 216.65 K). A temperature offset ``dT`` [K] shifts
the temperature at every altitude and leaves the pressure at the standard day's (the aviation convention: the
altitude is a pressure altitude), so the density is ``p_std(h) / (R (T_std(h) + dT))``.

The air laws take the density of each world's air from here every step, at the mean altitude of that world's
particles (:func:`warpsim.physics.kernels.controls.update_air_density`), unless the scene fixes it
(``[air] density``). An object's own height (a few metres) changes the density by about 0.1 % per 10 m, so one
density per world is what each of its triangles would see to that accuracy.
"""

from __future__ import annotations

import math

import numpy as np

GRAVITY = 9.80665
"""[m/s^2] the standard gravity ISO 2533 takes (the same as :data:`warpsim.physics.config.GRAVITY`)."""
SEA_LEVEL_TEMPERATURE = 288.15
"""[K] standard temperature at mean sea level (15 °C)."""
SEA_LEVEL_PRESSURE = 101325.0
"""[Pa] standard pressure at mean sea level."""
GAS_CONSTANT = 287.05287
"""[J/(kg K)] specific gas constant of dry air (ISO 2533)."""
LAPSE_RATE = 0.0065
"""[K/m] temperature fall with altitude in the troposphere."""
TROPOPAUSE = 11000.0
"""[m] top of the troposphere."""
LOWEST, HIGHEST = -2000.0, 20000.0
"""[m] the (geometric) altitudes a scene may fly at: the two modelled layers (ISO 2533 tabulates from -2 km)."""
EARTH_RADIUS = 6356766.0
"""[m] the radius ISO 2533 converts geometric to geopotential altitude with: ``H = r z / (r + z)``."""
TEMPERATURE_OFFSETS = (-70.0, 50.0)
"""[K] the temperature offsets a scene may give (ISA-70 is colder than any day measured at the surface; ISA+50 hotter
than any)."""

_EXPONENT = GRAVITY / (GAS_CONSTANT * LAPSE_RATE)  # 5.2559
_T11 = SEA_LEVEL_TEMPERATURE - LAPSE_RATE * TROPOPAUSE  # 216.65 K
_P11 = SEA_LEVEL_PRESSURE * (_T11 / SEA_LEVEL_TEMPERATURE) ** _EXPONENT  # 22632 Pa
SEA_LEVEL_DENSITY = SEA_LEVEL_PRESSURE / (GAS_CONSTANT * SEA_LEVEL_TEMPERATURE)
"""[kg/m^3] standard density at mean sea level (1.225)."""


def isa(altitude, temperature_offset: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Temperature [K], pressure [Pa] and density [kg/m^3] at ``altitude`` [m above mean sea level, geometric] (a
    number or an array, clamped to the modelled -2 km to 20 km) on a day ``temperature_offset`` [K] off the
    standard."""
    z = np.clip(np.asarray(altitude, dtype=np.float64), LOWEST, HIGHEST)
    h = EARTH_RADIUS * z / (EARTH_RADIUS + z)  # geopotential
    t_std = np.where(h < TROPOPAUSE, SEA_LEVEL_TEMPERATURE - LAPSE_RATE * h, _T11)
    p = np.where(
        h < TROPOPAUSE,
        SEA_LEVEL_PRESSURE * (t_std / SEA_LEVEL_TEMPERATURE) ** _EXPONENT,
        _P11 * np.exp(-GRAVITY * (h - TROPOPAUSE) / (GAS_CONSTANT * _T11)),
    )
    t = t_std + temperature_offset
    return t, p, p / (GAS_CONSTANT * t)


def check_altitude(altitude: float, what: str) -> None:
    """Raise ``ValueError`` (one line, naming ``what``) unless ``altitude`` [m] lies in the modelled atmosphere."""
    if not (math.isfinite(altitude) and LOWEST <= altitude <= HIGHEST):
        raise ValueError(
            f"{what} is at {altitude:.6g} m above sea level, outside the standard atmosphere's {LOWEST:g} to "
            f"{HIGHEST:g} m; lower it, or fix the density with [air] density"
        )


def air_density(air, height: float) -> float:
    """The density [kg/m^3] of an :class:`~warpsim.physics.config.AirConfig`'s air at ``height`` [m] above the
    scene's z = 0: its fixed ``density``, else the standard atmosphere's there (as :func:`scene_density`)."""
    return scene_density(
        {"density": air.density, "elevation": air.elevation, "temperature_offset": air.temperature_offset}, height
    )


def scene_density(air: dict, height: float) -> float:
    """The density [kg/m^3] of a scene's air (its ``[air]`` section, a dict with ``density``, ``elevation`` and
    ``temperature_offset``) at ``height`` [m] above the scene's z = 0: the fixed density it gives, else the standard
    atmosphere's there."""
    if float(air.get("density", 0.0)) > 0.0:
        return float(air["density"])
    altitude = height + float(air.get("elevation", 0.0))
    return float(isa(altitude, float(air.get("temperature_offset", 0.0)))[2])
