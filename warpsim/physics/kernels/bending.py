"""Bending stiffness of a cloth: hinges of three particles in a row against their curvature, and twists of a grid
cell's four corners against its twist.

A hinge ``(a, m, b)`` of equally spaced particles (spacing ``h`` [m], along a strip ``w`` [m] wide) bends by the
second difference ``c = x_a - 2 x_m + x_b``: its curvature is ``|c| / h^2``, and a plate of bending stiffness
``B`` [N m] stores ``B w h |c|^2 / (2 h^4)`` in it, so the hinge's stiffness is ``k = B w / h^3`` [N/m]. A twist
``(a, b, c, d)`` of a cell (``a``, ``b`` along one side, ``c``, ``d`` beside them; sides ``h_u``, ``h_v``) has the
mixed difference ``c = x_a - x_b - x_c + x_d`` = ``w_xy h_u h_v``, and a plate of Poisson's ratio 0 stores
``B w_xy^2`` per area, so ``k = 2 B / (h_u h_v)``. Each is a linear difference ``c = sum_j w_j x_j`` (weights
(1, -2, 1) and (1, -1, -1, 1)) with the energy ``k |c|^2 / 2`` and the forces ``-k w_j c``. The force is linear,
unchanged by moving or turning the cloth, and zero in the rest shape (straight, equally spaced rows; flat
parallelogram cells). A grid of hinges along its rows and columns and a twist in every cell gives the plate's
``B/2 (w_xx^2 + w_yy^2 + 2 w_xy^2)`` per area: a saddle ``w = a x y`` stores ``B a^2`` per area, exactly. It is
the plate's energy for small angles between neighbouring segments (0.95 of it at 0.8 rad, 0.81 at 90 degrees).

The force is explicit (read from the step's positions, like gravity and the air), so under Verlet it is stable
while ``omega dt < 2`` for the hinges' highest frequency: :func:`stable_dt` gives half that limit, and a scene
stepping past it is refused (forward Euler, the paper's mass-spring comparison, is stable at no step for an
undamped mode; its springs blow up first). Per particle the forces are gathered (each particle sums its own
hinges), so they are the same, bit for bit, on every device and at every thread count.
"""

from __future__ import annotations

import numpy as np
import warp as wp

wp.set_module_options({"enable_backward": False})  # forward-only: halves compile time


@wp.kernel
def _bending_force(
    particle_hinge_start: wp.array(dtype=wp.int32),
    particle_hinge_refs: wp.array(dtype=wp.int32),
    hinge_particles: wp.array(dtype=wp.vec4i),
    hinge_weights: wp.array(dtype=wp.vec4),
    hinge_stiffness: wp.array(dtype=wp.float32),
    particle_q: wp.array(dtype=wp.vec3d),
    particle_air: wp.array(dtype=wp.vec3),
    particle_force_out: wp.array(dtype=wp.vec3),
):
    i = wp.tid()
    force = wp.vec3d(0.0, 0.0, 0.0)
    for r in range(particle_hinge_start[i], particle_hinge_start[i + 1]):  # this particle's hinges and twists
        ref = particle_hinge_refs[r]
        h = ref // 4
        slot = ref - 4 * h
        p = hinge_particles[h]
        w = hinge_weights[h]
        bend = wp.vec3d(0.0, 0.0, 0.0)
        for j in range(4):
            if w[j] != 0.0:
                bend = bend + wp.float64(w[j]) * particle_q[p[j]]
        force = force - wp.float64(hinge_stiffness[h]) * wp.float64(w[slot]) * bend
    particle_force_out[i] = particle_air[i] + wp.vec3(force)


def bending_force(model, state, particle_air: wp.array, particle_force_out: wp.array) -> None:
    """Write each particle's own force ``particle_air`` (``[P]`` [N]: drag bodies' drag) plus its hinges' and
    twists' force [N] at ``state``'s positions into ``particle_force_out`` (``[P]``). For a model with hinges only."""
    wp.launch(
        _bending_force,
        dim=model.particle_count,
        inputs=[
            model.particle_hinge_start,
            model.particle_hinge_refs,
            model.hinge_particles,
            model.hinge_weights,
            model.hinge_stiffness,
            state.particle_q,
            particle_air,
        ],
        outputs=[particle_force_out],
        device=model.device,
    )


def stable_dt(hinges: np.ndarray, weights: np.ndarray, stiffness: np.ndarray, mass: np.ndarray) -> float:
    """The largest time step [s] at which explicit bending stays stable under Verlet: ``2 / ω`` for the highest
    frequency ``ω`` [rad/s] of the hinges and twists alone (``[H, 4]`` particles and weights, ``[H]`` stiffness
    [N/m]), bounded by Gershgorin's theorem on ``M⁻¹ K``: each particle's row sum of ``|K|``, ``k |w_i| Σ_j |w_j|``
    over its hinges (a hinge's ends 4 k, its middle 8 k; a twist's corners 4 k), over its mass [kg] (``inf`` for a
    nailed particle's). ``inf`` without hinges. Half of the limit is kept."""
    if len(hinges) == 0:
        return float("inf")
    w = np.abs(np.asarray(weights, dtype=np.float64))
    share = np.asarray(stiffness, dtype=np.float64)[:, None] * w * w.sum(axis=1, keepdims=True)
    row = np.zeros(len(mass), dtype=np.float64)
    np.add.at(row, hinges.reshape(-1), share.reshape(-1))
    omega2 = np.max(np.where(np.isfinite(mass), row / mass, 0.0))
    return float("inf") if omega2 <= 0.0 else float(1.0 / np.sqrt(omega2))
