"""Options of the Jacobi constraint solver: stick weights, mass splitting, Chebyshev acceleration."""

import numpy as np
import pytest

import warpsim as ws
from warpsim.physics.projection import chebyshev_weights, jacobi_equivalent_iterations


def _mesh(rng, device, double_first: str | None = None, nail_first: bool = False):
    """A perturbed free triangle mesh of random masses; the first stick doubled, the first particle nailed,
    as asked."""
    b = ws.ModelBuilder(gravity=0.0)
    b.add_subdivided_triangle((0, 0, 5), (2, 1, 5), (1, 2, 5.5), 4, mass=3.0)
    b.particle_mass = list(rng.uniform(0.1, 2.0, b.particle_count))
    b.particle_q = [tuple(np.add(p, rng.normal(0, 0.05, 3))) for p in b.particle_q]
    if double_first == "weight":
        b.stick_weight[0] = 2.0
    elif double_first == "duplicate":
        i, j = b.stick_particles[0]
        b.add_stick(i, j, rest=b.stick_rest[0])
    if nail_first:
        b.add_nail(0)
    return b.finalize(device)


def _project(project, m, iterations=20, mass_splitting=False, chebyshev=0.0):
    s, c = m.state(), m.control()
    project(m, s, c, iterations, mass_splitting=mass_splitting, chebyshev=chebyshev)
    return s.positions()


@pytest.mark.parametrize("mass_splitting", [False, True])
def test_weight_two_is_a_doubled_stick(device, mass_splitting, project):
    weighted = _project(project, _mesh(np.random.default_rng(3), device, "weight"), mass_splitting=mass_splitting)
    doubled = _project(project, _mesh(np.random.default_rng(3), device, "duplicate"), mass_splitting=mass_splitting)
    plain = _project(project, _mesh(np.random.default_rng(3), device), mass_splitting=mass_splitting)
    np.testing.assert_allclose(weighted, doubled, atol=2e-6)
    assert np.abs(weighted - plain).max() > 1e-4  # the weight really changed something


def test_mass_splitting_conserves_momentum_plain_average_does_not(device, project):
    m = _mesh(np.random.default_rng(5), device)
    mass = m.particle_mass[:, None]
    q0 = m.particle_q0.astype(np.float32).astype(np.float64)
    moments = {}
    for split in (False, True):
        moved = _project(project, m, iterations=1, mass_splitting=split)
        moments[split] = np.abs((mass * (moved - q0)).sum(axis=0)).max()
        scale = np.abs(mass * (moved - q0)).sum(axis=0).max()
    assert moments[True] < 1e-5 * scale
    assert moments[False] > 1e-2 * scale


def test_chebyshev_hanging_chain_sags_less(device):
    """A 16-particle chain hanging from a nail: Chebyshev at the same 55 iterations halves the sag."""
    worst = {}
    for rho in (0.0, 0.95):
        b = ws.ModelBuilder()
        b.set_terrain(ws.Heightfield.flat(height=-100.0))
        ids, _ = b.add_rope((0, 0, 0), (0, 0, -1.5), 16, mass=1.6)
        b.add_nail(ids[0])
        m = b.finalize(device)
        s, c = m.state(), m.control()
        solver = ws.SolverVerlet(m, chebyshev=rho, damping=0.01)
        for _ in range(300):
            solver.step(s, c, 0.01)
        worst[rho] = m.stick_stretch(s.positions()).max()
    assert worst[0.0] > 0.005  # the paper's iteration sags visibly (README: ~0.9 % per stick)
    assert worst[0.95] < 0.5 * worst[0.0]


def test_chebyshev_weights():
    assert chebyshev_weights(5, 0.0) == [1.0] * 5
    w = chebyshev_weights(60, 0.95, delay=10)
    assert w[:10] == [1.0] * 10 and w[10] == pytest.approx(2 / (2 - 0.95**2))
    assert all(1.0 < x < 2.0 for x in w[10:])  # over-relaxation that stays below 2
    assert w[-1] == pytest.approx(2 / (1 + np.sqrt(1 - 0.95**2)), rel=1e-3)  # the optimal SOR limit


