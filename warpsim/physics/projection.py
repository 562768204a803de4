"""The projection of the sticks, step by step on the host: the three schemes that launch
:mod:`warpsim.physics.kernels.constraints`'s kernels (:class:`FusedProjector`, :class:`ScatterProjector`,
:class:`GatherProjector`; :func:`make_projector` picks one) and the Chebyshev over-relaxation weights. The method,
its mass weighting and the schemes' trade-offs are in that module's notes.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import warp as wp

from .kernels.constraints import (
    PackedStick,
    ParticleIterate,
    apply_accumulated,
    copy_positions,
    fused_projection,
    gather_iteration,
    pack_steps,
    pack_sticks,
    scatter_corrections,
)

if TYPE_CHECKING:
    from .config import SolverConfig


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
                pack_sticks,
                model.stick_count,
                [model.stick_particles, self.stick_coef, self.stick_compliance],
                [self.packed],
                device=device,
            )
        wp.launch(pack_steps, n, [self.particle_scale, self.relaxation], [self.iterate], device=device)
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
            fused_projection,
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
                scatter_corrections,
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
                apply_accumulated,
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
                gather_iteration,
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
                copy_positions,
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
