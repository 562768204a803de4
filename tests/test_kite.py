"""The delta kite: counts, climb and settled line angle, rope end on the anchor, anchor control."""

import re

import numpy as np
import pytest

from benchmarks.validation.kite_rows import KITE_STEPS, KITE_WINDS
from warpsim.cli import main
from warpsim.objects.kite import line_state
from warpsim.run.simulation import Simulation
from warpsim.scene import descriptor
from warpsim.scene.descriptor import defaults


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


def test_frame_mass_moves_the_centre_of_mass_forward_and_keeps_the_total():
    # kite.frame_mass_fraction puts that share of the kite's mass on its spine's and leading edges' particles (real
    # spars weigh most of a delta); the cloth keeps what the virtual particles and the frame do not carry
    from warpsim.scene.values import DescriptorError

    def build(fraction):
        d = defaults("kite")
        d["kite"]["frame_mass_fraction"] = fraction
        m = Simulation(d).model
        rec = m.objects[0]
        kite = np.setdiff1d(rec.particles, np.concatenate([rec.parts["rope"], [rec.anchor_particle]]))
        mass, q = m.particle_free_mass[kite], m.particle_q0[kite]
        nose, tail = m.particle_q0[rec.spine[0]], m.particle_q0[rec.spine[-1]]
        axis = (tail - nose) / np.linalg.norm(tail - nose)
        centre = (mass[:, None] * q).sum(axis=0) / mass.sum()
        return m, rec, mass.sum(), float((centre - nose) @ axis / d["kite"]["spine"])  # share of the root chord

    m0, _, total0, chord0 = build(0.0)
    m6, rec, total6, chord6 = build(0.6)
    assert total0 == pytest.approx(0.12, rel=1e-12) and total6 == pytest.approx(0.12, rel=1e-12)
    assert 0.63 < chord0 < 0.67 and 0.57 < chord6 < 0.61, (chord0, chord6)  # measured 0.651, 0.587
    # every particle's cloth share shrinks to 0.3 / 0.9 of itself (the virtual particles keep their 0.1); what is
    # added lies on the frame's particles, evenly, 0.6 x 0.12 kg in all, a tip and the spine's tail among them
    added = m6.particle_free_mass - m0.particle_free_mass * np.where(
        np.isin(np.arange(m0.particle_count), rec.parts["sail"]), 0.3 / 0.9, 1.0
    )
    on_frame = added > 1e-9
    assert added[on_frame].sum() == pytest.approx(0.6 * 0.12, rel=1e-9)
    assert np.allclose(added[on_frame], added[on_frame][0], rtol=1e-9) and on_frame[[*rec.tips, rec.spine[-1]]].all()
    d = defaults("kite")
    with pytest.raises((DescriptorError, ValueError), match="below 1"):
        d["kite"]["frame_mass_fraction"] = 0.95
        Simulation(d)


def test_kite_climbs_and_line_angle_settles(flight):
    _, elevation, _, _ = flight
    start = defaults("kite")["kite"]["elevation"]
    assert elevation[:20].max() > start + 10.0  # climbs from its 10 degree launch
    settled = elevation[40:]  # 20 s .. 30 s
    # the flying design: tow point to anchor 53.3 degrees (measured); real single-line deltas fly at 45-70
    # (the paper's design stood at about 33, README, kite)
    assert settled.std() < 1.5 and 45.0 < settled.mean() < 70.0


def test_rope_end_stays_exactly_on_the_anchor(flight):
    _, _, anchor_err, _ = flight
    assert anchor_err == 0.0


def test_kite_frame_within_one_percent(flight):
    # the launch from 40 deg jolts the frame: 1.81 % at 0.5 s, 1.18 % at 5 s, within 1 % from 10 s on (0.94 %) and
    # 0.88 % in steady flight (measured; the spine's ties count 8, kite.spine_weight: at 4, with the sail's sleeve on
    # the spine, they stretch 1.36 %; the paper's design stays within 0.84 % throughout, README, kite)
    frame = flight[3]
    assert frame[20:].max() < 0.01 and frame.max() < 0.019, frame[:22]


