"""Recordings refused the way a person meets them: unwritable folders, scene files named like outputs, signals at
start-up and at the lock, empty, skeleton and crafted recordings, a writer killed in plain write mode, links at
the outputs, edited checkpoints, descriptors and controls: each one line, nothing written through, nothing left
half made."""

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
from pxr import Usd, UsdGeom
from recording_support import (
    CUDA_NOTE,
    _one_error_line,
    _start,
    _wait_for_frames,
    _wait_for_sigint_handler,
)

from warpsim.cli import EXIT_INTERRUPTED, EXIT_USAGE, main
from warpsim.io import temporary_path
from warpsim.io.h5format import descriptor_digest
from warpsim.io.hdf5 import H5Recorder
from warpsim.io.recording import Recording
from warpsim.run.simulation import Simulation
from warpsim.scene.descriptor import defaults, load_text, to_toml


@pytest.fixture
def read_only_dir(tmp_path):
    """A directory no file can be created in: mode 555 for a normal user, a read-only tmpfs for root."""
    d = tmp_path / "ro"
    d.mkdir()
    if os.geteuid() != 0:
        d.chmod(0o555)
        yield d
        d.chmod(0o755)
        return
    if (
        not shutil.which("mount")
        or subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=1m", "tmpfs", str(d)], capture_output=True).returncode
    ):
        pytest.skip("root without mount: no way to make a read-only directory here")
    yield d
    subprocess.run(["umount", "-l", str(d)], check=False)


def test_unwritable_outputs_are_refused_before_simulating(read_only_dir, tmp_path, capsys):
    (tmp_path / "adir.h5").mkdir()
    (tmp_path / "adir.usda").mkdir()
    cases = [
        (["--h5", str(read_only_dir / "k.h5")], "cannot write in"),
        (["--usd", str(read_only_dir / "k.usdz")], "cannot write in"),
        (["--h5", str(tmp_path / "adir.h5")], "is a directory"),
        (["--usd", str(tmp_path / "adir.usda")], "is a directory"),
    ]
    for extra, message in cases:
        start = time.monotonic()
        assert main(["run", "kite", "--seconds", "3600", *extra]) == EXIT_USAGE
        captured = capsys.readouterr()
        assert captured.out == "" and time.monotonic() - start < 30  # refused, not simulated for an hour
        _one_error_line(captured.err.strip().splitlines(), message)


def test_scene_file_named_like_an_output_is_refused(tmp_path, capsys):
    scene = tmp_path / "scene.h5"
    text = "[scene]\nobject = 'flag'\nseconds = 0.1\n"
    scene.write_text(text)
    assert main(["run", str(scene), "--h5", str(scene)]) == EXIT_USAGE
    _one_error_line(capsys.readouterr().err.strip().splitlines(), "is the scene file itself")
    scene.rename(tmp_path / "scene.usda")
    assert main(["run", str(tmp_path / "scene.usda"), "--usd", str(tmp_path / "scene.usda")]) == EXIT_USAGE
    assert (tmp_path / "scene.usda").read_text() == text


# 8. signals and odd recordings at the edges ---------------------------------------------------------------------------


@pytest.mark.parametrize("gap", [0.0, 0.015])
@pytest.mark.slow
def test_second_signal_during_the_export_still_writes_the_stage(gap, tmp_path):
    rec, usd = tmp_path / "k.h5", tmp_path / "k.usda"
    proc = _start("run", "kite", "--seconds", "3600", "--quiet", "--h5", rec, "--usd", usd)
    _wait_for_frames(rec, 300, proc)  # a stage big enough to take a while to export
    proc.send_signal(signal.SIGINT)
    time.sleep(gap)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    # -2 (a shell shows 130): the second signal came after the outputs were finished and the handlers restored
    assert proc.returncode in (EXIT_INTERRUPTED, -signal.SIGINT) and "Traceback" not in err, err
    with Recording(rec) as r:
        frames = r.frame_count
    stage = Usd.Stage.Open(str(usd))
    assert len(UsdGeom.Mesh(stage.GetPrimAtPath("/World/kite/sail")).GetPointsAttr().GetTimeSamples()) == frames
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


