"""Frames checked on the device: the report a run reads after each frame agrees with the host's measures, a run
that writes nothing copies no state to the host, and a frame kept by its reader still shows its own state."""

import numpy as np
import pytest

from warpsim.run import diagnostics
from warpsim.run.simulation import BlowUpError, Simulation
from warpsim.scene.descriptor import defaults


def _kites(count: int = 3) -> Simulation:
    d = defaults("kite")
    d["worlds"] = {"count": count, "wind": {"speed": list(np.linspace(4.0, 9.0, count))}}
    return Simulation(d)


def test_whole_frame_graph_steps_as_one_step_at_a_time():
    """`run` replays a frame (its steps and the probe's kernels) as one graph; the state is the same, bit for bit,
    as after the same steps one by one, with or without graphs."""
    runs = {}
    for label, use_graph, by_frames in (("frames", True, True), ("steps", True, False), ("plain", False, True)):
        sim = Simulation(defaults("hang-glider"), use_graph=use_graph)
        steps = 40 * sim.steps_per_frame
        if by_frames:
            sim.run(steps * sim.dt)
        else:
            sim.step(steps)
        assert sim.steps_taken == steps
        runs[label] = (sim.state.positions(), sim.state.particle_q_prev.numpy().copy(), sim.state.time)
    for label in ("steps", "plain"):
        np.testing.assert_array_equal(runs["frames"][0], runs[label][0])
        np.testing.assert_array_equal(runs["frames"][1], runs[label][1])
        assert runs["frames"][2] == runs[label][2]


@pytest.mark.parametrize("scene", ["hang-glider", "kites"])
def test_device_report_agrees_with_the_host(scene):
    """Worst stretch per world (with the glider's pretensioned sail, which shows none inside its band) and each
    object's lowest clearance above the terrain, from the device, against NumPy on the host copy."""
    sim = _kites() if scene == "kites" else Simulation(defaults("hang-glider"))
    model = sim.model
    owner = sim.contacts.owners()
    stick_world = model.particle_world_np[model.stick_particles_np[:, 0]]
    seen = []

    def check(frame):
        stretches = frame.stretches
        for w in range(model.world_count):
            host = stretches[stick_world == w].max()
            assert frame.world_stretch[w] == pytest.approx(host, rel=1e-4, abs=1e-6)
        assert frame.worst_stretch == pytest.approx(stretches[frame.worst_stick], rel=1e-4, abs=1e-6)
        q = frame.positions
        for k in range(len(model.objects)):
            mine = q[owner == k]
            host = (mine[:, 2] - model.terrain.height(mine[:, 0], mine[:, 1])).min()
            assert frame.clearance[k] == pytest.approx(host, abs=1e-4)
        assert frame.finite and frame.world_nonfinite.sum() == 0
        seen.append(frame.worst_stretch)

    sim.run(1.0, on_frame=check)
    assert len(seen) > 10 and max(seen) > 1e-4  # real stretches were compared, not only zeros


def test_a_run_that_writes_nothing_copies_no_state(monkeypatch):
    copies = []
    original = diagnostics.FrameSource.copy
    monkeypatch.setattr(diagnostics.FrameSource, "copy", lambda self: copies.append(1) or original(self))
    sim = Simulation(defaults("hang-glider"))
    summary = sim.run(2.0)
    assert summary.steps == round(2.0 / sim.dt) and copies == []  # the checks read the device's report only
    read = []
    sim.run(0.5, on_frame=lambda frame: read.append(frame.positions[0, 2]))
    assert len(copies) == len(read) > 10  # one copy per frame that was read, none more


def test_kept_frames_show_their_own_state():
    """Frames kept and read after the run show what they showed when handed out (the simulation copies a frame
    someone holds before the state moves on), bit for bit as frames read at once."""
    kept, now = [], []
    for sink in (kept, now):
        sim = _kites(2)
        if sink is kept:
            sim.run(0.7, on_frame=kept.append)
        else:
            sim.run(0.7, on_frame=lambda f: now.append((f.positions, f.velocities, f.stretches, f.wind, f.time)))
    assert len(kept) == len(now) > 10
    for frame, (q, v, stretches, wind, t) in zip(kept, now, strict=True):
        assert frame.time == t
        np.testing.assert_array_equal(frame.positions, q)
        np.testing.assert_array_equal(frame.velocities, v)
        np.testing.assert_array_equal(frame.stretches, stretches)
        np.testing.assert_array_equal(frame.wind, wind)
    assert np.abs(kept[-1].positions - kept[0].positions).max() > 0.1  # the kites moved


