"""Warp kernels of warpsim, one module per concern.

Each module keeps its kernels private and exposes a small host function that launches them;
shared math lives in ``@wp.func`` helpers. Launch parameters are grouped as model arrays, inputs,
scalars, then outputs (``_out``).
"""

from . import (
    aero,
    bending,
    canopy,
    collision,
    constraints,
    controls,
    frame,
    influence,
    momentum,
    springs,
    verlet,
    vortex,
    wake,
)

MODULES = (aero, bending, canopy, collision, constraints, controls, influence, momentum, springs, verlet, vortex, wake)
"""The solvers' kernel modules (``frame`` is the runner's)."""

__all__ = [
    "MODULES",
    "aero",
    "bending",
    "canopy",
    "collision",
    "constraints",
    "controls",
    "frame",
    "influence",
    "momentum",
    "springs",
    "verlet",
    "vortex",
    "wake",
]
