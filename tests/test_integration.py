"""Verlet integration, nails and the Jacobi-averaged stick projection, checked with numbers."""

import math

import numpy as np
import pytest

import warpsim as ws


def test_free_fall_matches_parabola(device):
    b = ws.ModelBuilder()
    b.set_terrain(ws.Heightfield.flat(height=-1.0e4))
    x0 = np.array([1.0, -2.0, 0.0])
    v0 = np.array([3.0, 0.5, 4.0])
    b.add_particle(x0, 1.0)
    m = b.finalize(device)
    dt, steps = 0.01, 200
    g = np.array([0.0, 0.0, -ws.GRAVITY])
    s, c = m.state(), m.control()
    # previous position consistent with the parabola: x(-dt)
    x_prev = x0 - v0 * dt + 0.5 * g * dt * dt
    s.particle_q_prev.assign(x_prev[None])
    solver = ws.SolverVerlet(m)
    x = x0.copy()
    a_dt2 = (g.astype(np.float32) * np.float32(dt * dt)).astype(np.float64)  # the kernel's float32 a dt^2
    for _ in range(steps):
        solver.step(s, c, dt)
        x, x_prev = x + (x - x_prev) + a_dt2, x
    t = steps * dt
    expected = x0 + v0 * t + 0.5 * g * t * t
    got = s.positions()[0]
    np.testing.assert_array_equal(got, x)  # the same float64 recurrence, bit for bit
    # against the exact parabola: only the float32 rounding of a dt^2 (relative 3e-8) and float64 sums remain
    np.testing.assert_allclose(got, expected, rtol=0, atol=2e-5)
    assert s.time == pytest.approx(t)


def test_nailed_particle_never_moves(device):
    b = ws.ModelBuilder()
    ids, _, _ = b.add_grid((0, 0, 10), (0.2, 0, 0), (0, 0.2, 0), 5, 5, mass=1.0)
    b.add_nail(int(ids[0, 0]))
    b.add_nail(int(ids[0, 4]))
    m = b.finalize(device)
    s, c = m.state(), m.control()
    c.set_wind((3.0, 2.0, 1.0))
    solver = ws.SolverVerlet(m)
    start = s.positions()[[ids[0, 0], ids[0, 4]]].copy()
    for _ in range(300):
        solver.step(s, c, 0.01)
        np.testing.assert_array_equal(s.positions()[[ids[0, 0], ids[0, 4]]], start)
    assert np.linalg.norm(s.positions()[ids[4, 2]] - m.particle_q0[ids[4, 2]]) > 0.3  # the rest did move


@pytest.mark.parametrize("length, direction", [(1.5, "shorter"), (0.5, "longer")])
def test_stick_moves_towards_rest_length(device, length, direction, project):
    b = ws.ModelBuilder(gravity=0.0)
    i = b.add_particle((0, 0, 5), 1.0)
    j = b.add_particle((length, 0, 5), 1.0)
    b.add_stick(i, j, rest=1.0)
    m = b.finalize(device)
    s, c = m.state(), m.control()
    project(m, s, c, 1)
    new_length = float(m.stick_lengths(s.positions())[0])
    assert (new_length < length) if direction == "shorter" else (new_length > length)
    assert new_length == pytest.approx(1.0, abs=1e-6)  # a lone stick is solved in one iteration


def test_mass_weighting_ratio_four_to_one(device, project):
    b = ws.ModelBuilder(gravity=0.0)
    i = b.add_particle((0, 0, 5), 1.0)
    j = b.add_particle((2.0, 0, 5), 4.0)
    b.add_stick(i, j, rest=1.0)
    m = b.finalize(device)
    s, c = m.state(), m.control()
    before = s.positions()
    project(m, s, c, 1)
    moved = np.linalg.norm(s.positions() - before, axis=1)
    assert moved[0] / moved[1] == pytest.approx(4.0, rel=1e-5)
    assert moved.sum() == pytest.approx(1.0, rel=1e-5)


