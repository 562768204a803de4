"""Solvers: :class:`SolverVerlet` (the paper's method) and :class:`SolverEuler` (its mass-spring comparison).

One call ``solver.step(state, control, dt)`` advances ``state`` in place by ``dt`` seconds. Buffers are
allocated once in ``__init__``. The whole step is captured once per ``(state, control, dt)`` as a Warp
graph and replayed with ``wp.capture_launch``, on the ``cpu`` device as on ``cuda``: a CPU kernel
launch from Python costs about 10 us, while a replayed graph costs about as much as the kernels
themselves. On the CPU the constraint projection is one launch (the ``fused`` scheme), so a step has
four (air force, Verlet, constraints, terrain); on CUDA it is one launch per iteration (``gather``), about 59.
"""

from __future__ import annotations

from dataclasses import dataclass

import warp as wp

from .kernels import MODULES
from .kernels.aero import AeroModel, triangle_air_force
from .kernels.collision import CollisionMode, collide_heightfield
from .kernels.constraints import StickProjector
from .kernels.springs import integrate_euler_springs
from .kernels.verlet import integrate_verlet
from .model import Control, Model, State


@dataclass
class AirSettings:
    """How the air acts on the triangles.

    Attributes:
        model: air-force law, :class:`AeroModel` (``PAPER`` default, ``PLATE`` lift-capable).
        scale: multiplier on the air force (1 = the model as written).
        shear_exponent: power-law wind shear exponent (0 = same wind at every height; ~0.14 over open land).
        shear_reference_height: height above the terrain [m] where the wind equals ``Control.wind``.
    """

    model: AeroModel = AeroModel.PAPER
    scale: float = 1.0
    shear_exponent: float = 0.0
    shear_reference_height: float = 10.0


@dataclass
class GroundSettings:
    """How particles meet the terrain.

    Attributes:
        mode: :class:`CollisionMode` (``NORMAL`` default, ``CLAMP`` = the paper's vertical clamp).
        friction: Coulomb-like friction coefficient (dimensionless, >= 0).
    """

    mode: CollisionMode = CollisionMode.NORMAL
    friction: float = 0.5


def _check_dt(dt: float) -> float:
    dt = float(dt)
    if not dt > 0.0 or dt == float("inf"):
        raise ValueError(f"dt must be a positive number of seconds, got {dt}")
    return dt


class _Solver:
    """Shared machinery: scratch buffers, graph capture and replay."""

    max_cached_graphs = 8

    def __init__(self, model: Model, air: AirSettings | None, ground: GroundSettings | None, use_graph: bool):
        self.model = model
        self.air = air or AirSettings()
        self.ground = ground or GroundSettings()
        if self.ground.friction < 0.0:
            raise ValueError(f"ground friction must be >= 0, got {self.ground.friction}")
        self.use_graph = bool(use_graph)
        self.tri_force = wp.zeros(max(model.tri_count, 1), dtype=wp.vec3, device=model.device)
        self._graphs: dict = {}

    def _launch(self, state: State, control: Control, dt: float) -> None:
        raise NotImplementedError

    def load_kernels(self) -> None:
        """Load every kernel module on the model's device, compiling those not in Warp's cache (seconds)."""
        for module in MODULES:
            wp.load_module(module, device=self.model.device)

    def prepare(self, state: State, control: Control, dt: float):
        """Load the kernels and, with ``use_graph``, capture the step for ``(state, control, dt)`` without
        running it, so that the next :meth:`step` only replays; the capture reads the model's values (gravity)
        as they are now. Returns the graph entry (None without graphs)."""
        dt = _check_dt(dt)
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
        dt = _check_dt(dt)
        if not self.use_graph:
            self._launch(state, control, dt)
        else:
            entry = self._graphs.get((id(state), id(control), dt)) or self.prepare(state, control, dt)
            wp.capture_launch(entry[0])
        state.time += dt