@pytest.mark.parametrize("delay", [0.1, 0.3, 0.6, 1.0])
def test_ctrl_c_during_start_up_is_one_line(delay, tmp_path):
    proc = _start("run", "kite", "--seconds", "5", "--h5", tmp_path / "k.h5", cwd=tmp_path)
    _wait_for_sigint_handler(proc)
    time.sleep(delay)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    lines = [line for line in err.splitlines() if line.strip() and CUDA_NOTE not in line and not line.startswith("\r")]
    # -2: Python ends by re-raising SIGINT when an interrupt lands in its own start-up or shut-down; a shell
    # shows that as 130 too
    assert "Traceback" not in err and proc.returncode in (0, EXIT_INTERRUPTED, -signal.SIGINT), err
    assert len(lines) <= 1, err
    if (tmp_path / "k.h5").exists():  # either no file or a readable recording
        with Recording(tmp_path / "k.h5") as r:
            assert r.frame_count >= 1


def test_sigterm_as_the_recording_is_created_leaves_no_empty_file(tmp_path):
    """SIGTERM in the first moments of `run --h5` (the file created, the recording not yet written) ended the process
    at once and left a 0-byte file that every reader called 'not an HDF5 file'; SIGINT there removed it. SIGTERM now
    does what SIGINT does: whenever it lands, the file is absent or a readable recording."""
    path = tmp_path / "k.h5"
    proc = _start("run", "kite", "--seconds", "5", "--h5", path, cwd=tmp_path)
    deadline = time.monotonic() + 120
    while not path.exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.001)
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=120)
    assert "Traceback" not in err and proc.returncode in (0, EXIT_INTERRUPTED), err
    if path.exists():
        with Recording(path) as r:
            assert r.frame_count >= 1


def test_an_interrupt_just_after_the_lock_creates_the_file_leaves_no_file(tmp_path, monkeypatch):
    """The window the test above hits by chance, hit every time: the writer's lock has created the empty file and
    Ctrl-C (or SIGTERM, which raises the same) lands before the recorder holds it. No 0-byte file is left; and a
    recording another run is writing is never removed by a run that could not claim it."""
    import warpsim.io.hdf5 as hdf5
    from warpsim.io.h5safe import WriterLock

    def claim_then_interrupted(path, create):
        WriterLock(path, create)
        raise KeyboardInterrupt

    d = defaults("flag")
    sim = Simulation(d)
    path = tmp_path / "k.h5"
    monkeypatch.setattr(hdf5, "claim", claim_then_interrupted)
    with pytest.raises(KeyboardInterrupt):
        H5Recorder(path, sim.model, sim.scene, sim.checkpoint, "flag")
    assert not path.exists()
    monkeypatch.undo()
    with H5Recorder(path, sim.model, sim.scene, sim.checkpoint, "flag") as first:
        with pytest.raises(Exception, match="another warpsim run is writing"):
            H5Recorder(path, sim.model, sim.scene, sim.checkpoint, "flag")
        assert path.exists() and first.file is not None


def test_empty_and_skeleton_recordings_are_refused(tmp_path, capsys):
    d = defaults("flag")
    empty = tmp_path / "empty.h5"
    sim = Simulation(d)
    H5Recorder(empty, sim.model, sim.scene, sim.checkpoint, "flag").close()  # created, closed before any frame
    skeleton = tmp_path / "skeleton.h5"
    with h5py.File(skeleton, "w") as f:
        f.attrs["format"] = "warpsim-recording"
    cases = [
        (["convert", str(empty), str(tmp_path / "e.usda")], "has no frames"),
        (["render", str(empty), str(tmp_path / "e.png")], "has no frames"),
        (["run", "--resume", str(empty)], "no frame to resume from"),
        (["convert", str(skeleton), str(tmp_path / "s.usda")], "incomplete warpsim recording"),
        (["run", "--resume", str(skeleton)], "incomplete warpsim recording"),
    ]
    for argv, message in cases:
        assert main(argv) == EXIT_USAGE, argv
        captured = capsys.readouterr()
        assert "->" not in captured.out
        _one_error_line(captured.err.strip().splitlines(), message)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["empty.h5", "skeleton.h5"]


def _crafted(tmp_path, name: str) -> Path:
    """A closed flag recording of a few frames, to be edited by hand the way an attacker would."""
    d = defaults("flag")
    d["scene"]["seconds"] = 0.1
    path = tmp_path / name
    sim = Simulation(d)
    with H5Recorder(path, sim.model, sim.scene, sim.checkpoint, "flag") as recorder:
        sim.run(0.1, on_frame=recorder.write)
    return path