def _oracle_iteration(q, inv_mass, sticks, rest, nails):
    """NumPy version of one Jacobi iteration with per-particle averaged, mass-weighted corrections."""
    q = q.astype(np.float64)
    total = np.zeros_like(q)
    count = np.zeros(len(q))
    for (a, b), r in zip(sticks, rest, strict=True):
        d = q[b] - q[a]
        length = np.linalg.norm(d)
        w = inv_mass[a] + inv_mass[b]
        c = d * (length - r) / length / w
        total[a] += inv_mass[a] * c
        total[b] -= inv_mass[b] * c
        count[a] += 1
        count[b] += 1
    moved = q + np.where(count[:, None] > 0, total / np.maximum(count, 1)[:, None], 0.0)
    moved[nails] = q[nails]
    return moved


def _perturbed_mesh(rng, device, order=None):
    b = ws.ModelBuilder(gravity=0.0)
    rows, sticks, _ = b.add_subdivided_triangle((0, 0, 5), (2, 1, 5), (1, 2, 5.5), 4, mass=3.0)
    b.particle_mass = list(rng.uniform(0.1, 2.0, b.particle_count))
    b.particle_q = [tuple(np.add(p, rng.normal(0, 0.05, 3))) for p in b.particle_q]
    if order is not None:
        b.stick_particles = [b.stick_particles[k] for k in order]
        b.stick_rest = [b.stick_rest[k] for k in order]
    b.add_nail(rows[0][0])
    return b.finalize(device)


@pytest.mark.parametrize("scheme", ["fused", "scatter", "gather"])
def test_jacobi_iteration_matches_numpy_oracle(device, rng, scheme, project):
    m = _perturbed_mesh(rng, device)
    s, c = m.state(), m.control()
    q0 = s.positions()
    expected = _oracle_iteration(
        q0, m.particle_inv_mass.numpy().astype(np.float64), m.stick_particles_np, m.stick_rest.numpy(), m.nail_particles
    )
    project(m, s, c, 1, scheme=scheme)
    got = s.positions()
    np.testing.assert_allclose(got, expected, atol=2e-6)
    shared = np.bincount(m.stick_particles_np.ravel()) >= 3
    assert shared.sum() > 5 and np.abs(got - q0)[shared].max() > 1e-4  # shared particles really moved


@pytest.mark.parametrize("scheme", ["fused", "scatter", "gather"])
def test_stick_order_does_not_change_result(device, scheme, project):
    rng_a, rng_b = np.random.default_rng(7), np.random.default_rng(7)
    m1 = _perturbed_mesh(rng_a, device)
    order = np.random.default_rng(99).permutation(m1.stick_count)
    m2 = _perturbed_mesh(rng_b, device, order=order)
    results = []
    for m in (m1, m2):
        s, c = m.state(), m.control()
        project(m, s, c, 55, scheme=scheme)
        results.append(s.positions())
    np.testing.assert_allclose(results[0], results[1], atol=1e-6)
    assert np.abs(results[0] - m1.particle_q0).max() > 1e-3


def test_pendulum_period(device):
    # float32 Verlet stores the velocity as x - x_prev: keep the step's displacement well above the
    # float spacing of the coordinates (pivot near the origin, dt = 5 ms)
    length, theta0, dt = 1.0, 0.2, 5e-3
    b = ws.ModelBuilder()
    b.set_terrain(ws.Heightfield.flat(height=-100.0))
    pivot = b.add_particle((0, 0, 1), 1.0)
    bob = b.add_particle((length * math.sin(theta0), 0, 1 - length * math.cos(theta0)), 1.0)
    b.add_stick(pivot, bob)
    b.add_nail(pivot)
    m = b.finalize(device)
    s, c = m.state(), m.control()
    solver = ws.SolverVerlet(m, iterations=5)
    xs = []
    for _ in range(int(8.0 / dt)):
        solver.step(s, c, dt)
        xs.append(s.particle_q.numpy()[bob, 0])
    xs = np.array(xs)
    # downward zero crossings, linearly interpolated
    idx = np.nonzero((xs[:-1] > 0) & (xs[1:] <= 0))[0]
    crossings = (idx + xs[idx] / (xs[idx] - xs[idx + 1]) + 1) * dt
    period = np.diff(crossings).mean()
    expected = 2 * math.pi * math.sqrt(length / ws.GRAVITY) * (1 + theta0**2 / 16 + 11 * theta0**4 / 3072)
    assert len(crossings) >= 3
    assert period == pytest.approx(expected, rel=5e-3)
