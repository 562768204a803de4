"""The parachute of Section 8: without the rim hoop it closes, with it it stays open and falls slower."""

import numpy as np
import pytest

from warpsim.objects.parachute import projected_radius
from warpsim.run.simulation import Simulation
from warpsim.scene.descriptor import defaults


def _drop(hoop: bool, seconds: float = 10.0, keep_momentum: bool = False):
    """``seconds`` of the default drop: the canopy radius each second [m], the descent speed at the end
    [m/s], and the worst hoop stick stretch seen every 0.5 s. The paper's experiment uses the paper's projection
    alone (``keep_momentum`` off); the default keeps the free parachute's momentum after each projection."""
    d = defaults("parachute")
    d["parachute"]["hoop"] = hoop
    d["solver"]["keep_momentum"] = keep_momentum
    sim = Simulation(d)
    rec = sim.model.objects[0]
    radii, hoop_stretch = [], 0.0
    for k in range(int(2 * seconds)):
        sim.step(50)
        q = sim.state.positions()
        if len(rec.stick_groups["hoop"]):
            hoop_stretch = max(hoop_stretch, np.abs(sim.model.stick_stretch(q)[rec.stick_groups["hoop"]]).max())
        if k % 2 == 1:
            radii.append(projected_radius(rec, q))
    descent = -sim.state.velocities(sim.dt)[rec.person, 2]
    return sim, np.array(radii), float(descent), hoop_stretch


@pytest.fixture(scope="module")
def drops():
    """10 s drops with and without the hoop (the issue's 10 s of flight)."""
    return {hoop: _drop(hoop) for hoop in (True, False)}


def test_canopy_counts(drops):
    sim = drops[True][0]
    rec = sim.model.objects[0]
    assert len(rec.parts["canopy"]) == 1 + 3 * 6 * 7  # centre + rings of 6, 12, ..., 36
    assert len(rec.tri_parts["canopy"]) == 6 * 6**2  # 216 triangles
    assert sim.model.tri_count == 216


def test_without_hoop_the_canopy_closes(drops):
    _, radii, _, _ = drops[False]
    assert radii[-1] < 0.5 * 3.5, f"radius {radii[-1]:.2f} m"


def test_with_hoop_the_canopy_stays_open(drops):
    _, radii, _, _ = drops[True]
    assert radii.min() > 0.6 * 3.5, f"radius {radii.min():.2f} m"


def test_hoop_frame_within_one_percent_over_ten_seconds(drops):
    """The hoop is the parachute's frame: its sticks stay within 1 % of rest length (measured 0.47 %)."""
    stretch = drops[True][3]
    assert 0.0 < stretch < 0.01, f"hoop stretch {stretch:.2%}"


def test_with_momentum_kept_the_hoop_still_decides():
    """At the defaults (momentum kept after each projection) the spurious drag of the plain average is gone: the
    canopy without its hoop still closes (to 51 % of its radius in 10 s, measured; 33 % with the paper's projection
    alone) and falls faster (6.2 against 5.4 m/s; 10.4 against 7.3)."""
    (_, open_radii, open_descent, _), (_, shut_radii, shut_descent, _) = (
        _drop(hoop, keep_momentum=True) for hoop in (True, False)
    )
    assert open_radii.min() > 0.9 * 3.5 and shut_radii[-1] < 0.6 * 3.5
    assert 0.0 < open_descent < shut_descent - 0.5


def test_hoop_slows_the_descent(drops):
    open_descent, closed_descent = drops[True][2], drops[False][2]
    assert 0.0 < open_descent < closed_descent - 2.0
    assert np.isfinite(drops[True][0].state.positions()).all()


def test_descent_does_not_depend_on_where_the_parachute_is():
    """The same drop at 400 m and near z = 0 (the ground lowered by 400 m) falls at the same speed.

    float32 positions at 400 m cannot hold the person's small per-iteration corrections; before the
    solver kept each iterate as origin + offset (warpsim.physics.kernels.constraints) they were rounded away and the
    descent after 20 s was 6.6 m/s up there against 4.3 m/s near zero. Measured now: 5.374 and 5.387 m/s.
    """
    speeds = []
    for ground in (0.0, -400.0):
        d = defaults("parachute")
        d["terrain"]["kind"] = "flat"
        d["terrain"]["height"] = ground
        d["solver"]["mass_splitting"] = True
        sim = Simulation(d)
        person = sim.model.objects[0].person
        sim.step(1500)
        z0 = sim.state.positions()[person, 2]
        sim.step(500)
        speeds.append((z0 - sim.state.positions()[person, 2]) / 5.0)
    assert abs(speeds[0] - speeds[1]) < 0.02 * speeds[0], speeds
