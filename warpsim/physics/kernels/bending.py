"""Bending stiffness of a cloth: hinges of three particles in a row, each resisting its own curvature.

A hinge ``(a, m, b)`` of equally spaced particles (spacing ``h`` [m], along a strip ``w`` [m] wide) bends by the
second difference ``c = x_a - 2 x_m + x_b``: its curvature is ``|c| / h^2``, and a plate of bending stiffness
``B`` [N m] stores ``B w h |c|^2 / (2 h^4)`` in it, so the hinge's stiffness is ``k = B w / h^3`` [N/m] and its
forces are ``-k c`` on the ends and ``+2 k c`` on the middle. The energy is quadratic in the positions: the force
is linear, unchanged by moving or turning the strip, and zero for a straight, equally spaced one (the rest shape:
flat cloth feels nothing). It is the plate's energy for small angles between neighbouring segments (0.95 of it at
0.8 rad, 0.81 at 90 degrees). A grid of such hinges along its rows and columns gives ``B (d4/dx4 + d4/dy4)``, a
plate without the twist term: a saddle (``z = a x y``) costs nothing, so a sheet's top and bottom edges may
flap opposite ways more freely than a real plate's.

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
    hinge_particles: wp.array(dtype=wp.vec3i),
    hinge_stiffness: wp.array(dtype=wp.float32),
    particle_q: wp.array(dtype=wp.vec3d),
    particle_air: wp.array(dtype=wp.vec3),
    particle_force_out: wp.array(dtype=wp.vec3),
):
    i = wp.tid()
    force = wp.vec3d(0.0, 0.0, 0.0)
    for r in range(particle_hinge_start[i], particle_hinge_start[i + 1]):
        ref = particle_hinge_refs[r]
        h = ref // 3
        role = ref - 3 * h  # 0 and 2: an end, 1: the middle
        p = hinge_particles[h]
        bend = particle_q[p[0]] - wp.float64(2.0) * particle_q[p[1]] + particle_q[p[2]]
        k = wp.float64(hinge_stiffness[h])
        if role == 1:
            force = force + wp.float64(2.0) * k * bend
        else:
            force = force - k * bend
    particle_force_out[i] = particle_air[i] + wp.vec3(force)


def bending_force(model, state, particle_air: wp.array, particle_force_out: wp.array) -> None:
    """Write each particle's own force ``particle_air`` (``[P]`` [N]: drag bodies' drag) plus its hinges' bending
    force [N] at ``state``'s positions into ``particle_force_out`` (``[P]``). For a model with hinges only."""
    wp.launch(
        _bending_force,
        dim=model.particle_count,
        inputs=[
            model.particle_hinge_start,
            model.particle_hinge_refs,
            model.hinge_particles,
            model.hinge_stiffness,
            state.particle_q,
            particle_air,
        ],
        outputs=[particle_force_out],
        device=model.device,
    )


def stable_dt(hinges: np.ndarray, stiffness: np.ndarray, mass: np.ndarray) -> float:
    """The largest time step [s] at which explicit bending stays stable: ``2 / ω`` for the highest frequency ``ω``
    [rad/s] of the hinges alone, bounded by Gershgorin's theorem on ``M⁻¹ K`` (each particle's row sum of
    ``|K|``, the ends' ``k (1 + 2 + 1)`` and the middle's ``k (2 + 4 + 2)``, over its mass [kg]; ``inf`` for a
    nailed particle's). ``inf`` without hinges. Verlet is stable for ``ω dt < 2``; half of that is kept."""
    if len(hinges) == 0:
        return float("inf")
    row = np.zeros(len(mass), dtype=np.float64)
    k = np.asarray(stiffness, dtype=np.float64)
    np.add.at(row, hinges[:, 0], 4.0 * k)
    np.add.at(row, hinges[:, 2], 4.0 * k)
    np.add.at(row, hinges[:, 1], 8.0 * k)
    omega2 = np.max(np.where(np.isfinite(mass), row / mass, 0.0))
    return float("inf") if omega2 <= 0.0 else float(1.0 / np.sqrt(omega2))
