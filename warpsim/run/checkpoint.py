"""The state that decides a run's future, as typed arrays: what a recording stores to be continued exactly.

A :class:`Checkpoint` holds the particles, the control arrays, the gust processes of every world and the
controls in force, each as a fixed-shape NumPy array (sizes known when the scene is built), so that a
recording can reserve its place once and overwrite it in place, and a reader can check every field's shape
and type and a digest of the whole before trusting it.
"""

from __future__ import annotations

import dataclasses
import hashlib

import numpy as np

from ..scene.controls import UNIT_CONTROLS, VECTOR_CONTROLS

DIGEST_BYTES = 32  # sha256


@dataclasses.dataclass
class Checkpoint:
    """Everything needed to continue a run bit for bit (``N`` particles, ``M`` sticks, ``W`` worlds,
    ``C`` controls the scene accepts, named by ``control_names``).

    Attributes:
        q: ``[N, 3]`` float64 positions [m].
        q_prev: ``[N, 3]`` float64 positions one step earlier [m] (Verlet's implicit velocity).
        time: ``[1]`` float64 simulated time [s].
        steps: ``[1]`` int64 solver steps taken since the scene started.
        stick_rest: ``[M]`` float32 current rest lengths [m] (the pilot's control sticks change).
        stick_rest_target: ``[M]`` float32 rest lengths [m] the control sticks are ramping to.
        nail_target: ``[N, 3]`` float64 where each nailed particle is held [m] (the kite's anchor moves).
        nail_target_goal: ``[N, 3]`` float64 where the controlled nails are moving to [m].
        canopy_side: ``[max(K, 1), 3]`` float32 the lagged side force [Pa] of each of the ``K`` parachute canopies
            (:mod:`warpsim.physics.kernels.canopy`; zeros without canopies).
        vortex_state: ``[1 + 16 V + 4 S]`` float32 the vortex law's step counter, then the inputs of its latest
            factorisations for the ``V`` panels and ``S`` surfaces of every world, in world order: corners, centroids,
            normals, wakes (:meth:`warpsim.physics.kernels.vortex.VortexScratch.save`; ``[1]`` without lifting
            surfaces), from which a resumed run factorises again, whatever its threads.
        vortex_wake: ``[1 + ...]`` float64 the shed wake's counter, then for every world its rows' points [m], its
            rings' circulations, its smoothed rates and its panels' circulations
            (:meth:`warpsim.physics.kernels.wake.ShedWake.save`; ``[1]`` without a shed wake).
        wind: ``[W, 3]`` float32 current wind of each world [m/s].
        gust_active: ``[W]`` uint8, 1 where the world has gusts.
        gust_g: ``[W, 3]`` float64 the gust processes' current values (dimensionless).
        gust_mean: ``[W, 3]`` float32 the mean wind the gusts blow around [m/s].
        gust_step: ``[W]`` int32 the gust processes' step counts (the counters of their random numbers).
        turbulence_shift: ``[W, 3]`` float64 where each world is in the scene's turbulence field [m] (zeros without).
        control_set: ``[C]`` uint8, 1 where the control has been set (is in force).
        control_value: ``[C, 3]`` float64 value in force (scalars in column 0; NaN padding).
        scheduled_set: ``[C]`` uint8, 1 where the schedule has set the control.
        scheduled_value: ``[C, 3]`` float64 the schedule's last value (so that held values are not set again).
        control_names: the ``C`` control names (not an array; fixed by the scene).
    """

    q: np.ndarray
    q_prev: np.ndarray
    time: np.ndarray
    steps: np.ndarray
    stick_rest: np.ndarray
    stick_rest_target: np.ndarray
    nail_target: np.ndarray
    nail_target_goal: np.ndarray
    canopy_side: np.ndarray
    vortex_state: np.ndarray
    vortex_wake: np.ndarray
    wind: np.ndarray
    gust_active: np.ndarray
    gust_g: np.ndarray
    gust_mean: np.ndarray
    gust_step: np.ndarray
    turbulence_shift: np.ndarray
    control_set: np.ndarray
    control_value: np.ndarray
    scheduled_set: np.ndarray
    scheduled_value: np.ndarray
    control_names: tuple[str, ...] = ()

    def arrays(self) -> dict[str, np.ndarray]:
        """The array fields by name, in a fixed order (what a recording stores)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name != "control_names"}

    def digest(self, frame: int) -> np.ndarray:
        """sha256 of ``frame``, the control names and every array's dtype, shape and bytes: ``[32]`` uint8."""
        h = hashlib.sha256()
        h.update(np.int64(frame).tobytes())
        h.update("\0".join(self.control_names).encode())
        for name, a in self.arrays().items():
            a = np.ascontiguousarray(a)
            h.update(f"{name}:{a.dtype.str}:{a.shape}".encode())
            h.update(a.tobytes())
        return np.frombuffer(h.digest(), dtype=np.uint8).copy()

    def check_like(self, other: Checkpoint) -> None:
        """Raise ``ValueError`` naming the first field whose shape or dtype differs from ``other``'s."""
        if tuple(self.control_names) != tuple(other.control_names):
            raise ValueError(f"controls {list(self.control_names)} differ from the scene's {list(other.control_names)}")
        for name, a in self.arrays().items():
            b = getattr(other, name)
            if a.shape != b.shape or a.dtype != b.dtype:
                raise ValueError(
                    f"checkpoint field {name} is {a.dtype}{list(a.shape)}, expected {b.dtype}{list(b.shape)}"
                )
        if not (np.isfinite(self.q).all() and np.isfinite(self.q_prev).all() and np.isfinite(self.time).all()):
            raise ValueError("checkpoint positions or time are not finite")
        if not all(np.isfinite(a).all() for a in (self.gust_g, self.gust_mean, self.turbulence_shift)):
            raise ValueError("checkpoint gusts or turbulence are not finite")
        if not (np.isfinite(self.vortex_state).all() and np.isfinite(self.vortex_wake).all()):
            raise ValueError("checkpoint vortex lattice or wake is not finite")
        if not (0 <= self.vortex_state[0] <= 2**24 and 0 <= self.vortex_wake[0] <= 2**24):
            raise ValueError("checkpoint vortex counters are out of range")
        if (self.gust_step < 0).any():
            raise ValueError("checkpoint gust step counts are negative")
        if not 0 <= self.steps[0] <= MAX_STEPS:
            raise ValueError(f"checkpoint step count {self.steps[0]} is outside 0..{MAX_STEPS}")

    def check_time(self, dt: float) -> None:
        """Raise ``ValueError`` unless the time is the step count's at ``dt`` [s] (to the rounding of summing the
        steps): a crafted time (1e300) would be accepted and make the recording unreadable afterwards."""
        expected = float(self.steps[0]) * float(dt)
        if not abs(float(self.time[0]) - expected) <= 1e-6 * expected + dt:
            raise ValueError(
                f"checkpoint time {float(self.time[0]):.6g} s is not its {int(self.steps[0])} steps of {dt:g} s"
            )