def test_recordings_declaring_more_than_they_hold_are_refused_before_any_build(tmp_path, capsys):
    """A 187 KB file that declared 10 M frames (its checkpoint's digest recomputed) kept `convert` busy for minutes
    and `--replay` at 4 GB; a descriptor of 4,096 worlds was built before its particles were compared; a dataset
    chunked in blocks of a million frames holds them in a few bytes. Each is one line and exit 2, in seconds."""
    many = _crafted(tmp_path, "many.h5")
    with Recording(many) as r:
        cp, slot = r.checkpoint(), r._slot
    declared = 10_000_000
    with h5py.File(many, "r+") as f:
        for name in ("time", "positions", "controls", "diagnostics/worst_stretch", "diagnostics/kinetic_energy"):
            f[name].resize(declared, axis=0)
        for name in ("diagnostics/centre", "diagnostics/altitude", "diagnostics/airspeed"):
            f[name].resize(declared, axis=0)
        f[f"checkpoint/slot{slot}/frame"][0] = declared - 1
        f[f"checkpoint/slot{slot}/digest"][...] = cp.digest(declared - 1)
    worlds = _crafted(tmp_path, "worlds.h5")
    with h5py.File(worlds, "r+") as f:
        d = load_text(str(f.attrs["descriptor"]), "test")
        d["worlds"] = {"count": 4096}
        f.attrs["descriptor"] = to_toml(d)
        f.attrs["descriptor_sha256"] = descriptor_digest(to_toml(d))  # as a careful forger would
    chunked = _crafted(tmp_path, "chunked.h5")
    with h5py.File(chunked, "r+") as f:
        times = f["time"][()]
        del f["time"]
        f.create_dataset("time", data=times, maxshape=(None,), chunks=(1_000_000,))
    cases = [
        (many, "declares 10,000,000 frames but dataset"),
        (worlds, "asks for 4,096 worlds, its frames hold 1 objects"),
        (chunked, "dataset time is not stored as warpsim writes it"),
    ]
    for path, message in cases:
        for argv in (
            ["convert", path, tmp_path / "out.usda"],
            ["render", path, tmp_path / "out.png"],
            ["run", "--replay", path, "--quiet"],
            ["run", "--resume", path, "--quiet"],
        ):
            started = time.perf_counter()
            assert main([str(a) for a in argv]) == EXIT_USAGE, argv
            assert time.perf_counter() - started < 10.0, argv
            _one_error_line(capsys.readouterr().err.strip().splitlines(), message)
    assert not (tmp_path / "out.usda").exists() and not (tmp_path / "out.png").exists()


def test_a_writer_killed_in_plain_write_mode_is_recovered(tmp_path):
    """`run --resume` opens the file in plain (not SWMR) write mode while it checks the layout; a kill -9 there left
    the superblock marked open for write, and `convert`, `render` and `--resume` called the whole recording damaged
    (only `h5clear -s` saved it, and nothing said so). They now clear the flags under the writer's lock."""
    from warpsim.io.h5safe import status_flags

    rec = tmp_path / "k.h5"
    assert main(["run", "kite", "--seconds", "0.2", "--h5", str(rec), "--quiet"]) == 0
    with Recording(rec) as r:
        frames = r.frame_count
    kill = "import h5py, os, sys; f = h5py.File(sys.argv[1], 'r+', locking=False); f.flush(); os.kill(os.getpid(), 9)"
    for command in ("convert", "render", "resume"):
        victim = tmp_path / f"{command}.h5"
        shutil.copy(rec, victim)
        subprocess.run([sys.executable, "-c", kill, str(victim)], check=False)
        assert status_flags(victim) & 1  # what the killed writer left
        argv = {
            "convert": ["convert", victim, tmp_path / "k.usda"],
            "render": ["render", victim, tmp_path / "k.png"],
            "resume": ["run", "--resume", victim, "--seconds", "0.1", "--quiet"],
        }[command]
        assert main([str(a) for a in argv]) == 0, command
        assert status_flags(victim) == 0
        with h5py.File(victim, "r") as f:  # plain HDF5 opens it again
            assert f["time"].shape[0] >= frames


