"""thinburn: physically based burning of thin shells (Liu et al. 2009, and beyond).

Units are SI with the scene unit = 1 m; world up is +z and gravity acts along -z.
"""
from __future__ import annotations

from ._threads import get_threads, hardware_threads, max_threads, set_threads
from .fire_front import FRONT_METHODS, arrival_times
from .materials import MATERIALS, Material
from .simulation import Simulation
from .surface_front import SurfaceCells, SurfaceFront, surface_arrival_times

__all__ = [
    "FRONT_METHODS", "MATERIALS", "Material", "Simulation", "arrival_times",
    "get_threads", "hardware_threads", "max_threads", "set_threads",
    "SurfaceCells", "SurfaceFront", "surface_arrival_times",
]
__version__ = "0.1.0"
