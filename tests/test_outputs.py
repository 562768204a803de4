"""Outputs: the animated USD stage, the streaming HDF5 recording, resume, convert, interruption, bad paths."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
from pxr import Usd, UsdGeom

from warpsim.cli import main
from warpsim.io.hdf5 import H5Recorder
from warpsim.io.recording import Recording
from warpsim.io.usd import UsdWriter, validate
from warpsim.run.simulation import Simulation
from warpsim.scene.descriptor import defaults


def _record(kind, tmp_path, seconds=0.5, suffix=".usda", **overrides):
    """Run ``kind`` with both outputs attached; returns (sim, frames as (index, time, positions), usd, h5)."""
    d = defaults(kind)
    for section, values in overrides.items():
        d[section].update(values)
    sim = Simulation(d)
    usd_path, h5_path = tmp_path / f"{kind}{suffix}", tmp_path / f"{kind}.h5"
    frames = []
    writer = UsdWriter(usd_path, sim.model, sim.steps_per_frame * sim.dt)
    with H5Recorder(h5_path, sim.model, sim.scene, sim.checkpoint, kind) as recorder:

        def on_frame(frame):
            frames.append((frame.index, frame.time, frame.positions))
            writer.write(frame.time, frame.positions)
            recorder.write(frame)

        sim.run(seconds, on_frame=on_frame)
    writer.close()
    return sim, frames, usd_path, h5_path


def _drawn(stage):
    return {str(p.GetPath()): p for p in stage.Traverse() if p.GetTypeName() in ("Mesh", "BasisCurves", "Sphere")}


@pytest.mark.parametrize("kind", ["flag", "hang-glider", "kite", "parachute"])
def test_stage_round_trip_and_validators(kind, tmp_path):
    sim, frames, usd_path, _ = _record(kind, tmp_path)
    stage = Usd.Stage.Open(str(usd_path))
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z and UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    assert stage.GetTimeCodesPerSecond() == pytest.approx(1.0 / (sim.steps_per_frame * sim.dt))
    assert stage.GetDefaultPrim().GetPath() == "/World"
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (
        0.0,
        pytest.approx(frames[-1][1] / (sim.steps_per_frame * sim.dt)),
    )
    names, errors = validate(usd_path)
    assert len(names) >= 20 and errors == []  # usd-core 26 ships 30 validators; all ran, none complained

    drawn = _drawn(stage)
    assert "/World/Terrain" in drawn
    # a run that does not end on the frame grid ends with a frame at a fractional time code: read each frame at
    # its exact code (a rounded one would read between two samples), compare the sample times rounded
    exact = [t / (sim.steps_per_frame * sim.dt) for _, t, _ in frames]
    exact = [float(round(c)) if abs(c - round(c)) < 1e-6 else c for c in exact]
    codes = [round(c, 6) for c in exact]
    record = sim.model.objects[0]
    points_drawn = 0
    for path, prim in drawn.items():
        if path == "/World/Terrain":
            continue
        if prim.GetTypeName() == "Sphere":
            op = UsdGeom.Xformable(prim).GetOrderedXformOps()[0]
            samples = op.GetAttr().GetTimeSamples()
            pilot = record.parts.get("pilot", record.parts.get("person"))[0]
            for (_, _, q), code in zip(frames, exact, strict=True):
                np.testing.assert_allclose(np.array(op.Get(code)), q[pilot], rtol=0, atol=1e-5)
            points_drawn += 1
        else:
            attr = UsdGeom.PointBased(prim).GetPointsAttr()
            samples = attr.GetTimeSamples()
            ids = _ids_of(sim, prim)
            for (_, _, q), code in zip(frames, exact, strict=True):
                np.testing.assert_array_equal(np.array(attr.Get(code)), q[ids].astype(np.float32))
            points_drawn += len(ids)
        assert [round(s, 6) for s in samples] == codes  # one time sample per frame
    virtual = record.parts.get("virtual", [])
    assert not set(np.asarray(virtual).tolist()) & set(_all_drawn_ids(sim, drawn))  # helpers are not drawn


def _ids_of(sim, prim):
    """Particle ids behind a mesh/curves prim, from the model (what the writer is meant to draw)."""
    record = sim.model.objects[0]
    part = prim.GetName()
    if prim.GetTypeName() == "Mesh":
        return np.unique(sim.model.tri_indices_np[record.tri_parts[part]].reshape(-1))
    return np.concatenate([np.asarray(c) for c in record.curves[part]])


def _all_drawn_ids(sim, drawn):
    out = []
    for path, prim in drawn.items():
        if path != "/World/Terrain" and prim.GetTypeName() != "Sphere":
            out += _ids_of(sim, prim).tolist()
    return out


@pytest.mark.parametrize("suffix", [".usdc", ".usdz"])
def test_binary_and_packaged_stages_open(suffix, tmp_path):
    _, frames, usd_path, _ = _record("kite", tmp_path, seconds=0.2, suffix=suffix)
    stage = Usd.Stage.Open(str(usd_path))
    sail = UsdGeom.Mesh(stage.GetPrimAtPath("/World/kite/sail"))
    assert len(sail.GetPointsAttr().GetTimeSamples()) == len(frames)
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []  # no temporary left


def test_recording_layout_and_round_trip(tmp_path):
    sim, frames, _, h5_path = _record("parachute", tmp_path, seconds=0.5)
    with Recording(h5_path) as rec:
        f = rec.file
        assert rec.frame_count == len(frames)
        np.testing.assert_array_equal(rec.time, [t for _, t, _ in frames])
        np.testing.assert_array_equal(rec.positions(), np.stack([q for _, _, q in frames]))  # float64, as simulated
        assert f["positions"].compression == "gzip" and f["positions"].chunks[0] == 1
        assert f.attrs["format"] == "warpsim-recording" and f.attrs["warp_version"]
        assert "[parachute]" in f.attrs["descriptor"] and f.attrs["dt"] == pytest.approx(sim.dt) == 0.0025
        np.testing.assert_array_equal(f["topology/sticks"][:], sim.model.stick_particles_np)
        np.testing.assert_array_equal(f["topology/triangles"][:], sim.model.tri_indices_np)
        parts = list(f["topology"].attrs["parts"])
        person = sim.model.objects[0].parts["person"][0]
        assert parts[f["topology/particle_part"][person]] == "parachute/person"
        assert f["diagnostics/centre"].shape == (len(frames), 1, 3)
        # the person falls: altitude decreases, airspeed grows from the 0 m/s start
        altitude, airspeed = f["diagnostics/altitude"][:, 0], f["diagnostics/airspeed"][:, 0]
        assert altitude[-1] < altitude[0] and airspeed[-1] > 1.0
        assert f["diagnostics/worst_stretch"][-1] > 0.0 and np.all(f["diagnostics/kinetic_energy"][:] >= 0)


@pytest.mark.parametrize(
    "scene", ["scenes/kite_gusty.toml", "scenes/hang_glider_dive.toml", "scenes/hang_glider_lattice.toml"]
)
def test_resume_equals_one_run_bit_for_bit(scene, tmp_path, monkeypatch):
    """2 s in one run == 1 s, then --resume for 1 s (gusts and control schedules included)."""
    monkeypatch.chdir(os.path.dirname(os.path.dirname(__file__)))
    one, two = tmp_path / "one.h5", tmp_path / "two.h5"
    assert main(["run", scene, "--seconds", "2", "--h5", str(one), "--quiet"]) == 0
    assert main(["run", scene, "--seconds", "1", "--h5", str(two), "--quiet"]) == 0
    assert main(["run", "--resume", str(two), "--seconds", "1", "--quiet"]) == 0
    with h5py.File(one) as a, h5py.File(two) as b:
        assert a["positions"].shape == b["positions"].shape
        for name in ("time", "positions", "diagnostics/centre"):
            np.testing.assert_array_equal(a[name][:], b[name][:], err_msg=name)
    with Recording(one) as a, Recording(two) as b:
        assert a.checkpoint_frame == b.checkpoint_frame == a.frame_count - 1
        for name, value in a.checkpoint().arrays().items():
            np.testing.assert_array_equal(value, getattr(b.checkpoint(), name), err_msg=name)


def test_convert_equals_direct_export(tmp_path):
    direct, rec, converted = tmp_path / "direct.usda", tmp_path / "rec.h5", tmp_path / "converted.usda"
    assert main(["run", "kite", "--seconds", "0.5", "--h5", str(rec), "--usd", str(direct), "--quiet"]) == 0
    assert main(["convert", str(rec), str(converted)]) == 0
    a, b = Usd.Stage.Open(str(direct)), Usd.Stage.Open(str(converted))
    assert a.GetTimeCodesPerSecond() == b.GetTimeCodesPerSecond() and a.GetEndTimeCode() == b.GetEndTimeCode()
    prims = [p for p in a.Traverse()]
    assert [p.GetPath() for p in prims] == [p.GetPath() for p in b.Traverse()]
    for prim in prims:
        for attr in prim.GetAttributes():
            other = b.GetPrimAtPath(prim.GetPath()).GetAttribute(attr.GetName())
            assert attr.GetTimeSamples() == other.GetTimeSamples(), attr.GetPath()
            for t in attr.GetTimeSamples() or [Usd.TimeCode.Default()]:
                assert attr.Get(t) == other.Get(t), (attr.GetPath(), t)


def _start(tmp_path, *extra):
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    cmd = [sys.executable, "-m", "warpsim.cli", "run", "kite", "--seconds", "3600", "--quiet", *extra]
    return subprocess.Popen(cmd, cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)


def _wait_for_frames(path, count, proc, timeout=120.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        assert proc.poll() is None, proc.communicate()
        if path.exists():
            try:
                with Recording(path) as rec:  # opened while the writer is running (SWMR)
                    if rec.frame_count >= count:
                        return rec.frame_count
            except Exception:  # the writer may not have switched to SWMR yet
                pass
        time.sleep(0.2)
    raise AssertionError(f"no {count} frames in {path} after {timeout} s")


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_signal_keeps_every_completed_frame(sig, tmp_path):
    rec, usd = tmp_path / "run.h5", tmp_path / "run.usdc"
    proc = _start(tmp_path, "--h5", rec.name, "--usd", usd.name)
    seen = _wait_for_frames(rec, 20, proc)
    proc.send_signal(sig)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err.decode()
    with Recording(rec) as r:
        assert r.frame_count >= seen
        assert r.checkpoint_frame == r.frame_count - 1
        assert np.isfinite(r.positions(r.frame_count - 1)).all()
        frames = r.frame_count
    stage = Usd.Stage.Open(str(usd))  # a complete stage of what was simulated
    assert len(UsdGeom.Mesh(stage.GetPrimAtPath("/World/kite/sail")).GetPointsAttr().GetTimeSamples()) == frames
    assert main(["run", "--resume", str(rec), "--seconds", "0.1", "--quiet"]) == 0  # and it continues
    with Recording(rec) as r:
        assert r.frame_count > frames


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["run", "kite", "--usd", "{tmp}/missing/out.usda"], "does not exist"),
        (["run", "kite", "--h5", "{tmp}/missing/out.h5"], "does not exist"),
        (["run", "kite", "--usd", "{tmp}/out.obj"], "unknown USD extension '.obj'"),
        (["run", "kite", "--h5", "{tmp}/out.txt"], "use .h5 or .hdf5"),
        (["run", "--resume", "{tmp}/plain.h5"], "not a warpsim recording"),
        (["run", "--resume", "{tmp}/text.h5"], "not an HDF5 file"),
        (["convert", "{tmp}/text.h5", "{tmp}/out.usda"], "not an HDF5 file"),
        (["convert", "{tmp}/nothing.h5", "{tmp}/out.usda"], "no such file"),
        (["run", "--resume", "{tmp}/plain.h5", "kite"], "not both"),
        (["run"], "missing SCENE"),
    ],
)
def test_bad_output_paths_and_recordings(argv, message, tmp_path, capsys):
    (tmp_path / "text.h5").write_text("not hdf5")
    with h5py.File(tmp_path / "plain.h5", "w") as f:
        f["x"] = [1, 2, 3]
    before = sorted(p.name for p in tmp_path.iterdir())
    assert main([a.format(tmp=tmp_path) for a in argv]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1, err
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing half-written left behind


def test_a_huge_terrain_is_sampled_in_the_stage(tmp_path, monkeypatch):
    """An 8192^2 terrain in `--usd` or `convert` grew past 6 GB and ended in a MemoryError traceback: a stage draws
    the ground with at most STAGE_TERRAIN_SIDE samples a side, its edges and heights where they are sampled kept."""
    import numpy as np
    from pxr import Usd, UsdGeom

    import warpsim.io.usd as usd
    from warpsim.cli import main

    monkeypatch.setattr(usd, "STAGE_TERRAIN_SIDE", 33)
    heights = np.add.outer(np.linspace(0.0, 5.0, 301), np.linspace(0.0, 2.0, 257))
    np.save(tmp_path / "ground.npy", heights)
    scene = tmp_path / "s.toml"
    scene.write_text(f'[scene]\nobject = "kite"\n[terrain]\nkind = "file"\nfile = "{tmp_path / "ground.npy"}"\n')
    out = tmp_path / "s.usda"
    assert main(["run", str(scene), "--seconds", "0.05", "--quiet", "--usd", str(out)]) == 0
    stage = Usd.Stage.Open(str(out))  # held: the prim lives as long as its stage
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/World/Terrain"))
    points = np.array(mesh.GetPointsAttr().Get())
    assert len(points) == 33 * 33
    assert points[:, 2].min() == pytest.approx(heights.min(), abs=1e-5)
    assert points[:, 2].max() == pytest.approx(heights.max(), abs=1e-5)


def test_png_output_draws_the_last_frame_and_a_bad_name_is_one_line(tmp_path, capsys):
    """`warpsim run --png` (the picture output, from the outputs table) draws the run's last frame as
    `warpsim render` draws a recording's: a 960 x 540 picture with the sail's blue in it, listed in the run's last
    lines; a name that is not a .png is a usage error before the run starts."""
    from PIL import Image

    out = tmp_path / "glider.png"
    assert main(["run", "hang_glider", "--seconds", "0.5", "--png", str(out)]) == 0
    assert f"picture: {out}" in capsys.readouterr().out
    pixels = np.asarray(Image.open(out).convert("RGB"), dtype=np.int64)
    assert pixels.shape == (540, 960, 3)
    blue = (pixels[..., 2] > pixels[..., 0] + 60) & (
        pixels[..., 2] > 150
    )  # the sail (the sky is pale, the ground green)
    assert 0.01 < blue.mean() < 0.6
    assert main(["run", "hang_glider", "--seconds", "0.5", "--png", str(tmp_path / "glider.gif")]) == 2
    err = capsys.readouterr().err
    assert "--png" in err and ".png" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "glider.gif").exists()


def test_a_new_output_is_one_line_of_the_outputs_table(tmp_path, monkeypatch, capsys):
    """A format added to `warpsim.io.outputs.OUTPUTS` is offered by `warpsim run --help`, checked before the run,
    opened with the run and handed every frame, and listed when the run ends: nothing else to touch."""
    from warpsim.io import OutputPathError, outputs
    from warpsim.io.protocol import FrameOutput

    frames = []

    class Counter(FrameOutput):
        def __init__(self, path):
            self.path = path

        def log_state(self, frame):
            frames.append(frame.index)

        def close(self):
            Path(self.path).write_text(f"{len(frames)} frames\n")

    def check(path):
        if not str(path).endswith(".count"):
            raise OutputPathError(f"{path}: a count is a .count")
        return Path(path)

    kind = outputs.OutputKind(
        "--count", "OUT.count", "count the frames", "frame count", check, lambda p, s, r: Counter(p)
    )
    monkeypatch.setattr(outputs, "OUTPUTS", (*outputs.OUTPUTS, kind))
    with pytest.raises(SystemExit):
        main(["run", "--help"])
    assert "--count OUT.count" in capsys.readouterr().out
    assert main(["run", "kite", "--seconds", "0.5", "--count", str(tmp_path / "a.txt")]) == 2
    assert "a count is a .count" in capsys.readouterr().err
    out = tmp_path / "a.count"
    assert main(["run", "kite", "--seconds", "0.5", "--count", str(out)]) == 0
    assert f"frame count: {out}" in capsys.readouterr().out
    # 0.5 s in frames of 13 kite steps of 2.5 ms (30 a second, rounded to whole steps; the last one partial), frame 0
    assert frames == list(range(17)) and out.read_text() == "17 frames\n"