def test_the_terrain_is_part_of_the_recording_and_found_beside_its_scene(tmp_path, monkeypatch):
    """After the scene's terrain .npy was edited, `run --resume` exited 0 with half the frames differing from an
    uninterrupted run; `terrain.file` was looked up from the current directory, not the scene file's. The heights
    are now stored in the recording (resume, replay, convert and render use them) and the path is the scene's."""
    scenes = tmp_path / "scenes"
    scenes.mkdir()
    rng = np.random.default_rng(7)
    np.save(scenes / "hills.npy", rng.normal(0.0, 3.0, (48, 48)))
    scene = scenes / "hills.toml"
    scene.write_text("[scene]\nobject = 'kite'\n[terrain]\nkind = 'file'\nfile = 'hills.npy'\nsize = 200\n")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)  # the scene is run from another folder, by its path
    whole, cut = tmp_path / "whole.h5", tmp_path / "cut.h5"
    assert main(["run", str(scene), "--seconds", "0.6", "--h5", str(whole), "--quiet"]) == 0
    assert main(["run", str(scene), "--seconds", "0.3", "--h5", str(cut), "--quiet"]) == 0
    np.save(scenes / "hills.npy", np.zeros((48, 48)))  # the terrain file edited ...
    assert main(["run", "--resume", str(cut), "--seconds", "0.3", "--quiet"]) == 0
    with Recording(whole) as a, Recording(cut) as b:
        assert a.frame_count == b.frame_count > 10
        np.testing.assert_array_equal(a.positions(), b.positions())  # ... and the resume flew the recorded hills
        assert a.terrain().heights.std() > 1.0
    (scenes / "hills.npy").unlink()  # ... and gone: the recording still converts and renders
    assert main(["convert", str(cut), str(tmp_path / "c.usda")]) == 0
    assert main(["render", str(cut), str(tmp_path / "c.png")]) == 0
    assert main(["run", "--replay", str(cut), "--seconds", "0.1", "--quiet"]) == 0


@pytest.mark.slow
def test_ctrl_c_during_start_up_under_load_is_one_line_every_time(tmp_path):
    """`test_ctrl_c_during_start_up_is_one_line[0.3]` once printed "Exception ignored ... KeyboardInterrupt" under
    load: the interrupt landed in an import or a finaliser. With two busy processes loading the cores, runs are
    interrupted at moments spread over their start-up (imports, Warp, the model, the first frames): every one ends
    with at most one line, exit 130 (or 0 when it finished first), and either no recording or a readable one.
    (Before the interpreter reaches warpsim's first line, about 0.05 s, Python's own handling applies.)"""
    burners = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(2)]
    try:
        for k, delay in enumerate((0.2, 0.35, 0.5, 0.7, 0.9, 1.2)):
            folder = tmp_path / f"run{k}"
            folder.mkdir()
            proc = _start("run", "kite", "--seconds", "3", "--h5", folder / "k.h5", cwd=folder)
            _wait_for_sigint_handler(proc)
            time.sleep(delay)
            proc.send_signal(signal.SIGINT)
            out, err = proc.communicate(timeout=120)
            lines = [line for line in err.splitlines() if line.strip() and CUDA_NOTE not in line]
            lines = [line for line in lines if not line.startswith("\r")]
            assert proc.returncode in (0, EXIT_INTERRUPTED), (delay, proc.returncode, err)
            assert "Traceback" not in err and "Exception ignored" not in err and len(lines) <= 1, (delay, err)
            if (folder / "k.h5").exists():
                with Recording(folder / "k.h5") as r:
                    assert r.frame_count >= 1
    finally:
        for burner in burners:
            burner.kill()
            burner.wait()


@pytest.mark.parametrize("output", ["k.png", "k.usda"])
def test_a_link_planted_at_the_temporary_name_is_not_written_through(output, tmp_path):
    """Pictures and stages are written to `.NAME.PID.tmp.EXT` and renamed; a link planted under that name (a shared
    folder such as /tmp) made the writer write into the linked file. The temporary is now created with O_EXCL |
    O_NOFOLLOW after removing whatever is there."""
    rec = tmp_path / "k.h5"
    assert main(["run", "kite", "--seconds", "0.1", "--h5", str(rec), "--quiet"]) == 0
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    out = tmp_path / output
    temporary_path(out).symlink_to(victim)
    assert main(["render" if output.endswith(".png") else "convert", str(rec), str(out)]) == 0
    assert victim.read_text() == "precious" and out.is_file() and not out.is_symlink()
    assert not os.path.lexists(temporary_path(out))


def test_a_link_at_the_recording_is_never_written_through(tmp_path, capsys):
    """`--h5 LINK` truncated the link's target and wrote the recording into it (exit 0): a link there is refused in
    one line, exit 2, its target untouched; a link planted at a sweep chunk's recording is removed, not followed."""
    from warpsim.scene.descriptor import resolve
    from warpsim.sweeps.chunk import _chunk_recorder

    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    link = tmp_path / "a.h5"
    link.symlink_to(victim)
    assert main(["run", "kite", "--seconds", "0.05", "--quiet", "--h5", str(link)]) == EXIT_USAGE
    err = capsys.readouterr().err
    assert "symbolic link" in err and err.count("\n") == 1
    assert victim.read_text() == "precious" and link.is_symlink()

    class Task:
        h5 = str(tmp_path / "cases-000000-000000.h5")

    os.symlink(victim, Task.h5)
    sim = Simulation(resolve("kite")[0])
    recorder = _chunk_recorder(Task, sim)
    recorder.close()
    assert victim.read_text() == "precious" and not os.path.islink(Task.h5) and os.path.getsize(Task.h5) > 0


