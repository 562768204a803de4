"""What every object's own figures are read from (:class:`FigureView`) and what measures them (:data:`Measure`).
Each object's figures (what a pilot or an observer reads off it besides its altitude, airspeed and sink: their
units, meanings and measures, its heads-up text) live in its own module; :mod:`.registry` hands them to
:class:`warpsim.run.figures.Figures`, so that a new object's figures are added there and in its ``ObjectSpec``,
not in the diagnostics."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


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
