"""Frame bookkeeping on the device: what a run checks after every frame, without copying the state to the host.

Two kernels bracket the steps of a frame (and are captured in the same graph as them):

* ``_frame_begin`` clears the frame's report;
* ``_frame_measure`` writes the report: each world's worst stick stretch and count of non-finite particles, and
  each object's lowest clearance above the terrain; and it keeps a copy of the positions in one of two slots,
  so that the slot of the last good frame is still there when a frame turns out bad (a blow-up goes back to it).

The host reads the report, ``2 W + K`` floats, instead of the positions (``W`` worlds, ``K`` objects).
"""

from __future__ import annotations

import numpy as np
import warp as wp

from .collision import HeightfieldData, terrain_height

wp.set_module_options({"enable_backward": False})  # forward-only: halves compile time

NO_CONTACT = 1.0e30
"""Clearance [m] reported for an object with no particle that can touch the terrain."""


@wp.kernel
def _frame_begin(world_count: int, object_count: int, report_out: wp.array(dtype=wp.float32)):
    i = wp.tid()
    if i < world_count:
        report_out[i] = 0.0
        report_out[world_count + i] = 0.0
    if i < object_count:
        report_out[2 * world_count + i] = NO_CONTACT


@wp.func
def _finite(v: wp.vec3d) -> bool:
    return wp.isfinite(v[0]) and wp.isfinite(v[1]) and wp.isfinite(v[2])


@wp.kernel
def _frame_measure(
    hf: HeightfieldData,
    particle_q: wp.array(dtype=wp.vec3d),
    particle_q_prev: wp.array(dtype=wp.vec3d),
    particle_world: wp.array(dtype=wp.int32),
    particle_owner: wp.array(dtype=wp.int32),
    stick_particles: wp.array(dtype=wp.vec2i),
    stick_rest: wp.array(dtype=wp.float32),
    stick_pretension: wp.array(dtype=wp.float32),
    stick_world: wp.array(dtype=wp.int32),
    nail_target: wp.array(dtype=wp.vec3d),
    world_count: int,
    report_out: wp.array(dtype=wp.float32),
    snap_q_out: wp.array(dtype=wp.vec3d),
    snap_q_prev_out: wp.array(dtype=wp.vec3d),
    snap_rest_out: wp.array(dtype=wp.float32),
    snap_nail_out: wp.array(dtype=wp.vec3d),
):
    i = wp.tid()
    if i < nail_target.shape[0]:
        snap_nail_out[i] = nail_target[i]
    if i < particle_q.shape[0]:
        x = particle_q[i]
        snap_q_out[i] = x
        snap_q_prev_out[i] = particle_q_prev[i]
        if not (_finite(x) and _finite(x - particle_q_prev[i])):  # a position or a velocity
            wp.atomic_add(report_out, world_count + particle_world[i], 1.0)
        elif particle_owner[i] >= 0:
            clearance = float(x[2] - terrain_height(hf, x[0], x[1]))
            wp.atomic_min(report_out, 2 * world_count + particle_owner[i], clearance)
    if i < stick_particles.shape[0]:
        snap_rest_out[i] = stick_rest[i]
        ends = stick_particles[i]
        length = wp.length(wp.vec3(particle_q[ends[1]] - particle_q[ends[0]]))
        rest = wp.max(stick_rest[i], 1.0e-12)
        built = rest / (1.0 - stick_pretension[i])
        high = wp.max(rest, built)
        stretch = length / high - 1.0
        if stretch <= 0.0:  # a pretensioned stick between its rest length and its length as built shows none
            stretch = wp.max(1.0 - length / wp.min(rest, built), 0.0)
        if wp.isfinite(stretch):  # a NaN is counted by the particle check
            wp.atomic_max(report_out, stick_world[i], stretch)


class FrameProbe:
    """Device buffers and launches of the frame bookkeeping of one model (see the module's docstring).

    Args:
        model: the :class:`~warpsim.physics.model.Model`.
        owner: host ``[P]`` index of the object whose terrain contact each particle tells, -1 for particles whose
            contact is not news (nailed, or parts meant to lie on the ground).
    """

    def __init__(self, model, owner: np.ndarray):
        device = model.device
        self.model = model
        self.world_count = model.world_count
        self.object_count = len(model.objects)
        self.slots = [
            (
                *(wp.zeros(model.particle_count, dtype=wp.vec3d, device=device) for _ in range(2)),
                wp.zeros(max(model.stick_count, 1), dtype=wp.float32, device=device),
                wp.zeros(max(model.nail_count, 1), dtype=wp.vec3d, device=device),
            )
            for _ in range(2)
        ]  # per slot: (positions, previous positions, rest lengths, nail targets)
        self.report = wp.zeros(2 * self.world_count + max(self.object_count, 1), dtype=wp.float32, device=device)
        self.owner = wp.array(np.asarray(owner, dtype=np.int32), dtype=wp.int32, device=device)
        ends = model.stick_particles_np
        pretension = model.stick_pretension.astype(np.float32)
        self.stick_pretension = wp.array(pretension, dtype=wp.float32, device=device)
        world = model.particle_world_np
        self.stick_world = wp.array(world[ends[:, 0]] if len(ends) else np.zeros(0), dtype=wp.int32, device=device)
        self._host = self.report.numpy() if device.is_cpu else None  # a view: no copy to read it on the CPU

    def begin(self) -> None:
        """Clear the report."""
        wp.launch(
            _frame_begin,
            dim=max(self.world_count, self.object_count),
            inputs=[self.world_count, self.object_count],
            outputs=[self.report],
            device=self.model.device,
        )

    def measure(self, state, control, slot: int) -> None:
        """Write the report of ``state`` (stretches against ``control``'s rest lengths), after :meth:`begin`, and
        keep its positions in ``slot`` (0 or 1)."""
        m = self.model
        wp.launch(
            _frame_measure,
            dim=max(m.particle_count, m.stick_count),
            inputs=[
                m.terrain_data,
                state.particle_q,
                state.particle_q_prev,
                m.particle_world,
                self.owner,
                m.stick_particles,
                control.stick_rest,
                self.stick_pretension,
                self.stick_world,
                control.nail_target,
                self.world_count,
            ],
            outputs=[self.report, *self.slots[slot]],
            device=m.device,
        )

    def read(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The report on the host: ``([W] worst stick stretch, [W] non-finite particles, [K] lowest clearance [m]
        of each object's particles that can touch the terrain, :data:`NO_CONTACT` for none)``, new arrays."""
        report = self._host.copy() if self._host is not None else self.report.numpy()
        w = self.world_count
        return report[:w], report[w : 2 * w], report[2 * w : 2 * w + self.object_count]

    def kept(self, slot: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Host copies of the ``(positions, previous positions)`` ``[P, 3]`` [m], the rest lengths ``[M]`` [m] and
        the nail targets ``[max(N, 1), 3]`` [m] kept in ``slot``."""
        q, q_prev, rest, nails = (a.numpy().copy() for a in self.slots[slot])
        return q, q_prev, rest[: self.model.stick_count], nails
