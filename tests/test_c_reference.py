"""The benchmark's plain C step (benchmarks/c_reference/step.c) does the same work as warpsim's step, so the
c-reference rows compare like with like. Skipped where no C compiler is installed."""

import json

import numpy as np
import pytest

from benchmarks import c_reference
from benchmarks.__main__ import main
from warpsim import descriptor
from warpsim.runner import Simulation

pytestmark = pytest.mark.skipif(c_reference.compiler() is None, reason="no C compiler on the PATH")


@pytest.fixture(scope="module")
def program(tmp_path_factory):
    return c_reference.build(tmp_path_factory.mktemp("c"))


@pytest.mark.parametrize(
    "scene, override, tolerance",
    [
        ("hang-glider", {}, 1e-4),  # sail air, drag bodies, strap
        ("hang-glider", {"hang_glider": {"design": "paper"}, "air": {"model": "plate"}}, 1e-4),
        ("kite", {}, 1e-5),  # 2e-6 measured: the float32 sums' order
        ("parachute", {}, 3e-4),
        ("flag", {"terrain": {"kind": "procedural", "amplitude": 5.0}, "flag": {"pole_height": 0.5}}, 1e-4),
    ],
)
def test_c_step_agrees_with_warpsim(program, scene, override, tolerance):
    sim = Simulation(descriptor.merge("test", descriptor.resolve(scene)[0], override), device="cpu")
    start = sim.state.positions().copy()
    seconds, q, spent = c_reference.run(program, sim, 3, parts=True)
    sim.step(3)
    np.testing.assert_allclose(q, sim.state.positions(), atol=tolerance, rtol=0)
    assert np.abs(q - start).max() > 100 * tolerance  # the steps moved things: the comparison means something
    assert seconds > 0 and set(spent) == {"air", "verlet", "constraints", "terrain"}


def test_c_reference_refuses_wind_shear(tmp_path):
    sim = Simulation(descriptor.merge("test", descriptor.resolve("flag")[0], {"wind": {"shear_exponent": 0.14}}))
    with pytest.raises(ValueError, match="no wind shear"):
        c_reference.export(sim, tmp_path / "m.bin")


def test_benchmark_row_compares_with_c(tmp_path):
    out = tmp_path / "c.json"
    assert main(["-k", "c-reference-hang-glider", "--min-time", "0.05", "--json", str(out)]) == 0
    (row,) = json.loads(out.read_text())["results"]
    assert row["baseline_steps_per_s"] > 0 and row["ratio"] == pytest.approx(
        row["steps_per_s"] / row["baseline_steps_per_s"]
    )
    assert row["c_differs_after_3_steps_m"] <= 1e-4 and "constraints" in row["c_profile"]
