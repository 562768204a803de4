"""Model (static arrays), State (positions) and Control (time-varying inputs).

Units are SI throughout: metres, kilograms, seconds; Z is up. Device arrays are Warp arrays on
``model.device``; host-side metadata (names, labels) are NumPy arrays or Python lists.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np
import warp as wp

from . import _warp
from .config import AIR_DENSITY, GRAVITY
from .kernels.collision import HeightfieldData
from .lattice import Lattice
from .terrain import Heightfield

_warp.init()  # every warpsim object needs Warp; start it without its CPU-machine chatter

__all__ = ["AIR_DENSITY", "GRAVITY", "Control", "Model", "ObjectRecord", "State"]


@dataclass(kw_only=True)
class ObjectRecord:
    """What a builder of a flying object added to a model: names and index ranges for diagnostics and output.
    Objects with more to tell (reference particles, control sticks) extend it with typed fields.

    Attributes:
        name: instance name, e.g. ``"hang_glider"``.
        kind: object kind (``flag``, ``hang-glider``, ``kite``, ``parachute``).
        world: world index the object lives in.
        particles: indices of its particles, shape ``[n]``.
        parts: part name -> particle indices (e.g. ``"sail"``, ``"pilot"``, ``"virtual"``).
        tri_parts: part name -> triangle indices.
        stick_groups: group name -> stick indices (e.g. ``"frame"``, ``"control"``).
        curves: part name -> chains of particle indices drawn as curves by outputs (ropes, lines).
    """

    name: str
    kind: str
    world: int = 0
    particles: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int32))
    parts: dict[str, np.ndarray] = field(default_factory=dict)
    tri_parts: dict[str, np.ndarray] = field(default_factory=dict)
    stick_groups: dict[str, np.ndarray] = field(default_factory=dict)
    curves: dict[str, list[list[int]]] = field(default_factory=dict)

    def controlled_sticks(self) -> np.ndarray:
        """The sticks whose rest lengths this object's controls set [int32 indices]: the solver ramps them
        (``SolverConfig.control_rate``). None here; an object with controls says which."""
        return np.zeros(0, dtype=np.int32)

    def controlled_nails(self) -> np.ndarray:
        """The nails this object's controls move [int32 indices into ``Control.nail_target``]: the solver ramps
        them (``SolverConfig.nail_rate``). None here; an object with controls says which."""
        return np.zeros(0, dtype=np.int32)


class Model:
    """Everything static about a simulation, built once by :meth:`warpsim.ModelBuilder.finalize`.

    Device arrays (``wp.array``) live on :attr:`device`; host arrays (NumPy) are named ``*_np`` when they copy a
    device array, for diagnostics and outputs that must not read device memory every frame. Shapes use
    ``P`` particles, ``S`` sticks, ``T`` triangles, ``N`` nails, ``W`` worlds.
    """

    device: wp.Device
    """Warp device the arrays live on."""
    particle_count: int
    """``P``, particles in every world together."""
    stick_count: int
    """``S``, distance constraints."""
    tri_count: int
    """``T``, air-force triangles."""
    nail_count: int
    """``N``, nailed particles."""
    world_count: int
    """``W``, independent copies of the scene stepped together."""
    particle_mass: np.ndarray
    """Host ``[P]`` masses [kg], ``inf`` for nailed particles."""
    particle_free_mass: np.ndarray
    """Host ``[P]`` masses [kg] with nailed particles 0 (momentum, energy and mass centres of what moves)."""
    particle_inv_mass: wp.array
    """``[P]`` float32 inverse masses [1/kg]; 0 = nailed."""
    particle_world: wp.array
    """``[P]`` int32 world index of each particle; ``particle_world_np`` is its host copy."""
    particle_world_np: np.ndarray
    particle_nail: wp.array
    """``[P]`` int32 index into ``Control.nail_target``, -1 for a free particle."""
    particle_q0: np.ndarray
    """Host ``[P, 3]`` float64 build positions [m]."""
    particle_qd0: np.ndarray
    """Host ``[P, 3]`` float64 build velocities [m/s]."""
    particle_stick_weight: np.ndarray
    """Host ``[P]`` float64 summed weight of each particle's sticks."""
    particle_stick_start: wp.array
    """``[P + 1]`` int32 CSR offsets into ``particle_stick_refs``."""
    particle_stick_refs: wp.array
    """int32 ``2 * stick + end`` (end 0 = a, 1 = b) of each particle's sticks, in stick order."""
    hinge_count: int
    """``H``, bending hinges and cell twists (:mod:`warpsim.physics.kernels.bending`); 0 for cloth without bending
    stiffness."""
    hinge_particles: wp.array
    """``[H]`` vec4i the particles of each hinge (end, middle, end, and a padding slot of weight 0) or twist (a
    cell's four corners); ``hinge_particles_np`` its host copy."""
    hinge_particles_np: np.ndarray
    hinge_weights: wp.array
    """``[H]`` vec4 the weights ``w_j`` of each one's difference ``c = sum_j w_j x_j``: (1, -2, 1, 0) for a hinge,
    (1, -1, -1, 1) for a twist; ``hinge_weights_np`` its host copy."""
    hinge_weights_np: np.ndarray
    hinge_stiffness: wp.array
    """``[H]`` float32 stiffness ``k`` [N/m] of each against its difference: ``B w / h^3`` a hinge, ``2 B / (h_u
    h_v)`` a twist."""
    particle_hinge_start: wp.array
    """``[P + 1]`` int32 CSR offsets into ``particle_hinge_refs``."""
    particle_hinge_refs: wp.array
    """int32 ``4 * hinge + slot`` of each particle's hinges and twists, in hinge order (no padding slots)."""
    bending_dt: float
    """The largest time step [s] at which the hinges' explicit forces are stable
    (:func:`~warpsim.physics.kernels.bending.stable_dt`); ``inf`` without hinges."""
    particle_tri_start: wp.array
    """``[P + 1]`` int32 CSR offsets into ``particle_tri_ids``."""
    particle_tri_ids: wp.array
    """int32 triangles of each particle, in triangle order."""
    lattice: Lattice
    """The vortex lattice of the lifting surfaces builders declared (:mod:`warpsim.physics.lattice`; empty without)."""
    vortex_arrays: dict
    """Device copies of :attr:`lattice`'s arrays, by name (:func:`warpsim.physics.kernels.vortex.lattice_arrays`)."""
    stick_particles: wp.array
    """``[S]`` vec2i, the two particles of each stick; ``stick_particles_np`` is its host ``[S, 2]`` copy."""
    stick_particles_np: np.ndarray
    stick_rest: wp.array
    """``[S]`` float32 rest lengths [m] as built (``Control.stick_rest`` starts from them)."""
    stick_weight: wp.array
    """``[S]`` float32 weight of each stick in the per-particle average (1 = the paper)."""
    stick_pretension: np.ndarray
    """Host ``[S]`` float64 share by which a stick's rest length is shorter than it was built (a tensioned sail;
    0 for most sticks). A pretensioned stick anywhere between its rest length and its length as built,
    ``rest / (1 - pretension)``, shows no stretch (:meth:`stick_stretch`)."""
    stick_compliance: np.ndarray
    """Host ``[S]`` float64 compliance [m/N] of each stick as a whole (its weight included): 0 for a rigid stick (the
    paper's), ``c`` for one that stretches ``c`` metres per newton of tension (:meth:`ModelBuilder.set_compliance
    <warpsim.physics.builder.ModelBuilder.set_compliance>`)."""
    tri_indices: wp.array
    """``[T]`` vec3i triangle vertices; ``tri_indices_np`` is its host ``[T, 3]`` copy."""
    tri_indices_np: np.ndarray
    tri_loading: wp.array
    """``[T]`` float32 chordwise loading factor (``plate`` and ``sail`` air models; 1 = uniform)."""
    tri_sail: wp.array
    """``[T]`` vec4 ``sail`` air model coefficients (lift slope [1/rad], induced-drag factor, profile drag
    coefficient, stall angle [rad]; see :func:`warpsim.physics.kernels.aero.sail_coefficients`)."""
    tri_span: wp.array
    """``[T]`` vec2i the two particles (root, tip) of the leading edge each triangle sits behind, ``(-1, -1)``
    for none (``sail`` air model: simple sweep theory)."""
    drag_count: int
    """Number of drag bodies (particles with a drag area, ``sail`` air model only)."""
    drag_particles: wp.array
    """``[D]`` int32 particle of each drag body."""
    drag_area: wp.array
    """``[D]`` float32 drag area ``C_D A`` [m^2] of each drag body."""
    canopy_count: int
    """Number of parachute canopies whose air force is the whole canopy's (:mod:`warpsim.physics.kernels.canopy`)."""
    canopy_tri_start: wp.array
    """``[C + 1]`` int32 offsets of each canopy's triangles in ``canopy_tri_ids``."""
    canopy_tri_ids: wp.array
    """int32 the canopies' triangles, canopy by canopy; ``canopy_tri_owner`` the canopy of each."""
    canopy_tri_owner: wp.array
    canopy_table: wp.array
    """``[C * TABLE_ROWS]`` vec2 ``(C_T, C_N)`` of each canopy at angles of attack 0, 5, ..., 180 degrees."""
    canopy_params: wp.array
    """``[C]`` vec4 nominal area [m^2], projected area as built [m^2], orientation of the area vector (+-1), wake
    lag of its side force [projected diameters of travel]."""
    canopy_nominal_area: np.ndarray
    """Host ``[C]`` nominal (cloth) area [m^2] of each canopy."""
    nail_particles: np.ndarray
    """Host ``[N]`` int32 particle of each nail."""
    nail_target0: np.ndarray
    """Host ``[N, 3]`` float64 nail positions [m] as built."""
    terrain: Heightfield
    """The ground every world shares."""
    terrain_data: HeightfieldData
    """Device view of :attr:`terrain` for the kernels."""
    gravity: wp.vec3
    """Gravity vector [m/s^2] (Z up)."""
    objects: list[ObjectRecord]
    """The :class:`ObjectRecord` of every object built into the model, world by world."""

    def __init__(self):
        self.device = None
        self.particle_count = self.stick_count = self.tri_count = self.nail_count = self.drag_count = 0
        self.canopy_count = 0
        self.world_count = 1
        self.gravity = wp.vec3(0.0, 0.0, -GRAVITY)
        self.objects = []

    # ------------------------------------------------------------------ construction of runtime data
    def state(self, dt: float | None = None) -> State:
        """A new :class:`State` at the build positions, moving at the build velocities for steps of ``dt`` [s]
        (Verlet keeps ``x_prev = x - v dt``). ``dt`` may be left out when nothing moves at the start.

        Raises ``ValueError`` when some particle has a build velocity and no ``dt`` is given.
        """
        q = np.asarray(self.particle_q0, dtype=np.float64)
        s = State(
            particle_q=wp.array(q, dtype=wp.vec3d, device=self.device),
            particle_q_prev=wp.array(q, dtype=wp.vec3d, device=self.device),
        )
        if np.any(self.particle_qd0):
            if dt is None:
                raise ValueError("the model's particles move at the start: give the time step, model.state(dt)")
            s.set_velocity(self.particle_qd0, dt)
        return s

    def control(self) -> Control:
        """A new :class:`Control` with the built rest lengths, nail targets and zero wind."""
        c = Control(
            stick_rest=wp.array(self.stick_rest.numpy(), dtype=wp.float32, device=self.device),
            stick_rest_target=wp.array(self.stick_rest.numpy(), dtype=wp.float32, device=self.device),
            nail_target=wp.array(
                self.nail_target0.reshape(-1, 3) if self.nail_count else np.zeros((1, 3)),
                dtype=wp.vec3d,
                device=self.device,
            ),
            wind=wp.zeros(self.world_count, dtype=wp.vec3, device=self.device),
            air_density=wp.full(self.world_count, AIR_DENSITY, dtype=wp.float32, device=self.device),
            turbulence=Turbulence.off(self.world_count, self.device),
        )
        c.nail_target_goal = wp.clone(c.nail_target)
        return c

    def constraint_weights(self, mass_splitting: bool) -> tuple[np.ndarray, np.ndarray]:
        """Per-particle factors of the Jacobi constraint solver, host ``(share, scale)`` ``[particle_count]``.

        A stick ``(a, b)`` splits its error in proportion to ``share``; particle ``a`` moves by ``scale_a``
        times the sum of its sticks' corrections. Plain averaging (the paper): ``share = w`` (inverse mass),
        ``scale = w / n`` (``n`` = summed stick weight). Mass splitting: ``share = w n``, ``scale = w``.
        See :mod:`warpsim.physics.kernels.constraints`.
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
        """Relative stretch ``(l - r)/r`` of every stick (dimensionless), ``r`` its rest length (``rest``, or the
        model's as built). A pretensioned stick (:attr:`stick_pretension`) is measured against the nearer end of
        its band: its stretch is ``l / (r / (1 - pretension)) - 1`` past its length as built, ``l / r - 1``
        below its rest length and 0 between (a tensioned sail between its pulled and its built size)."""
        rest = self.stick_rest.numpy() if rest is None else rest
        rest = np.maximum(rest, 1e-12)
        built = rest / (1.0 - self.stick_pretension)
        low, high = np.minimum(rest, built), np.maximum(rest, built)
        lengths = self.stick_lengths(positions)
        past_high = lengths / high - 1.0
        return np.where(past_high > 0.0, past_high, np.minimum(lengths / low - 1.0, 0.0))

    def __repr__(self) -> str:
        return (
            f"Model({self.particle_count} particles, {self.stick_count} sticks, {self.tri_count} triangles, "
            f"{self.nail_count} nails, {self.world_count} world(s), device={self.device})"
        )


@dataclass
class State:
    """What changes every step: positions now and one step ago (Verlet keeps no velocity).

    Attributes:
        particle_q: ``[particle_count]`` float64 vec3d positions [m] (float64 so that a step's ``a dt^2``, 1e-3 m
            at dt 0.01, is kept in full far from the origin: float32 is spaced 3e-5 m at 300 m, 1e-3 m at 10 km).
        particle_q_prev: ``[particle_count]`` float64 vec3d positions one step earlier [m].
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
        self.particle_q_prev.assign(q - np.asarray(velocity, dtype=np.float64) * dt)


@dataclass
class Control:
    """Inputs a pilot or a script changes while the simulation runs, kept in device arrays so that a
    captured step graph sees new values without being captured again.

    Attributes:
        stick_rest: ``[stick_count]`` current rest lengths [m] (the hang glider's control sticks change).
        stick_rest_target: ``[stick_count]`` rest lengths [m] the control sticks move to, at most
            ``SolverConfig.control_rate`` [m/s] (the solver moves ``stick_rest`` each step); None: controls write
            ``stick_rest`` at once.
        nail_target_goal: ``[max(nail_count, 1)]`` float64 vec3d where the controlled nails (the kite's anchor) move
            to, at most ``SolverConfig.nail_rate`` [m/s]; None: controls write ``nail_target`` at once.
        nail_target: ``[max(nail_count, 1)]`` float64 vec3d nail positions [m] (the kite's rope anchor moves).
        wind: ``[world_count]`` vec3 wind velocity [m/s] at the reference height (with gusts, what they blow now).
        gusts: the worlds' gust processes (:class:`Gusts`), advanced every step; None when no world has gusts.
        air_density: ``[world_count]`` float32 density of each world's air [kg/m^3], set by every step
            (:func:`warpsim.physics.kernels.controls.update_air_density`).
        turbulence: every world's frozen turbulence (:class:`Turbulence`; :meth:`Turbulence.off` when none).
    """

    stick_rest: wp.array
    nail_target: wp.array
    wind: wp.array
    air_density: wp.array
    turbulence: Turbulence
    stick_rest_target: wp.array | None = None
    nail_target_goal: wp.array | None = None
    gusts: Gusts | None = None

    def set_wind(self, wind) -> None:
        """Set the wind [m/s]: one 3-vector for every world, or an array ``[world_count, 3]``."""
        w = np.asarray(wind, dtype=np.float32)
        if w.shape == (3,):
            w = np.tile(w, (self.wind.shape[0], 1))
        self.wind.assign(w)


@dataclass
class Gusts:
    """Every world's gusts, in device arrays the step advances (:func:`warpsim.physics.kernels.controls.advance_gusts`):
    the wind is ``mean + intensity * |mean| * (g_x, g_y, g_z / 2)``, ``g`` an Ornstein-Uhlenbeck process of unit
    variance and correlation time ``period``, stepped with the solver's ``dt`` so that the gusts a flight meets do not
    depend on how often it is drawn or recorded.

    Attributes:
        mean: ``[W]`` vec3 mean wind [m/s] the gusts blow around (the ``wind`` control sets it).
        intensity: ``[W]`` float32 gusts' standard deviation as a fraction of the mean speed (0: no gusts there).
        period: ``[W]`` float32 correlation time [s] (> 0).
        seed: ``[W]`` int32 seed of each world's random numbers.
        g: ``[W]`` vec3d the process's current value (dimensionless).
        step: ``[W]`` int32 steps each process has taken (the counter of its random numbers).
    """

    mean: wp.array
    intensity: wp.array
    period: wp.array
    seed: wp.array
    g: wp.array
    step: wp.array

    @classmethod
    def start(cls, winds, device) -> Gusts | None:
        """The gusts of worlds blowing ``winds`` (their :class:`~warpsim.physics.config.WindConfig`), at their
        stationary start (``g`` drawn from each world's seed); None when no world has gusts."""
        if not any(w.gust_intensity > 0.0 for w in winds):
            return None
        g0 = np.array([np.random.default_rng(w.gust_seed).standard_normal(3) for w in winds])

        def array(values, dtype):
            return wp.array(np.asarray(values), dtype=dtype, device=device)

        return cls(
            mean=array([w.velocity for w in winds], wp.vec3),
            intensity=array([w.gust_intensity for w in winds], wp.float32),
            period=array([w.gust_period for w in winds], wp.float32),
            seed=array([w.gust_seed % 2**31 for w in winds], wp.int32),
            g=array(g0, wp.vec3d),
            step=array(np.zeros(len(winds)), wp.int32),
        )

    def view(self, first: int, end: int) -> Gusts:
        """The gusts of worlds ``first`` to ``end - 1`` (views of the same arrays)."""
        return Gusts(*(getattr(self, f.name)[first:end] for f in dataclasses.fields(self)))


@dataclass
class Turbulence:
    """Every world's frozen turbulence (:mod:`warpsim.physics.turbulence`): one field shared by the worlds, each world
    entering it at its own point and carried through it by its wind, stepped with the solver
    (:func:`warpsim.physics.kernels.controls.advance_turbulence`).

    Attributes:
        data: the :class:`~warpsim.physics.kernels.aero.TurbulenceData` the air kernels sample (field, shift, scale).
        intensity: ``[W]`` float32 each world's turbulence intensity (standard deviation over the wind's speed at the
            reference height; 0: none).
        field: the host :class:`~warpsim.physics.turbulence.Field` (None when no world has turbulence).
    """

    data: object
    intensity: wp.array
    field: object = None

    @classmethod
    def off(cls, worlds: int, device) -> Turbulence:
        """No turbulence in any of ``worlds`` worlds (a 2x2x2 zero field the kernels never read: their scale is 0)."""
        from .kernels.aero import TurbulenceData

        data = TurbulenceData()
        data.velocity = wp.zeros((2, 2, 2), dtype=wp.vec3, device=device)
        data.inv_cell = 1.0
        data.shift = wp.zeros(worlds, dtype=wp.vec3d, device=device)
        data.scale = wp.zeros(worlds, dtype=wp.float32, device=device)
        return cls(data, wp.zeros(worlds, dtype=wp.float32, device=device))

    @classmethod
    def start(cls, winds, device) -> Turbulence:
        """The turbulence of worlds blowing ``winds`` (their :class:`~warpsim.physics.config.WindConfig`): the field of
        their ``turbulence_length`` (``ValueError`` when turbulent worlds differ in it), each world at the entry point
        of its ``turbulence_seed``; :meth:`off` when no world has turbulence."""
        from . import turbulence
        from .kernels.aero import TurbulenceData

        turbulent = [w for w in winds if w.turbulence_intensity > 0.0]
        if not turbulent:
            return cls.off(len(winds), device)
        lengths = sorted({w.turbulence_length for w in turbulent})
        if len(lengths) > 1:
            raise ValueError(
                f"worlds share one turbulence field: give them one wind.turbulence_length (got {lengths}); vary "
                "wind.turbulence_seed or wind.turbulence_intensity instead"
            )
        field = turbulence.field(lengths[0])
        data = TurbulenceData()
        data.velocity = wp.array(field.velocity, dtype=wp.vec3, device=device)
        data.inv_cell = 1.0 / field.cell
        shift = np.array([turbulence.world_offset(w.turbulence_seed, field) for w in winds])
        data.shift = wp.array(shift, dtype=wp.vec3d, device=device)
        intensity = np.array([w.turbulence_intensity for w in winds], dtype=np.float32)
        speed = np.linalg.norm(np.array([w.velocity for w in winds], dtype=np.float32), axis=1)
        data.scale = wp.array(intensity * speed, dtype=wp.float32, device=device)
        return cls(data, wp.array(intensity, dtype=wp.float32, device=device), field)

    def view(self, first: int, end: int) -> Turbulence:
        """The turbulence of worlds ``first`` to ``end - 1`` (views of the same arrays, the same field)."""
        from .kernels.aero import TurbulenceData

        data = TurbulenceData()
        data.velocity, data.inv_cell = self.data.velocity, self.data.inv_cell
        data.shift, data.scale = self.data.shift[first:end], self.data.scale[first:end]
        return Turbulence(data, self.intensity[first:end], self.field)
