"""Distance constraints (sticks) solved by Jacobi iterations with per-particle averaged corrections.

Paper Section 4, Fig. 8 and slide 12, made mass-weighted: in one iteration every stick ``s = (a, b)``
of rest length ``r`` measures ``d = x_b - x_a`` and proposes

    dx_a = +w_a / (w_a + w_b) * (|d| - r) * d / |d|,    dx_b = -w_b / (w_a + w_b) * (|d| - r) * d / |d|

(``w`` = inverse mass; equal masses give the paper's factor 0.5). Then every particle moves by the
*average* of the corrections it received, times an over-relaxation factor (1.0 = the paper), and
nailed particles are put back on their nails. Reading only the previous iterate makes the result
independent of the order of the stick list; the per-particle gather runs in a fixed order, so the
same input gives bit-identical output.

Two kernels per iteration: one thread per stick writes ``stick_delta = d (|d| - r) / (|d| (w_a + w_b))``,
then one thread per particle sums the deltas of its sticks through a CSR adjacency (no atomics).
"""

from __future__ import annotations

import warp as wp

wp.set_module_options({"enable_backward": False})  # forward-only: halves compile time


@wp.func
def gather_stick_values(
    i: int,
    particle_stick_start: wp.array(dtype=wp.int32),
    particle_stick_refs: wp.array(dtype=wp.int32),
    stick_value: wp.array(dtype=wp.vec3),
) -> wp.vec3:
    """Signed sum over the sticks of particle ``i``: ``+value`` where ``i`` is end a, ``-value`` where end b.

    ``particle_stick_refs`` holds ``2 * stick + end`` (end 0 = a, 1 = b).
    """
    total = wp.vec3(0.0)
    for k in range(particle_stick_start[i], particle_stick_start[i + 1]):
        ref = particle_stick_refs[k]
        value = stick_value[ref >> 1]
        if (ref & 1) == 0:
            total += value
        else:
            total -= value
    return total


@wp.kernel
def _stick_deltas(
    stick_particles: wp.array(dtype=wp.vec2i),
    particle_inv_mass: wp.array(dtype=wp.float32),
    stick_rest: wp.array(dtype=wp.float32),
    particle_q: wp.array(dtype=wp.vec3),
    stick_delta_out: wp.array(dtype=wp.vec3),
):
    s = wp.tid()
    ends = stick_particles[s]
    w = particle_inv_mass[ends[0]] + particle_inv_mass[ends[1]]
    d = particle_q[ends[1]] - particle_q[ends[0]]
    length = wp.length(d)
    if w == 0.0 or length == 0.0:
        stick_delta_out[s] = wp.vec3(0.0)
        return
    stick_delta_out[s] = d * ((length - stick_rest[s]) / (length * w))


@wp.kernel
def _apply_averaged_corrections(
    particle_stick_start: wp.array(dtype=wp.int32),
    particle_stick_refs: wp.array(dtype=wp.int32),
    particle_inv_mass: wp.array(dtype=wp.float32),
    particle_nail: wp.array(dtype=wp.int32),
    nail_target: wp.array(dtype=wp.vec3),
    stick_delta: wp.array(dtype=wp.vec3),
    relaxation: float,
    particle_q: wp.array(dtype=wp.vec3),
):
    i = wp.tid()
    nail = particle_nail[i]
    if nail >= 0:
        particle_q[i] = nail_target[nail]
        return
    start = particle_stick_start[i]
    count = particle_stick_start[i + 1] - start
    inv_mass = particle_inv_mass[i]
    if count == 0 or inv_mass == 0.0:
        return
    total = gather_stick_values(i, particle_stick_start, particle_stick_refs, stick_delta)
    particle_q[i] = particle_q[i] + total * (relaxation * inv_mass / float(count))


def project_sticks(model, state, control, iterations: int, relaxation: float, stick_delta: wp.array) -> None:
    """Run ``iterations`` Jacobi iterations on ``state.particle_q`` in place.

    ``stick_delta`` is a scratch array of shape ``[stick_count]`` (vec3) owned by the caller.
    Rest lengths come from ``control.stick_rest`` so that control sticks can change while running.
    """
    if model.stick_count == 0:
        return
    for _ in range(iterations):
        wp.launch(
            _stick_deltas,
            dim=model.stick_count,
            inputs=[model.stick_particles, model.particle_inv_mass, control.stick_rest, state.particle_q],
            outputs=[stick_delta],
            device=model.device,
        )
        wp.launch(
            _apply_averaged_corrections,
            dim=model.particle_count,
            inputs=[
                model.particle_stick_start,
                model.particle_stick_refs,
                model.particle_inv_mass,
                model.particle_nail,
                control.nail_target,
                stick_delta,
                float(relaxation),
            ],
            outputs=[state.particle_q],
            device=model.device,
        )
