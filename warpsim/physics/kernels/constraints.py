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

Three schemes, one class each (:class:`FusedProjector`, :class:`ScatterProjector`, :class:`GatherProjector`;
:func:`make_projector` picks one), compute the same iteration:

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
per second, ``sqrt(k) / dt`` (:func:`jacobi_equivalent_iterations`), grows with every rung of a convergence ladder.

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

import math
from typing import TYPE_CHECKING

import numpy as np
import warp as wp

from .nails import pin_to_nail

if TYPE_CHECKING:
    from ..config import SolverConfig

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
def _scatter_corrections(
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
def _apply_accumulated(
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
def _gather_iteration(
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
def _pack_sticks(
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
def _pack_steps(
    particle_scale: wp.array(dtype=wp.float32), relaxation: float, iterate_out: wp.array(dtype=ParticleIterate)
):
    i = wp.tid()
    it = ParticleIterate()
    it.step = relaxation * particle_scale[i]
    iterate_out[i] = it


@wp.kernel
def _fused_projection(
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
    # ends, factors and step sizes were packed once (_pack_sticks, _pack_steps); per step only the rest
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
def _copy_positions(src: wp.array(dtype=wp.vec3d), dst_out: wp.array(dtype=wp.vec3d)):
    i = wp.tid()
    dst_out[i] = src[i]


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


def jacobi_equivalent_iterations(iterations: int, rho: float, delay: int = 10) -> float:
    """How many plain Jacobi iterations reduce a projection's slowest errors as much as ``iterations`` with
    :func:`chebyshev_weights` ``(iterations, rho, delay)`` do: ``delay + (iterations - delay) / sqrt(1 - rho^2)``
    (``iterations`` for ``rho = 0``).

    An error mode the Jacobi iteration shrinks by ``lambda = 1 - eps`` per iteration (``eps`` small: the cloth's long,
    soft waves) is left at ``lambda^k ~ exp(-k eps)`` after ``k`` plain iterations; the Chebyshev polynomial
    ``T_m(lambda / rho) / T_m(1 / rho)`` of its ``m = iterations - delay`` accelerated ones leaves
    ``exp(-m eps / sqrt(1 - rho^2))`` (the slope of ``arccosh`` at ``1 / rho``). The count sets how stiff the
    unconverged sticks are: ``sqrt(k) / dt`` [1/s] grows as a rung of the convergence ladder halves ``dt`` and
    doubles the iterations (docs/objects.md, the kite's limits). Within ~2.5 % for modes with
    ``eps <= 1e-4`` from 40 iterations up (4 % at ``eps = 1e-3``).
    """
    if rho <= 0.0 or iterations <= delay:
        return float(iterations)
    return delay + (iterations - delay) / math.sqrt(1.0 - rho * rho)


class StickProjector:
    """Jacobi projection of a model's sticks: the per-stick factors and per-particle scales every scheme shares,
    made once. Use a scheme's subclass, or :func:`make_projector` to pick one.

    Args:
        model: the :class:`~warpsim.physics.model.Model`.
        config: the :class:`~warpsim.physics.config.SolverConfig` whose ``relaxation`` (over-relaxation factor, 1 = the
            paper), ``mass_splitting`` (split masses instead of the paper's plain average) and ``chebyshev``
            (spectral-radius estimate for :func:`chebyshev_weights`, 0 = plain Jacobi) it uses.
    """

    scheme = ""

    def __init__(self, model, config: SolverConfig):
        self.model = model
        self.relaxation = float(config.relaxation)
        self.chebyshev = float(config.chebyshev)
        share, scale = model.constraint_weights(config.mass_splitting)
        device = model.device
        self.particle_scale = wp.array(scale.astype(np.float32), dtype=wp.float32, device=device)
        ends = model.stick_particles_np
        total = share[ends[:, 0]] + share[ends[:, 1]] if len(ends) else np.zeros(0)
        coef = np.divide(model.stick_weight.numpy(), total, out=np.zeros(len(ends)), where=total > 0)
        self.stick_coef = wp.array(coef if len(coef) else np.zeros(1), dtype=wp.float32, device=device)
        compliance = model.stick_compliance
        self.elastic = bool(np.any(compliance > 0.0))  # then a projection needs the step's dt
        if self.elastic and not config.mass_splitting:
            # the plain average moves a stick's two ends by shares that do not follow its masses, so no lam per
            # stick is its tension: the stretch would come out n times too large, and differ at its two ends
            raise ValueError(
                "elastic sticks (a compliance > 0: kite.sail_compliance, kite.frame_compliance, "
                "flag.cloth_compliance or flag.shear_compliance) need solver.mass_splitting = true; make them "
                "rigid (every one of those keys 0) for the paper's plain average"
            )
        self.stick_compliance = wp.array(
            compliance.astype(np.float32) if len(compliance) else np.zeros(1, dtype=np.float32),
            dtype=wp.float32,
            device=device,
        )

    def prepare(self, iterations: int):
        """Make what a projection of ``iterations`` needs before a graph capture (see :class:`FusedProjector`)."""
        return None

    def project(self, state, control, iterations: int, dt: float | None = None) -> None:
        """Run ``iterations`` Jacobi iterations on ``state.particle_q`` in place.

        Rest lengths come from ``control.stick_rest`` and nail targets from ``control.nail_target``, so both
        can change between steps (and a captured graph sees the new values). ``dt`` [s], the step, is needed
        when the model has elastic sticks (their compliance acts as ``compliance / dt^2``).
        """
        if self.elastic and not (dt is not None and dt > 0.0):
            raise ValueError(f"the model has elastic sticks: project needs the step's dt > 0, got {dt}")
        if self.model.stick_count:
            self._project(state, control, iterations, 1.0 / (dt * dt) if self.elastic else 0.0)

    def _project(self, state, control, iterations: int, inv_dt2: float) -> None:
        raise NotImplementedError

    def _apply_inputs(self, control) -> tuple:
        """The per-particle inputs the scatter and gather schemes pass to every iteration."""
        return (self.particle_scale, self.model.particle_nail, control.nail_target, self.relaxation)

    def _make_iterate_buffers(self) -> None:
        """Per-particle last increment, offset and origin of the scatter and gather schemes (see the module text)."""
        n, device = self.model.particle_count, self.model.device
        self.last_inc = wp.zeros(n, dtype=wp.vec3, device=device)
        self.offset = wp.zeros(n, dtype=wp.vec3, device=device)
        self.origin = wp.zeros(n, dtype=wp.vec3d, device=device)


class FusedProjector(StickProjector):
    """The whole projection in one single-thread launch over packed records (the CPU default)."""

    scheme = "fused"

    def __init__(self, model, config: SolverConfig):
        super().__init__(model, config)
        device, n = model.device, model.particle_count
        self.accum = wp.zeros(n, dtype=wp.vec3, device=device)
        self.packed = wp.zeros(model.stick_count, dtype=PackedStick, device=device)
        self.iterate = wp.zeros(n, dtype=ParticleIterate, device=device)
        self.stick_lam = wp.zeros(max(model.stick_count, 1), dtype=wp.vec2, device=device)
        if model.stick_count:
            wp.launch(
                _pack_sticks,
                model.stick_count,
                [model.stick_particles, self.stick_coef, self.stick_compliance],
                [self.packed],
                device=device,
            )
        wp.launch(_pack_steps, n, [self.particle_scale, self.relaxation], [self.iterate], device=device)
        self._omegas: dict[int, wp.array] = {}  # each iteration count's Chebyshev weights, made once

    def prepare(self, iterations: int):
        """Make the device array of ``iterations``' Chebyshev weights the kernel reads (once per count) and return
        it. Call it before a graph capture that projects with that count: an array made during a CPU capture
        was read wrong by the replayed graph (every position NaN for 256 iterations and more)."""
        weights = self._omegas.get(iterations)
        if weights is None:
            omegas = np.array(chebyshev_weights(iterations, self.chebyshev), dtype=np.float32)
            weights = self._omegas[iterations] = wp.array(omegas, dtype=wp.float32, device=self.model.device)
        return weights

    def _project(self, state, control, iterations: int, inv_dt2: float) -> None:
        m = self.model
        wp.launch(
            _fused_projection,
            dim=1,
            inputs=[
                control.stick_rest,
                m.particle_nail,
                control.nail_target,
                self.prepare(iterations),
                inv_dt2,
                self.relaxation,
            ],
            outputs=[self.accum, state.particle_q, self.packed, self.iterate, self.stick_lam],
            device=m.device,
        )


class ScatterProjector(StickProjector):
    """Two launches per iteration: one thread per stick adds its correction to its ends (atomics), then one
    thread per particle applies its sum. Bit-identical to :class:`FusedProjector` on the CPU."""

    scheme = "scatter"

    def __init__(self, model, config: SolverConfig):
        super().__init__(model, config)
        self.accum = wp.zeros(model.particle_count, dtype=wp.vec3, device=model.device)
        self.stick_lam = wp.zeros(max(model.stick_count, 1), dtype=wp.vec2, device=model.device)
        self._make_iterate_buffers()

    def _project(self, state, control, iterations: int, inv_dt2: float) -> None:
        m = self.model
        apply = self._apply_inputs(control)
        for k, omega in enumerate(chebyshev_weights(iterations, self.chebyshev)):
            wp.launch(
                _scatter_corrections,
                dim=m.stick_count,
                inputs=[
                    m.stick_particles,
                    control.stick_rest,
                    self.stick_coef,
                    self.stick_compliance,
                    inv_dt2,
                    int(k == 0),
                    self.relaxation,
                    float(omega),
                    state.particle_q,
                ],
                outputs=[self.accum, self.stick_lam],
                device=m.device,
            )
            wp.launch(
                _apply_accumulated,
                dim=m.particle_count,
                inputs=[*apply, float(omega), int(k == 0)],
                outputs=[self.accum, state.particle_q, self.last_inc, self.offset, self.origin],
                device=m.device,
            )


class GatherProjector(StickProjector):
    """One launch per iteration, one thread per particle walking its sticks (no atomics; the CUDA default),
    ping-ponging the positions through a second buffer."""

    scheme = "gather"

    def __init__(self, model, config: SolverConfig):
        super().__init__(model, config)
        self._make_iterate_buffers()
        self.scratch = wp.zeros(model.particle_count, dtype=wp.vec3d, device=model.device)
        refs = model.particle_stick_refs
        self.entry_lam = wp.zeros(max(refs.shape[0], 1), dtype=wp.vec2, device=model.device)  # lam per stick end

    def _project(self, state, control, iterations: int, inv_dt2: float) -> None:
        m = self.model
        apply = self._apply_inputs(control)
        omegas = chebyshev_weights(iterations, self.chebyshev)
        buffers = (state.particle_q, self.scratch)
        for k, omega in enumerate(omegas):
            wp.launch(
                _gather_iteration,
                dim=m.particle_count,
                inputs=[
                    m.particle_stick_start,
                    m.particle_stick_refs,
                    m.stick_particles,
                    control.stick_rest,
                    self.stick_coef,
                    self.stick_compliance,
                    inv_dt2,
                    *apply,
                    float(omega),
                    int(k == 0),
                    buffers[k % 2],
                ],
                outputs=[buffers[(k + 1) % 2], self.last_inc, self.offset, self.origin, self.entry_lam],
                device=m.device,
            )
        if len(omegas) % 2 == 1:
            wp.launch(
                _copy_positions,
                dim=m.particle_count,
                inputs=[self.scratch],
                outputs=[state.particle_q],
                device=m.device,
            )


SCHEMES: dict[str, type[StickProjector]] = {
    cls.scheme: cls for cls in (ScatterProjector, GatherProjector, FusedProjector)
}
"""Scheme name -> projector class."""


def make_projector(model, config: SolverConfig, scheme: str | None = None) -> StickProjector:
    """The projector of ``scheme`` (``"fused"``, ``"scatter"``, ``"gather"``) for ``model``; None picks fused on
    the CPU and gather on CUDA. Raises ``ValueError`` for an unknown scheme."""
    if scheme is None:
        scheme = "fused" if wp.get_device(model.device).is_cpu else "gather"
    if scheme not in SCHEMES:
        raise ValueError(f"constraint scheme must be one of {', '.join(SCHEMES)}, got {scheme!r}")
    return SCHEMES[scheme](model, config)
