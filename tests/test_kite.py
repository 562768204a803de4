"""The delta kite: counts, climb and settled line angle, rope end on the anchor, anchor control."""

import numpy as np
import pytest

from warpsim.cli import main
from warpsim.descriptor import defaults
from warpsim.objects.kite import line_state
from warpsim.runner import Simulation


@pytest.fixture(scope="module")
def flight():
    """30 s of the default kite in its steady 6 m/s wind; line state sampled every 0.5 s."""
    sim = Simulation(defaults("kite"))
    rec = sim.model.objects[0]
    samples, anchor_err, frame = [], 0.0, []
    for _ in range(60):
        sim.step(int(round(0.5 / sim.dt)))
        q = sim.state.positions()
        samples.append(line_state(rec, q)["elevation_deg"])
        anchor_err = max(anchor_err, np.abs(q[rec.anchor_particle] - sim.model.nail_target0[0]).max())
        frame.append(np.abs(sim.model.stick_stretch(q)[rec.stick_groups["frame"]]).max())
    return sim, np.array(samples), anchor_err, np.array(frame)


def test_counts_match_info(capsys):
    m = Simulation(defaults("kite")).model
    rec = m.objects[0]
    assert len(rec.parts["sail"]) == 14 * 15 // 2  # 14 particles per side, as the paper
    assert len(rec.parts["rope"]) == 14 and m.nail_count == 1
    assert len(rec.parts["keel"]) == 6 * 7 // 2 - 6  # 6 per side; its top edge is the spine's particles
    assert main(["info", "kite"]) == 0
    out = capsys.readouterr().out
    assert f"particles {m.particle_count}, sticks {m.stick_count}, triangles {m.tri_count}" in out
    assert "particles 152, sticks 458, triangles 221" in out


def test_kite_climbs_and_line_angle_settles(flight):
    _, elevation, _, _ = flight
    start = defaults("kite")["kite"]["elevation"]
    assert elevation[:20].max() > start + 10.0  # climbs from its 10 degree launch
    settled = elevation[40:]  # 20 s .. 30 s
    # the flying design: tow point to anchor 56 degrees (measured); real single-line deltas fly at 45-70
    # (the paper's design stood at about 33, README, kite)
    assert settled.std() < 1.5 and 45.0 < settled.mean() < 70.0


def test_rope_end_stays_exactly_on_the_anchor(flight):
    _, _, anchor_err, _ = flight
    assert anchor_err == 0.0


def test_kite_frame_within_one_percent(flight):
    # the launch from 40 deg jolts the frame: 1.58 % at 0.5 s, 1.05 % at 5 s, within 1 % from 6 s on and 0.79 % in
    # steady flight (measured; the paper's design stayed within 0.84 % throughout, README, kite)
    frame = flight[3]
    assert frame[12:].max() < 0.01 and frame.max() < 0.017, frame[:14]


def test_moving_the_anchor_moves_the_kite():
    sims = []
    for anchor in ((0.0, 0.0), (10.0, 0.0)):
        sim = Simulation(defaults("kite"))
        sim.step(500)
        sim.set_controls(anchor=anchor)
        sim.step(1100)  # the anchor walks there at solver.nail_rate, 2 m/s: 10 m in 5 s
        rec = sim.model.objects[0]
        q = sim.state.positions()
        assert np.array_equal(q[rec.anchor_particle, :2], np.float32(anchor))
        sims.append(line_state(rec, q)["tow"])
    moved = sims[1] - sims[0]
    assert moved[0] > 5.0  # the kite followed the anchor downwind


def test_anchor_control_is_checked():
    sim = Simulation(defaults("kite"))
    with pytest.raises(ValueError, match="anchor must be a list of 2 numbers"):
        sim.set_controls(anchor=(1.0, 2.0, 3.0))
    with pytest.raises(ValueError, match="controls are: anchor, wind"):
        sim.set_controls(pitch=0.5)


def test_the_anchor_walks_instead_of_jumping():
    """Issue 33 (review): set_controls(anchor=(3, 0)) moved the anchor 3 m in one step and threw the rope's next
    particle at 42 m/s. The anchor now walks at solver.nail_rate (2 m/s): 1 cm per 5 ms step, there in 1.5 s, and
    the rope's particles stay slower than 6 m/s (about 1.2 m/s before the walk, measured)."""
    sim = Simulation(defaults("kite"))
    sim.step(1000)
    rec = sim.model.objects[0]
    rope = rec.parts["rope"]
    start = sim.state.positions()[rec.anchor_particle].copy()
    sim.set_controls(anchor=(3.0, 0.0))
    path, fastest = [], 0.0
    for _ in range(400):
        sim.step(1)
        path.append(sim.state.positions()[rec.anchor_particle].copy())
        fastest = max(fastest, float(np.linalg.norm(sim.state.velocities(sim.dt)[rope], axis=1).max()))
    steps = np.linalg.norm(np.diff(np.vstack([start, path]), axis=0), axis=1)
    assert steps.max() <= 2.0 * sim.dt * (1 + 1e-9) and np.linalg.norm(path[-1][:2] - (3.0, 0.0)) < 1e-9
    assert np.linalg.norm(path[299][:2] - (3.0, 0.0)) < 1e-9 and np.linalg.norm(path[297][:2] - (3.0, 0.0)) > 0.0
    assert fastest < 6.0