def pack_controls(names: tuple[str, ...], values: dict) -> tuple[np.ndarray, np.ndarray]:
    """Controls by name (floats, or tuples for vectors) as ``([C] set flags, [C, 3] values)``."""
    flags = np.zeros(len(names), dtype=np.uint8)
    table = np.full((len(names), 3), np.nan, dtype=np.float64)
    for k, name in enumerate(names):
        if name in values:
            flags[k] = 1
            v = np.atleast_1d(np.asarray(values[name], dtype=np.float64))
            table[k, : len(v)] = v
    return flags, table


def unpack_controls(names: tuple[str, ...], flags: np.ndarray, table: np.ndarray) -> dict:
    """The controls dict of a :func:`pack_controls` pair (floats for unit controls, tuples for vectors)."""
    out = {}
    for k, name in enumerate(names):
        if not flags[k]:
            continue
        if name in UNIT_CONTROLS:
            out[name] = float(table[k, 0])
        else:
            out[name] = tuple(float(v) for v in table[k, : VECTOR_CONTROLS[name]])
    return out


MAX_STEPS = 2**53
"""The most solver steps a checkpoint may count (exact in float64; centuries of simulated time at 1 ms)."""


def take_checkpoint(sim) -> Checkpoint:
    """The :class:`Checkpoint` of :class:`~warpsim.run.simulation.Simulation` ``sim`` as it is now (host copies)."""
    c = sim.control
    return Checkpoint(
        q=sim.state.particle_q.numpy().copy(),
        q_prev=sim.state.particle_q_prev.numpy().copy(),
        time=np.array([sim.state.time], dtype=np.float64),
        steps=np.array([sim.steps_taken], dtype=np.int64),
        stick_rest=c.stick_rest.numpy().copy(),
        stick_rest_target=c.stick_rest_target.numpy().copy(),
        nail_target=c.nail_target.numpy().copy(),
        nail_target_goal=c.nail_target_goal.numpy().copy(),
        canopy_side=canopy_sides(sim),
        vortex_state=vortex_states(sim),
        vortex_wake=wake_states(sim),
        wind=c.wind.numpy().copy(),
        **sim.inputs.save(),
        control_names=sim.inputs.names,
    )


