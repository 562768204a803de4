"""Heightfield: sampling, nothing below the ground, friction on a slope."""

import numpy as np
import pytest

import warpsim as ws
from warpsim.physics.kernels.collision import CollisionMode


def test_bilinear_height_and_normal():
    hf = ws.Heightfield(np.array([[0.0, 1.0], [2.0, 3.0]]), size=(2.0, 2.0), origin=(0.0, 0.0))
    assert hf.height(1.0, 1.0) == pytest.approx(1.5)
    assert hf.height(2.0, 0.0) == pytest.approx(1.0)
    n = hf.normal(0.5, 0.5)
    np.testing.assert_allclose(n, np.array([-0.5, -1.0, 1.0]) / np.sqrt(2.25), rtol=1e-6)


def test_procedural_terrain_is_seeded():
    a = ws.Heightfield.procedural(seed=3)
    assert a.heights.shape == (256, 256)
    np.testing.assert_array_equal(a.heights, ws.Heightfield.procedural(seed=3).heights)
    assert not np.array_equal(a.heights, ws.Heightfield.procedural(seed=4).heights)
    assert a.heights.max() - a.heights.min() > 20.0


def test_load_npy(tmp_path):
    path = tmp_path / "hills.npy"
    np.save(path, np.arange(16, dtype=np.float32).reshape(4, 4))
    hf = ws.Heightfield.load(path, size=30.0)
    assert hf.height(15.0, 15.0) == pytest.approx(15.0)
    with pytest.raises(ValueError, match="npy"):
        ws.Heightfield.load(tmp_path / "hills.png")


@pytest.mark.parametrize("mode", [CollisionMode.CLAMP, CollisionMode.NORMAL])
def test_no_particle_below_terrain_after_any_step(device, mode):
    terrain = ws.Heightfield.procedural(size=60.0, amplitude=6.0, seed=5)
    b = ws.ModelBuilder()
    b.set_terrain(terrain)
    # 0.3 kg/m^2: the explicit air force is stable at dt = 0.01 s while rho |w| dt / (m/A) < ~1
    b.add_grid((-6, -6, 8), (0.6, 0, 0), (0, 0.6, 0), 20, 20, mass=20.0, vel=(3.0, 1.0, -5.0))
    m = b.finalize(device)
    s, c = m.state(0.01), m.control()
    c.set_wind((6.0, 0.0, 0.0))
    solver = ws.SolverVerlet(m, iterations=20, ground=ws.GroundConfig(collision=mode, friction=0.5))
    touched = 0
    for _ in range(300):
        solver.step(s, c, 0.01)
        q = s.positions()
        gap = q[:, 2] - terrain.height(q[:, 0], q[:, 1])
        assert gap.min() >= -1e-4, f"particle {gap.argmin()} is {-gap.min():.2e} m below the terrain"
        touched += int((gap < 1e-3).sum())
    assert touched > 1000  # the cloth really lay on the ground


def _slide_distance(device, friction, slope_deg=20.0):
    n = 64
    size = 100.0
    x = np.linspace(-size / 2, size / 2, n)
    heights = np.tile(-np.tan(np.radians(slope_deg)) * x, (n, 1))  # downhill towards +x
    terrain = ws.Heightfield(heights, (size, size))
    b = ws.ModelBuilder()
    b.set_terrain(terrain)
    b.add_particle((0.0, 0.0, 0.5), 1.0)
    m = b.finalize(device)
    s, c = m.state(), m.control()
    solver = ws.SolverVerlet(m, ground=ws.GroundConfig(friction=friction))
    for _ in range(200):
        solver.step(s, c, 0.01)
    return s.positions()[0, 0]


def test_more_friction_slides_less(device):
    slick, rough, sticky = (_slide_distance(device, mu) for mu in (0.05, 0.2, 1.0))
    assert slick > rough > sticky
    assert slick > 2.0  # on a 20 degree slope a nearly frictionless particle runs away
    assert abs(sticky) < 0.3  # friction 1.0 > tan(20 deg) holds it (it only settles)


def test_outside_the_grid_the_edge_height_holds_and_host_equals_kernel(device):
    """Beyond the far edges the lookup uses the last cell up to its edge (no sample past the array is read): the
    height is the edge's, the normal the edge cell's, and the host query gives the kernel's float32 numbers."""
    n = 64
    heights = np.zeros((n, n), dtype=np.float32)
    heights[:, -1] = 5.0  # a ramp up to 5 m along the +x edge; the -x edge at -3 m
    heights[:, 0] = -3.0
    hf = ws.Heightfield(heights, (100.0, 100.0))
    cell = 100.0 / (n - 1)
    x = np.array([50.0, 60.0, 1e4, -1e4, 50.0 - 0.5 * cell])
    y = np.array([0.0, 49.0, 1e4, -1e4, 0.0])
    h, normal = hf.sample(x, y)
    np.testing.assert_array_equal(h[:4], [5.0, 5.0, 5.0, -3.0])
    assert h[4] == pytest.approx(2.5, abs=1e-4)  # halfway up the last cell
    slope = 5.0 / cell  # the last cell's rise: the normal beyond the edge keeps it
    np.testing.assert_allclose(normal[1], np.array([-slope, 0.0, 1.0]) / np.hypot(slope, 1.0), rtol=1e-5)
    # a particle beyond the +x edge, below the edge height, ends on it (the kernels see the same terrain)
    b = ws.ModelBuilder(gravity=0.0)
    b.set_terrain(hf)
    b.add_particle((70.0, 10.0, 1.0), 1.0)
    m = b.finalize(device)
    s, c = m.state(), m.control()
    ws.SolverVerlet(m, ground=ws.GroundConfig(collision="clamp")).step(s, c, 0.01)
    assert s.positions()[0, 2] == np.float32(5.0)
