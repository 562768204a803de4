"""Solvers: :class:`SolverVerlet` (the paper's method) and :class:`SolverEuler` (its mass-spring comparison).

One call ``solver.step(state, control, dt)`` advances ``state`` in place by ``dt`` seconds. Buffers are
allocated once in ``__init__``. The whole step is captured once per ``(state, control, dt)`` as a Warp
graph and replayed with ``wp.capture_launch``, on the ``cpu`` device as on ``cuda``: a CPU kernel
launch from Python costs about 10 us, while a replayed graph costs about as much as the kernels
themselves. On the CPU the constraint projection is one launch (the ``fused`` scheme), so a step has
four (air force, Verlet, constraints, terrain); on CUDA it is one launch per iteration (``gather``), about 59.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import warp as wp

from .config import AirConfig, GroundConfig, SolverConfig, WindConfig
from .kernels import (
    MODULES,
    aero,
    bending,
    canopy,
    collision,
    constraints,
    controls,
    influence,
    momentum,
    springs,
    verlet,
    vortex,
    wake,
)
from .kernels.aero import AeroModel, body_drag, triangle_air_force
from .kernels.bending import bending_force
from .kernels.canopy import canopy_air_force
from .kernels.collision import collide_heightfield
from .kernels.controls import (
    advance_gusts,
    advance_turbulence,
    ramp_nail_targets,
    ramp_rest_lengths,
    update_air_density,
)
from .kernels.momentum import MomentumKeeper
from .kernels.springs import integrate_euler_springs
from .kernels.verlet import integrate_verlet
from .model import Control, Model, State
from .projection import make_projector

LOAD_WORKERS = 2
"""Kernel modules compiled at once on a cold cache. Measured on a 2-core CPU (the glider's five modules, Warp
1.19): 2.78 s one after another, 2.02 s two at a time, 3.47 s four at a time. Each thread's first compilation
costs ~1.2 s more than its later ones, so the modules are best loaded together, once, before any other use."""


def load_modules(modules, device) -> None:
    """Load the kernel modules ``modules`` (Python modules of Warp kernels) on ``device``, compiling those not in
    Warp's cache, :data:`LOAD_WORKERS` at a time (seconds on a cold cache; nothing to do on a warm one)."""
    modules = [wp.get_module(m.__name__) for m in modules]
    wp.force_load(wp.get_device(device), modules=modules, max_workers=LOAD_WORKERS)  # None: Warp's default device


def _check_dt(dt: float) -> float:
    dt = float(dt)
    if not dt > 0.0 or dt == float("inf"):
        raise ValueError(f"dt must be a positive number of seconds, got {dt}")
    return dt


