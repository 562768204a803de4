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

Both ends share one per-stick factor ``c_s = k / (n_a w_a + n_b w_b)`` (computed once; 0 for a stick
between two immovable particles), so a stick's correction is ``c_s (|d| - r) d / |d|``.

Three schemes, one class each in :mod:`warpsim.physics.projection` (``FusedProjector``, ``ScatterProjector``,
``GatherProjector``; ``make_projector`` picks one), compute the same iteration:

- ``fused`` (the default on the CPU): one thread runs the whole projection, every iteration's stick pass
  (each stick computes its correction once and adds it to its two particles' accumulators, in
  stick-list order) then particle pass (each particle applies and clears its accumulator), with the
  sticks and the per-particle iterate data packed (once, when the projector is made) into per-stick and
  per-particle records; per step only the rest lengths (a control) are copied in. A CPU launch runs serially
  anyway, so this is one launch per step instead of two per iteration.
- ``scatter``: the same two passes as two launches per iteration, one thread per stick then one per
  particle. On the CPU it gives bit-identical results to ``fused`` (same float operations in the same order); on
  CUDA its atomics add in the order the threads arrive, so it agrees with ``fused`` to float rounding and may
  differ from run to run in the last bits.
- ``gather`` (the default on CUDA, where concurrent float atomics would add in a varying order): one
  thread per particle walks its sticks through a CSR adjacency (no atomics), measuring each stick from
  its own end, and writes the next iterate into a second buffer (ping-pong). Each stick is
  measured twice, once from each end; the per-particle order is fixed, so this is bit-identical from
  run to run, and agrees with the others to float rounding.
  Only the positions need two buffers: a particle's increment, offset and origin are its own thread's.

