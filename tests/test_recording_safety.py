"""Recordings and stages under attack: a second writer, kill -9, corruption, a full disk, hostile names and paths,
signals at the edges. Each drives the real command line in a subprocess where a process must die or a disk
must fill, and checks exit codes, the one error line, that nothing hangs, and what is still readable and
resumable afterwards."""

import os
import random
import re
import resource
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
    ROOT,
    _one_error_line,
    _start,
    _wait_for_frames,
)

from warpsim.cli import EXIT_INTERRUPTED, EXIT_OUTPUT, EXIT_USAGE, main
from warpsim.io import remove_stale_temporaries, temporary_path
from warpsim.io.h5safe import writer_active
from warpsim.io.hdf5 import H5Recorder
from warpsim.io.recording import Recording
from warpsim.objects import registry
from warpsim.run.simulation import Simulation
from warpsim.scene.descriptor import defaults, load_text, to_toml


def _cli(*args, cwd=None, timeout=120, preexec_fn=None):
    """Run ``python -m warpsim ARGS``; returns (exit code, stdout, stderr lines without Warp's driver note)."""
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.run(
        [sys.executable, "-m", "warpsim", *map(str, args)],
        cwd=cwd or ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
        preexec_fn=preexec_fn,
    )
    err = [line for line in proc.stderr.splitlines() if line.strip() and CUDA_NOTE not in line]
    return proc.returncode, proc.stdout, err


"""A progress line ``run`` prints off a terminal every 10 s of wall time (a loaded machine takes that long)."""


def _reference_positions(seconds: float, tmp_path: Path, scene="kite") -> np.ndarray:
    """Positions of an uninterrupted run of ``seconds``."""
    ref = tmp_path / f"ref{seconds:.6g}.h5"
    assert main(["run", scene, "--seconds", f"{seconds:.6g}", "--h5", str(ref), "--quiet"]) == 0
    with Recording(ref) as r:
        return r.positions()


# 1. a second writer --------------------------------------------------------------------------------------------


@pytest.mark.slow
def test_second_writer_and_resume_are_refused_and_the_first_recording_survives(tmp_path):
    rec = tmp_path / "two.h5"
    first = _start("run", "kite", "--seconds", "3600", "--quiet", "--h5", rec)
    try:
        seen = _wait_for_frames(rec, 10, first)
        assert writer_active(rec)
        start = time.monotonic()
        code, out, err = _cli("run", "flag", "--seconds", "5", "--h5", rec)
        assert code == EXIT_USAGE and out == ""
        _one_error_line(err, "two.h5", "another warpsim run is writing")
        code, out, err = _cli("run", "--resume", rec, "--seconds", "1")
        assert code == EXIT_USAGE
        _one_error_line(err, "another warpsim run is writing")
        assert time.monotonic() - start < 60
        with Recording(rec) as r:  # still the kite, still growing, readable while written
            assert "[kite]" in r.descriptor_text and r.frame_count >= seen and r.live
    finally:
        first.send_signal(signal.SIGINT)
        first.communicate(timeout=60)
    assert first.returncode == EXIT_INTERRUPTED
    with Recording(rec) as r:
        assert r.frame_count > seen and load_text(r.descriptor_text, "rec")["scene"]["object"] == "kite"
        assert np.isfinite(r.positions()).all() and not r.live


# 2. kill -9 at random moments, then read, convert and resume ---------------------------------------------------


@pytest.mark.parametrize("seed", [1, 2])
@pytest.mark.slow
def test_killed_run_reads_converts_and_resumes_bit_for_bit(seed, tmp_path):
    rng = random.Random(seed)
    rec, usd = tmp_path / "k.h5", tmp_path / "k.usdc"
    proc = _start("run", "kite", "--seconds", "3600", "--quiet", "--h5", rec, "--usd", usd)
    _wait_for_frames(rec, 5, proc)
    time.sleep(rng.uniform(0.0, 1.5))
    proc.kill()
    proc.communicate(timeout=30)
    assert not usd.exists()  # the stage is written at the end only: a killed run leaves none
    with pytest.raises(OSError):  # the killed writer's flags: a plain reader refuses (see README)
        h5py.File(rec, "r").close()
    with h5py.File(rec, "r", swmr=True) as f:  # what the README tells other tools to do
        assert f["positions"].shape[0] >= 1
    with Recording(rec) as r:
        frames, t = r.frame_count, float(r.time[-1])
        assert frames >= 5 and r.checkpoint_frame == frames - 1 and np.isfinite(r.positions()).all()
    code, _, err = _cli("convert", rec, tmp_path / "k.usda")
    assert code == 0 and err == []
    stage = Usd.Stage.Open(str(tmp_path / "k.usda"))
    assert len(UsdGeom.Mesh(stage.GetPrimAtPath("/World/kite/sail")).GetPointsAttr().GetTimeSamples()) == frames
    # the kite's frames are 32.5 ms apart (13 steps of 2.5 ms): 0.325 s is 10 more frames
    assert main(["run", "--resume", str(rec), "--seconds", "0.325", "--quiet"]) == 0
    with h5py.File(rec, "r") as f:  # the resume cleared the flags
        resumed = f["positions"][:]
    assert resumed.shape[0] == frames + 10
    np.testing.assert_array_equal(resumed, _reference_positions(t + 0.325, tmp_path))


