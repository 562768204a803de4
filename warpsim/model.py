"""Model (static arrays), State (positions) and Control (time-varying inputs).

Units are SI throughout: metres, kilograms, seconds; Z is up. Device arrays are Warp arrays on
``model.device``; host-side metadata (names, labels) are NumPy arrays or Python lists.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import warp as wp

from . import _warp
from .kernels.collision import HeightfieldData
from .terrain import Heightfield

_warp.init()  # every warpsim object needs Warp; start it without its CPU-machine chatter

GRAVITY = 9.80665
"""Standard gravity [m/s^2] (slide 14; the paper's text misprints 9.80655)."""

AIR_DENSITY = 1.294217666
"""Air density [kg/m^3] used by the paper (slide 14)."""


@dataclass
class ObjectRecord:
    """What a builder of a flying object added to a model: names and index ranges for diagnostics and output.

    Attributes:
        name: instance name, e.g. ``"hang_glider"``.
        kind: object kind (``flag``, ``hang-glider``, ``kite``, ``parachute``).
        world: world index the object lives in.
        particles: indices of its particles, shape ``[n]``.
        parts: part name -> particle indices (e.g. ``"sail"``, ``"pilot"``, ``"virtual"``).
        tri_parts: part name -> triangle indices.
        stick_groups: group name -> stick indices (e.g. ``"frame"``, ``"control"``).
        meta: object-specific values (paper counts, control-stick tables, reference points); ``curves``:
            part name -> list of particle chains drawn as curves in outputs (ropes, lines).
    """

    name: str
    kind: str
    world: int = 0
    particles: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int32))
    parts: dict[str, np.ndarray] = field(default_factory=dict)
    tri_parts: dict[str, np.ndarray] = field(default_factory=dict)
    stick_groups: dict[str, np.ndarray] = field(default_factory=dict)
    meta: dict = field(default_factory=dict)


class Model:
    """Everything static about a simulation, built once by :class:`warpsim.ModelBuilder.finalize`.

    Attributes:
        device: Warp device the arrays live on.
        particle_count, stick_count, tri_count, nail_count, world_count: sizes.
        particle_mass: host ``[particle_count]`` masses [kg] (``inf`` for nailed particles).
        particle_free_mass: host ``[particle_count]`` masses [kg] with nailed particles 0 (for momentum,
            energy and mass centres of what moves freely).
        particle_inv_mass: ``[particle_count]`` inverse masses [1/kg]; 0 = nailed or kinematic.
        particle_world: ``[particle_count]`` world index of each particle.
        particle_nail: ``[particle_count]`` index into ``Control.nail_target``, -1 when free.
        particle_q0, particle_qd0: host ``[particle_count, 3]`` build positions [m] and velocities [m/s].
        stick_particles: ``[stick_count]`` vec2i, the two particle indices of each stick.
        stick_rest: ``[stick_count]`` rest lengths [m] as built (``Control.stick_rest`` starts from them).
        stick_weight: ``[stick_count]`` weight of each stick in the per-particle average (1 = the paper).
        particle_stick_weight: host ``[particle_count]`` summed weight of each particle's sticks.
        tri_indices: ``[tri_count]`` vec3i triangle vertices.
        tri_loading: ``[tri_count]`` chordwise loading factor of each triangle (``plate`` air model; 1 = uniform).
        particle_stick_start, particle_stick_refs: CSR adjacency particle -> ``2*stick + end``.
        particle_tri_start, particle_tri_ids: CSR adjacency particle -> triangle.
        nail_particles: host ``[nail_count]`` particle index of each nail.
        nail_target0: host ``[nail_count, 3]`` nail positions [m] as built.
        terrain: the :class:`Heightfield`; ``terrain_data`` its device view.
        gravity: gravity vector [m/s^2]. air_density: [kg/m^3].
        objects: :class:`ObjectRecord` of every object built into the model.
    """

    def __init__(self):
        self.device = None
        self.particle_count = 0
        self.stick_count = 0
        self.tri_count = 0
        self.nail_count = 0
        self.world_count = 1
        self.objects: list[ObjectRecord] = []

    # ------------------------------------------------------------------ construction of runtime data
    def state(self) -> State:
        """A new :class:`State` at the build positions; the previous position encodes the build velocity
        for the default time step ``dt = 0.01`` s (call :meth:`State.set_velocity` for another dt)."""
        with np.errstate(over="ignore"):  # an absurd size overflows float32: Simulation reports it
            q = self.particle_q0.astype(np.float32)
        s = State(
            particle_q=wp.array(q, dtype=wp.vec3, device=self.device),
            particle_q_prev=wp.array(q, dtype=wp.vec3, device=self.device),
        )
        s.set_velocity(self.particle_qd0, 0.01)
        return s

    def control(self) -> Control:
        """A new :class:`Control` with the built rest lengths, nail targets and zero wind."""
        return Control(
            stick_rest=wp.array(self.stick_rest.numpy(), dtype=wp.float32, device=self.device),
            nail_target=wp.array(
                self.nail_target0.reshape(-1, 3) if self.nail_count else np.zeros((1, 3)),
                dtype=wp.vec3,
                device=self.device,
            ),
            wind=wp.zeros(self.world_count, dtype=wp.vec3, device=self.device),
        )

    def constraint_weights(self, mass_splitting: bool) -> tuple[np.ndarray, np.ndarray]:
        """Per-particle factors of the Jacobi constraint solver, host ``(share, scale)`` ``[particle_count]``.

        A stick ``(a, b)`` splits its error in proportion to ``share``; particle ``a`` moves by ``scale_a``
        times the sum of its sticks' corrections. Plain averaging (the paper): ``share = w`` (inverse mass),
        ``scale = w / n`` (``n`` = summed stick weight). Mass splitting: ``share = w n``, ``scale = w``.
        See :mod:`warpsim.kernels.constraints`.
        """
        w = self.particle_inv_mass.numpy().astype(np.float64)
        n = self.particle_stick_weight
        if mass_splitting:
            return w * n, w
        return w, np.divide(w, n, out=np.zeros_like(w), where=n > 0)

    def stick_lengths(self, positions: np.ndarray) -> np.ndarray:
        """Current stick lengths [m] for host ``positions`` ``[particle_count, 3]``."""
        ends = self.stick_particles_np
        return np.linalg.norm(positions[ends[:, 1]] - positions[ends[:, 0]], axis=1)

    def stick_stretch(self, positions: np.ndarray, rest: np.ndarray | None = None) -> np.ndarray:
        """Relative stretch ``(l - r)/r`` of every stick (dimensionless)."""
        rest = self.stick_rest.numpy() if rest is None else rest
        return self.stick_lengths(positions) / np.maximum(rest, 1e-12) - 1.0

    def __repr__(self) -> str:
        return (
            f"Model({self.particle_count} particles, {self.stick_count} sticks, {self.tri_count} triangles, "
            f"{self.nail_count} nails, {self.world_count} world(s), device={self.device})"
        )


