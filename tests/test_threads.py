"""Worlds stepped by threads: any number of threads gives the frames of one thread, bit for bit, and blow-ups,
checkpoints, recordings, sweep chunks and Ctrl-C behave as with one thread."""

import dataclasses
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from warpsim import Scene
from warpsim.cli import EXIT_INTERRUPTED, main
from warpsim.io.recording import Recording
from warpsim.run.simulation import BlowUpError, Simulation
from warpsim.scene import descriptor as desc_mod

ROOT = Path(__file__).resolve().parent.parent
WORLDS = 5  # odd, and fewer than the most threads asked for below


def _kites(count: int = WORLDS) -> dict:
    """``count`` kites, each in its own wind and gusts (so that every world differs from the others)."""
    desc = desc_mod.merge("test", desc_mod.defaults("kite"), {"wind": {"gust_intensity": 0.2}})
    speeds = np.linspace(4.0, 8.0, count).tolist()
    return desc_mod.merge(
        "test", desc, {"worlds": {"count": count, "wind": {"speed": speeds, "gust_seed": list(range(count))}}}
    )


def _flight(threads: int, seconds: float = 0.53):
    """Every frame of a run (a partial last frame included) with the anchor moved at frame 10, as host arrays,
    then the final checkpoint and the air forces the figures read."""
    sim = Simulation(_kites(), threads=threads)
    frames = []

    def keep(frame):
        frames.append(
            (
                frame.index,
                frame.time,
                frame.steps,
                frame.positions.copy(),
                frame.velocities.copy(),
                frame.world_stretch.copy(),
                frame.world_nonfinite.copy(),
                frame.clearance.copy(),
                dict(frame.controls),
            )
        )

    def before(index):
        if index == 10:
            sim.set_controls(anchor=(1.5, -0.5))

    summary = sim.run(seconds, on_frame=keep, before=before)
    return sim, frames, summary


@pytest.fixture(scope="module")
def one_thread():
    return _flight(1)


def _assert_same_frames(a, b):
    assert len(a) == len(b)
    for x, y in zip(a, b, strict=True):
        for u, v in zip(x, y, strict=True):
            if isinstance(u, np.ndarray):
                np.testing.assert_array_equal(u, v)
            else:
                assert u == v


@pytest.mark.parametrize("threads", [2, 3, 8])
def test_threads_give_the_frames_of_one_thread_bit_for_bit(threads, one_thread):
    ref, ref_frames, ref_summary = one_thread
    sim, frames, summary = _flight(threads)
    assert sim.threads == min(threads, WORLDS)
    _assert_same_frames(ref_frames, frames)
    assert summary.steps == ref_summary.steps and summary.worst_stretch == ref_summary.worst_stretch
    assert summary.ground_contacts == ref_summary.ground_contacts
    np.testing.assert_array_equal(sim.solver.tri_force.numpy(), ref.solver.tri_force.numpy())  # figures' line pull
    a, b = ref.checkpoint(), sim.checkpoint()
    for name in ("q", "q_prev", "time", "steps", "stick_rest", "nail_target", "wind", "gust_g"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))


def test_one_world_or_one_thread_is_the_plain_simulation():
    assert Simulation(_kites(1), threads=4).threads == 1
    sim = Simulation(_kites(3), threads=1)
    assert sim.threads == 1 and sim._groups[0].model is sim.model and sim._groups[0].state is sim.state


def test_threaded_run_resumes_from_a_checkpoint_bit_for_bit(one_thread):
    whole = one_thread[0]
    first = Simulation(_kites(), threads=2)
    first.run(0.25, before=lambda i: i == 10 and first.set_controls(anchor=(1.5, -0.5)))
    second = Simulation(_kites(), threads=3)
    second.restore(first.checkpoint())
    second.run(0.28, before=lambda i: i == 10 and second.set_controls(anchor=(1.5, -0.5)))
    np.testing.assert_array_equal(whole.state.positions(), second.state.positions())


def _poisoned_run(threads: int):
    """A NaN put into world 4 (the last group's) after frame 3: the run goes back to frame 3 and says where."""
    sim = Simulation(_kites(), threads=threads)
    poisoned = sim.model.objects[4].particles[5]

    def poison(frame):
        if frame.index == 3:
            q = sim.state.particle_q.numpy()
            q[poisoned] = np.nan
            sim.state.particle_q.assign(q)

    with pytest.raises(BlowUpError) as info:
        sim.run(1.0, on_frame=poison)
    return sim, info.value