def test_stale_temporaries_of_a_killed_export_are_removed(tmp_path):
    target = tmp_path / "k.usdz"
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    stale = target.with_name(f".{target.name}.{dead.pid}.tmp.usdz")
    stale.write_bytes(b"half a package")
    mine = temporary_path(target)
    other = tmp_path / ".other.usdz.123.tmp.usdz"
    other.write_bytes(b"")
    assert remove_stale_temporaries(target) == [stale] and not stale.exists() and other.exists()
    assert mine.name == f".k.usdz.{os.getpid()}.tmp.usdz"
    stale.write_bytes(b"half a package")
    assert main(["run", "kite", "--seconds", "0.1", "--quiet", "--usd", str(target)]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == [".other.usdz.123.tmp.usdz", "k.usdz"]


# 3. corruption: fail fast with one line, never read wrong data --------------------------------------------------

_CORRUPTION_SCRIPT = r"""
import contextlib, io, json, sys, time
from warpsim.cli import main
out = []
for path, target in json.loads(sys.argv[1]):
    start = time.monotonic()
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = main(["convert", path, target])
    lines = [l for l in err.getvalue().splitlines() if l.strip() and "Warp CUDA warning" not in l]
    out.append([path, code, lines, time.monotonic() - start])
print(json.dumps(out))
"""


def _pristine(tmp_path) -> Path:
    rec = tmp_path / "pristine.h5"
    assert main(["run", "kite", "--seconds", "2", "--quiet", "--h5", str(rec)]) == 0
    return rec


def _flip(src: Path, dst: Path, offset: int, mask: int = 0x10) -> Path:
    data = bytearray(src.read_bytes())
    data[offset] ^= mask
    dst.write_bytes(bytes(data))
    return dst


def _end_time(stage: str) -> float:
    return float(re.search(r"endTimeCode = ([0-9.e+-]+)", stage).group(1))


@pytest.mark.slow
def test_corrupted_recordings_fail_within_seconds_or_read_exactly(tmp_path):
    """Byte flips all over the file and cuts: ``convert`` ends with exit 2 and one line, or (a flip in unused
    bytes) writes exactly the stage of the pristine file; none waits in HDF5's retries."""
    rec = _pristine(tmp_path)
    assert main(["convert", str(rec), str(tmp_path / "pristine.usda")]) == 0
    reference = (tmp_path / "pristine.usda").read_text()
    size = rec.stat().st_size
    rng = random.Random(7)
    offsets = [9, 11, 20, 44, 48, 60, 100, 200, 300, 500, 800, 1200, 2000, 4000]
    offsets += sorted(rng.sample(range(4096, size), 12)) + [size - 1]
    cases = [(str(_flip(rec, tmp_path / f"flip{o}.h5", o)), str(tmp_path / f"flip{o}.usda")) for o in offsets]
    for fraction in (0.1, 0.5, 0.9):
        cut = tmp_path / f"cut{fraction}.h5"
        cut.write_bytes(rec.read_bytes()[: int(size * fraction)])
        cases.append((str(cut), str(tmp_path / f"cut{fraction}.usda")))
    proc = subprocess.run(
        [sys.executable, "-c", _CORRUPTION_SCRIPT, __import__("json").dumps(cases)],
        capture_output=True,
        text=True,
        timeout=240,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    results = __import__("json").loads(proc.stdout.strip().splitlines()[-1])
    failed = 0
    for (path, code, lines, seconds), (_, target) in zip(results, cases, strict=True):
        assert seconds < 20, (path, seconds)  # a hang in HDF5's retries takes minutes
        if code == 0:
            text = Path(target).read_text()
            # a flip in unused bytes changes nothing; one in the newest checkpoint (its digest fails) shows the
            # frames up to the older checkpoint: the same stage, ended earlier
            assert lines == [] and (text == reference or _end_time(text) < _end_time(reference)), path
        else:
            failed += 1
            assert code == EXIT_USAGE and len(lines) == 1 and Path(path).name in lines[0], (path, lines)
            assert not Path(target).exists()
    assert failed >= len(cases) // 2  # most flips land in metadata or data and are caught


_CRASH_SCRIPT = """
import os, signal, sys
import warpsim.io.h5safe as h5safe
from warpsim.cli import main
parent, read = os.getpid(), h5safe.open_for_reading
def crashing(path, live):  # HDF5 crashing on a damaged file, in the probe's forked child only
    if os.getpid() != parent:
        os.kill(os.getpid(), signal.SIGSEGV)
    return read(path, live)
h5safe.open_for_reading = crashing
sys.exit(main(["convert", sys.argv[1], sys.argv[2]]))
"""


def test_a_recording_that_crashes_hdf5_is_refused_in_one_line(tmp_path):
    """A file on which the library itself crashes (a segmentation fault in HDF5's reading of its attributes, which
    the probe's child meets first) is one line, exit 2, not a crash of warpsim: the parent never reads it."""
    rec = _pristine(tmp_path)
    out = tmp_path / "out.usda"
    proc = subprocess.run(
        [sys.executable, "-c", _CRASH_SCRIPT, str(rec), str(out)], capture_output=True, text=True, timeout=120
    )
    lines = [line for line in proc.stderr.splitlines() if line.strip() and "Warp CUDA" not in line]
    assert proc.returncode == EXIT_USAGE, proc.stderr[-2000:]
    assert len(lines) == 1 and "HDF5 crashed (SIGSEGV)" in lines[0] and rec.name in lines[0], lines
    assert not out.exists()


def _slot_offsets(path: Path) -> dict[str, tuple[int, int]]:
    """``slot name -> (frame, file offset of its q array)``."""
    with h5py.File(path, "r") as f:
        return {
            slot: (int(f[f"checkpoint/{slot}/frame"][0]), f[f"checkpoint/{slot}/q"].id.get_offset())
            for slot in ("slot0", "slot1")
        }


def test_a_damaged_checkpoint_falls_back_to_the_other_slot_and_two_are_refused(tmp_path):
    rec = tmp_path / "k.h5"
    d = defaults("kite")
    sim = Simulation(d)
    with H5Recorder(rec, sim.model, sim.scene, sim.checkpoint, "kite") as recorder:
        recorder.sync_interval = 0.0  # a checkpoint after every frame: both slots filled
        sim.run(1.0, on_frame=recorder.write)
    slots = _slot_offsets(rec)
    newest = max(slots, key=lambda s: slots[s][0])
    older = min(slots, key=lambda s: slots[s][0])
    assert slots[newest][0] == slots[older][0] + 1 > 20
    one = _flip(rec, tmp_path / "one.h5", slots[newest][1] + 5, 0x01)
    with Recording(one) as r:
        assert r.checkpoint_frame == slots[older][0] and r.frame_count == slots[older][0] + 1
    assert main(["run", "--resume", str(one), "--seconds", "0.3", "--quiet"]) == 0
    with Recording(one) as r:
        np.testing.assert_array_equal(r.positions(), _reference_positions(float(r.time[-1]), tmp_path))
    both = _flip(rec, tmp_path / "both.h5", slots[newest][1] + 5, 0x01)
    both = _flip(both, both, slots[older][1] + 7)
    code, _, err = _cli("run", "--resume", both, "--seconds", "1")
    assert code == EXIT_USAGE
    _one_error_line(err, "checkpoints are damaged")


# 4. a full disk ---------------------------------------------------------------------------------------------------


@pytest.fixture
def small_disk(tmp_path):
    """``(directory, preexec_fn)``: a 2 MB tmpfs where this machine lets us mount one, else a file-size limit of
    2 MB on the child process (writes past it fail with EFBIG, as a full disk fails them with ENOSPC)."""
    mount = tmp_path / "small"
    mount.mkdir()
    command = ["mount", "-t", "tmpfs", "-o", "size=2m", "tmpfs", str(mount)]
    root = os.geteuid() == 0 and shutil.which("mount")
    mounted = root and not subprocess.run(command, capture_output=True).returncode
    if mounted:
        yield mount, None, "No space left on device"
        subprocess.run(["umount", "-l", str(mount)], check=False)
        return

    _cli("run", "kite", "--seconds", "0.03", "--quiet")  # kernels compiled and cached before the limit applies

    def limit():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (2_000_000, 2_000_000))

    yield mount, limit, "File too large"


@pytest.mark.slow
def test_full_disk_recording_stops_with_one_line_and_stays_resumable(small_disk, tmp_path):
    directory, preexec, cause = small_disk
    rec = directory / "k.h5"
    code, out, err = _cli("run", "kite", "--seconds", "600", "--h5", rec, preexec_fn=preexec, timeout=300)
    assert code == EXIT_OUTPUT, (out, err)
    line = _one_error_line(err, str(rec), cause, "keeps frames 0-", "--resume")
    kept = int(line.split("keeps frames 0-")[1].split()[0])
    assert "interrupted" in out or "done" in out  # the summary is still printed
    with Recording(rec) as r:  # every frame shown was written; none after the last checkpoint
        assert r.frame_count == kept + 1 and r.checkpoint_frame == kept
        q = r.positions()
        assert np.isfinite(q).all() and (np.abs(q).reshape(len(q), -1).max(axis=1) > 0).all()
        t = float(r.time[-1])
    moved = shutil.copy(rec, tmp_path / "moved.h5")  # space found elsewhere: it continues
    assert main(["run", "--resume", str(moved), "--seconds", "0.3", "--quiet"]) == 0
    with Recording(moved) as r:
        np.testing.assert_array_equal(r.positions(), _reference_positions(t + 0.3, tmp_path))


@pytest.mark.parametrize("suffix", [".usdz", ".usda", ".usdc"])
@pytest.mark.slow
def test_full_disk_stage_is_not_written_under_its_name(suffix, small_disk):
    directory, preexec, cause = small_disk
    if preexec is None:
        (directory / "filler").write_bytes(bytes(1_800_000))  # leave ~200 kB
    target = directory / f"k{suffix}"
    code, out, err = _cli("run", "kite", "--seconds", "60", "--usd", target, preexec_fn=preexec)
    assert code == EXIT_OUTPUT
    _one_error_line(err, str(target), cause, "nothing was written under that name")
    assert "done:" in out
    assert not target.exists() and not [p for p in directory.iterdir() if p.name.startswith(".")]


# 5. checkpoints of many gusty worlds --------------------------------------------------------------------------------


@pytest.mark.slow
def test_256_gusty_worlds_record_and_resume_bit_for_bit(tmp_path):
    scene = str(ROOT / "scenes" / "kite_gusty.toml")
    whole, cut = tmp_path / "whole.h5", tmp_path / "cut.h5"
    common = ["--worlds", "256", "--vary", "wind.gust_seed=0:255", "--quiet"]
    assert main(["run", scene, "--seconds", "0.12", "--h5", str(whole), *common]) == 0
    assert main(["run", scene, "--seconds", "0.06", "--h5", str(cut), *common]) == 0
    assert main(["run", "--resume", str(cut), "--seconds", "0.06", "--quiet"]) == 0
    with Recording(whole) as a, Recording(cut) as b:
        assert a.frame_count == b.frame_count == 5
        np.testing.assert_array_equal(a.positions(), b.positions())
        assert a.checkpoint().gust_active.sum() == 256
        for name, value in a.checkpoint().arrays().items():
            np.testing.assert_array_equal(value, getattr(b.checkpoint(), name), err_msg=name)


# 6. strings in the stored descriptor --------------------------------------------------------------------------------


def test_descriptor_strings_round_trip_through_the_recording(tmp_path):
    odd = tmp_path / 'dir "quoted" \\ back\\slash'
    odd.mkdir()
    terrain = odd / "hills.npy"
    np.save(terrain, np.zeros((8, 8), dtype=np.float32))
    scene = tmp_path / "odd.toml"
    scene.write_text(f"[scene]\nobject = 'kite'\nseconds = 0.1\n[terrain]\nkind = 'file'\nfile = '''{terrain}'''\n")
    rec = tmp_path / "odd.h5"
    assert main(["run", str(scene), "--h5", str(rec), "--quiet"]) == 0
    with Recording(rec) as r:
        assert load_text(r.descriptor_text, "rec")["terrain"]["file"] == str(terrain)
    assert main(["run", "--resume", str(rec), "--seconds", "0.1", "--quiet"]) == 0
    assert main(["convert", str(rec), str(tmp_path / "odd.usda")]) == 0


@pytest.mark.parametrize("kind", list(registry.OBJECTS))
def test_every_descriptor_value_type_round_trips(kind):
    d = defaults(kind)
    d["terrain"]["file"] = "a \"b\" \\c\\ \t\n\u00e9\u2603 'd'"
    d["controls"] = [{"time": 1.0, "ramp": True, "wind": (1.0, 2.0, 3.0)}]
    d["worlds"] = {"count": 2, "wind": {"gust_seed": [1, 2]}}
    d["wind"]["velocity"] = [float("inf"), -0.0, 1e-300]
    text = to_toml(d)
    back = __import__("tomllib").loads(text)
    assert back["terrain"]["file"] == d["terrain"]["file"]
    assert back["wind"]["velocity"][0] == float("inf") and back["worlds"]["wind"]["gust_seed"] == [1, 2]
    assert back["controls"][0]["wind"] == [1.0, 2.0, 3.0] and back["controls"][0]["ramp"] is True
    for kind_defaults in (defaults(kind),):
        assert load_text(to_toml(kind_defaults), "x") == kind_defaults


# 7. outputs that cannot be written: refused before simulating -------------------------------------------------------
