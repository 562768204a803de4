"""Each object kind's own figures (what a pilot or an observer reads off it besides its altitude, airspeed and sink):
their units and meanings, and how they are measured from a frame. :mod:`.registry` hands them to
:class:`warpsim.run.figures.Figures`, so that a new object's figures are added here and in its ``ObjectSpec``,
not in the diagnostics."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..physics.atmosphere import air_density
from ..physics.config import GRAVITY
from ..physics.model import Model, ObjectRecord
from .hang_glider import bank
from .kite import anchor_pull, line_elevation
from .parachute import projected_radius, swing_angle


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
    "line_pull": ("N", "the line's pull at the anchor, from the rope's sag (objects.kite.anchor_pull)"),
}


def kite_figures(model: Model, record: ObjectRecord) -> Measure:
    """The kite's :data:`KITE_FIGURES` of a frame, measured from the particles (the pull from the rope's sag:
    NaN while the rope does not sag, :func:`~warpsim.objects.kite.anchor_pull`)."""

    def measure(view: FigureView) -> dict[str, float]:
        return {
            "line_angle": line_elevation(record, view.positions),
            "line_pull": anchor_pull(record, view.positions, model.particle_free_mass, GRAVITY),
        }

    return measure


FLAG_FIGURES = {
    "flap": (
        "m",
        "sideways offset of the flag's top trailing corner from the plane of its pole and the wind; its window "
        "frequency is the flapping frequency (the mesh's without a bending stiffness its mesh resolves, the elastic "
        "cloth's with one: the run's note says which, flag_caveat)",
    ),
}


def flag_figures(model: Model, record: ObjectRecord) -> Measure:
    """The flag's :data:`FLAG_FIGURES` of a frame. The flag is a grid whose rows run from the pole outwards, the
    top row last (:func:`~warpsim.objects.flag.build_flag`): its last particle is the top trailing corner, the
    pole's last the top of the pole."""
    corner, pole_top = int(record.parts["cloth"][-1]), int(record.parts["pole"][-1])

    def measure(view: FigureView) -> dict[str, float]:
        across = np.array([-view.wind[1], view.wind[0], 0.0], dtype=np.float64)  # horizontal, left of the wind
        speed = np.linalg.norm(across)
        across = across / speed if speed > 1e-6 else np.array([0.0, 1.0, 0.0])  # no wind: across the flag as built
        return {"flap": float((view.positions[corner] - view.positions[pole_top]) @ across)}

    return measure


PARACHUTE_FIGURES = {
    "radius": ("m", "mean horizontal distance of the canopy's rim from its centre"),
    "swing": ("deg", "angle of the line from the person to the canopy's centre from the vertical"),
}


def parachute_figures(model: Model, record: ObjectRecord) -> Measure:
    """The parachute's :data:`PARACHUTE_FIGURES` of a frame."""

    def measure(view: FigureView) -> dict[str, float]:
        return {"radius": projected_radius(record, view.positions), "swing": swing_angle(record, view.positions)}

    return measure


def glider_hud(f: dict[str, float]) -> str:
    """The hang glider's heads-up text: sink rate, glide ratio and bank with its side."""
    glide = f"{f['glide']:4.1f}" if np.isfinite(f["glide"]) else " -- "
    side = "right" if f["bank"] > 0.5 else "left" if f["bank"] < -0.5 else ""
    return f"sink {f['sink']:5.2f} m/s  glide {glide}  bank {abs(f['bank']):3.0f} deg {side}"


def kite_hud(f: dict[str, float]) -> str:
    """The kite's heads-up text: the line's elevation and its pull at the anchor."""
    return f"line {f['line_angle']:4.1f} deg  pull ~{f['line_pull']:5.1f} N"


def flag_hud(f: dict[str, float]) -> str:
    """The flag's heads-up text: its trailing corner's sideways offset."""
    return f"flap {f['flap']:+5.2f} m"


SHEET_ITERATIONS = 7
"""Iterations per particle along the flag at which the validation's sheet flag is converged in its iterations (twice
as many flap the same at resolutions 9, 17 and 33; benchmarks/validation/flag_rows.py SHEET_FLAG)."""


