"""The benchmark's plain NumPy step (benchmarks/numpy_step.py) does the same work as warpsim's step, at the same
precision (float64 positions, float32 differences), with the momentum of free worlds kept as warpsim does."""

import numpy as np
import pytest

from benchmarks.numpy_step import NumpyVerlet
from warpsim.run.simulation import Simulation
from warpsim.scene import descriptor


# Positions are float64 on both sides, the rest float32 in the kernels' order, except the per-particle sums:
# np.bincount sums in float64 and rounds once, warpsim in float32 in stick / triangle order. That leaves
# differences of a float32 rounding of the forces and corrections, measured (NumPy 2.4, Warp 1.19, CPU):
# glider 1.3e-7 m (plate 1.0e-7, paper 1.1e-7; 1.7e-7 without keep_momentum), kite 2.9e-7 with its elastic
# cloth (1.3e-7 over-relaxed after 30 steps; 3.2e-5 and 1.0e-4 if the reference took the cloth as rigid),
# rigid cloth 1.7e-7 (paper 2e-8), parachute 1.8e-7 at 400 m up, the sheared flag 6.6e-8 after 50 steps; the flag
# on the ground 3.1e-7 after 100 (with the float32 positions of the previous version: up to 3e-4 m).
@pytest.mark.parametrize(
    "scene, override, steps, tolerance",
    [
        ("hang-glider", {}, 3, 1e-6),
        ("hang-glider", {"air": {"model": "plate"}}, 3, 1e-6),
        ("hang-glider", {"hang_glider": {"design": "paper"}}, 3, 1e-6),
        ("hang-glider", {"solver": {"keep_momentum": False}}, 3, 1e-6),
        ("kite", {}, 3, 1e-6),  # its sail's cloth sticks are elastic (XPBD)
        ("kite", {"kite": {"sail_compliance": 0.0, "frame_compliance": 0.0}}, 3, 1e-6),  # rigid sticks
        ("kite", {"solver": {"chebyshev": 0.0, "relaxation": 1.5}}, 30, 1e-6),  # elastic, over-relaxed
        ("kite", {"solver": {"relaxation": 1.5}}, 30, 1e-6),  # elastic, over-relaxed and Chebyshev-accelerated
        ("kite", {"kite": {"design": "paper"}}, 3, 1e-6),
        ("parachute", {}, 3, 1e-6),  # it starts at 400 m: float64 positions keep every step there too
        ("parachute", {"parachute": {"canopy": "paper"}}, 3, 1e-6),  # the paper's per-triangle air
        ("scenes/parachute.toml", {"wind": {"gust_intensity": 0.0}}, 30, 1e-6),  # whole canopy, in a breeze
        (
            "flag",
            {
                "flag": {"design": "paper"},  # no bending: the NumPy has none
                "wind": {"shear_exponent": 0.14},
                "solver": {"damping": 0.01, "dt": 0.01, "iterations": 55},
            },
            50,
            1e-6,
        ),
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
    assert ref.q.dtype == np.float64
    assert np.abs(q - start).max() > 1e4 * tolerance  # the step moved things: the comparison means something


def test_numpy_collision_matches_on_the_ground():
    """A flag pole taller than its flag is short: the cloth lies on sloped terrain in both versions."""
    desc = descriptor.merge(
        "test",
        descriptor.resolve("flag")[0],
        {
            "terrain": {"kind": "procedural", "amplitude": 5.0},
            "flag": {"design": "paper", "pole_height": 0.5, "height": 1.2},
        },
    )
    sim = Simulation(desc, device="cpu")
    ref = NumpyVerlet(sim)
    for _ in range(100):
        ref.step()
    sim.step(100)
    q = sim.state.positions()
    ground = sim.model.terrain.height(q[:, 0], q[:, 1])
    assert (q[:, 2] - ground < 0.01).sum() > 3  # some particles rest on the terrain
    np.testing.assert_allclose(ref.q, q, atol=1e-6, rtol=0)  # 3.1e-7 m measured