@dataclass
class State:
    """What changes every step: positions now and one step ago (Verlet keeps no velocity).

    Attributes:
        particle_q: ``[particle_count]`` vec3 positions [m].
        particle_q_prev: ``[particle_count]`` vec3 positions one step earlier [m].
        time: simulated time [s].
    """

    particle_q: wp.array
    particle_q_prev: wp.array
    time: float = 0.0

    def positions(self) -> np.ndarray:
        """Host copy of the positions, shape ``[particle_count, 3]`` [m] (never a view of device memory)."""
        return self.particle_q.numpy().copy()

    def velocities(self, dt: float) -> np.ndarray:
        """Host velocities ``(x - x_prev)/dt`` [m/s] for the step ``dt`` [s] being used."""
        return (self.particle_q.numpy() - self.particle_q_prev.numpy()) / dt  # new array

    def set_velocity(self, velocity: np.ndarray, dt: float) -> None:
        """Set ``x_prev = x - velocity * dt`` so that the state moves at ``velocity`` [m/s] with step ``dt`` [s]."""
        q = self.particle_q.numpy()
        self.particle_q_prev.assign((q - np.asarray(velocity, dtype=np.float64) * dt).astype(np.float32))

    def assign(self, other: State) -> None:
        """Copy ``other`` into this state (same model)."""
        wp.copy(self.particle_q, other.particle_q)
        wp.copy(self.particle_q_prev, other.particle_q_prev)
        self.time = other.time


@dataclass
class Control:
    """Inputs a pilot or a script changes while the simulation runs, kept in device arrays so that a
    captured step graph sees new values without being captured again.

    Attributes:
        stick_rest: ``[stick_count]`` current rest lengths [m] (the hang glider's control sticks change).
        nail_target: ``[max(nail_count, 1)]`` vec3 nail positions [m] (the kite's rope anchor moves).
        wind: ``[world_count]`` vec3 wind velocity [m/s] at the reference height.
    """

    stick_rest: wp.array
    nail_target: wp.array
    wind: wp.array

    def set_wind(self, wind) -> None:
        """Set the wind [m/s]: one 3-vector for every world, or an array ``[world_count, 3]``."""
        w = np.asarray(wind, dtype=np.float32)
        if w.shape == (3,):
            w = np.tile(w, (self.wind.shape[0], 1))
        self.wind.assign(w)


def heightfield_data(terrain: Heightfield, device) -> HeightfieldData:
    """Device view of a heightfield for the kernels."""
    data = HeightfieldData()
    data.heights = wp.array(terrain.heights, dtype=wp.float32, device=device)
    data.origin = wp.vec2(*terrain.origin)
    data.cell = wp.vec2(*terrain.cell)
    return data
