"""Worlds stepped by threads: a batch cut into groups of consecutive worlds, one per thread.

Each :class:`WorldGroup` has its own model (built from its worlds' descriptors, numbered from 0), solver, frame
probe and frame graphs, on views of the whole simulation's state and control arrays, so that inputs, checkpoints
and frames see every world in one array and nothing is copied when the threads meet. Warp's CPU kernel launches
and graph replays are calls through ``ctypes`` that release the GIL, so the groups' replays run at the same time
on separate cores. A world computes exactly what it computes alone, so the frames are bit for bit those of one
thread.
"""

from __future__ import annotations

import concurrent.futures
import itertools
import weakref
from collections.abc import Callable

import numpy as np

from ..physics.kernels import frame as frame_kernels
from ..physics.model import Control, State
from ..physics.solver import make_solver
from .diagnostics import GroundContacts


class WorldGroup:
    """Consecutive worlds of a simulation that one thread steps (see the module's docstring)."""

    def __init__(self, model, state: State, control: Control, solver, probe: frame_kernels.FrameProbe):
        self.model, self.state, self.control, self.solver, self.probe = model, state, control, solver, probe
        self.graphs = None  # (slot 0, slot 1) frame graphs, when the solver replays graphs
        self.prepared = False  # the solver's one-step graph is captured (Simulation.step)


def split_worlds(sim, threads: int, where: str) -> list[WorldGroup]:
    """Cut the worlds of :class:`~warpsim.run.simulation.Simulation` ``sim`` into at most ``threads`` groups of
    consecutive worlds, as even in size as they can be (one group on a GPU, which steps every world in one launch).
    One group is the simulation's own model, state, control and solver.

    Raises ``RuntimeError`` when the worlds are not laid out one after another in the whole model (the groups'
    views need each world's particles, sticks and triangles in one run, in order).
    """
    count = max(1, min(int(threads), sim.world_count)) if sim.model.device.is_cpu else 1
    if count == 1:
        probe = frame_kernels.FrameProbe(sim.model, sim.contacts.owners())
        return [WorldGroup(sim.model, sim.state, sim.control, sim.solver, probe)]
    cfg, whole, groups = sim.settings, sim.model, []
    bounds = [sim.world_count * k // count for k in range(count + 1)]
    p = s = t = n = 0  # where the group's particles, sticks, triangles and nails start in the whole model
    for first, end in itertools.pairwise(bounds):
        model = sim.scene.build_model(whole.device, where, terrain=whole.terrain, worlds=range(first, end))
        if not (
            np.array_equal(model.stick_particles_np + p, whole.stick_particles_np[s : s + model.stick_count])
            and np.array_equal(model.tri_indices_np + p, whole.tri_indices_np[t : t + model.tri_count])
        ):
            raise RuntimeError(f"worlds {first}-{end - 1} are not laid out one after another: cannot thread them")
        state = State(
            particle_q=sim.state.particle_q[p : p + model.particle_count],
            particle_q_prev=sim.state.particle_q_prev[p : p + model.particle_count],
        )
        c = sim.control
        control = Control(
            stick_rest=c.stick_rest[s : s + model.stick_count],
            stick_rest_target=c.stick_rest_target[s : s + model.stick_count],
            nail_target=c.nail_target[n : n + model.nail_count] if model.nail_count else None,
            nail_target_goal=c.nail_target_goal[n : n + model.nail_count] if model.nail_count else None,
            wind=c.wind[first:end],
            air_density=c.air_density[first:end],
            turbulence=c.turbulence.view(first, end),
            gusts=None if c.gusts is None else c.gusts.view(first, end),
        )
        if control.nail_target is None:  # a model without nails keeps one unused target
            unused = model.control()
            control.nail_target, control.nail_target_goal = unused.nail_target, unused.nail_target_goal
        solver = make_solver(
            model, cfg.solver, air=cfg.air, wind=cfg.wind, ground=cfg.ground, use_graph=sim.solver.use_graph
        )
        if model.tri_count:  # readers of sim.solver.tri_force (figures) see every group's air forces
            solver.tri_force = sim.solver.tri_force[t : t + model.tri_count]
        probe = frame_kernels.FrameProbe(model, GroundContacts(model).owners())
        groups.append(WorldGroup(model, state, control, solver, probe))
        p, s, t = p + model.particle_count, s + model.stick_count, t + model.tri_count
        n += model.nail_count
    return groups


class GroupThreads:
    """The threads that step a simulation's groups: the first group on the caller's thread, each other on a thread
    of its own pool (shut down when ``owner`` is collected)."""

    def __init__(self, groups: list[WorldGroup], owner):
        self.groups = groups
        self.pool = None
        if len(groups) > 1:
            self.pool = concurrent.futures.ThreadPoolExecutor(len(groups) - 1, thread_name_prefix="warpsim-group")
            weakref.finalize(owner, self.pool.shutdown, wait=False)

    def each(self, work: Callable[[WorldGroup], None]) -> None:
        """Call ``work(group)`` for every group, each on its own thread, and return when all are done, also when
        this thread is interrupted (no thread is left writing the state); a thread's error is raised here."""
        first, *rest = self.groups
        if self.pool is None:
            work(first)
            return
        others = [self.pool.submit(work, group) for group in rest]
        try:
            work(first)
        finally:
            concurrent.futures.wait(others)
        for done in others:
            done.result()
