"""Each object kind's own figures (what a pilot or an observer reads off it besides its altitude, airspeed and sink):
their units and meanings, and how they are measured from a frame. :mod:`.registry` hands them to
:class:`warpsim.run.figures.Figures`, so that a new object's figures are added here and in its ``ObjectSpec``,
not in the diagnostics."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..physics.config import GRAVITY
from ..physics.model import Model, ObjectRecord
from .hang_glider import bank
from .kite import line_elevation
from .parachute import projected_radius


@dataclass(frozen=True)
class FigureView:
    """What an object's figures are read from in one frame.

    Attributes:
        positions: host ``[P, 3]`` particle positions of the frame [m].
        velocity: ``[3]`` velocity of the object's mass centre [m/s].
        wind: ``[3]`` its world's wind [m/s].
        tri_force: host ``[T, 3]`` air force per triangle vertex [N] (each vertex's third), or None when the
            caller has none (a figure that needs it is then NaN).
    """

    positions: np.ndarray
    velocity: np.ndarray
    wind: np.ndarray
    tri_force: np.ndarray | None


Measure = Callable[[FigureView], dict[str, float]]
"""One object's figures of a frame, by name, as floats in their units."""


GLIDER_FIGURES = {
    "glide": (
        "-",
        "glide ratio: horizontal airspeed / sink of the mass centre (NaN unless it sinks faster than 0.05 m/s)",
    ),
    "bank": ("deg", "bank of the sail, tip to tip against the horizontal, + = right tip lower"),
}


def glider_figures(model: Model, record: ObjectRecord) -> Measure:
    """The hang glider's :data:`GLIDER_FIGURES` of a frame."""

    def measure(view: FigureView) -> dict[str, float]:
        sink = float(-view.velocity[2])
        horizontal = float(np.linalg.norm((view.velocity - view.wind)[:2]))
        return {"glide": horizontal / sink if sink > 0.05 else float("nan"), "bank": bank(record, view.positions)}

    return measure


KITE_FIGURES = {
    "line_angle": ("deg", "elevation of the line above the horizontal, from the anchor to the tow point"),
    "line_pull": ("N", "|air force on the kite + its weight|, the steady line tension"),
}


def kite_figures(model: Model, record: ObjectRecord) -> Measure:
    """The kite's :data:`KITE_FIGURES` of a frame; its triangles and their mass are found once, here."""
    triangles = np.concatenate([np.asarray(t) for t in record.tri_parts.values()]).astype(np.int64)
    mass = float(model.particle_free_mass[np.unique(model.tri_indices_np[triangles])].sum())

    def measure(view: FigureView) -> dict[str, float]:
        values = {"line_angle": line_elevation(record, view.positions), "line_pull": math.nan}
        if view.tri_force is not None:
            air = 3.0 * view.tri_force[triangles].sum(axis=0)  # tri_force is each vertex's third
            values["line_pull"] = float(np.linalg.norm(air - np.array([0.0, 0.0, GRAVITY * mass])))
        return values

    return measure


PARACHUTE_FIGURES = {"radius": ("m", "mean horizontal distance of the canopy's rim from its centre")}


def parachute_figures(model: Model, record: ObjectRecord) -> Measure:
    """The parachute's :data:`PARACHUTE_FIGURES` of a frame."""

    def measure(view: FigureView) -> dict[str, float]:
        return {"radius": projected_radius(record, view.positions)}

    return measure