@pytest.mark.parametrize("iterations, rho", [(55, 0.99), (220, 0.99), (880, 0.99), (110, 0.95), (440, 0.95), (55, 0.0)])
def test_jacobi_equivalent_iterations_match_the_weights_on_slow_modes(iterations, rho):
    # a mode plain Jacobi shrinks by lam = 1 - eps per iteration, run through the weights' own recurrence
    # (x_{k+1} = omega lam x_k + (1 - omega) x_{k-1}, the kernels' increment form): the count of plain iterations
    # that shrink it as much, log P / log lam, against the closed form
    for eps in (1e-6, 1e-5, 1e-4):
        lam, prev, cur = 1.0 - eps, 1.0, 1.0
        for omega in chebyshev_weights(iterations, rho):
            prev, cur = cur, omega * lam * cur + (1.0 - omega) * prev
        measured = np.log(cur) / np.log(lam)
        assert measured == pytest.approx(jacobi_equivalent_iterations(iterations, rho), rel=0.025), (eps, measured)
    if rho:
        assert jacobi_equivalent_iterations(iterations, rho) > 2.5 * iterations  # rho 0.95: 3.2 x, 0.99: 7.1 x


def test_solver_refuses_bad_chebyshev(device):
    m = _mesh(np.random.default_rng(1), device)
    with pytest.raises(ValueError, match="chebyshev"):
        ws.SolverVerlet(m, chebyshev=1.0)


@pytest.mark.parametrize("iterations", [1, 20, 55])
def test_schemes_agree_and_repeat_bit_for_bit(device, iterations, project):
    """On the CPU fused and scatter do the same float operations in the same order (bit-identical); gather differs
    only in the order of float additions. On CUDA scatter's atomics add in the order the threads arrive, so there it
    agrees with the others to float rounding (seen on an H200: 2e-8 m) and need not repeat itself; fused (one thread)
    and gather (no atomics) repeat themselves exactly on every device. A moved nail is honoured by all."""
    m = _mesh(np.random.default_rng(11), device, nail_first=True)
    results = {}
    for scheme in ("fused", "scatter", "gather"):
        runs = []
        for _ in range(2):
            s, c = m.state(), m.control()
            c.nail_target.assign(np.array([m.nail_target0[0] + (0.3, -0.2, 0.1)], dtype=np.float32))
            project(m, s, c, iterations, mass_splitting=True, chebyshev=0.9, scheme=scheme)
            runs.append(s.positions())
        if device == "cpu" or scheme != "scatter":
            np.testing.assert_array_equal(runs[0], runs[1])
        np.testing.assert_allclose(runs[0][0], m.nail_target0[0] + (0.3, -0.2, 0.1), atol=1e-6)  # on its nail
        results[scheme] = runs[0]
    if device == "cpu":
        np.testing.assert_array_equal(results["fused"], results["scatter"])
    np.testing.assert_allclose(results["fused"], results["scatter"], atol=2e-6)
    np.testing.assert_allclose(results["scatter"], results["gather"], atol=2e-6)
    assert np.abs(results["scatter"] - m.particle_q0).max() > 1e-3  # it did move


def test_unknown_scheme_is_refused(device):
    with pytest.raises(ValueError, match="scatter, gather, fused"):
        ws.SolverVerlet(_mesh(np.random.default_rng(1), device), constraint_scheme="red-black")