@pytest.mark.parametrize(
    "field, value, message",
    [("time", 1e300, "is not its"), ("steps", 2**62, "is outside 0..")],
)
def test_a_crafted_checkpoint_time_or_step_count_is_one_line(tmp_path, capsys, field, value, message):
    """A checkpoint time of 1e300 (its digest recomputed) was resumed, exit 0, and then every reader refused the
    whole recording; a step count of 2**62 ended `run --resume` in a 27-line ValueError. Each is one line, exit 2,
    and the recording is left as it was."""
    path = _crafted(tmp_path, "crafted.h5")
    with Recording(path) as r:
        cp, slot, frame = r.checkpoint(), r._slot, r.checkpoint_frame
    getattr(cp, field)[0] = value
    with h5py.File(path, "r+") as f:
        f[f"checkpoint/slot{slot}/{field}"][0] = value
        f[f"checkpoint/slot{slot}/digest"][...] = cp.digest(frame)
    before = path.read_bytes()
    assert main(["run", "--resume", str(path), "--seconds", "0.2", "--quiet"]) == EXIT_USAGE
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1, err
    assert path.read_bytes() == before


def test_a_replay_of_controls_its_scene_lacks_is_one_line(tmp_path, capsys):
    """A recording whose stored control names were edited (`pitch` for the kite) ended `run --replay` in a 29-line
    KeyError: one line, exit 2."""
    d = defaults("kite")
    path = tmp_path / "kite.h5"
    sim = Simulation(d)
    sim.set_controls(anchor=(1.0, 0.0))
    with H5Recorder(path, sim.model, sim.scene, sim.checkpoint, "kite") as recorder:
        sim.run(0.1, on_frame=recorder.write)
    with Recording(path) as r:
        cp, slot, frame = r.checkpoint(), r._slot, r.checkpoint_frame
    cp.control_names = tuple("pitch" if n == "anchor" else n for n in cp.control_names)
    with h5py.File(path, "r+") as f:  # the names and the newest checkpoint's digest, as a careful forger would
        f["checkpoint"].attrs["control_names"] = list(cp.control_names)
        f[f"checkpoint/slot{slot}/digest"][...] = cp.digest(frame)
    assert main(["run", "--replay", str(path), "--quiet"]) == EXIT_USAGE
    err = capsys.readouterr().err
    assert "pitch" in err and err.count("\n") == 1, err


def test_a_recording_whose_descriptor_was_changed_is_refused(tmp_path, capsys):
    """A recording whose stored descriptor was swapped for another object's was replayed with exit 0, flying the
    other object; an edited one (another wind) was accepted by replay, resume, convert and render. The descriptor's
    sha256 is stored beside it: each command refuses the changed one in one line, exit 2."""
    path = _crafted(tmp_path, "flag.h5")
    with h5py.File(path, "r+") as f:
        d = load_text(str(f.attrs["descriptor"]), "test")
        d["wind"]["velocity"] = [9.0, 0.0, 0.0]
        f.attrs["descriptor"] = to_toml(d)
    for argv in (
        ["run", "--replay", str(path), "--quiet"],
        ["run", "--resume", str(path), "--seconds", "0.2", "--quiet"],
        ["convert", str(path), str(tmp_path / "out.usda")],
    ):
        assert main(argv) == EXIT_USAGE
        err = capsys.readouterr().err
        assert "was changed after its frames were recorded" in err and err.count("\n") == 1, err


def test_a_crafted_checkpoint_frame_number_is_one_line(tmp_path, capsys):
    """A checkpoint's frame number set to 2**62 (its digest recomputed) ended `run --resume` in a 27-line ValueError:
    a checkpoint past the frames the file holds is one line, exit 2, for every reader."""
    path = _crafted(tmp_path, "frame.h5")
    with Recording(path) as r:
        cp, slot = r.checkpoint(), r._slot
    with h5py.File(path, "r+") as f:
        f[f"checkpoint/slot{slot}/frame"][0] = 2**62
        f[f"checkpoint/slot{slot}/digest"][...] = cp.digest(2**62)
    resume = ["run", "--resume", str(path), "--seconds", "0.2", "--quiet"]
    for argv in (resume, ["convert", str(path), str(tmp_path / "o.usda")]):
        assert main(argv) == EXIT_USAGE
        err = capsys.readouterr().err
        assert "its checkpoint is of frame" in err and err.count("\n") == 1, err