def test_moving_the_anchor_moves_the_kite():
    sims = []
    for anchor in ((0.0, 0.0), (10.0, 0.0)):
        sim = Simulation(defaults("kite"))
        sim.step(int(round(2.5 / sim.dt)))
        sim.set_controls(anchor=anchor)
        sim.step(int(round(5.5 / sim.dt)))  # the anchor walks there at solver.nail_rate, 2 m/s: 10 m in 5 s
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
    particle at 42 m/s. The anchor now walks at solver.nail_rate (2 m/s): 2 m/s times the step each step, there in
    1.5 s, and the rope's particles stay slower than 6 m/s (about 1.2 m/s before the walk, measured)."""
    sim = Simulation(defaults("kite"))
    sim.step(int(round(5.0 / sim.dt)))
    there = int(round(1.5 / sim.dt))  # steps to walk 3 m
    rec = sim.model.objects[0]
    rope = rec.parts["rope"]
    start = sim.state.positions()[rec.anchor_particle].copy()
    sim.set_controls(anchor=(3.0, 0.0))
    path, fastest = [], 0.0
    for _ in range(there + 100):
        sim.step(1)
        path.append(sim.state.positions()[rec.anchor_particle].copy())
        fastest = max(fastest, float(np.linalg.norm(sim.state.velocities(sim.dt)[rope], axis=1).max()))
    steps = np.linalg.norm(np.diff(np.vstack([start, path]), axis=0), axis=1)
    assert steps.max() <= 2.0 * sim.dt * (1 + 1e-9) and np.linalg.norm(path[-1][:2] - (3.0, 0.0)) < 1e-9
    assert np.linalg.norm(path[there - 1][:2] - (3.0, 0.0)) < 1e-9
    assert np.linalg.norm(path[there - 3][:2] - (3.0, 0.0)) > 0.0
    assert fastest < 6.0


# Issue 35: the sail's trim, the kite launched across the wind range and the line's pull at the anchor. The runs
# are those of the validation's kite-flight rows (benchmarks.validation.kite_rows.kite_flight: 40 s, second half).


@pytest.fixture(scope="module")
def launched():
    from benchmarks.validation.kite_rows import KITE_STEPS, kite_flight

    runs, iterations = {}, dict(KITE_STEPS)

    def run(wind, dt):  # the validation's rungs: the defaults (5 ms/55), dt halved with the iterations doubled, ...
        if (wind, dt) not in runs:
            runs[(wind, dt)] = kite_flight(wind, dt, iterations=iterations[dt])
        return runs[(wind, dt)]

    return run


@pytest.mark.parametrize("dt", [KITE_STEPS[0][0], KITE_STEPS[1][0]])
@pytest.mark.slow
def test_sail_trims_at_a_real_angle_of_attack_and_lifts_as_a_delta(launched, dt):
    # single-line deltas fly their sail at 10-25 deg with C_L about 0.6-1.0 (Hosking; issue 35); with the load
    # spread evenly over the sail (centre of pressure at the area centroid at every angle) it sat at ~5 deg with
    # C_L 0.31. Measured (2.5 ms/45, 1.25 ms/90): 10.5 / 10.9 deg, C_L 0.635 / 0.655 (120 g, 25 deg of dihedral;
    # at the former 5 ms/55 and 2.5 ms/110: C_L 0.611 / 0.638); the 150 g kite at 30 deg of dihedral lifted 0.581 at
    # 10.3 deg at 5 ms, below the band.
    r = launched(6.0, dt)
    assert 10.0 <= r["alpha"] <= 25.0, r
    assert 0.6 <= r["lift"] <= 1.0, r
    assert r["drag"] < r["lift"] / 2.5, r