Elastic sticks (a compliance ``c`` [m/N] > 0, :meth:`~warpsim.physics.builder.ModelBuilder.set_compliance`) are
solved as XPBD does (Macklin, Müller & Chentanez 2016, "XPBD: position-based simulation of compliant constrained
dynamics"), with the split masses' factor in place of the inverse mass sum: each keeps, through one projection, the
sum ``lam`` of its corrections and corrects by ``dlam = c_s (|d| - r - alpha lam) / (1 + alpha c_s)`` with
``alpha = c / dt^2``, so the iterations converge to the stretch of a spring of stiffness ``1 / c`` under its
tension, the same at every time step. Rigid sticks (``c = 0``, the paper's) converge to no stretch at all, so the
finer the step and the more the iterations, the stiffer they are: how far the corrections reach across the cloth
per second, ``sqrt(k) / dt`` (:func:`warpsim.physics.projection.jacobi_equivalent_iterations`), grows with every
rung of a convergence ladder.

Positions are float64 (``State.particle_q``) and everything measured from them is float32: a stick's
ends are subtracted in float64 and only the difference, at most a few metres, is rounded to float32, so a
stick is measured as well 10 km from the origin as next to it (float32 world coordinates would be quantised
to 1e-3 m there, a tenth of a percent of a 1 m stick). Each particle keeps, across the iterations of one
projection, its float64 *origin* (its position when the projection began) and its float32 *offset* from it,
the sum of its increments; every iterate is ``origin + offset``, and Chebyshev extrapolation works on the
last *increment*.

``fused`` is the fastest on the CPU: it drops two launches per iteration, reads packed records and runs
plain ``while`` loops (the per-scheme costs are in ``benchmarks/results.md``). On CUDA it would run on a
single GPU thread: correct, but slow, hence ``gather`` there.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import warp as wp

from .nails import pin_to_nail

if TYPE_CHECKING:
    pass

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


@wp.func
def stick_correction(d: wp.vec3, rest: float, coef: float) -> wp.vec3:
    """Correction ``coef (|d| - rest) d / |d|`` of a stick whose ends are ``d`` apart (zero if ``d`` is zero)."""
    length = wp.length(d)
    if length == 0.0:
        return wp.vec3(0.0)
    return d * (coef * (length - rest) / length)


@wp.func
def compliant_correction(
    d: wp.vec3, rest: float, coef: float, alpha: float, lam: wp.vec2, relaxation: float, omega: float
):
    """An elastic stick's correction and its new ``lam`` (XPBD, Macklin et al. 2016, with the split masses' factor
    ``coef``): ``dlam = coef (|d| - rest - alpha lam) / (1 + alpha coef)`` and the correction ``dlam d / |d|``.
    ``alpha`` is the stick's compliance over ``dt^2`` [1/kg]. ``lam`` holds the stick's accumulated ``lam`` [kg m]
    and its last increment: ``lam`` moves as the stick's ends do, by ``relaxation dlam``, Chebyshev-extrapolated by
    ``omega`` from the last increment (:func:`iterate_increment`), so that the ends' displacement stays
    ``w lam`` and the iterations stop only at ``|d| - rest = alpha lam``: the stretch of a spring of stiffness
    ``1 / compliance`` under the tension ``lam / dt^2``, whatever the step, the over-relaxation or the
    acceleration."""
    length = wp.length(d)
    if length == 0.0:
        return wp.vec3(0.0), lam
    dlam = coef * ((length - rest) - alpha * lam[0]) / (1.0 + alpha * coef)
    inc = relaxation * dlam
    if omega != 1.0:
        inc = inc * omega + lam[1] * (omega - 1.0)
    return d * (dlam / length), wp.vec2(lam[0] + inc, inc)


@wp.func
def stick_or_spring_correction(
    d: wp.vec3,
    rest: float,
    coef: float,
    alpha: float,
    first: int,
    relaxation: float,
    omega: float,
    lam_out: wp.array(dtype=wp.vec2),
    slot: int,
) -> wp.vec3:
    """:func:`compliant_correction` for an elastic stick (``alpha > 0``), its ``lam`` and last increment kept in
    ``lam_out[slot]`` (read as zero on the ``first`` iteration of a projection), else :func:`stick_correction`."""
    if alpha > 0.0:
        lam = wp.vec2(0.0)
        if first == 0:
            lam = lam_out[slot]
        elastic, new_lam = compliant_correction(d, rest, coef, alpha, lam, relaxation, omega)
        lam_out[slot] = new_lam
        return elastic
    return stick_correction(d, rest, coef)


@wp.func
def iterate_increment(total: wp.vec3, step: float, omega: float, last: wp.vec3) -> wp.vec3:
    """How far the next iterate lies from the current one: ``step * total``, Chebyshev-extrapolated by
    ``omega`` from the ``last`` increment when ``omega != 1`` (``older + omega (x + step total - older)``
    with ``older = x - last``)."""
    inc = total * step
    if omega != 1.0:
        inc = inc * omega + last * (omega - 1.0)
    return inc


@wp.func
def advance_offset(origin: wp.vec3d, offset: wp.vec3, inc: wp.vec3):
    """Adds the float32 increment ``inc`` [m] to a particle's float32 ``offset`` [m]: returns the new offset and
    the float64 iterate ``origin + offset`` (every scheme does exactly these operations)."""
    moved = offset + inc
    return moved, origin + wp.vec3d(moved)


@wp.func
def next_position(
    i: int,
    x: wp.vec3d,
    total: wp.vec3,
    step: float,
    omega: float,
    first: int,
    last_inc_out: wp.array(dtype=wp.vec3),
    offset_out: wp.array(dtype=wp.vec3),
    origin_out: wp.array(dtype=wp.vec3d),
) -> wp.vec3d:
    """Particle ``i``'s next float64 position [m] from ``x`` and its summed float32 corrections ``total``.

    The iterate is
    ``origin_out[i] + offset_out[i]``: the position when the projection began (stored on the
    ``first`` iteration, which also reads the last increment and the offset_out as zero) plus the sum of the
    increments so far; the increment is kept in ``last_inc_out[i]`` for Chebyshev extrapolation.
    """
    last = wp.vec3(0.0)
    off = wp.vec3(0.0)
    x0 = x
    if first == 0:
        last = last_inc_out[i]
        off = offset_out[i]
        x0 = origin_out[i]
    else:
        origin_out[i] = x
    inc = iterate_increment(total, step, omega, last)
    moved, q = advance_offset(x0, off, inc)
    offset_out[i] = moved
    last_inc_out[i] = inc
    return q


@wp.kernel
def scatter_corrections(
    stick_particles: wp.array(dtype=wp.vec2i),
    stick_rest: wp.array(dtype=wp.float32),
    stick_coef: wp.array(dtype=wp.float32),
    stick_compliance: wp.array(dtype=wp.float32),
    inv_dt2: float,
    first: int,
    relaxation: float,
    omega: float,
    particle_q: wp.array(dtype=wp.vec3d),
    accum_out: wp.array(dtype=wp.vec3),
    stick_lam_out: wp.array(dtype=wp.vec2),
):
    s = wp.tid()
    ends = stick_particles[s]
    d = wp.vec3(particle_q[ends[1]] - particle_q[ends[0]])
    alpha = stick_compliance[s] * inv_dt2
    c = stick_or_spring_correction(d, stick_rest[s], stick_coef[s], alpha, first, relaxation, omega, stick_lam_out, s)
    wp.atomic_add(accum_out, ends[0], c)
    wp.atomic_sub(accum_out, ends[1], c)


@wp.kernel
def apply_accumulated(
    particle_scale: wp.array(dtype=wp.float32),
    particle_nail: wp.array(dtype=wp.int32),
    nail_target: wp.array(dtype=wp.vec3d),
    relaxation: float,
    omega: float,
    first: int,
    accum_out: wp.array(dtype=wp.vec3),
    particle_q_out: wp.array(dtype=wp.vec3d),
    last_inc_out: wp.array(dtype=wp.vec3),
    offset_out: wp.array(dtype=wp.vec3),
    origin_out: wp.array(dtype=wp.vec3d),
):
    i = wp.tid()
    total = accum_out[i]
    accum_out[i] = wp.vec3(0.0)
    if pin_to_nail(i, particle_nail, nail_target, particle_q_out):
        return
    scale = particle_scale[i]
    if scale == 0.0:
        return
    particle_q_out[i] = next_position(
        i, particle_q_out[i], total, relaxation * scale, omega, first, last_inc_out, offset_out, origin_out
    )


@wp.kernel
def gather_iteration(
    particle_stick_start: wp.array(dtype=wp.int32),
    particle_stick_refs: wp.array(dtype=wp.int32),
    stick_particles: wp.array(dtype=wp.vec2i),
    stick_rest: wp.array(dtype=wp.float32),
    stick_coef: wp.array(dtype=wp.float32),
    stick_compliance: wp.array(dtype=wp.float32),
    inv_dt2: float,
    particle_scale: wp.array(dtype=wp.float32),
    particle_nail: wp.array(dtype=wp.int32),
    nail_target: wp.array(dtype=wp.vec3d),
    relaxation: float,
    omega: float,
    first: int,
    q_in: wp.array(dtype=wp.vec3d),
    q_out: wp.array(dtype=wp.vec3d),
    last_inc_out: wp.array(dtype=wp.vec3),
    offset_out: wp.array(dtype=wp.vec3),
    origin_out: wp.array(dtype=wp.vec3d),
    entry_lam_out: wp.array(dtype=wp.vec2),
):
    i = wp.tid()
    if pin_to_nail(i, particle_nail, nail_target, q_out):
        return
    x = q_in[i]
    scale = particle_scale[i]
    if scale == 0.0:
        q_out[i] = x
        return
    total = wp.vec3(0.0)
    for k in range(particle_stick_start[i], particle_stick_start[i + 1]):
        ref = particle_stick_refs[k]
        s = ref >> 1
        ends = stick_particles[s]
        other = ends[1]
        if (ref & 1) == 1:
            other = ends[0]
        d = wp.vec3(q_in[other] - x)
        alpha = stick_compliance[s] * inv_dt2
        # an elastic stick's lam is kept per stick end (entry k): both ends do the same float operations on the
        # same length, so the two copies stay equal without a thread sharing them
        total += stick_or_spring_correction(
            d, stick_rest[s], stick_coef[s], alpha, first, relaxation, omega, entry_lam_out, k
        )
    # only this thread reads and writes its own increment, offset and origin
    q_out[i] = next_position(i, x, total, relaxation * scale, omega, first, last_inc_out, offset_out, origin_out)


@wp.struct
class PackedStick:
    """One stick as the fused scheme reads it: both ends, rest length [m], factor ``c_s`` and compliance [m/N], in 20
    bytes (an elastic stick's ``lam`` lives apart, so that only it is written back each iteration)."""

    a: wp.int32
    b: wp.int32
    rest: wp.float32
    coef: wp.float32
    compliance: wp.float32


@wp.struct
class ParticleIterate:
    """A particle's per-projection data in the fused scheme: last increment [m], offset [m] from the origin
    [m] (its position when the projection began), and ``relaxation * scale`` (0 = the particle does not
    move)."""

    last: wp.vec3
    offset: wp.vec3
    origin: wp.vec3d
    step: wp.float32


@wp.kernel
def pack_sticks(
    stick_particles: wp.array(dtype=wp.vec2i),
    stick_coef: wp.array(dtype=wp.float32),
    stick_compliance: wp.array(dtype=wp.float32),
    packed_out: wp.array(dtype=PackedStick),
):
    s = wp.tid()
    ends = stick_particles[s]
    p = PackedStick()
    p.a = ends[0]
    p.b = ends[1]
    p.coef = stick_coef[s]
    p.compliance = stick_compliance[s]
    packed_out[s] = p


@wp.kernel
def pack_steps(
    particle_scale: wp.array(dtype=wp.float32), relaxation: float, iterate_out: wp.array(dtype=ParticleIterate)
):
    i = wp.tid()
    it = ParticleIterate()
    it.step = relaxation * particle_scale[i]
    iterate_out[i] = it


@wp.kernel
def fused_projection(
    stick_rest: wp.array(dtype=wp.float32),
    particle_nail: wp.array(dtype=wp.int32),
    nail_target: wp.array(dtype=wp.vec3d),
    omegas: wp.array(dtype=wp.float32),
    inv_dt2: float,
    relaxation: float,
    accum_out: wp.array(dtype=wp.vec3),
    particle_q_out: wp.array(dtype=wp.vec3d),
    packed_out: wp.array(dtype=PackedStick),
    iterate_out: wp.array(dtype=ParticleIterate),
    stick_lam_out: wp.array(dtype=wp.vec2),
):
    if wp.tid() != 0:  # one thread; reading tid also lets Warp compile constant array strides on the CPU
        return
    # ends, factors and step sizes were packed once (pack_sticks, pack_steps); per step only the rest
    # lengths (a control) come in, and every particle starts at its origin with a zero increment.
    # The loops are `while` loops on purpose: Warp's `range` handles a step of either sign at run time,
    # which costs a measurable share of the stick pass on the CPU.
    particle_count = particle_q_out.shape[0]
    i = int(0)  # noqa: UP018 -- Warp needs int() to make a variable a loop may change
    while i < particle_count:
        it = iterate_out[i]
        it.last = wp.vec3(0.0)
        it.offset = wp.vec3(0.0)
        it.origin = particle_q_out[i]
        iterate_out[i] = it
        i += 1
    stick_count = packed_out.shape[0]
    s = int(0)  # noqa: UP018 -- Warp needs int() to make a variable a loop may change
    while s < stick_count:
        p = packed_out[s]
        p.rest = stick_rest[s]
        packed_out[s] = p
        s += 1
    # the scatter scheme's two passes per iteration, with the same float operations in the same order
    k = int(0)  # noqa: UP018 -- Warp needs int() to make a variable a loop may change
    while k < omegas.shape[0]:
        omega = omegas[k]
        first = int(0)  # noqa: UP018 -- Warp needs int() to make a variable a loop may change
        if k == 0:
            first = 1
        s = int(0)  # noqa: UP018 -- Warp needs int() to make a variable a loop may change
        while s < stick_count:
            p = packed_out[s]
            d = wp.vec3(particle_q_out[p.b] - particle_q_out[p.a])
            c = stick_or_spring_correction(
                d, p.rest, p.coef, p.compliance * inv_dt2, first, relaxation, omega, stick_lam_out, s
            )
            accum_out[p.a] = accum_out[p.a] + c
            accum_out[p.b] = accum_out[p.b] - c
            s += 1
        i = int(0)  # noqa: UP018 -- Warp needs int() to make a variable a loop may change
        while i < particle_count:
            total = accum_out[i]
            accum_out[i] = wp.vec3(0.0)
            it = iterate_out[i]
            if it.step != 0.0:
                inc = iterate_increment(total, it.step, omega, it.last)
                moved, q = advance_offset(it.origin, it.offset, inc)
                it.offset = moved
                it.last = inc
                iterate_out[i] = it
                particle_q_out[i] = q
            else:
                pin_to_nail(i, particle_nail, nail_target, particle_q_out)  # nailed particles have step 0
            i += 1
        k += 1


@wp.kernel
def copy_positions(src: wp.array(dtype=wp.vec3d), dst_out: wp.array(dtype=wp.vec3d)):
    i = wp.tid()
    dst_out[i] = src[i]
