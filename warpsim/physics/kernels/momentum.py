"""Momentum of free bodies: the constraint projection's numerical error in linear and angular momentum, removed.

The sticks are internal forces: they cannot change a free body's linear momentum, nor its angular momentum
(central forces). The Jacobi projection keeps linear momentum with mass splitting, but neither scheme keeps
angular momentum: each iteration corrects along the sticks' *current* directions, not along their directions
at the step's start (SHAKE's, which keep it), so a spinning body slows down, by ``(omega dt)^2`` per step
(measured: a spinning hang glider lost 30 % of its angular momentum in 60 s at dt 0.01, 20 % at 0.005).
SHAKE's fixed directions keep it exactly, but their Jacobi iteration diverged on the glider past 90
iterations with Chebyshev acceleration (its iteration matrix is not symmetric), so warpsim keeps the paper's
directions and projects the result back onto the invariants instead (Hairer, Lubich & Wanner, *Geometric
Numerical Integration*, 2nd ed., Section IV.4: projection methods), by the smallest mass-weighted correction:

    x_i += -dP / M - I^-1 dL x r_i

where ``dP = sum m_i (x_i - x*_i)`` and ``dL = sum m_i r_i x (x_i - x*_i)`` are the momentum the projection
moved the body's particles by (``x*`` the positions before it, ``x`` after), ``r_i`` the particles' offsets
from the mass centre at the step's start and ``I`` the inertia tensor about it. The correction is a uniform
shift and a small rigid rotation: it changes no stick's length to first order. The discrete angular momentum
of Verlet, ``sum m x_n x (x_{n+1} - x_n) / dt``, changes then only by the torque of gravity and the air over
the step (and of the terrain, applied after).

The correction is made per *body*: the particles the sticks connect (a connected piece of the stick graph), so
that two objects in one world keep their momenta apart. Only *free* bodies are corrected: a body with a nailed or
an immovable particle is held from outside (the flag's pole, the kite's anchor), and its momentum is not the
sticks' alone to keep. A body whose particles lie on a line (a rope, a dumbbell) has no inertia about that line
and no angular momentum about it either: ``I`` is solved with ``1e-9 tr(I)`` added to its diagonal, exact to 1e-9
for other bodies. One thread per body sums over its particles in a fixed order, so the result is deterministic
on every device.
"""

from __future__ import annotations

import numpy as np
import warp as wp

wp.set_module_options({"enable_backward": False})  # forward-only: halves compile time


@wp.kernel
def _copy(src: wp.array(dtype=wp.vec3d), dst_out: wp.array(dtype=wp.vec3d)):
    i = wp.tid()
    dst_out[i] = src[i]


@wp.kernel
def _restore_momentum(
    body_start: wp.array(dtype=wp.int32),
    body_particles: wp.array(dtype=wp.int32),
    particle_inv_mass: wp.array(dtype=wp.float32),
    particle_q_prev: wp.array(dtype=wp.vec3d),
    predicted: wp.array(dtype=wp.vec3d),
    particle_q_out: wp.array(dtype=wp.vec3d),
):
    b = wp.tid()
    start = body_start[b]
    end = body_start[b + 1]
    zero = wp.float64(0.0)
    mass = zero
    centre = wp.vec3d(zero, zero, zero)
    k = start
    while k < end:  # mass centre at the step's start
        i = body_particles[k]
        m = wp.float64(1.0) / wp.float64(particle_inv_mass[i])
        mass += m
        centre += particle_q_prev[i] * m
        k += 1
    centre = centre / mass
    d_p = wp.vec3d(zero, zero, zero)
    d_l = wp.vec3d(zero, zero, zero)
    inertia = wp.mat33d(zero, zero, zero, zero, zero, zero, zero, zero, zero)
    eye = wp.identity(n=3, dtype=wp.float64)
    k = start
    while k < end:  # momentum the projection added, inertia about the centre
        i = body_particles[k]
        m = wp.float64(1.0) / wp.float64(particle_inv_mass[i])
        r = particle_q_prev[i] - centre
        delta = particle_q_out[i] - predicted[i]
        d_p += delta * m
        d_l += wp.cross(r, delta) * m
        inertia += (eye * wp.dot(r, r) - wp.outer(r, r)) * m
        k += 1
    spin = wp.vec3d(zero, zero, zero)
    size = inertia[0, 0] + inertia[1, 1] + inertia[2, 2]
    if size > zero:  # more than one place; a line of particles has no inertia (and no momentum) about itself
        spin = wp.inverse(inertia + eye * (size * wp.float64(1.0e-9))) @ d_l
    shift = d_p / mass
    k = start
    while k < end:
        i = body_particles[k]
        particle_q_out[i] = particle_q_out[i] - shift - wp.cross(spin, particle_q_prev[i] - centre)
        k += 1