# at dt/4 with 4x the iterations (1.25 ms/220) and dt/8 (0.625 ms/220) the validation rows "kite in 3 m/s, dt 1.25
# ms/220" and "kite in 3 m/s, beyond the ladder" track the light-wind trim (16.3 / 16.1 deg); see also the slow test
# below
@pytest.mark.parametrize("dt, wind", [(dt, wind) for dt in (KITE_STEPS[0][0], KITE_STEPS[1][0]) for wind in KITE_WINDS])
@pytest.mark.slow
def test_kite_launched_in_its_wind_flies_high_and_steady(launched, wind, dt):
    # line 40-70 deg, steady within 5 deg, less than 5 m to the side (issue 35's band), at the defaults and at dt
    # halved with the iterations doubled. In the standard atmosphere (since 2026-12-06) the lightest wind is 3.1 m/s,
    # the dynamic pressure 3.0 m/s had in the paper's air: at 3.0 m/s and 1.25 ms/90 the trim went over the sail's
    # stall (24.9 deg, line 38.9-53.3 deg); at 3.1 m/s it flies at 16.2 deg, line 54.5-54.7 deg. Earlier figures,
    # in the paper's air: measured (2.5 ms/45, 1.25 ms/90): 54.1-54.6 / 54.4-54.6 deg in 3 m/s (angle
    # of attack 15.3 / 16.3 deg), 59.5 / 60.2 deg in 6 m/s, 59.8 / 60.8 deg in 10 m/s, 0.0 m to the side in each (at
    # the former 5 ms/55: 52.4-53.1, 57.6 and 56.6-56.8 deg, 1.5 m in 10 m/s). The 150 g kite at Chebyshev 0.95
    # fell into a deep stall in 3 m/s at 2.5 ms/110 (28 deg, line 36.9-44.1 deg); before the keel was cut taut
    # (kite.keel_tension) and the sail sleeved on the spine
    # (kite.spine_sleeve), 10 m/s at 5 ms swooped 9-32 deg and 23 m to the side.
    r = launched(wind, dt)
    assert r["alpha"] < 20.0, r  # below the sail's stall, not in a deep stall at ~30 deg
    assert 40.0 <= r["angle_min"] and r["angle_max"] <= 70.0 and r["angle_max"] - r["angle_min"] < 5.0, r
    assert r["drift"] < 5.0, r


@pytest.mark.slow
def test_light_wind_kite_flies_at_a_quarter_of_the_step_with_five_times_the_iterations():
    # 3 m/s at 0.625 ms/220 (a quarter of the defaults' 2.5 ms, about five times their 45 iterations; dt/8 of the
    # former 5 ms/55, where it was "beyond the ladder"), 30 s of flight, the second half: the trim stays under the
    # sail's 18 deg stall and the kite stays centred (measured at the former settings: 16.3 deg, line 53.6-54.9 deg,
    # 0.0 m in this 30 s flight). The frame's ties and the keel are elastic
    # (kite.frame_compliance, 1e-4 m/N): with the paper's rigid ties the iterations approach a rigid frame as the
    # steps are refined, and there the trim rose over the stall (this flight: 23.4 deg, line 42.2-51.5 deg, 8.9 m to
    # the side; validation row "kite in 3 m/s, beyond the ladder")
    from benchmarks.validation.kite_rows import kite_flight

    r = kite_flight(3.0, 0.000625, seconds=30.0, iterations=220)
    assert r["alpha"] < 18.0, r
    assert 40.0 <= r["angle_min"] and r["angle_max"] <= 70.0 and r["angle_max"] - r["angle_min"] < 5.0, r
    assert r["drift"] < 2.0, r


def test_kite_follows_a_small_crosswind_as_its_geometry_says_and_mirrors_it():
    # launched in 6 m/s with 0.05 m/s across (0.5 deg): a laterally stable, symmetric kite turns with the wind about
    # its anchor, by its reach times the wind's angle (0.126 m); measured at the defaults 0.126 m at 20 s (at the
    # former 5 ms/55: 0.104 m, still creeping towards it), and the same to 1e-5 m the other way with the crosswind
    # reversed
    from benchmarks.validation.kite_rows import kite_crosswind_offset

    plus = kite_crosswind_offset(6.0, 0.05, *KITE_STEPS[0], seconds=20.0)
    minus = kite_crosswind_offset(6.0, -0.05, *KITE_STEPS[0], seconds=20.0)
    assert 0.5 < plus["offsets"][-1] / plus["expected"] < 1.5, plus
    assert np.allclose(plus["offsets"], [-o for o in minus["offsets"]], atol=1e-3), (plus, minus)


