"""Verlet integration (paper Section 3.2, slide 5): position and previous position, no velocity.

``x_new = x + (1 - damping) * (x - x_prev) + a * dt^2``, then ``x_prev = x``. (The paper's Fig. 5
prints ``2 * (x - x_prev)``; the correct step is the one above with damping 0, as on slide 5.)
``a`` is gravity plus the air force of the particle's triangles (and its own drag, for a drag body)
divided by its mass. Nailed
particles ignore forces and are placed on their nail.
"""

from __future__ import annotations

import warp as wp

from .aero import gather_air_force
from .nails import pin_to_nail

wp.set_module_options({"enable_backward": False})  # forward-only: halves compile time


@wp.kernel
def _integrate_verlet(
    particle_inv_mass: wp.array(dtype=wp.float32),
    particle_nail: wp.array(dtype=wp.int32),
    particle_tri_start: wp.array(dtype=wp.int32),
    particle_tri_ids: wp.array(dtype=wp.int32),
    nail_target: wp.array(dtype=wp.vec3d),
    tri_force: wp.array(dtype=wp.vec3),
    particle_air: wp.array(dtype=wp.vec3),
    gravity: wp.vec3,
    dt: float,
    damping: float,
    particle_q_out: wp.array(dtype=wp.vec3d),
    particle_q_prev_out: wp.array(dtype=wp.vec3d),
):
    i = wp.tid()
    x = particle_q_out[i]
    x_prev = particle_q_prev_out[i]
    particle_q_prev_out[i] = x
    if pin_to_nail(i, particle_nail, nail_target, particle_q_out):
        return
    inv_mass = particle_inv_mass[i]
    if inv_mass == 0.0:
        return
    force = gather_air_force(i, particle_tri_start, particle_tri_ids, tri_force) + particle_air[i]
    acceleration = gravity + force * inv_mass
    # float64 positions: the step's a dt^2 (1e-3 m at dt 0.01, 6e-5 m at 0.0025) is kept in full anywhere
    particle_q_out[i] = x + (x - x_prev) * (wp.float64(1.0) - wp.float64(damping)) + wp.vec3d(acceleration * (dt * dt))


def integrate_verlet(
    model, state, control, tri_force: wp.array, particle_air: wp.array, dt: float, damping: float
) -> None:
    """Advance ``state`` by one Verlet step of ``dt`` seconds (in place) under the triangles' air forces
    ``tri_force`` and the drag bodies' ``particle_air`` [N]."""
    wp.launch(
        _integrate_verlet,
        dim=model.particle_count,
        inputs=[
            model.particle_inv_mass,
            model.particle_nail,
            model.particle_tri_start,
            model.particle_tri_ids,
            control.nail_target,
            tri_force,
            particle_air,
            model.gravity,
            float(dt),
            float(damping),
        ],
        outputs=[state.particle_q, state.particle_q_prev],
        device=model.device,
    )