def restore_checkpoint(sim, checkpoint: Checkpoint) -> None:
    """Put ``checkpoint`` (already checked to fit, :meth:`Checkpoint.check_like`) back into ``sim``'s state,
    control arrays, canopies and inputs."""
    sim.state.particle_q.assign(checkpoint.q)
    sim.state.particle_q_prev.assign(checkpoint.q_prev)
    sim.state.time = float(checkpoint.time[0])
    sim.steps_taken = int(checkpoint.steps[0])
    c = sim.control
    c.stick_rest.assign(checkpoint.stick_rest)
    c.stick_rest_target.assign(checkpoint.stick_rest_target)
    c.nail_target.assign(checkpoint.nail_target)
    c.nail_target_goal.assign(checkpoint.nail_target_goal)
    c.wind.assign(checkpoint.wind)
    k = 0
    for group in sim.groups:  # each group's solver holds its canopies' lagged side forces
        count = group.model.canopy_count
        if count:
            side = group.solver.canopy_side.numpy()
            side[:count] = checkpoint.canopy_side[k : k + count]
            group.solver.canopy_side.assign(side)
            k += count
    groups = [g for g in sim.groups if g.solver.vortex is not None]  # and the lifting surfaces' factors
    if groups:
        sizes = [g.solver.vortex.sizes() for g in groups]
        counter, parts = _unpack(checkpoint.vortex_state, sizes)
        for group, basis in zip(groups, parts, strict=True):
            group.solver.vortex.load(group.model, counter, basis)
    groups = [g for g in groups if g.solver.vortex.shed is not None]  # and their shed wakes
    if groups:
        sizes = [g.solver.vortex.shed.sizes(g.solver.vortex.gamma) for g in groups]
        counter, parts = _unpack(checkpoint.vortex_wake, sizes)
        for group, state in zip(groups, parts, strict=True):
            group.solver.vortex.shed.load(counter, state, group.solver.vortex.gamma)
    sim.inputs.load(checkpoint)


def canopy_sides(sim) -> np.ndarray:
    """``[max(K, 1), 3]`` float32 the lagged side force [Pa] of every canopy, from the groups' solvers."""
    groups = [g for g in sim.groups if g.model.canopy_count]
    sides = [g.solver.canopy_side.numpy()[: g.model.canopy_count] for g in groups]
    return np.concatenate(sides).astype(np.float32) if sides else np.zeros((1, 3), dtype=np.float32)


def _pack(saved: list[tuple[int, list[np.ndarray]]], dtype) -> np.ndarray:
    """One array of the groups' ``(counter, arrays)``: the counter, then each kind of array for every group in world
    order (so that the layout does not depend on how the worlds are split into groups)."""
    if not saved:
        return np.zeros(1, dtype=dtype)
    kinds = zip(*(arrays for _, arrays in saved), strict=True)
    return np.concatenate([np.array([saved[0][0]], dtype=dtype), *(a.astype(dtype) for kind in kinds for a in kind)])


def _unpack(packed: np.ndarray, sizes: list[list[int]]) -> tuple[int, list[list[np.ndarray]]]:
    """The counter and each group's arrays of a :func:`_pack` (``sizes``: each group's array lengths)."""
    k, parts = 1, [[] for _ in sizes]
    for kind in range(len(sizes[0])):
        for g, size in enumerate(sizes):
            parts[g].append(packed[k : k + size[kind]])
            k += size[kind]
    return int(packed[0]), parts


def vortex_states(sim) -> np.ndarray:
    """The checkpoint's ``vortex_state`` (see :class:`Checkpoint`) of every group with lifting surfaces."""
    return _pack([g.solver.vortex.save() for g in sim.groups if g.solver.vortex is not None], np.float32)


def wake_states(sim) -> np.ndarray:
    """The checkpoint's ``vortex_wake`` (see :class:`Checkpoint`) of every group with a shed wake."""
    vortices = [g.solver.vortex for g in sim.groups if g.solver.vortex is not None and g.solver.vortex.shed is not None]
    return _pack([v.shed.save(v.gamma) for v in vortices], np.float64)