@pytest.mark.slow
@pytest.mark.parametrize("compliance, limit", [(None, 0.5), (0.0, None)])
def test_kite_follows_a_small_crosswind_at_a_quarter_of_the_time_step(compliance, limit):
    # the test above at 0.625 ms/220 (a quarter of the defaults' step, about five times their iterations; 5 s).
    # With the sail's cloth and the frame
    # elastic (the defaults kite.sail_compliance, 5e-5 m/N, and kite.frame_compliance, 1e-4 m/N) the iterations
    # converge to that kite and it stays centred: +0.10 m at 5 s, +0.12 m to 30 s (validation row "kite in 6 m/s,
    # 0.5° crosswind, time step"). With rigid sticks (both 0, the paper's) they converge towards a rigid kite, and
    # it goes to one side: +5.5 m at 5 s, +10.7 m at 10 s, line 52 deg (docs/objects.md, the kite's limits;
    # python -m benchmarks.validation.kite_side)
    from benchmarks.validation.kite_rows import kite_crosswind_offset

    overrides = (
        None if compliance is None else {"kite": {"sail_compliance": compliance, "frame_compliance": compliance}}
    )
    r = kite_crosswind_offset(6.0, 0.05, 0.000625, 220, seconds=5.0, overrides=overrides)
    if limit is None:
        assert abs(r["offsets"][-1]) > 2.0, r  # rigid cloth: 5.5 m
    else:
        assert abs(r["offsets"][-1]) < limit, r


def test_elastic_cloth_needs_mass_splitting(capsys):
    # kite.sail_compliance and kite.frame_compliance > 0 with the paper's plain average: one line naming the
    # settings, no traceback
    assert main(["run", "kite", "--set", "solver.mass_splitting=false", "--seconds", "0.1"]) == 2
    err = capsys.readouterr().err
    assert "mass_splitting = true" in err and "kite.sail_compliance" in err and "Traceback" not in err, err


@pytest.mark.parametrize("wind", [3.0, 6.0])
def test_anchor_pull_from_the_rope_matches_the_force_balance(launched, wind):
    # the pull from the rope's sag (no air force in it) against |air force on every particle - weight of kite and
    # rope| (measured at the defaults 12.24 vs 12.22 N in 6 m/s, 3.39 vs 3.38 N in 3 m/s)
    r = launched(wind, KITE_STEPS[0][0])
    assert abs(r["pull"] / r["balance"] - 1.0) < 0.02, r
    assert r["pull"] > 1.5 * 9.80665 * defaults("kite")["kite"]["mass"]  # the line holds more than the kite's weight


def test_anchor_pull_of_a_hanging_chain_is_its_tension():
    """anchor_pull on a chain whose shape is the statics of known tension: horizontal tension H, slope stepping up by
    m g / H at every particle; the pull along the anchor's segment is H sqrt(1 + slope0^2)."""
    from types import SimpleNamespace

    from warpsim.objects.kite import anchor_pull

    g, m, h_tension, slope0, seg = 9.80665, 0.002, 7.5, 0.8, 2.0
    points = [np.zeros(3)]
    for k in range(10):
        s = slope0 + k * m * g / h_tension
        step = np.array([1.0, 0.0, s]) / np.hypot(1.0, s) * seg
        points.append(points[-1] + step)
    q = np.array(points)
    record = SimpleNamespace(sag_chain=np.arange(len(q)))
    mass = np.full(len(q), m)
    assert anchor_pull(record, q, mass, g) == pytest.approx(h_tension * np.hypot(1.0, slope0), rel=1e-12)
    slack = q.copy()
    slack[:, 2] = 0.0  # a rope lying flat does not sag: no pull to read
    assert np.isnan(anchor_pull(record, slack, mass, g))


def test_figures_report_the_anchor_pull():
    """The summary, the HUD and the sweeps read line_pull from diagnostics.Figures: the rope's pull at the anchor."""
    from warpsim.objects.kite import anchor_pull
    from warpsim.run.figures import Figures

    sim = Simulation(defaults("kite"))
    figures = Figures(sim.model)
    frames = []
    sim.run(12.0, on_frame=frames.append)
    f = frames[-1]
    rec = sim.model.objects[0]
    pull = figures(f)[0]["line_pull"]
    assert pull == anchor_pull(rec, f.positions, sim.model.particle_free_mass) and 5.0 < pull < 20.0