@pytest.mark.parametrize("iterations", [1, 255, 256, 257, 1000, 10000])
def test_graph_captured_fused_solver_matches_scatter_across_the_allowed_range(device, iterations):
    """The whole allowed range of ``solver.iterations`` (1..10000): the captured fused step (the CPU default) gives
    the positions of the scatter scheme launched kernel by kernel, bit for bit (at 256 and more the fused scheme
    once read Chebyshev weights made during the capture and turned every position to NaN at step 3). On CUDA,
    where scatter's atomics add in a varying order, the captured fused step gives the fused step launched without a
    graph bit for bit, and scatter's to float rounding (seen on an H200: 1.2e-6 m after 4 steps of 10000 iterations,
    2.4 float32 steps of a 5 m coordinate)."""
    results = {}
    for scheme, use_graph in (("fused", True), ("scatter", False), ("fused", False)):
        m = _mesh(np.random.default_rng(5), device, nail_first=True)
        solver = ws.SolverVerlet(m, iterations=iterations, use_graph=use_graph, constraint_scheme=scheme)
        s, c = m.state(), m.control()
        for _ in range(4):
            solver.step(s, c, 0.01)
        results[scheme, use_graph] = s.positions()
    captured = results["fused", True]
    assert np.isfinite(captured).all()
    if device == "cpu":
        np.testing.assert_array_equal(captured, results["scatter", False])
    np.testing.assert_allclose(captured, results["scatter", False], atol=5e-6)
    np.testing.assert_array_equal(captured, results["fused", False])


@pytest.mark.parametrize("scheme", ["fused", "scatter", "gather"])
@pytest.mark.parametrize("dt", [0.01, 0.0025])
@pytest.mark.parametrize("chebyshev, relaxation", [(0.0, 1.0), (0.99, 1.0), (0.0, 1.5)])
def test_elastic_sticks_stretch_as_springs_at_every_step(device, scheme, dt, chebyshev, relaxation):
    # a 2 kg weight hung from a nail by two elastic sticks in series, a 0.5 kg particle between them, the lower stick
    # of weight 2 (twice as stiff): at rest each stick stretches its tension times its compliance (Hooke), the
    # upper (2.5 kg) g c, the lower 2 g c / 2, whatever the step (XPBD's compliance / dt^2), the over-relaxation or
    # the Chebyshev acceleration (lam is extrapolated as the positions are); rigid sticks do not
    g, c = 9.80665, 2e-4  # [m/s^2], [m/N]: 0.5 mm / 0.2 mm, far above float32's resolution of a 0.3 m stick
    results = {}
    for compliance in (c, 0.0):
        b = ws.ModelBuilder()
        top = b.add_particle((0.0, 0.0, 2.0), 1.0)
        mid = b.add_particle((0.0, 0.0, 1.7), 0.5)
        low = b.add_particle((0.0, 0.0, 1.4), 2.0)
        upper, lower = b.add_stick(top, mid), b.add_stick(mid, low, weight=2.0)
        b.set_compliance([upper, lower], compliance)
        b.add_nail(top)
        m = b.finalize(device)
        config = ws.SolverConfig(
            dt=dt, iterations=55, chebyshev=chebyshev, relaxation=relaxation, mass_splitting=True, damping=0.02
        )
        solver = ws.SolverVerlet(m, config, constraint_scheme=scheme)
        state, control = m.state(), m.control()
        for _ in range(int(round(4.0 / dt))):
            solver.step(state, control, dt)
        q = state.positions()
        results[compliance] = (np.linalg.norm(q[mid] - q[top]) - 0.3, np.linalg.norm(q[low] - q[mid]) - 0.3)
    assert results[c][0] == pytest.approx(2.5 * g * c, rel=0.01), results
    assert results[c][1] == pytest.approx(2.0 * g * c / 2.0, rel=0.01), results
    assert abs(results[0.0][0]) < 0.02 * 2.5 * g * c and abs(results[0.0][1]) < 0.02 * 2.5 * g * c, results


def test_elastic_sticks_need_the_step(device, project):
    b = ws.ModelBuilder()
    b.add_particle((0.0, 0.0, 1.0), 1.0)
    b.add_particle((0.0, 0.0, 0.5), 1.0)
    b.set_compliance([b.add_stick(0, 1)], 1e-3)
    m = b.finalize(device)
    with pytest.raises(ValueError, match="dt"):
        project(m, m.state(), m.control(), 5, mass_splitting=True)
    with pytest.raises(ValueError, match="mass_splitting"):  # the plain average has no per-stick tension
        project(m, m.state(), m.control(), 5, mass_splitting=False)
    with pytest.raises(ValueError, match="compliance"):
        b.set_compliance([0], -1.0)