class _Solver:
    """Shared machinery: settings, scratch buffers, graph capture and replay.

    Args:
        model: the model to simulate.
        config: :class:`~warpsim.physics.config.SolverConfig` (default: its defaults, those of a scene descriptor);
            ``settings`` given by keyword replace its fields, e.g. ``SolverVerlet(model, iterations=40)``.
        air, wind, ground: :class:`~warpsim.physics.config.AirConfig`,
            :class:`~warpsim.physics.config.WindConfig` (its shear
            profile; the wind itself is ``Control.wind``), :class:`~warpsim.physics.config.GroundConfig`.
        use_graph: capture the step as a graph and replay it (default); False launches kernel by kernel.
    """

    max_cached_graphs = 8

    def __init__(
        self,
        model: Model,
        config: SolverConfig | None = None,
        *,
        air: AirConfig | None = None,
        wind: WindConfig | None = None,
        ground: GroundConfig | None = None,
        use_graph: bool = True,
        **settings,
    ):
        self.model = model
        self.config = dataclasses.replace(config or SolverConfig(), **settings)
        self.air = air or AirConfig()
        self.wind = wind or WindConfig()
        self.ground = ground or GroundConfig()
        self.use_graph = bool(use_graph)
        self.tri_force = wp.zeros(max(model.tri_count, 1), dtype=wp.vec3, device=model.device)
        self.particle_air = wp.zeros(model.particle_count, dtype=wp.vec3, device=model.device)  # drag bodies' drag
        # with hinges: each particle's own force, its drag and its bending (kernels.bending), else particle_air itself
        self.particle_force = self.particle_air
        if model.hinge_count:
            self.particle_force = wp.zeros(model.particle_count, dtype=wp.vec3, device=model.device)
        self.vortex = vortex.VortexScratch(model) if model.lattice.panel_count else None
        """The vortex law's buffers when the model has lifting surfaces (:mod:`warpsim.physics.kernels.vortex`)."""
        if self.vortex is not None and self.air.wake == "shed":
            self.vortex.shed = wake.ShedWake(model, self.air.wake_rows, self.air.wake_interval)
        self.canopy_load = wp.zeros(max(model.canopy_count, 1), dtype=wp.vec4, device=model.device)
        self.canopy_side = wp.zeros(max(model.canopy_count, 1), dtype=wp.vec3, device=model.device)
        sticks = np.unique(np.concatenate([np.zeros(0, np.int32), *(r.controlled_sticks() for r in model.objects)]))
        self.control_sticks = wp.array(sticks.astype(np.int32), dtype=wp.int32, device=model.device)
        """``[K]`` the sticks whose rest lengths the controls set (they ramp: :func:`ramp_rest_lengths`)."""
        nails = np.unique(np.concatenate([np.zeros(0, np.int32), *(r.controlled_nails() for r in model.objects)]))
        self.control_nails = wp.array(nails.astype(np.int32), dtype=wp.int32, device=model.device)
        """``[N]`` the nails the controls move (the kites' anchors; they ramp: :func:`ramp_nail_targets`)."""
        worlds = np.searchsorted(model.particle_world_np, np.arange(model.world_count + 1)).astype(np.int32)
        self.world_start = wp.array(worlds, dtype=wp.int32, device=model.device)
        """``[W + 1]`` where each world's particles start (worlds are built one after another)."""
        self._graphs: dict = {}

    def update_air(self, state: State, control: Control) -> None:
        """Set every world's air density [kg/m^3] in ``control.air_density`` for ``state`` (each step does this
        first; see :func:`~warpsim.physics.kernels.controls.update_air_density`)."""
        update_air_density(self.model, state, self.air, self.world_start, control.air_density)

    def _launch(self, state: State, control: Control, dt: float) -> None:
        raise NotImplementedError

    def _vortex(self, state: State, control: Control, dt: float) -> None:
        """The vortex law on the lifting surfaces, under ``air.model = "vortex"`` (its forces replace the per-triangle
        law's on the surfaces' triangles and are written into ``particle_air``)."""
        if self.vortex is not None and int(self.air.model) == AeroModel.VORTEX:
            vortex.vortex_air_force(
                self.model, state, control, dt, self.air, self.wind, self.vortex, self.tri_force, self.particle_air
            )

    def _particle_forces(self, state: State) -> wp.array:
        """Each particle's own force [N] this step: the drag bodies' drag, plus the bending hinges' force when the
        model has hinges."""
        if self.model.hinge_count:
            bending_force(self.model, state, self.particle_air, self.particle_force)
        return self.particle_force

    def check_dt(self, dt: float) -> float:
        """``dt`` [s] as a float, or ValueError for one this solver cannot step: not a positive number, or past the
        explicit limit of the model's bending hinges (``Model.bending_dt``)."""
        dt = _check_dt(dt)
        if dt > self.model.bending_dt:
            raise ValueError(
                f"dt {dt:g} s is too long for the cloth's bending stiffness at this mesh: its explicit forces need "
                f"dt <= {self.model.bending_dt:.3g} s (kernels.bending.stable_dt); lower dt, the bending "
                "stiffness or the resolution"
            )
        return dt

    def _ramp_controls(self, control: Control, dt: float) -> None:
        """Move the control sticks' rest lengths toward their targets, at most ``control_rate * dt`` [m], and the
        controlled nails toward theirs, at most ``nail_rate * dt`` [m]; advance the gusts and the turbulence by
        ``dt``."""
        advance_gusts(self.model, control, dt)
        advance_turbulence(self.model, control, dt)
        ramp_rest_lengths(self.model, control, self.control_sticks, self.config.control_rate * dt)
        ramp_nail_targets(self.model, control, self.control_nails, self.config.nail_rate * dt)

    def launch(self, state: State, control: Control, dt: float) -> None:
        """Launch one step's kernels on ``state`` (no graph, ``state.time`` left alone): what a caller records
        when it captures several steps, with kernels of its own, in one graph (see :meth:`load_kernels`)."""
        self._launch(state, control, self.check_dt(dt))

    modules: tuple = MODULES
    """The kernel modules this solver launches (:meth:`load_kernels` loads only these)."""

    def load_kernels(self) -> None:
        """Load the solver's kernel modules on the model's device (see :func:`load_modules`)."""
        load_modules(self.modules, self.model.device)

    def prepare(self, state: State, control: Control, dt: float):
        """Load the kernels and, with ``use_graph``, capture the step for ``(state, control, dt)`` without
        running it, so that the next :meth:`step` only replays; the capture reads the model's values (gravity)
        as they are now. Returns the graph entry (None without graphs)."""
        dt = self.check_dt(dt)
        self.load_kernels()
        if not self.use_graph:
            return None
        key = (id(state), id(control), dt)
        entry = self._graphs.get(key)
        if entry is None:
            if len(self._graphs) >= self.max_cached_graphs:
                self._graphs.clear()
            with wp.ScopedCapture(device=self.model.device) as capture:
                self._launch(state, control, dt)
            # keep state and control alive with the graph so their ids cannot be reused
            entry = self._graphs[key] = (capture.graph, state, control)
        return entry

    def step(self, state: State, control: Control, dt: float) -> None:
        """Advance ``state`` by ``dt`` seconds (in place) under ``control``."""
        dt = self.check_dt(dt)
        if not self.use_graph:
            self._launch(state, control, dt)
        else:
            entry = self._graphs.get((id(state), id(control), dt)) or self.prepare(state, control, dt)
            wp.capture_launch(entry[0])
        state.time += dt


