"""ISA atmosphere from the maintained ``ambiance`` library (ISO 2533, geometric altitude)."""

from __future__ import annotations

from dataclasses import dataclass

from ambiance import Atmosphere


@dataclass(frozen=True)
class Air:
    """Air state at one altitude. altitude [m] (geometric), density [kg/m^3],
    speed_of_sound [m/s], gravity [m/s^2]."""

    altitude: float
    density: float
    speed_of_sound: float
    gravity: float


def isa(altitude_m: float) -> Air:
    """ISA air at geometric altitude ``altitude_m`` [m] (valid -5 km .. 81 km)."""
    a = Atmosphere(float(altitude_m))
    return Air(float(altitude_m), float(a.density[0]), float(a.speed_of_sound[0]), float(a.grav_accel[0]))
