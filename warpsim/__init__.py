"""warpsim: real-time simulation of flying fabric objects with NVIDIA Warp.

Verlet particles, Jacobi-averaged distance constraints, per-triangle air force and a heightfield
terrain, after Beaudry, Egli & Patenaude, "Simulation de deltaplanes et de cerf-volants en temps
réel" (2005).
"""

from __future__ import annotations

import importlib

from ._version import __version__

# name -> module: imported on first use, so that the command line starts (and answers --help or Ctrl-C) without
# loading Warp first
_EXPORTS = {
    "AIR_DENSITY": "physics.config",
    "GRAVITY": "physics.config",
    "AeroModel": "physics.kernels.aero",
    "BlowUpError": "run.simulation",
    "AirConfig": "physics.config",
    "CollisionMode": "physics.kernels.collision",
    "Control": "physics.model",
    "DescriptorError": "scene.descriptor",
    "FlagConfig": "objects.flag",
    "Flight": "run.simulation",
    "Frame": "run.simulation",
    "GroundConfig": "physics.config",
    "HangGliderConfig": "objects.hang_glider",
    "Heightfield": "physics.terrain",
    "KiteConfig": "objects.kite",
    "MeshConfig": "objects.mesh",
    "Model": "physics.model",
    "ModelBuilder": "physics.builder",
    "NullBackend": "viewer",
    "ObjectRecord": "physics.model",
    "ParachuteConfig": "objects.parachute",
    "Recording": "io.recording",
    "RunSummary": "run.simulation",
    "Scene": "scene.scene",
    "Simulation": "run.simulation",
    "SolverConfig": "physics.config",
    "SolverEuler": "physics.solver",
    "SolverVerlet": "physics.solver",
    "State": "physics.model",
    "Viewer": "viewer",
    "WindConfig": "physics.config",
    "build_flag": "objects.flag",
    "build_hang_glider": "objects.hang_glider",
    "build_kite": "objects.kite",
    "build_parachute": "objects.parachute",
    "defaults": "scene.descriptor",
    "load_scene": "scene.descriptor",
    "make_solver": "physics.solver",
    "merge": "scene.descriptor",
    "sweep": "sweeps",
    "to_toml": "scene.descriptor",
}

__all__ = [*sorted(_EXPORTS), "__version__"]


def __getattr__(name: str):
    if name in _EXPORTS:
        value = getattr(importlib.import_module(f".{_EXPORTS[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