def test_a_blow_up_in_one_group_goes_back_as_with_one_thread():
    ref, ref_err = _poisoned_run(1)
    sim, err = _poisoned_run(3)
    assert str(err) == str(ref_err) and err.object == "kite_w4" and err.last_good_frame == 3
    assert err.summary.steps == ref_err.summary.steps
    np.testing.assert_array_equal(sim.state.positions(), ref.state.positions())
    assert np.isfinite(sim.state.positions()).all()
    # and it runs on from there as one thread does
    sim.run(0.1)
    ref.run(0.1)
    np.testing.assert_array_equal(sim.state.positions(), ref.state.positions())


def _datasets(path):
    out = {}

    def keep(name, item):  # returns None: visititems goes on
        if isinstance(item, h5py.Dataset):
            out[name] = item[()]

    with h5py.File(path) as f:
        f.visititems(keep)
    return out


def test_recordings_of_threads_are_those_of_one_thread(tmp_path):
    args = ["run", "kite", "--worlds", "3", "--vary", "wind.speed=4:7", "--seconds", "0.4", "--quiet"]
    assert main([*args, "--threads", "1", "--h5", str(tmp_path / "one.h5")]) == 0
    assert main([*args, "--threads", "2", "--h5", str(tmp_path / "two.h5")]) == 0
    one, two = _datasets(tmp_path / "one.h5"), _datasets(tmp_path / "two.h5")
    assert one.keys() == two.keys() and "positions" in one
    for name, value in one.items():
        if value.dtype.kind == "f":
            np.testing.assert_array_equal(value, two[name], err_msg=name)  # NaNs in the same places
        else:
            assert np.array_equal(value, two[name]), name


def test_sweep_chunk_rows_are_the_same_on_threads():
    from warpsim import sweeps

    desc = desc_mod.defaults("kite")
    plan = sweeps.SweepPlan(Scene(desc), sweeps.parse_axes(Scene(desc), ["wind.speed=4,6,8"]), 0.4)
    (task,) = plan.chunks(8)
    one = sweeps.run_chunk(task)
    two = sweeps.run_chunk(dataclasses.replace(task, threads=2))
    assert len(one) == 3
    for a, b in zip(one, two, strict=True):
        assert a.keys() == b.keys()
        for key in a:
            assert a[key] == b[key] or (a[key] != a[key] and b[key] != b[key]), key  # NaN == NaN here


def test_ctrl_c_stops_a_threaded_run_and_keeps_its_recording(tmp_path):
    rec = tmp_path / "kites.h5"
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen(
        [sys.executable, "-m", "warpsim", "run", "kite", "--worlds", "4", "--threads", "2", "--seconds", "3600"]
        + ["--quiet", "--h5", str(rec)],
        cwd=ROOT,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.2)
            if rec.exists():
                try:
                    with Recording(rec) as r:
                        if r.frame_count >= 5:
                            break
                except Exception:  # not written far enough to be read yet
                    pass
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == EXIT_INTERRUPTED and "Traceback" not in err, err
    with Recording(rec) as r:
        assert r.frame_count >= 5 and np.isfinite(r.positions()).all() and not r.live


def test_the_viewer_flies_threaded_worlds_as_one_thread():
    """Keys, the heads-up display (its figures read the air forces) and R on 3 threads: the frames of 1."""
    sys.path.insert(0, str(Path(__file__).parent))
    from viewer_driver import Clock

    from warpsim.viewer.backend import NullBackend
    from warpsim.viewer.core import Viewer

    seen = {}
    for threads in (1, 3):
        backend = NullBackend()
        viewer = Viewer(Simulation(_kites(), threads=threads), backend, say=lambda line: None)
        clock = Clock(viewer)
        backend.press("W")  # walk the anchor
        clock.seconds(0.5)
        backend.release("W")
        hud = viewer.hud()
        positions = viewer.frame.positions.copy()
        backend.tap("R")
        clock.ticks(3)
        seen[threads] = (hud, positions, viewer.frame.positions.copy())
    assert seen[1][0][1:] == seen[3][0][1:]  # the first line gives wall-clock shares
    assert sum("pull ~" in line for line in seen[3][0]) == WORLDS  # every group's air forces reach the figures
    for a, b in zip(seen[1][1:], seen[3][1:], strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("kind", ["flag", "hang-glider", "parachute"])
def test_every_object_threads_bit_for_bit(kind):
    desc = desc_mod.merge("test", desc_mod.defaults(kind), {"worlds": {"count": 3}, "scene": {"fps": 25.0}})
    finals = []
    for threads in (1, 2):
        sim = Simulation(desc, threads=threads)
        sim.run(0.3)
        finals.append(sim.checkpoint())
    for name in ("q", "q_prev", "time", "steps"):
        np.testing.assert_array_equal(getattr(finals[0], name), getattr(finals[1], name))
