"""Euler mass-spring integration: the paper's comparison method (slides 7-8, Fig. 4).

Every stick is a spring of stiffness ``k`` [N/m] and damping ``c`` [N s/m]. With ``L = x_b - x_a``,
``l = |L|`` and ``V = v_b - v_a`` the spring pulls end a with ``F = L/l * (k (l - r) + c (V.L)/l)``
and end b with ``-F`` (slide 8, signs made explicit). Explicit Euler as in Fig. 4: the position
moves with the old velocity, then the velocity takes the new acceleration.

The state stays in the Verlet form (``x``, ``x_prev``) so both solvers share one ``State``: the
velocity is ``(x - x_prev)/dt`` and the step writes ``x_prev = x_new - v_new dt``.
"""

from __future__ import annotations

import warp as wp

from .aero import gather_air_force
from .constraints import gather_stick_values
from .nails import pin_to_nail

wp.set_module_options({"enable_backward": False})  # forward-only: halves compile time


@wp.kernel
def _spring_forces(
    stick_particles: wp.array(dtype=wp.vec2i),
    stick_rest: wp.array(dtype=wp.float32),
    particle_q: wp.array(dtype=wp.vec3d),
    particle_q_prev: wp.array(dtype=wp.vec3d),
    dt: float,
    stiffness: float,
    damping: float,
    spring_force_out: wp.array(dtype=wp.vec3),
):
    s = wp.tid()
    ends = stick_particles[s]
    L = wp.vec3(particle_q[ends[1]] - particle_q[ends[0]])  # float64 ends, float32 difference
    length = wp.length(L)
    if length == 0.0:
        spring_force_out[s] = wp.vec3(0.0)
        return
    moved = (particle_q[ends[1]] - particle_q_prev[ends[1]]) - (particle_q[ends[0]] - particle_q_prev[ends[0]])
    V = wp.vec3(moved) / dt
    f = stiffness * (length - stick_rest[s]) + damping * wp.dot(V, L) / length
    spring_force_out[s] = L * (f / length)


@wp.kernel
def _integrate_euler(
    particle_inv_mass: wp.array(dtype=wp.float32),
    particle_nail: wp.array(dtype=wp.int32),
    particle_tri_start: wp.array(dtype=wp.int32),
    particle_tri_ids: wp.array(dtype=wp.int32),
    particle_stick_start: wp.array(dtype=wp.int32),
    particle_stick_refs: wp.array(dtype=wp.int32),
    nail_target: wp.array(dtype=wp.vec3d),
    tri_force: wp.array(dtype=wp.vec3),
    particle_air: wp.array(dtype=wp.vec3),
    spring_force: wp.array(dtype=wp.vec3),
    gravity: wp.vec3,
    dt: float,
    particle_q_out: wp.array(dtype=wp.vec3d),
    particle_q_prev_out: wp.array(dtype=wp.vec3d),
):
    i = wp.tid()
    x = particle_q_out[i]
    if pin_to_nail(i, particle_nail, nail_target, particle_q_out):
        particle_q_prev_out[i] = x
        return
    inv_mass = particle_inv_mass[i]
    if inv_mass == 0.0:
        particle_q_prev_out[i] = x
        return
    force = gather_air_force(i, particle_tri_start, particle_tri_ids, tri_force) + particle_air[i]
    force += gather_stick_values(i, particle_stick_start, particle_stick_refs, spring_force)
    step = wp.float64(dt)
    velocity = (x - particle_q_prev_out[i]) / step  # float64, as the positions
    x_new = x + velocity * step
    velocity_new = velocity + wp.vec3d((gravity + force * inv_mass) * dt)
    particle_q_out[i] = x_new
    particle_q_prev_out[i] = x_new - velocity_new * step


def integrate_euler_springs(
    model,
    state,
    control,
    tri_force: wp.array,
    particle_air: wp.array,
    spring_force: wp.array,
    dt: float,
    stiffness: float,
    damping: float,
) -> None:
    """One explicit-Euler mass-spring step of ``dt`` seconds (in place) under the triangles' air forces
    ``tri_force`` and the drag bodies' ``particle_air`` [N]; scratch arrays owned by the caller."""
    if model.stick_count:
        wp.launch(
            _spring_forces,
            dim=model.stick_count,
            inputs=[
                model.stick_particles,
                control.stick_rest,
                state.particle_q,
                state.particle_q_prev,
                float(dt),
                float(stiffness),
                float(damping),
            ],
            outputs=[spring_force],
            device=model.device,
        )
    wp.launch(
        _integrate_euler,
        dim=model.particle_count,
        inputs=[
            model.particle_inv_mass,
            model.particle_nail,
            model.particle_tri_start,
            model.particle_tri_ids,
            model.particle_stick_start,
            model.particle_stick_refs,
            control.nail_target,
            tri_force,
            particle_air,
            spring_force,
            model.gravity,
            float(dt),
        ],
        outputs=[state.particle_q, state.particle_q_prev],
        device=model.device,
    )
