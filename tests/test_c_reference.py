"""The benchmark's plain C step (benchmarks/c_reference/step.c) does the same work as warpsim's step, so the
c-reference rows compare like with like: same precision (float64 positions, float32 differences), same float
operations in the same order, so the same positions bit for bit. Skipped where no C compiler is installed."""

import json

import numpy as np
import pytest

from benchmarks import c_reference
from benchmarks.__main__ import main
from warpsim.physics.config import AIR_DENSITY
from warpsim.run.simulation import Simulation
from warpsim.scene import descriptor

pytestmark = pytest.mark.skipif(c_reference.compiler() is None, reason="no C compiler on the PATH")


@pytest.fixture(scope="module")
def program(tmp_path_factory):
    return c_reference.build(tmp_path_factory.mktemp("c"))


# Measured (gcc 12, -O3 -march=native, Warp 1.19 on the CPU): the C positions equal warpsim's bit for bit in
# every case below, after 3 steps and after 30 (max difference 0.0 m); the steps move them by 0.036 m (kite)
# to 1.3 m (flag) in 3 steps. The sums run in the same order (triangles and sticks in index order, float32;
# the momentum keeper's in particle order, float64) and neither side fuses multiply-adds, so any difference
# is a change of arithmetic on one side. The glider and the parachute are free worlds: warpsim gives them back
# the momentum the projection moved (keep_momentum, on by default: 5e-5 m on the glider and 1.2e-3 m on the
# parachute after 3 steps), and so does the C.
PAPER_CANOPY = {"parachute": {"canopy": "paper"}}  # the C has the per-triangle laws only (the NumPy has the canopy)
# the paper's flag: the C has no bending stiffness (refused, below)
GROUND = {"terrain": {"kind": "procedural", "amplitude": 5.0}, "flag": {"design": "paper", "pole_height": 0.5}}


@pytest.mark.parametrize(
    "scene, override, steps",
    [
        ("hang-glider", {}, 3),  # sail air, drag bodies, strap
        ("hang-glider", {"hang_glider": {"design": "paper"}, "air": {"model": "plate"}}, 3),
        ("hang-glider", {"solver": {"keep_momentum": False}}, 3),  # the paper's projection alone
        ("kite", {}, 3),  # a nail (the rope's anchor), the sail's elastic cloth sticks (XPBD)
        ("kite", {}, 30),
        ("kite", {"solver": {"relaxation": 1.0}}, 30),  # elastic, plain averaging (the kite over-relaxes by 1.5)
        ("kite", {"kite": {"sail_compliance": 0.0, "frame_compliance": 0.0}}, 30),  # rigid, the paper's sticks
        ("parachute", PAPER_CANOPY, 3),  # 400 m up
        ("parachute", PAPER_CANOPY, 30),
        ("flag", GROUND, 3),  # 6 particles on sloped terrain: normal push-out with friction
        ("flag", {**GROUND, "ground": {"collision": "clamp"}}, 30),
    ],
)
def test_c_step_agrees_with_warpsim(program, scene, override, steps):
    fixed = descriptor.merge("test", descriptor.resolve(scene)[0], {"air": {"density": AIR_DENSITY}})  # the C's air
    sim = Simulation(descriptor.merge("test", fixed, override), device="cpu")
    start = sim.state.positions().copy()
    seconds, q, spent = c_reference.run(program, sim, steps, parts=True)
    sim.step(steps)
    assert q.dtype == np.float64
    np.testing.assert_array_equal(q, sim.state.positions())  # bit for bit
    assert np.abs(q - start).max() > 0.01  # the steps moved things: the comparison means something
    assert seconds > 0 and set(spent) == {"air", "verlet", "constraints", "terrain"}


def test_c_reference_refuses_the_whole_canopy_force(tmp_path):
    sim = Simulation(descriptor.resolve("parachute")[0])
    with pytest.raises(ValueError, match="whole-canopy"):
        c_reference.export(sim, tmp_path / "model.bin")


def test_c_reference_refuses_bending(tmp_path):
    sim = Simulation(descriptor.resolve("flag")[0])  # the default flag: a sheet, with hinges and twists
    with pytest.raises(ValueError, match="no bending stiffness: set flag.design = paper"):
        c_reference.export(sim, tmp_path / "m.bin")


def test_c_reference_refuses_wind_shear(tmp_path):
    sheared = {"flag": {"design": "paper"}, "wind": {"shear_exponent": 0.14}}
    sim = Simulation(descriptor.merge("test", descriptor.resolve("flag")[0], sheared))
    with pytest.raises(ValueError, match="no wind shear"):
        c_reference.export(sim, tmp_path / "m.bin")


def test_benchmark_row_compares_with_c(tmp_path):
    out = tmp_path / "c.json"
    assert main(["-k", "c-reference-hang-glider", "--min-time", "0.05", "--json", str(out)]) == 0
    (row,) = json.loads(out.read_text())["results"]
    assert row["baseline_steps_per_s"] > 0 and row["ratio"] == pytest.approx(
        row["steps_per_s"] / row["baseline_steps_per_s"]
    )
    assert row["c_differs_after_3_steps_m"] == 0.0 and "constraints" in row["c_profile"]  # bit for bit
    assert "-march=native" in row["baseline"]