def test_the_papers_kite_stands_at_its_line_angle():
    # the paper's design (kite.design = "paper": its air law, 10 ms, Chebyshev 0.95) settles at 33.4 deg over 20-30 s
    # (docs/objects.md); with the flying kite's Chebyshev 0.99 carried into it by mistake it sank to the ground by 30 s
    from warpsim.scene.descriptor import resolve

    d = resolve("scenes/kite_paper.toml")[0]
    assert d["solver"]["chebyshev"] == 0.95, d["solver"]
    sim = Simulation(d)
    rec = sim.model.objects[0]
    angles = []
    sim.run(30.0, on_frame=lambda f: angles.append((f.time, line_state(rec, f.positions)["elevation_deg"])))
    settled = np.array([a for t, a in angles if t >= 20.0])
    assert 32.0 < settled.min() and settled.max() < 35.0, (settled.min(), settled.max())


def test_an_object_whose_designs_set_different_keys_is_refused():
    # every design must set the keys any other design sets, or switching design keeps the other's value
    from warpsim.objects import kite
    from warpsim.objects.registry import ObjectSpec

    presets = {"flying": kite.PRESETS["flying"], "paper": {**kite.PRESETS["paper"], "solver": {"dt": 0.01}}}
    with pytest.raises(ValueError, match=r"preset 'paper' leaves out solver\.chebyshev"):
        ObjectSpec(config=kite.KiteConfig, build=kite.build_kite, presets=presets)
    ObjectSpec(config=kite.KiteConfig, build=kite.build_kite, presets=kite.PRESETS)  # the shipped ones agree


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--wind", "-3"], "must be positive"),
        (["--seconds", "7"], "multiple of 5"),
        (["0.005"], "DT/ITERATIONS"),
        (["--set", "kite.frame_mas_fraction=0.6", "0.005/55"], "did you mean 'frame_mass_fraction'"),
        (["--set", "kite.frame_mass_fraction=0.95", "0.005/55"], "must be below 1"),
    ],
)
def test_kite_side_refuses_bad_input_in_one_line(capsys, argv, message):
    # python -m benchmarks.validation.kite_side: a bad wind, flight time, rung or --set is a usage error (exit 2)
    # that names the problem, before any flight
    from benchmarks.validation.kite_side import main as kite_side

    with pytest.raises(SystemExit) as stop:
        kite_side(argv)
    err = capsys.readouterr().err
    assert stop.value.code == 2 and message in err and "Traceback" not in err, err


def test_a_rope_lying_on_the_ground_has_no_pull_from_its_sag():
    """A kite in 1 m/s falls and its rope lies on the ground: the sag's statics, which would give ~1e10 N there, give
    no pull (NaN), and the run's figures leave it out; a flying kite's rope gives its pull."""
    from warpsim.objects.kite import anchor_pull

    d = descriptor.merge("test", descriptor.resolve("kite")[0], {"wind": {"velocity": [1.0, 0.0, 0.0]}})
    sim = Simulation(d)
    sim.run(10.0)
    record = sim.model.objects[0]
    assert np.isnan(anchor_pull(record, sim.state.positions(), sim.model.particle_free_mass))
    flying = Simulation(descriptor.resolve("kite")[0])
    flying.run(10.0)
    assert 5.0 < anchor_pull(record, flying.state.positions(), flying.model.particle_free_mass) < 30.0


@pytest.mark.slow
@pytest.mark.parametrize("wind, flies", [(3.0, False), (4.0, True), (13.0, True)])
def test_the_sport_kite_flies_in_the_winds_its_scene_says(capsys, wind, flies):
    """scenes/kite_sport.toml says where it flies (in the standard atmosphere at the defaults: 60.1 deg in 4 m/s,
    62.5 deg in 13 m/s over 30-60 s; 60.7 and 63.8 at dt/2 with twice the iterations) and where it stops (3 m/s:
    23.0 deg; 3.5 m/s flies at the defaults but not at dt/2, not claimed); the run's own line angle, 20-40 s."""
    args = ["run", "scenes/kite_sport.toml", "--seconds", "40", "--set", f"wind.velocity=[{wind},0,0]"]
    assert main(args) == 0
    angle = float(re.search(r"line angle ([\d.]+) deg", capsys.readouterr().out).group(1))
    assert (55.0 <= angle <= 65.0) if flies else (angle < 35.0), angle