def test_blow_up_goes_back_to_the_last_good_frame_and_its_controls():
    """A bad frame is undone whole: positions from the probe's slot of the last good frame, and the controls,
    even when they changed at the bad frame's start."""
    sim = Simulation(defaults("hang-glider"))
    sim.run(9 * sim.steps_per_frame * sim.dt)  # to a frame's end: the next advance starts a frame
    good = (sim.state.positions(), sim.state.particle_q_prev.numpy().copy(), sim.state.time, sim.steps_taken)
    rest = sim.control.stick_rest.numpy().copy()
    before = dict(sim.controls)
    poisoned = sim.model.objects[0].particles[3]

    def pull_and_poison(index):
        sim.set_controls(roll=0.8)  # the pilot moves: control sticks change their rest lengths
        q = sim.state.particle_q.numpy()
        q[poisoned] = np.inf  # and the frame about to be stepped goes bad
        sim.state.particle_q.assign(q)

    with pytest.raises(Exception, match="non-finite"):
        sim.advance(before=pull_and_poison)
    np.testing.assert_array_equal(sim.state.positions(), good[0])
    np.testing.assert_array_equal(sim.state.particle_q_prev.numpy(), good[1])
    assert (sim.state.time, sim.steps_taken) == good[2:]
    np.testing.assert_array_equal(sim.control.stick_rest.numpy(), rest)
    assert sim.controls == before
    sim.run(0.3)  # and it goes on from there
    assert np.isfinite(sim.state.positions()).all()


def test_long_frames_step_without_a_frame_graph_and_give_the_same_bits(monkeypatch):
    """A frame of more steps than `MAX_FRAME_GRAPH_STEPS` (a low --fps) is not captured as one graph (at --fps 0.001
    that was 100,000 steps, twice: gigabytes and minutes of start-up); it steps through the solver's one-step graph
    and gives the same state, bit for bit, as the frame replayed as one graph."""
    from warpsim.run import simulation as runner

    d = defaults("kite")
    d["scene"]["fps"] = 1.0 / (60 * d["solver"]["dt"])  # 60 steps a frame
    monkeypatch.setattr(runner, "MAX_FRAME_GRAPH_STEPS", 30)
    stepped = Simulation(d)
    assert stepped.steps_per_frame == 60 and stepped._groups[0].graphs is None
    monkeypatch.setattr(runner, "MAX_FRAME_GRAPH_STEPS", 60)
    whole = Simulation(d)
    assert whole._groups[0].graphs is not None
    for sim in (stepped, whole):
        sim.run(2 * 60 * sim.dt)
        assert sim.steps_taken == 120
    np.testing.assert_array_equal(stepped.state.positions(), whole.state.positions())
    np.testing.assert_array_equal(stepped.state.particle_q_prev.numpy(), whole.state.particle_q_prev.numpy())


@pytest.mark.parametrize("fps", [0.001, 1e-6])
def test_a_low_frame_rate_starts_in_bounded_time(fps):
    """`warpsim run kite --fps 0.001 --seconds 0.1` took > 120 s and 2.1 GB capturing a graph of a 100,000-step
    frame; now the start-up (build and capture) is that of a normal run."""
    d = defaults("kite")
    d["scene"]["fps"] = fps
    sim = Simulation(d)
    assert sim._groups[0].graphs is None
    assert sim.startup_time < 5.0
    sim.run(0.1)
    assert sim.steps_taken == round(0.1 / sim.dt)


def test_the_frame_iterator_gives_run_s_frames_and_checks_each_world_alone():
    """`Simulation.frames` is what `run`, the viewer and a sweep's chunk step by: it yields the current state, then
    `run`'s frames, bit for bit; it steps only when asked (a consumer that stops leaves the state at its last
    frame); checked world by world, a world that goes bad is named in that frame's `blowups` and the others go
    on, where the whole check goes back to the last good frame and ends the iterator."""
    ran, seen = _kites(2), []
    ran.run(12 * ran.steps_per_frame * ran.dt, on_frame=lambda f: seen.append((f.index, f.steps, f.positions.copy())))
    it = _kites(2)
    got = [(f.index, f.steps, f.positions.copy()) for f in it.frames(12 * it.steps_per_frame * it.dt)]
    assert [g[:2] for g in got] == [s[:2] for s in seen] and len(got) == 13
    for (_, _, a), (_, _, b) in zip(got, seen, strict=True):
        np.testing.assert_array_equal(a, b)

    sim = _kites(2)
    frames = sim.frames()  # for as long as it is asked
    for _ in range(4):
        next(frames)
    assert sim.steps_taken == 3 * sim.steps_per_frame  # the fourth frame given is the third stepped; no more
    frames.close()

    poisoned = sim.model.objects[1].particles[5]  # a particle of the second world

    def poison(index):
        q = sim.state.particle_q.numpy()
        q[poisoned] = np.nan
        sim.state.particle_q.assign(q)

    alone = sim.frames(5 * sim.steps_per_frame * sim.dt, before=poison, each_world=True)
    frames = list(alone)
    assert len(frames) == 6 and frames[0].blowups == {}
    assert all(set(f.blowups) == {1} and "non-finite" in f.blowups[1] for f in frames[1:])
    assert np.isfinite(frames[-1].positions[sim.model.objects[0].particles]).all()  # the first world flew on
    whole = _kites(2)
    whole.run(3 * whole.steps_per_frame * whole.dt)
    good = whole.state.positions()
    with pytest.raises(BlowUpError, match="non-finite"):
        list(whole.frames(1.0, before=lambda index: whole.state.particle_q.assign(np.full_like(good, np.nan))))
    np.testing.assert_array_equal(whole.state.positions(), good)  # back to the last good frame