def free_bodies(model) -> list[np.ndarray]:
    """The model's free bodies: each a host array of particle indices [int32] (increasing) that the sticks connect,
    of more than one particle, none nailed or immovable."""
    n = model.particle_count
    ends = np.asarray(model.stick_particles_np, dtype=np.int64).reshape(-1, 2)
    label = np.arange(n)
    while True:  # each particle takes the smallest label of its stick neighbours, then its label's label
        lowest = label.copy()
        np.minimum.at(lowest, ends[:, 0], label[ends[:, 1]])
        np.minimum.at(lowest, ends[:, 1], label[ends[:, 0]])
        lowest = lowest[lowest]
        if np.array_equal(lowest, label):
            break
        label = lowest
    held = (model.particle_nail.numpy() >= 0) | (model.particle_inv_mass.numpy() == 0.0)
    free = ~np.isin(label, label[held])
    order = np.argsort(label, kind="stable")  # particles grouped by body, increasing within each
    starts = np.flatnonzero(np.diff(label[order], prepend=-1))
    return [body.astype(np.int32) for body in np.split(order, starts[1:]) if len(body) > 1 and free[body[0]]]


class MomentumKeeper:
    """Removes the constraint projection's change of each free body's linear and angular momentum (see the
    module's docstring): :meth:`before` keeps the positions the projection starts from, :meth:`after` corrects.

    Args:
        model: the :class:`~warpsim.physics.model.Model`.
    """

    def __init__(self, model):
        device = model.device
        self.model = model
        bodies = free_bodies(model)
        self.body_count = len(bodies)
        """How many free bodies the model has (each corrected by one thread)."""
        order = np.concatenate(bodies) if bodies else np.zeros(0, dtype=np.int32)
        start = np.concatenate([[0], np.cumsum([len(b) for b in bodies])]).astype(np.int32)
        self.body_start = wp.array(start, dtype=wp.int32, device=device)
        """``[B + 1]`` where each body's particles start in :attr:`body_particles`."""
        self.body_particles = wp.array(order.astype(np.int32), dtype=wp.int32, device=device)
        """``[sum of the bodies' sizes]`` the bodies' particles, body by body."""
        self.predicted = wp.zeros(model.particle_count, dtype=wp.vec3d, device=device)

    @property
    def active(self) -> bool:
        """Whether the model has a free body (otherwise :meth:`before` and :meth:`after` launch nothing)."""
        return self.body_count > 0

    def before(self, state) -> None:
        """Keep ``state``'s positions [m] before the projection."""
        if self.active:
            m = self.model
            wp.launch(_copy, m.particle_count, [state.particle_q], [self.predicted], device=m.device)

    def after(self, state) -> None:
        """Correct ``state``'s positions [m] after the projection (in place)."""
        if self.active:
            m = self.model
            wp.launch(
                _restore_momentum,
                self.body_count,
                [
                    self.body_start,
                    self.body_particles,
                    m.particle_inv_mass,
                    state.particle_q_prev,
                    self.predicted,
                ],
                [state.particle_q],
                device=m.device,
            )
