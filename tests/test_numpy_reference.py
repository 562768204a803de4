"""The benchmark's plain NumPy step (benchmarks/numpy_step.py) does the same work as warpsim's step."""

import numpy as np
import pytest

from benchmarks.numpy_step import NumpyVerlet
from warpsim import descriptor
from warpsim.runner import Simulation


@pytest.mark.parametrize(
    "scene, override, steps, tolerance",
    [
        # at 300 m a float32 ulp is 3e-5 m; the iterates' float32 offsets keep the sums' order differences
        # (np.bincount vs stick-order atomics), which used to round away: up to 2 ulps after 3 steps
        ("hang-glider", {}, 3, 1e-4),
        ("hang-glider", {"air": {"model": "plate"}}, 3, 1e-4),
        ("hang-glider", {"hang_glider": {"design": "paper"}}, 3, 1e-4),
        ("kite", {}, 3, 1e-5),
        ("kite", {"kite": {"design": "paper"}}, 3, 1e-5),
        ("parachute", {}, 3, 3e-4),  # it starts at 400 m, where a float32 ulp is 3e-5 m
        ("flag", {"wind": {"shear_exponent": 0.14}, "solver": {"damping": 0.01}}, 50, 1e-4),
    ],
)
def test_numpy_step_agrees_with_warpsim(scene, override, steps, tolerance):
    desc = descriptor.merge("test", descriptor.resolve(scene)[0], override)
    sim = Simulation(desc, device="cpu")
    ref = NumpyVerlet(sim)
    start = ref.q.copy()
    for _ in range(steps):
        ref.step()
    sim.step(steps)
    q = sim.state.positions()
    np.testing.assert_allclose(ref.q, q, atol=tolerance, rtol=0)
    assert np.abs(q - start).max() > 100 * tolerance  # the step moved things: the comparison means something


def test_numpy_collision_matches_on_the_ground():
    """A flag pole taller than its flag is short: the cloth lies on sloped terrain in both versions."""
    desc = descriptor.merge(
        "test",
        descriptor.resolve("flag")[0],
        {"terrain": {"kind": "procedural", "amplitude": 5.0}, "flag": {"pole_height": 0.5, "height": 1.2}},
    )
    sim = Simulation(desc, device="cpu")
    ref = NumpyVerlet(sim)
    for _ in range(100):
        ref.step()
    sim.step(100)
    q = sim.state.positions()
    ground = sim.model.terrain.height(q[:, 0], q[:, 1])
    assert (q[:, 2] - ground < 0.01).sum() > 3  # some particles rest on the terrain
    np.testing.assert_allclose(ref.q, q, atol=1e-4, rtol=0)
