"""Blow-up detection: NaN/Inf or a stick past ``solver.max_stretch`` stops the run at the last good frame,
with a message naming the step, time and object, and every output kept up to that frame."""

import h5py
import numpy as np
import pytest
from pxr import Usd, UsdGeom

from warpsim.cli import EXIT_BLOWUP, main
from warpsim.io.recording import Recording
from warpsim.run.simulation import BlowUpError, Simulation
from warpsim.scene.descriptor import defaults, merge


def _euler_flag(**solver):
    """The paper's flag on the Euler mass-spring integrator at dt = 0.01 s: far above its stable step, it blows up."""
    d = merge("test", defaults("flag"), {"flag": {"design": "paper"}})
    d["solver"].update({"method": "euler", "dt": 0.01, **solver})
    return Simulation(d)


def test_runaway_stretch_stops_at_last_good_frame():
    sim = _euler_flag()
    frames = []
    with pytest.raises(BlowUpError) as info:
        sim.run(2.0, on_frame=frames.append)
    err = info.value
    assert err.object == "flag" and "stretched" in err.reason and "solver.max_stretch" in err.reason
    assert f"step {err.step}" in str(err) and "flag" in str(err)
    assert frames and all(f.worst_stretch <= 1.0 and np.isfinite(f.positions).all() for f in frames)
    assert err.last_good_frame == frames[-1].index and err.last_good_time == frames[-1].time
    assert err.step > sim.steps_taken  # the bad frame lies after the state we went back to
    assert sim.state.time == pytest.approx(frames[-1].time)
    np.testing.assert_array_equal(sim.state.positions(), frames[-1].positions)  # back at the last good state
    assert err.summary.blew_up and err.summary.steps == sim.steps_taken


def test_nan_is_caught_with_stretch_check_off():
    sim = _euler_flag(max_stretch=0.0)  # no stretch limit: the flag runs on until its numbers overflow
    frames = []
    with pytest.raises(BlowUpError) as info:
        sim.run(5.0, on_frame=frames.append)
    assert "non-finite" in info.value.reason
    assert max(f.worst_stretch for f in frames) > 1.0  # it went far past the default limit first
    assert np.isfinite(sim.state.positions()).all()


def test_the_world_that_blew_up_is_named():
    d = defaults("kite")
    d["worlds"]["count"] = 4
    sim = Simulation(d)
    poisoned = sim.model.objects[2].particles[5]

    def poison(frame):
        if frame.index == 3:  # a NaN appears in world 2 between frames 3 and 4
            q = sim.state.particle_q.numpy()
            q[poisoned] = np.nan
            sim.state.particle_q.assign(q)

    with pytest.raises(BlowUpError) as info:
        sim.run(1.0, on_frame=poison)
    assert info.value.object == "kite_w2" and "non-finite" in info.value.reason
    assert np.isfinite(sim.state.positions()).all()
    assert info.value.last_good_frame == 3


def test_cli_exit_code_message_and_kept_outputs(tmp_path, capsys):
    rec, usd = tmp_path / "flag.h5", tmp_path / "flag.usda"
    code = main(
        ["run", "flag_paper", "--set", "solver.method=euler", "--dt", "0.01", "--h5", str(rec), "--usd", str(usd)]
    )
    assert code == EXIT_BLOWUP == 3
    captured = capsys.readouterr()
    assert "blew up" in captured.out  # the summary says so
    first = captured.err.strip().splitlines()[0]
    assert first.startswith("warpsim run: error: the simulation blew up at step") and "in flag" in first
    with h5py.File(rec, "r") as f:
        frames = f["time"].shape[0]
        assert np.isfinite(f["positions"][:]).all() and f["diagnostics/worst_stretch"][:].max() <= 1.0
    with Recording(rec) as r:
        assert frames >= 2 and r.checkpoint_frame == r.frame_count - 1 == frames - 1  # the last good frame
        np.testing.assert_array_equal(r.checkpoint().q, r.positions(frames - 1))
    stage = Usd.Stage.Open(str(usd))
    assert len(UsdGeom.Mesh(stage.GetPrimAtPath("/World/flag/cloth")).GetPointsAttr().GetTimeSamples()) == frames
    # resuming the blown-up recording meets the same blow-up again and adds nothing
    assert main(["run", "--resume", str(rec), "--quiet"]) == EXIT_BLOWUP
    with h5py.File(rec, "r") as f:
        assert f["time"].shape[0] == frames
