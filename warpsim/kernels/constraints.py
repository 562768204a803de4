"""Distance constraints (sticks) solved by Jacobi iterations with per-particle averaged corrections.

Paper Section 4, Fig. 8 and slide 12, made mass-weighted. In one iteration every stick ``s = (a, b)``
of rest length ``r`` measures ``d = x_b - x_a``; every particle then moves by the *average* of the
corrections its sticks propose (times an over-relaxation factor, 1.0 = the paper), and nailed
particles are put back on their nails. Reading only the previous iterate makes the result independent
of the order of the stick list; the per-particle gather runs in a fixed order, so the same input gives
bit-identical output.

Mass weighting uses *split masses* (Tonge et al. 2012, "Mass splitting for jitter-free parallel rigid
body simulation"): a particle of inverse mass ``w_a`` with ``n_a`` sticks lends each stick the mass
``m_a / n_a``, each stick splits its error between its ends by those split masses, and each particle
averages what it received:

    dx_a = (1 / n_a) * sum_s  n_a w_a / (n_a w_a + n_b w_b) * (|d| - r) * d / |d|
         = w_a * sum_s (|d| - r) d / (|d| (n_a w_a + n_b w_b))

For equal masses and stick counts this is exactly the paper's plain average with factor 0.5; unlike a
plain average of ``w_a / (w_a + w_b)`` shares it conserves momentum when neighbours differ in mass or
in number of sticks (a heavy pilot on a light frame, a cloth edge on a spar), so constraints never
push an object as a whole. A stick of weight ``k`` counts exactly as ``k`` identical sticks (``n`` is
the sum of the weights), the paper's way of stiffening its kite rope ("des tiges ont été doublées",
Section 7.2) without the cost of a second stick.

Two kernels per iteration: one thread per stick writes
``stick_delta = k d (|d| - r) / (|d| (n_a w_a + n_b w_b))``, then one thread per particle sums the
deltas of its sticks through a CSR adjacency (no atomics) and multiplies by ``w_a``.
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
    particle_share: wp.array(dtype=wp.float32),
    stick_rest: wp.array(dtype=wp.float32),
    stick_weight: wp.array(dtype=wp.float32),
    particle_q: wp.array(dtype=wp.vec3),
    stick_delta_out: wp.array(dtype=wp.vec3),
):
    s = wp.tid()
    ends = stick_particles[s]
    a = ends[0]
    b = ends[1]
    w = particle_share[a] + particle_share[b]
    d = particle_q[b] - particle_q[a]
    length = wp.length(d)
    if w == 0.0 or length == 0.0:
        stick_delta_out[s] = wp.vec3(0.0)
        return
    stick_delta_out[s] = d * (stick_weight[s] * (length - stick_rest[s]) / (length * w))


@wp.kernel
def _apply_averaged_corrections(
    particle_stick_start: wp.array(dtype=wp.int32),
    particle_stick_refs: wp.array(dtype=wp.int32),
    particle_scale: wp.array(dtype=wp.float32),
    particle_nail: wp.array(dtype=wp.int32),
    nail_target: wp.array(dtype=wp.vec3),
    stick_delta: wp.array(dtype=wp.vec3),
    relaxation: float,
    omega: float,
    particle_q: wp.array(dtype=wp.vec3),
    particle_q_iter: wp.array(dtype=wp.vec3),
):
    i = wp.tid()
    nail = particle_nail[i]
    if nail >= 0:
        particle_q[i] = nail_target[nail]
        return
    scale = particle_scale[i]
    if scale == 0.0:
        return
    total = gather_stick_values(i, particle_stick_start, particle_stick_refs, stick_delta)
    x = particle_q[i]
    y = x + total * (relaxation * scale)
    if omega != 1.0:
        older = particle_q_iter[i]
        y = older + (y - older) * omega
    particle_q_iter[i] = x
    particle_q[i] = y


def chebyshev_weights(iterations: int, rho: float, delay: int = 10) -> list[float]:
    """Chebyshev semi-iterative weights ``omega_k`` (Wang 2015) for ``iterations`` Jacobi iterations.

    ``rho`` in [0, 1) is the estimated spectral radius of one Jacobi iteration; 0 returns all ones (plain
    Jacobi, the paper). The first ``delay`` iterations stay plain, as Wang recommends.
    """
    weights = []
    omega = 1.0
    for k in range(iterations):
        if rho <= 0.0 or k < delay:
            omega = 1.0
        elif k == delay:
            omega = 2.0 / (2.0 - rho * rho)
        else:
            omega = 4.0 / (4.0 - rho * rho * omega)
        weights.append(omega)
    return weights


def project_sticks(
    model,
    state,
    control,
    iterations: int,
    relaxation: float,
    stick_delta: wp.array,
    q_iter: wp.array | None = None,
    weights: tuple[wp.array, wp.array] | None = None,
    chebyshev: float = 0.0,
) -> None:
    """Run ``iterations`` Jacobi iterations on ``state.particle_q`` in place.

    ``stick_delta`` (``[stick_count]`` vec3) and ``q_iter`` (``[particle_count]`` vec3) are scratch arrays
    owned by the caller; ``weights`` is ``model.constraint_weights(mass_splitting)`` (default: the
    paper's plain average); ``chebyshev`` is the spectral-radius estimate of :func:`chebyshev_weights`.
    Rest lengths come from ``control.stick_rest`` so that control sticks can change while running.
    Passing ``None`` allocates (fine for a one-off call, not inside a captured step).
    """
    if model.stick_count == 0:
        return
    if q_iter is None:
        q_iter = wp.zeros(model.particle_count, dtype=wp.vec3, device=model.device)
    if weights is None:
        weights = model.constraint_weights(False)
    for omega in chebyshev_weights(iterations, chebyshev):
        wp.launch(
            _stick_deltas,
            dim=model.stick_count,
            inputs=[
                model.stick_particles,
                weights[0],
                control.stick_rest,
                model.stick_weight,
                state.particle_q,
            ],
            outputs=[stick_delta],
            device=model.device,
        )
        wp.launch(
            _apply_averaged_corrections,
            dim=model.particle_count,
            inputs=[
                model.particle_stick_start,
                model.particle_stick_refs,
                weights[1],
                model.particle_nail,
                control.nail_target,
                stick_delta,
                float(relaxation),
                float(omega),
            ],
            outputs=[state.particle_q, q_iter],
            device=model.device,
        )