def flag_caveat(flag, settings) -> str:
    """What the flag's flapping figures are not (the mesh's, the iterations'), and which cloth's they are.

    Without a bending stiffness they are the mesh's: the paper's air law is local and its cloth folds freely, so
    nothing but the mesh picks a wavelength (converged in the time step, resolution 5 flaps at f L/U 0.96 and
    resolution 9 at 1.36; docs/objects.md, "The flag at fine resolution"). With one, the validation's sheet flag
    (B 0.1 N m, a woven cloth, masses by area) flaps within 0.1 % at resolutions 17 and 33 and 2 % slower at 9:
    its figures are the flag's on a mesh finer than resolution 17 and than the bending length
    ``(B / (rho U^2))^(1/3)``, with elastic sticks and at least :data:`SHEET_ITERATIONS` iterations per particle
    along it (the rigid sticks' iterations never converge on a fine mesh, and the flapping follows their count).
    Even then they are the cloth's in its plane: a woven cloth (``flag.shear_compliance``, stiff threads and a soft
    shear, as the validation's sheet flag) flaps the same whatever its threads' stiffness, one of like sticks flaps
    slower the stiffer it is made (its crossed cells lock; less so on a finer mesh), so that a paper sheet's
    in-plane stiffness is beyond these meshes (the validation's rows 'sheet flag frequency, thread stiffness' and
    'every stick alike').
    The Euler mass-spring comparison's flapping is not validated."""
    solver = settings.solver  # flag: its FlagConfig; settings: the scene's (solver, wind, air) of its world
    resolution, bending = int(flag.resolution), float(flag.bending_stiffness)
    where = "(docs/flag.md, 'The flag at fine resolution')"
    if bending <= 0.0:
        return (
            f"note: the flap's frequency and size are those of this mesh (resolution {resolution}), not a real "
            f"flag's: the local air law and the bending-free cloth pick no wavelength, so a finer mesh flaps "
            f'otherwise; the default flag (flag.design = "sheet") converges {where}'
        )
    if solver.method != "verlet":
        return f"note: the Euler mass-spring comparison's flapping is not validated {where}"
    if float(flag.cloth_compliance) <= 0.0 or not solver.mass_splitting:
        return (
            "note: with rigid sticks (flag.cloth_compliance = 0) the flapping follows the iteration count on a fine "
            "mesh; set flag.cloth_compliance (e.g. 1e-3) and solver.mass_splitting = true for one that converges "
            f"{where}"
        )
    speed = float(np.linalg.norm(settings.wind.velocity))
    spacing = float(flag.width) / (resolution - 1)
    density = air_density(settings.air, 0.0)  # a flag flies near the ground
    length = (bending / (density * max(speed, 1e-3) ** 2)) ** (1.0 / 3.0)
    if resolution < 17 or spacing > length:
        finest = max(17, int(np.ceil(float(flag.width) / length)) + 1)
        alike = ", 8 % with every stick alike" if float(flag.shear_compliance) <= 0.0 else ""
        return (
            f"note: at resolution {resolution} (spacing {spacing:.2g} m against a bending length of {length:.2g} m) "
            f"the flapping is still the mesh's in part (the validation's sheet flag flaps 2 % slower at resolution 9 "
            f"than at 33{alike}); resolution {finest} or more should converge {where}"
        )
    if int(solver.iterations) < SHEET_ITERATIONS * resolution:
        return (
            f"note: {solver.iterations} iterations, fewer than the {SHEET_ITERATIONS} per particle along the flag "
            f"({SHEET_ITERATIONS * resolution}) at which the validation's sheet flag flaps as with twice as many "
            f"{where}"
        )
    if float(flag.shear_compliance) > 0.0:
        return (
            f"note: the flapping is this flag's, a woven cloth ({1.0 / float(flag.shear_compliance):,.0f} N/m in "
            "shear) with a card's bending, converged in its mesh, step, iterations and threads (the validation's, at "
            "100 N/m); the worst stick stretch is its diagonals as the cloth shears, as meant. A fabric's waves are "
            f"finer than this mesh, and a sheet stiff in shear (paper) locks on it {where}"
        )
    stiffness = 1.5 / float(flag.cloth_compliance)
    return (
        f"note: the flapping is this cloth's, every stick alike, about {stiffness:,.0f} N/m in its plane (1.5 / "
        "flag.cloth_compliance: a pull stretches the diagonals too): a "
        "stiffer one flaps slower (16 times stiffer: 15 % at resolution 17, 11 % at 33; its crossed cells lock), "
        "and a paper sheet, a hundred times stiffer or more, is out of reach here; a woven cloth "
        f"(flag.shear_compliance, the default flag's) does not depend on its threads' stiffness {where}"
    )


def parachute_hud(f: dict[str, float]) -> str:
    """The parachute's heads-up text: rate of descent, canopy radius and swing."""
    return f"descent {f['sink']:5.2f} m/s  radius {f['radius']:4.2f} m  swing {f['swing']:3.0f} deg"