class SolverVerlet(_Solver):
    """The paper's solver: Verlet integration + Jacobi-averaged distance constraints + terrain collision.

    Args:
        model: the model to simulate.
        iterations: constraint iterations per step (paper: 40-55; default 55).
        relaxation: over-relaxation factor on the averaged correction (1.0 = the paper; < 2).
        chebyshev: estimated spectral radius ``rho`` in [0, 1) of one Jacobi iteration for Chebyshev
            semi-iterative acceleration (Wang 2015); 0 = plain Jacobi, the paper. Same cost per iteration.
        mass_splitting: split each particle's mass over its sticks so that constraints conserve momentum
            between particles of different mass or stick count (see :mod:`warpsim.kernels.constraints`);
            False = the paper's plain average.
        damping: fraction of the velocity removed per step (0 = none, the paper).
        air: :class:`AirSettings`. ground: :class:`GroundSettings`.
        use_graph: capture the step as a graph and replay it (default); False launches kernel by kernel.
        constraint_scheme: ``"fused"``, ``"scatter"`` or ``"gather"``
            (:class:`~warpsim.kernels.constraints.StickProjector`); None = fused on the CPU, gather on CUDA.
    """

    def __init__(
        self,
        model: Model,
        iterations: int = 55,
        relaxation: float = 1.0,
        damping: float = 0.0,
        air: AirSettings | None = None,
        ground: GroundSettings | None = None,
        use_graph: bool = True,
        chebyshev: float = 0.95,
        mass_splitting: bool = False,
        constraint_scheme: str | None = None,
    ):
        super().__init__(model, air, ground, use_graph)
        if not 0.0 <= chebyshev < 1.0:
            raise ValueError(f"chebyshev (spectral radius estimate) must be in [0, 1), got {chebyshev}")
        if int(iterations) != iterations or iterations < 1:
            raise ValueError(f"iterations must be a whole number >= 1, got {iterations}")
        if not 0.0 < relaxation < 2.0:
            raise ValueError(f"relaxation must be in (0, 2), got {relaxation}")
        if not 0.0 <= damping < 1.0:
            raise ValueError(f"damping must be in [0, 1), got {damping}")
        self.iterations = int(iterations)
        self.relaxation = float(relaxation)
        self.damping = float(damping)
        self.chebyshev = float(chebyshev)
        self.mass_splitting = bool(mass_splitting)
        self.projector = StickProjector(model, self.relaxation, self.mass_splitting, self.chebyshev, constraint_scheme)
        self.projector.prepare(self.iterations)  # before any graph capture

    def _launch(self, state: State, control: Control, dt: float) -> None:
        m = self.model
        triangle_air_force(m, state, control, dt, self.air, self.tri_force)
        integrate_verlet(m, state, control, self.tri_force, dt, self.damping)
        self.projector.project(state, control, self.iterations)
        collide_heightfield(m, state, self.ground.mode, self.ground.friction)


class SolverEuler(_Solver):
    """The paper's comparison: explicit Euler on a mass-spring network (every stick is a spring).

    Args:
        model: the model to simulate.
        stiffness: spring constant ``k`` [N/m] of every stick.
        damping: spring damping ``c`` [N s/m].
        air, ground, use_graph: as for :class:`SolverVerlet`.
    """

    def __init__(
        self,
        model: Model,
        stiffness: float = 2000.0,
        damping: float = 1.0,
        air: AirSettings | None = None,
        ground: GroundSettings | None = None,
        use_graph: bool = True,
    ):
        super().__init__(model, air, ground, use_graph)
        if not stiffness > 0.0:
            raise ValueError(f"spring stiffness must be positive, got {stiffness}")
        if not damping >= 0.0:
            raise ValueError(f"spring damping must be >= 0, got {damping}")
        self.stiffness = float(stiffness)
        self.damping = float(damping)
        self.spring_force = wp.zeros(max(model.stick_count, 1), dtype=wp.vec3, device=model.device)

    def _launch(self, state: State, control: Control, dt: float) -> None:
        m = self.model
        triangle_air_force(m, state, control, dt, self.air, self.tri_force)
        integrate_euler_springs(m, state, control, self.tri_force, self.spring_force, dt, self.stiffness, self.damping)
        collide_heightfield(m, state, self.ground.mode, self.ground.friction)
