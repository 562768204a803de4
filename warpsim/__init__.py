"""warpsim: real-time simulation of flying fabric objects with NVIDIA Warp.

Verlet particles, Jacobi-averaged distance constraints, per-triangle air force and a heightfield
terrain, after Beaudry, Egli & Patenaude, "Simulation de deltaplanes et de cerf-volants en temps
réel" (2005).
"""

from .builder import ModelBuilder
from .kernels.aero import AeroModel
from .kernels.collision import CollisionMode
from .model import AIR_DENSITY, GRAVITY, Control, Model, ObjectRecord, State
from .solver import AirSettings, GroundSettings, SolverEuler, SolverVerlet
from .terrain import Heightfield

__version__ = "0.1.0"

__all__ = [
    "AIR_DENSITY",
    "GRAVITY",
    "AeroModel",
    "AirSettings",
    "CollisionMode",
    "Control",
    "GroundSettings",
    "Heightfield",
    "Model",
    "ModelBuilder",
    "ObjectRecord",
    "SolverEuler",
    "SolverVerlet",
    "State",
    "__version__",
]
