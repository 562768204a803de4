"""The standard atmosphere (warpsim.physics.atmosphere): its table, the density every step gives each world, a
canopy's descent at altitude, and bad settings in one line."""

import math

import numpy as np
import pytest

from benchmarks.validation.atmosphere_rows import ISO_TABLE, atmosphere_table, canopy_descent
from warpsim.cli import main
from warpsim.physics.atmosphere import SEA_LEVEL_DENSITY, isa, scene_density
from warpsim.physics.config import AIR_DENSITY
from warpsim.run.simulation import Simulation
from warpsim.scene import descriptor


def test_density_follows_iso_2533_and_a_hot_day_is_thinner():
    assert all(row.ok for row in atmosphere_table()), [row.measured for row in atmosphere_table()]
    assert SEA_LEVEL_DENSITY == pytest.approx(ISO_TABLE[0.0], rel=1e-4)
    t, p, rho = isa(0.0, 15.0)  # ISA+15: the standard pressure, 15 K warmer
    assert t == pytest.approx(303.15) and p == pytest.approx(101325.0) and rho == pytest.approx(1.225 * 288.15 / 303.15)
    assert scene_density({"density": 1.1}, 5000.0) == 1.1  # a fixed density is fixed
    assert scene_density({"density": 0.0, "elevation": 2000.0}, 1000.0) == pytest.approx(isa(3000.0)[2])


@pytest.mark.parametrize("worlds", [1, 3])
def test_each_world_breathes_the_air_of_its_own_altitude(worlds):
    """The kernel's density (float32, every step) against the host's ISA at each world's mean particle height, for
    parachutes 400, 2400 and 4400 m up on a 1 km plateau on a hot day; a fixed density stays fixed."""
    d = descriptor.merge(
        "test",
        descriptor.resolve("parachute")[0],
        {"air": {"density": 0.0, "elevation": 1000.0, "temperature_offset": 20.0}},
    )
    if worlds > 1:
        heights = {"count": worlds, "parachute": {"altitude": [400.0, 2400.0, 4400.0]}}
        d = descriptor.merge("test", d, {"worlds": heights})
    sim = Simulation(d)
    sim.step(5)
    q = sim.state.particle_q_prev.numpy()  # the density of the last step is the one of the positions it started at
    start = sim.solver.world_start.numpy()
    # the kernel takes at most about 64 of a world's particles, evenly spaced
    strides = [max(int(start[w + 1] - start[w]) // 64, 1) for w in range(worlds)]
    expected = [isa(q[start[w] : start[w + 1] : strides[w], 2].mean() + 1000.0, 20.0)[2] for w in range(worlds)]
    np.testing.assert_allclose(sim.control.air_density.numpy(), expected, rtol=2e-6)
    if worlds > 1:
        assert expected[0] > expected[1] > expected[2]
    fixed = Simulation(descriptor.merge("test", descriptor.resolve("parachute")[0], {"air": {"density": AIR_DENSITY}}))
    fixed.step(5)
    assert fixed.control.air_density.numpy()[0] == np.float32(AIR_DENSITY)


def test_a_canopy_falls_faster_in_thin_air_as_the_square_root_of_the_density():
    """The ringslot canopy in still air near sea level and near 3 km, measured from the particles: v ~ rho^-1/2
    (the validation table has 1, 3 and 5 km, dt halved and 10 km out)."""
    v0, h0 = canopy_descent(350.0, seconds=20.0)
    v3, h3 = canopy_descent(3250.0, seconds=20.0)
    expected = v0 * math.sqrt(isa(h0)[2] / isa(h3)[2])
    assert v3 == pytest.approx(expected, rel=0.03)
    assert v3 > 1.15 * v0  # it really is faster up there (ISA: 0.909 against 1.20 kg/m^3)


@pytest.mark.parametrize(
    ("setting", "message"),
    [
        ("air.elevation=25000", "air.elevation = 25000"),
        ("air.temperature_offset=-100", "air.temperature_offset"),
        ("air.density=-1", "air.density"),
        ("parachute.altitude=30000", "outside the standard atmosphere's -2000 to 20000 m"),
    ],
)
def test_bad_atmosphere_settings_are_one_line(setting, message, capsys):
    code = main(["run", "parachute", "--seconds", "0.1", "--set", "air.density=0", "--set", setting])
    err = capsys.readouterr().err
    assert code == 2 and message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1, err


@pytest.mark.slow
def test_a_run_says_the_air_its_figures_depend_on(capsys):
    """The figures of a run say the air they depend on: the standard atmosphere's density at the end (the default),
    a fixed density, and turbulence."""
    args = ["run", "parachute", "--seconds", "1", "--set", "air.elevation=1500"]
    assert main([*args, "--set", "wind.turbulence_intensity=0.1"]) == 0
    out = capsys.readouterr().out
    assert "air: the standard atmosphere" in out and "1500 m above sea level" in out
    assert "turbulence: von Karman, intensity 0.1, length scale 24.5 m" in out
    assert main(["run", "parachute", "--seconds", "1", "--set", f"air.density={AIR_DENSITY}"]) == 0
    out = capsys.readouterr().out
    assert "air: a fixed density, 1.29422 kg/m^3" in out and "standard atmosphere, " not in out
    assert "turbulence:" not in out