class SolverVerlet(_Solver):
    """The paper's solver: Verlet integration + Jacobi-averaged distance constraints + terrain collision.

    Uses ``iterations``, ``relaxation``, ``chebyshev``, ``mass_splitting``, ``keep_momentum`` and ``damping`` of its
    :class:`~warpsim.physics.config.SolverConfig` (arguments as for the shared base, see ``_Solver``), plus
    ``constraint_scheme``: ``"fused"``, ``"scatter"`` or ``"gather"`` (:mod:`warpsim.physics.projection`);
    None = fused on the CPU, gather on CUDA.
    """

    modules = (aero, bending, canopy, collision, constraints, controls, influence, momentum, verlet, vortex, wake)

    def __init__(self, model: Model, config: SolverConfig | None = None, *, constraint_scheme=None, **kwargs):
        super().__init__(model, config, **kwargs)
        self.projector = make_projector(model, self.config, constraint_scheme)
        self.projector.prepare(self.config.iterations)  # before any graph capture
        self.momentum = MomentumKeeper(model) if self.config.keep_momentum else None

    def _launch(self, state: State, control: Control, dt: float) -> None:
        m, cfg = self.model, self.config
        self._ramp_controls(control, dt)
        self.update_air(state, control)
        triangle_air_force(m, state, control, dt, self.air, self.wind, self.tri_force)
        canopy_air_force(m, state, control, dt, self.air, self.wind, self.canopy_side, self.canopy_load, self.tri_force)
        self._vortex(state, control, dt)
        body_drag(m, state, control, dt, self.air, self.wind, self.particle_air)
        forces = self._particle_forces(state)
        integrate_verlet(m, state, control, self.tri_force, forces, dt, cfg.damping)
        if self.momentum is not None:
            self.momentum.before(state)
        self.projector.project(state, control, cfg.iterations, dt)
        if self.momentum is not None:
            self.momentum.after(state)
        collide_heightfield(m, state, self.ground.collision, self.ground.friction)


class SolverEuler(_Solver):
    """The paper's comparison: explicit Euler on a mass-spring network (every stick is a spring of
    ``spring_stiffness`` [N/m] and ``spring_damping`` [N s/m] from its :class:`~warpsim.physics.config.SolverConfig`;
    arguments as for :class:`SolverVerlet`, without a constraint scheme)."""

    modules = (aero, bending, canopy, collision, controls, influence, springs, vortex, wake)

    def __init__(self, model: Model, config: SolverConfig | None = None, **kwargs):
        super().__init__(model, config, **kwargs)
        self.spring_force = wp.zeros(max(model.stick_count, 1), dtype=wp.vec3, device=model.device)

    def _launch(self, state: State, control: Control, dt: float) -> None:
        m, cfg = self.model, self.config
        self._ramp_controls(control, dt)
        self.update_air(state, control)
        triangle_air_force(m, state, control, dt, self.air, self.wind, self.tri_force)
        canopy_air_force(m, state, control, dt, self.air, self.wind, self.canopy_side, self.canopy_load, self.tri_force)
        self._vortex(state, control, dt)
        body_drag(m, state, control, dt, self.air, self.wind, self.particle_air)
        forces = self._particle_forces(state)
        integrate_euler_springs(
            m,
            state,
            control,
            self.tri_force,
            forces,
            self.spring_force,
            dt,
            cfg.spring_stiffness,
            cfg.spring_damping,
        )
        collide_heightfield(m, state, self.ground.collision, self.ground.friction)


SOLVERS = {"verlet": SolverVerlet, "euler": SolverEuler}
"""``SolverConfig.method`` -> solver class."""


def make_solver(model: Model, config: SolverConfig | None = None, **kwargs) -> _Solver:
    """The solver of ``config.method`` for ``model`` (keyword arguments as for :class:`SolverVerlet`)."""
    config = config or SolverConfig()
    return SOLVERS[config.method](model, config, **kwargs)
