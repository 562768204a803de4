"""The live viewer (``warpsim view``): its logic with the null backend, and the real window on a virtual X screen.

The window tests start Xvfb and drive ``tests/viewer_driver.py`` in a subprocess with keys injected by
xdotool; they are skipped where Xvfb, xdotool or pyglet are missing, unless ``WARPSIM_REQUIRE_DISPLAY_TESTS=1``
(``.ci/run`` sets it and installs them), where a missing piece fails.
"""

from __future__ import annotations

import importlib.util
import json
import math
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from warpsim._extras import install_hint
from warpsim.cli import main
from warpsim.io.recording import Recording
from warpsim.objects.hang_glider import bank
from warpsim.run.simulation import Simulation
from warpsim.scene.descriptor import merge, resolve, to_toml
from warpsim.scene.dirs import scene_dirs
from warpsim.viewer import NullBackend, Viewer

sys.path.insert(0, str(Path(__file__).parent))
from viewer_driver import Clock  # noqa: E402  (the wall clock the window driver gives too)

HERE = Path(__file__).parent


def _viewer(scene: str, record=None, **overrides) -> tuple[Viewer, NullBackend]:
    descriptor, _, where = resolve(scene, scene_dirs())
    if overrides:
        descriptor = merge("test", descriptor, overrides)
    backend = NullBackend()
    viewer = Viewer(Simulation(descriptor), backend, record=record, descriptor_text=to_toml(descriptor), scene=where)
    viewer.say = lambda line: None
    return viewer, backend


def _bank(viewer: Viewer) -> float:
    """Bank of the hang glider [deg], positive with the right wing down."""
    return bank(viewer.model.objects[0], viewer.frame.positions)


# ---------------------------------------------------------------------------------------------- null backend


@pytest.mark.parametrize("key, side", [("RIGHT", 1.0), ("LEFT", -1.0)])
def test_held_arrow_ramps_roll_and_banks_that_way_then_release_ramps_back(key, side):
    viewer, keys = _viewer("hang-glider")
    clock = Clock(viewer)
    keys.press(key)
    clock.ticks(5)
    # RAMP per simulated second: 5 frames ramp by 5 * RAMP * frame interval
    assert viewer.sim.controls["roll"] == pytest.approx(side * min(1.0, 5 * viewer.RAMP * viewer.frame_interval))
    clock.seconds(2.0 - 5 * viewer.frame_interval)
    assert viewer.sim.controls["roll"] == side
    # banked towards the held side within 2 simulated seconds: the flying design's pilot swings on a strap and
    # full weight shift rolls the wing 6.8 degrees in 2 s from the launch and 12 in 6 s (measured; the paper's
    # rigid control sticks rolled it past 10 in 2 s)
    assert side * _bank(viewer) > 5.0
    keys.release(key)
    clock.ticks(3)
    assert abs(viewer.sim.controls["roll"]) == pytest.approx(1.0 - 3 * viewer.RAMP * viewer.frame_interval)
    clock.seconds(1.0)
    assert viewer.sim.controls["roll"] == 0.0


def test_hands_off_the_glider_does_not_bank():
    viewer, _ = _viewer("hang-glider")
    Clock(viewer).seconds(2.0)
    assert abs(_bank(viewer)) < 1.0
    assert "roll" not in viewer.sim.controls  # nothing was set: the keyboard sets only what changes


def test_up_arrow_pulls_the_bar_in():
    viewer, keys = _viewer("hang-glider")
    clock = Clock(viewer)
    keys.press("UP")
    clock.seconds(1.0)
    assert viewer.sim.controls["pitch"] == 1.0
    keys.release("UP")
    keys.press("DOWN")
    clock.seconds(1.5)
    assert viewer.sim.controls["pitch"] == -1.0


def test_w_walks_the_kite_anchor_towards_the_kite_and_s_back():
    viewer, keys = _viewer("kite")
    clock = Clock(viewer)
    start = np.array(viewer._anchor())
    kite = viewer.frame.positions[viewer.model.objects[0].parts["sail"]].mean(axis=0)[:2]
    towards = (kite - start) / np.linalg.norm(kite - start)
    keys.press("W")
    clock.seconds(1.0)
    keys.release("W")
    moved = np.array(viewer.sim.controls["anchor"]) - start
    assert moved @ towards == pytest.approx(viewer.walk_keys.speed * 1.0, rel=0.05)  # walking speed [m/s] x 1 s
    record = viewer.model.objects[0]
    nail = viewer.sim.control.nail_target.numpy()[record.anchor_nail]
    assert nail[:2] == pytest.approx(viewer.sim.controls["anchor"], abs=1e-5)  # the rope's ground end moved
    keys.press("S")
    clock.seconds(1.0)
    assert np.linalg.norm(np.array(viewer.sim.controls["anchor"]) - start) < 0.2


def test_a_mesh_designs_line_is_walked_and_its_figures_shown_as_a_kites():
    """The viewer knows the design of one's own by what it has (a line to a nailed anchor), not by its name: W walks
    the diamond kite's anchor towards it, and the heads-up line shows its line angle."""
    viewer, keys = _viewer("diamond_kite")
    clock = Clock(viewer)
    record = viewer.model.objects[0]
    assert viewer.walked is record and record.kind == "mesh"
    start = np.array(viewer._anchor())
    kite = viewer.frame.positions[record.parts["cloth"]].mean(axis=0)[:2]
    towards = (kite - start) / np.linalg.norm(kite - start)
    keys.press("W")
    clock.seconds(1.0)
    keys.release("W")
    moved = np.array(viewer.sim.controls["anchor"]) - start
    assert moved @ towards == pytest.approx(viewer.walk_keys.speed * 1.0, rel=0.05)
    nail = viewer.sim.control.nail_target.numpy()[record.anchor_nail]
    assert nail[:2] == pytest.approx(viewer.sim.controls["anchor"], abs=1e-5)
    figures = viewer.figures(viewer.frame)[0]  # what the heads-up panel shows
    assert 0.0 < figures["line_angle"] < 90.0 and figures["line_pull"] > 0.0


def test_wind_keys_change_speed_and_direction():
    viewer, keys = _viewer("kite")  # 6 m/s along +x
    clock = Clock(viewer)
    keys.tap("PLUS")
    keys.tap("PLUS")
    clock.ticks(1)  # the wind moves at WIND_RATE towards what was asked for
    assert viewer.sim.controls["wind"] == pytest.approx((6.0 + viewer.WIND_RATE * viewer.frame_interval, 0.0, 0.0))
    clock.seconds(1.0)
    assert viewer.sim.controls["wind"] == pytest.approx((8.0, 0.0, 0.0))
    assert viewer.sim.control.wind.numpy()[0] == pytest.approx([8.0, 0.0, 0.0])
    keys.tap("[")
    clock.ticks(1)
    w = np.array(viewer.sim.controls["wind"])
    assert math.degrees(math.atan2(w[1], w[0])) == pytest.approx(viewer.WIND_TURN)
    assert np.linalg.norm(w) == pytest.approx(8.0)
    for _ in range(12):
        keys.tap("MINUS")
        clock.seconds(0.5)
    clock.seconds(1.0)
    assert np.linalg.norm(viewer.sim.controls["wind"]) == 0.0  # never below calm


def test_a_short_tap_of_plus_asks_one_step_and_a_press_while_paused_counts():
    """A page's + held for 0.1 s asks 1 m/s, not one per frame it was held (it once gave 2); a press while paused
    is kept for when the flight goes on (a page's press once came and went between two frame starts)."""
    viewer, keys = _viewer("kite")  # 6 m/s
    clock = Clock(viewer)
    keys.press("PLUS")
    clock.seconds(0.1)
    keys.release("PLUS")
    clock.seconds(2.0)
    assert np.linalg.norm(viewer.sim.controls["wind"]) == pytest.approx(7.0)
    keys.tap("SPACE")
    clock.ticks(1)
    keys.press("PLUS")
    clock.ticks(2)
    keys.release("PLUS")
    clock.ticks(2)
    keys.tap("SPACE")
    clock.seconds(2.0)
    assert np.linalg.norm(viewer.sim.controls["wind"]) == pytest.approx(8.0)


def test_plus_never_lowers_a_wind_beyond_the_objects_limit():
    """A schedule (or a control set from elsewhere) may blow harder than the kite's limit: + then leaves it alone
    (it once pulled such a wind down to the limit), - still lowers it."""
    viewer, keys = _viewer("kite")
    clock = Clock(viewer)
    viewer.sim.set_controls(wind=(18.0, 0.0, 0.0))
    clock.ticks(1)
    keys.tap("PLUS")
    clock.seconds(1.0)
    assert viewer.wind_limit == 12.0 and np.linalg.norm(viewer.sim.controls["wind"]) == pytest.approx(18.0)
    keys.tap("MINUS")
    clock.seconds(1.0)
    assert np.linalg.norm(viewer.sim.controls["wind"]) == pytest.approx(17.0)


def test_the_wind_keeps_its_direction_through_a_calm():
    """Down to calm, turned while calm, up again: it blows from where it was, turned (it came back along +x, and a
    turn while calm was lost)."""
    viewer, keys = _viewer("kite", wind={"velocity": [0.0, 2.0, 0.0]})  # towards +y (90 deg)
    clock = Clock(viewer)
    for _ in range(2):
        keys.tap("MINUS")
    clock.seconds(1.5)
    assert np.linalg.norm(viewer.sim.controls["wind"]) == 0.0
    keys.tap("[")  # 15 deg anticlockwise, while calm
    clock.ticks(1)
    keys.tap("PLUS")
    clock.seconds(1.0)
    w = np.array(viewer.sim.controls["wind"])
    assert np.linalg.norm(w) == pytest.approx(1.0)
    assert math.degrees(math.atan2(w[1], w[0])) == pytest.approx(90.0 + viewer.WIND_TURN)


def test_each_object_says_its_keys_and_the_help_shows_the_scenes_own():
    """The keys come from the objects (ObjectSpec.keys), not from the viewer: the help lists those of the scene's
    objects and the common ones, and an object the viewer has never heard of is steered by the keys it declares."""
    helps = {}
    for scene in ("flag", "hang-glider", "kite"):
        viewer, _ = _viewer(scene)
        viewer.show_help = True
        helps[scene] = "\n".join(viewer.overlay())
        assert [k for k, _ in viewer.backend.keys] == [line.lstrip().split("   ")[0] for line in viewer.overlay()]
    assert "Up / Down" not in helps["flag"] and "W A S D" not in helps["flag"] and "Space" in helps["flag"]
    assert "Up / Down" in helps["hang-glider"] and "W A S D" not in helps["hang-glider"]
    assert "W A S D" in helps["kite"] and "Left / Right" not in helps["kite"]


def test_an_object_with_keys_of_its_own_is_steered_by_them(monkeypatch):
    import dataclasses

    from warpsim.objects import registry
    from warpsim.objects.keys import AxisKeys

    seen = []  # a flag that leans its pole: no such flag is built in, and the viewer is told nothing of it
    spec = dataclasses.replace(
        registry.OBJECTS["flag"],
        controls=("roll",),
        apply_controls=lambda record, targets, values: seen.append(values.get("roll")),
        keys=(AxisKeys("roll", "J", "K", "J / K", "flag: lean the pole left / right", rate=4.0),),
    )
    monkeypatch.setitem(registry.OBJECTS, "flag", spec)
    viewer, keys = _viewer("flag")
    clock = Clock(viewer)
    keys.press("K")
    clock.seconds(1.0)
    assert viewer.sim.controls["roll"] == 1.0 and seen[-1] == 1.0
    viewer.show_help = True
    assert any("flag: lean the pole left / right" in line for line in viewer.overlay())
    assert "roll +1.00" in viewer.hud()[-2]
    with pytest.raises(ValueError, match="'roll'"):
        dataclasses.replace(spec, controls=())  # a key bound to a control the object lacks


@pytest.mark.parametrize("how", ["held", "auto-repeat"])
def test_holding_plus_raises_the_wind_at_a_bounded_rate_and_stops_at_the_scenes_limit(how):
    """A held + (a page's held key, or the window's auto-repeat: a press every 1/30 s) raises the wind at
    WIND_RATE; once let go it runs on at most WIND_LEAD; it never passes the kite's wind limit. (It once took
    the kite's wind from 7 to 38 m/s in 2 s, and the kite blew up.)"""
    viewer, keys = _viewer("kite")  # 6 m/s
    clock = Clock(viewer)
    if how == "held":
        keys.press("PLUS")
        clock.seconds(2.0)
        keys.release("PLUS")
    else:
        for _ in range(60):
            keys.tap("PLUS")
            clock.seconds(1 / 30)
    speed = float(np.linalg.norm(viewer.sim.controls["wind"]))
    assert speed == pytest.approx(6.0 + viewer.sim.state.time * viewer.WIND_RATE, abs=0.1)
    clock.seconds(2.0)
    after = float(np.linalg.norm(viewer.sim.controls["wind"]))
    assert speed <= after <= speed + viewer.WIND_LEAD + 1e-9
    keys.press("PLUS")
    clock.seconds(4.0)
    assert np.linalg.norm(viewer.sim.controls["wind"]) == pytest.approx(viewer.wind_limit) == 12.0
    assert not viewer.blew_up


def test_space_stops_simulated_time_and_period_steps_one_frame():
    viewer, keys = _viewer("flag")
    clock = Clock(viewer)
    clock.ticks(3)
    keys.tap("SPACE")
    clock.ticks(1)
    t = viewer.sim.state.time
    clock.ticks(20)
    assert viewer.paused and viewer.sim.state.time == t
    keys.tap(".")
    clock.ticks(1)
    assert viewer.sim.state.time == pytest.approx(t + viewer.frame_interval)
    keys.tap("SPACE")
    clock.ticks(4)
    assert viewer.sim.state.time == pytest.approx(t + 5 * viewer.frame_interval)


def test_r_restores_the_initial_state_and_controls():
    viewer, keys = _viewer("hang-glider")
    clock = Clock(viewer)
    initial = viewer.frame.positions.copy()
    keys.press("RIGHT")
    clock.seconds(1.0)
    keys.release("RIGHT")
    keys.tap("R")
    clock.ticks(1)
    assert viewer.sim.state.time == 0.0 and viewer.sim.steps_taken == 0
    assert np.array_equal(viewer.frame.positions, initial)
    assert np.array_equal(viewer.sim.state.particle_q.numpy(), initial)
    assert viewer.sim.controls == {} and viewer.axes == {"pitch": 0.0, "roll": 0.0}


def test_machine_too_slow_slows_down_instead_of_owing_frames(monkeypatch):
    viewer, _ = _viewer("flag")
    viewer.BUDGET = 0.0  # one frame per tick at most, as on a machine that cannot keep up
    clock = Clock(viewer)
    clock.now += 10.0  # ten wall seconds pass in one tick
    viewer.tick(clock.now)
    assert viewer.behind and viewer.sim.state.time == pytest.approx(viewer.frame_interval)
    assert "machine too slow" in viewer.hud()[0]
    clock.ticks(1)  # the debt was dropped: back to one frame per frame interval
    assert not viewer.behind and viewer.sim.state.time == pytest.approx(2 * viewer.frame_interval)


def test_camera_cycles_and_mouse_orbits_and_zooms():
    viewer, keys = _viewer("parachute")
    clock = Clock(viewer)
    seen = []
    for _ in range(3):
        seen.append(viewer.camera)
        view = viewer.view()
        assert np.isfinite(view.eye).all() and np.linalg.norm(view.eye - view.target) > 1.0
        keys.tap("C")
        clock.ticks(1)
    assert seen == ["orbit", "chase", "ground"] and viewer.camera == "orbit"
    distance, azimuth = viewer.orbit["distance"], viewer.orbit["azimuth"]
    keys.send("scroll", 2)
    keys.send("drag", 100, 0)
    clock.ticks(1)
    assert viewer.orbit["distance"] == pytest.approx(distance * 0.81)
    assert viewer.orbit["azimuth"] == pytest.approx(azimuth - 30.0)


def test_hud_shows_time_rates_object_figures_and_controls():
    viewer, keys = _viewer("hang-glider")
    clock = Clock(viewer)
    keys.press("RIGHT")
    clock.seconds(1.0)
    hud = keys.last_hud
    assert hud[0].startswith("t =") and "real time" in hud[0] and "steps/s" in hud[0]
    assert any("hang_glider: altitude" in line and "sink" in line and "glide" in line for line in hud)
    assert any("roll +1.00" in line for line in hud)
    assert viewer.rates()[0] == pytest.approx(1.0, rel=0.05)  # paced to the (test's) wall clock
    kite, kite_keys = _viewer("kite")
    Clock(kite).ticks(2)
    assert any("line" in line and "deg" in line and "pull" in line for line in kite_keys.last_hud)
    chute, chute_keys = _viewer("parachute")
    Clock(chute).ticks(2)
    assert any("descent" in line and "radius" in line for line in chute_keys.last_hud)
    keys.tap("H")
    clock.ticks(1)
    assert any("R" in line and "restart" in line for line in keys.last_overlay)


def test_blowup_is_shown_state_kept_at_the_last_good_frame_and_r_restarts(tmp_path):
    path = tmp_path / "flight.h5"
    viewer, keys = _viewer("kite", record=path, solver={"max_stretch": 1e-4})
    messages = []
    viewer.say = messages.append
    clock = Clock(viewer)
    clock.ticks(3)
    assert viewer.paused and "blew up" in viewer.error and "press R" in viewer.error
    assert any("blew up" in m for m in messages)  # said on stderr too
    assert "blew up" in " ".join(keys.last_overlay)
    assert viewer.sim.steps_taken == 0  # back at the last good frame: the start
    keys.tap("R")
    clock.ticks(1)
    assert viewer.error == "" and not viewer.paused
    viewer.close()
    with Recording(path) as recording:
        assert recording.frame_count == 1  # the initial frame, kept; the bad one never written


def test_a_flight_recorded_in_the_viewer_replays_headless_bit_for_bit(tmp_path):
    path = tmp_path / "flight.h5"
    viewer, keys = _viewer("hang-glider", record=path)
    clock = Clock(viewer)
    for key, seconds in (("RIGHT", 0.7), ("UP", 0.5), ("LEFT", 0.4), (None, 0.3)):
        if key:
            keys.press(key)
        clock.seconds(seconds)
        if key:
            keys.release(key)
    keys.tap("PLUS")
    clock.seconds(0.6)  # the wind reaches 1 m/s after 0.5 s (WIND_RATE)
    viewer.close()
    again = tmp_path / "again.h5"
    assert main(["run", "--replay", str(path), "--h5", str(again), "--quiet"]) == 0
    with Recording(path) as flown, Recording(again) as replayed:
        assert flown.frame_count == replayed.frame_count > 50
        assert np.array_equal(flown.positions(), replayed.positions())
        assert np.array_equal(flown.time, replayed.time)
        rolls = [flown.controls(k).get("roll", 0.0) for k in range(flown.frame_count)]
        assert max(rolls) == 1.0 and min(rolls) < -0.5  # the flight did use the controls (left ramps from +1)
        assert flown.controls(flown.frame_count - 1)["wind"] == (1.0, 0.0, 0.0)
        assert replayed.controls(replayed.frame_count - 1) == flown.controls(flown.frame_count - 1)


def test_restart_while_recording_starts_a_new_take(tmp_path):
    path = tmp_path / "flight.h5"
    viewer, keys = _viewer("flag", record=path)
    clock = Clock(viewer)
    clock.ticks(5)
    keys.tap("R")
    clock.ticks(3)  # the first restarts (no step), the next two step
    viewer.close()
    with Recording(path) as first, Recording(tmp_path / "flight.take2.h5") as second:
        assert first.frame_count == 6 and second.frame_count == 3  # each with its initial frame, none lost


# ---------------------------------------------------------------------------------------------- command line


def _cli(argv, env=None, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "warpsim", *argv], capture_output=True, text=True, env=env, cwd=cwd, timeout=300
    )


def test_no_display_is_one_line_exit_2(tmp_path):
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    result = _cli(["view", "kite", "--h5", str(tmp_path / "x.h5")], env=env)
    assert result.returncode == 2, result.stderr
    assert result.stderr.count("\n") == 1 and "no display" in result.stderr and "xvfb-run" in result.stderr
    assert not list(tmp_path.iterdir())


def test_missing_viewer_extra_is_one_line_exit_2(tmp_path):
    stub = tmp_path / "stub"
    stub.mkdir()
    (stub / "pyglet.py").write_text("raise ImportError('No module named pyglet')\n")
    env = {**os.environ, "PYTHONPATH": str(stub)}
    result = _cli(["view", "kite"], env=env)
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1 and install_hint("viewer") in result.stderr


@pytest.mark.parametrize(
    "argv, words",
    [
        (["view", "kite", "--set", "kite.rope_length=-1"], "rope_length"),
        (["view", "nope"], "nope"),
        (["view", "kite", "--h5", "out.txt"], "extension"),
        (["view", "kite", "--screenshot", "shot.jpg"], "extension"),
        (["view", "kite", "--size", "0x0"], "size"),
    ],
)
def test_bad_view_arguments_are_one_line_exit_2(argv, words, capsys):
    try:
        code = main(argv)
    except SystemExit as exit:  # argparse's own refusals
        code = exit.code
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and words in err, err


# ---------------------------------------------------------------------------------------------- real window


def _missing() -> str:
    missing = [tool for tool in ("Xvfb", "xdotool") if shutil.which(tool) is None]
    if importlib.util.find_spec("pyglet") is None:
        missing.append("pyglet")
    return ", ".join(missing)


@pytest.fixture(scope="module")
def display():
    """A virtual X screen for the module's window tests: yields the environment that points at it."""
    missing = _missing()
    if missing:
        if os.environ.get("WARPSIM_REQUIRE_DISPLAY_TESTS") == "1":
            pytest.fail(f"window tests need {missing} (WARPSIM_REQUIRE_DISPLAY_TESTS=1)")
        pytest.skip(f"window tests need {missing} (apt install xvfb xdotool; pip install pyglet)")
    from warpsim.viewer.xvfb import virtual_display

    with virtual_display((1280, 720)) as env:
        yield env


def _drive(display, scenario: str, out: Path) -> dict:
    result = subprocess.run(
        [sys.executable, str(HERE / "viewer_driver.py"), scenario, str(out)],
        env=display,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    return json.loads((out / f"{scenario}.json").read_text())


@pytest.fixture(scope="module")
def glider_flight(display, tmp_path_factory):
    out = tmp_path_factory.mktemp("glider")
    return _drive(display, "glider", out), out


@pytest.mark.display
def test_window_first_picture_shows_the_sail_where_the_glider_is(glider_flight):
    from PIL import Image

    result, out = glider_flight
    picture = np.asarray(Image.open(out / "first.png").convert("RGB")).astype(float) / 255
    assert picture.std() > 0.05  # not blank
    r, g, b = picture[..., 0], picture[..., 1], picture[..., 2]
    sail = (b > 0.25) & (r < 0.3 * b) & (g < 0.8 * b)  # the sail's blue, shaded; the sky is much paler
    assert sail.sum() > 200
    rows, cols = np.nonzero(sail)
    x, y = result["sail_pixel"]  # where the sail's centre projects
    h, w = picture.shape[:2]
    assert abs(cols.mean() - x) < 0.1 * w and abs(rows.mean() - y) < 0.1 * h
    sky = picture[5:40, w - 3 :]  # the right edge: the heads-up panel leaves at least 4 pixels there
    assert (sky[..., 2] > sky[..., 0]).all()  # a blue sky above


@pytest.mark.display
def test_window_held_right_arrow_banks_right_within_two_seconds(glider_flight):
    result, _ = glider_flight
    held = np.array(result["held"])  # time [s], roll, bank [deg]
    assert held[-1, 0] <= 2.0 + 1e-9
    assert held[:, 1].max() == 1.0 and np.all(np.diff(held[:, 1]) >= 0)  # ramped up, held
    assert held[-1, 2] > 5.0  # banked right (6.8 degrees measured: see the null-backend test above)
    assert 0.0 < result["roll_after_release"] < 1.0  # ramping back after the key was released


@pytest.mark.display
def test_window_space_pauses_period_steps_r_restarts_escape_closes(glider_flight):
    result, _ = glider_flight
    before, after, paused = result["paused"]
    assert paused and after == before
    assert result["one_frame"] == pytest.approx(0.03, abs=0.011)  # one frame of the scene
    assert result["restart_time"] == 0.0 and result["restart_same"]
    assert result["takes"] == ["flown.h5", "flown.take2.h5"] == result["takes_said"]
    assert result["closed"]


@pytest.mark.display
def test_window_flight_replays_headless_bit_for_bit(glider_flight, tmp_path):
    _, out = glider_flight
    again = tmp_path / "again.h5"
    assert main(["run", "--replay", str(out / "flown.h5"), "--h5", str(again), "--quiet"]) == 0
    with Recording(out / "flown.h5") as flown, Recording(again) as replayed:
        assert flown.frame_count == replayed.frame_count > 60
        assert np.array_equal(flown.positions(), replayed.positions())
        assert max(flown.controls(k).get("roll", 0.0) for k in range(flown.frame_count)) == 1.0


@pytest.mark.display
def test_window_counts_every_typed_plus_minus_and_question_mark(display, tmp_path):
    """'+' is typed as shift+=; pyglet on X reported only the first of three in a row (it took the key's release,
    reported unshifted as '=', for another key's), so the wind rose 1 m/s instead of 3. The window now reads
    the character keys from the typed text: each press counts once, the keypad's too."""
    steps = _drive(display, "typed", tmp_path)["steps"]
    speeds = [round(speed, 6) for _, speed, _, _ in steps]
    start = float(np.linalg.norm([4.0, 0.5]))  # the flag's wind
    assert speeds == [round(start + k, 6) for k in (1, 2, 3, 4, 5, 4, 3, 2, 2, 2, 2, 2, 2, 2)], steps
    assert [shown for _, _, shown, _ in steps][-6:] == [True, False, True, True, True, True]  # ? ? / then [ ] ]
    headings = [heading for *_, heading in steps][-4:]
    assert np.allclose(np.diff(headings), [15.0, -15.0, -15.0]), steps  # '[' anticlockwise, ']' clockwise


@pytest.mark.display
def test_window_w_walks_the_kite_anchor(display, tmp_path):
    result = _drive(display, "kite", tmp_path)
    start, end, kite = (np.array(result[k]) for k in ("anchor_start", "anchor_end", "kite"))
    towards = (kite - start) / np.linalg.norm(kite - start)
    assert (end - start) @ towards > 1.5  # about 2 m in about 1 s of walking


@pytest.mark.display
def test_view_command_on_the_virtual_screen_saves_a_screenshot_and_recording(display, tmp_path):
    result = _cli(
        ["view", "parachute", "--seconds", "1", "--size", "640x360", "--screenshot", "s.png", "--h5", "f.h5"],
        env=display,
        cwd=tmp_path,
    )
    assert result.returncode == 0, result.stderr
    from PIL import Image

    picture = np.asarray(Image.open(tmp_path / "s.png").convert("RGB"))
    assert picture.shape == (360, 640, 3) and picture.std() > 10
    with Recording(tmp_path / "f.h5") as recording:
        assert recording.time[-1] == pytest.approx(1.0, abs=0.04)


@pytest.mark.display
def test_sigterm_closes_the_viewer_like_ctrl_c(tmp_path):
    """SIGTERM to `warpsim view --h5 --screenshot` died by the signal (143) with the recording left open (plain h5py
    refused it), up to 0.5 s of frames lost and no screenshot. It now quits as Ctrl-C and Esc do."""
    if shutil.which("Xvfb") is None or importlib.util.find_spec("pyglet") is None:
        pytest.skip("needs Xvfb and pyglet")
    import h5py

    from warpsim.io.h5safe import status_flags
    from warpsim.viewer.xvfb import virtual_display

    with virtual_display((640, 480)) as env:
        proc = subprocess.Popen(
            [sys.executable, "-m", "warpsim", "view", "parachute", "--size", "320x240"]
            + ["--screenshot", "s.png", "--h5", "f.h5", "--seconds", "600"],
            env=env,
            cwd=tmp_path,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        deadline = time.monotonic() + 120
        frames = 0
        while time.monotonic() < deadline and proc.poll() is None and frames < 20:
            time.sleep(0.2)
            try:
                with Recording(tmp_path / "f.h5") as recording:
                    frames = recording.frame_count
            except Exception:  # noqa: BLE001 - not written yet
                pass
        proc.send_signal(signal.SIGTERM)
        out, err = proc.communicate(timeout=60)
    assert proc.returncode == 0 and "Traceback" not in err, (out, err)
    assert (tmp_path / "s.png").stat().st_size > 1000 and "screenshot: s.png" in out
    assert status_flags(tmp_path / "f.h5") == 0  # closed: plain HDF5 opens it
    simulated = float(out.split("simulated ")[1].split(" s")[0])
    with h5py.File(tmp_path / "f.h5", "r") as plain:
        assert plain["time"].shape[0] >= 20
    with Recording(tmp_path / "f.h5") as recording:
        assert recording.frame_count >= 20
        assert recording.time[-1] == pytest.approx(simulated, abs=0.006)  # every frame flown is kept


def _our_xvfb(screen: str) -> int:
    """The process id of this process's Xvfb child started with ``-screen 0 SCREEN``."""
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            args = (entry / "cmdline").read_bytes().split(b"\0")
            parent = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
        except (OSError, IndexError, ValueError):
            continue
        if args[0].endswith(b"Xvfb") and screen.encode() in args and parent == os.getpid():
            return int(entry.name)
    raise AssertionError(f"no Xvfb child with screen {screen}")


@pytest.mark.display
def test_the_display_going_away_keeps_the_recording_and_screenshot(tmp_path):
    """When the X server died under `warpsim view`, Xlib printed two lines and exited 1 with the recording left open
    and no screenshot. Now the recording is closed with every frame, the screenshot saved, one line, exit 130."""
    if shutil.which("Xvfb") is None or importlib.util.find_spec("pyglet") is None:
        pytest.skip("needs Xvfb and pyglet")
    from warpsim.io.h5safe import status_flags
    from warpsim.viewer.xvfb import virtual_display

    with virtual_display((656, 496)) as env:  # a size of its own, to tell its server from others
        server = _our_xvfb("656x496x24")
        proc = subprocess.Popen(
            [sys.executable, "-m", "warpsim", "view", "parachute", "--size", "320x240"]
            + ["--screenshot", "s.png", "--h5", "f.h5", "--seconds", "600"],
            env=env,
            cwd=tmp_path,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        frames, deadline = 0, time.monotonic() + 120
        while time.monotonic() < deadline and proc.poll() is None and frames < 20:
            time.sleep(0.2)
            try:
                with Recording(tmp_path / "f.h5") as recording:
                    frames = recording.frame_count
            except Exception:  # noqa: BLE001 - not written yet
                pass
        os.kill(server, signal.SIGKILL)
        out, err = proc.communicate(timeout=60)
    lines = [line for line in err.splitlines() if line.strip() and not line.startswith("recording to")]
    assert proc.returncode == 130 and len(lines) == 1, (proc.returncode, err)
    assert "the display went away" in lines[0] and "recording: f.h5" in lines[0] and "screenshot: s.png" in lines[0]
    assert (tmp_path / "s.png").stat().st_size > 1000 and status_flags(tmp_path / "f.h5") == 0
    simulated = float(lines[0].split("at t = ")[1].split(" s")[0])
    with Recording(tmp_path / "f.h5") as recording:
        assert recording.frame_count >= 20 and recording.time[-1] == pytest.approx(simulated, abs=0.006)


# ---------------------------------------------------------------------------------------------- what is drawn


@pytest.fixture(scope="module")
def pictures(display, tmp_path_factory):
    """Screenshots of a flag, a kite from the ground, a glider from the side and two worlds, with where their drawn
    parts project (tests/viewer_driver.py pictures)."""
    from PIL import Image

    out = tmp_path_factory.mktemp("pictures")
    result = _drive(display, "pictures", out)
    shots = {name: np.asarray(Image.open(out / f"{name}.png").convert("RGB")).astype(int) for name in result}
    return result, shots


def _found(picture: np.ndarray, point, test, reach: int = 2) -> bool:
    """Whether a pixel within ``reach`` of ``point`` (column, row) passes ``test`` ([n, 3] rgb -> [n] bool)."""
    x, y = (int(round(v)) for v in point)
    patch = picture[max(y - reach, 0) : y + reach + 1, max(x - reach, 0) : x + reach + 1].reshape(-1, 3)
    return bool(len(patch)) and bool(test(patch).any())


def _dark(p):
    return p.max(axis=1) < 90


def test_hud_text_is_on_a_dark_panel_and_the_objects_below_it(pictures):
    result, shots = pictures
    for name, picture in shots.items():
        height = int(result[name]["panel_height"])
        assert 40 < height < picture.shape[0] // 2, name
        panel = picture[4 : height - 4, 8:300]
        assert (panel.max(axis=2) < 110).mean() > 0.6, name  # dark blue-grey, semi-opaque
        assert (panel.min(axis=2) > 200).sum() > 50, name  # white text on it
    flag = shots["flag"]  # the flag's red cloth is all below the panel
    red = (flag[..., 0] > 80) & (flag[..., 1] < 50) & (flag[..., 2] < 50)
    assert red.sum() > 500 and np.flatnonzero(red.any(axis=1)).min() > result["flag"]["panel_height"]


def test_flag_has_a_pole(pictures):
    result, shots = pictures

    def grey(p):  # the pole's light grey; grass is green, sky blue
        return (np.ptp(p, axis=1) < 15) & (p.min(axis=1) > 100)

    for point in ("pole_low", "pole_mid"):  # under the cloth, down to the ground
        assert _found(shots["flag"], result["flag"][point], grey), point


def test_kite_line_is_drawn_and_the_ground_camera_frames_horizon_and_kite(pictures):
    result, shots = pictures
    kite, where = shots["kite"], result["kite"]
    on_line = [_found(kite, where[f"line_{k}"], _dark) for k in range(2, 9)]
    assert all(on_line), on_line  # a dark line 2 pixels wide against the sky, tens of metres away
    h, w = kite.shape[:2]
    x, y = where["sail"]
    assert 0 < x < w and where["panel_height"] < y < h  # the kite in the picture, below the panel
    assert where["horizon"][1] < h - 5  # the horizon in the picture too: ground under it, sky above
    ground = kite[-4:].reshape(-1, 3)
    assert (ground[:, 1] > ground[:, 2]).mean() > 0.9  # green
    sky = kite[int(where["panel_height"]) + 5 : int(where["panel_height"]) + 15, -20:].reshape(-1, 3)
    assert (sky[:, 2] > sky[:, 0] + 30).all()  # blue


def test_glider_has_a_control_frame_and_a_pilot_on_the_strap(pictures):
    result, shots = pictures
    glider, where = shots["glider"], result["glider"]
    uprights = [_found(glider, where[f"upright_{k}"], _dark) for k in range(3, 9)]
    assert all(uprights), uprights  # the A-frame's upright from the hang point to the base bar
    assert _found(glider, where["harness"], lambda p: p.max(axis=1) < 70)  # the pilot's harness
    assert _found(glider, where["head"], lambda p: (p[:, 0] > 120) & (p[:, 1] > 100) & (p[:, 2] < 60), reach=3)


def test_worlds_are_drawn_apart(pictures):
    result, shots = pictures
    worlds, where = shots["worlds"], result["worlds"]
    a, b = np.array(where["world_0"]), np.array(where["world_1"])
    assert np.linalg.norm(a - b) > 60  # pixels apart at 640 x 360

    def red(p):
        return (p[:, 0] > 80) & (p[:, 1] < 50) & (p[:, 2] < 50)

    assert _found(worlds, a, red) and _found(worlds, b, red)
    middle = (a + b) / 2  # between the two flags: not cloth
    assert not _found(worlds, middle, red, reach=3)
    cloth = (worlds[..., 0] > 80) & (worlds[..., 1] < 50) & (worlds[..., 2] < 50)
    assert np.flatnonzero(cloth.any(axis=1)).min() > where["panel_height"]


@pytest.mark.slow
@pytest.mark.display
def test_window_360_turn_and_reversal_flown_with_the_keys(display, tmp_path):
    """Issue 53: the lattice glider flown with injected arrow keys through a 360° turn and a reversal
    (benchmarks/validation/keys_flight.py, as docs/keys_flight.png was made): it rolls to 30° in a few seconds,
    completes the turn and reverses, never flies tail first, and slips at most about 18° (the sail law's glider, flown
    the same way, 53°)."""
    try:
        script = [sys.executable, "-m", "benchmarks.validation.keys_flight"]
        result = subprocess.run(
            [*script, "scenes/hang_glider_lattice.toml", str(tmp_path)],
            env=display,
            cwd=HERE.parent,
            capture_output=True,
            text=True,
            timeout=600,
        )
    finally:  # a killed flight must not leave an arrow held down for the module's other window tests
        subprocess.run(["xdotool", "keyup", "Left", "Right"], env=display, capture_output=True, timeout=20)
    assert result.returncode == 0, result.stderr[-3000:]
    figures = json.loads((tmp_path / "keys_flight.json").read_text())
    assert 1.5 <= figures["time_to_30"] <= 4.0
    assert figures["turned_deg"] >= 360.0 and figures["turn_360_s"] < 20.0 and 3.0 <= figures["reversal_s"] <= 5.0
    assert figures["alpha_max"] < 90.0 and figures["beta_max"] < 20.0  # measured 18°: issue 53's ±15° is missed
    from PIL import Image

    for name in ("keys_flight.png", "keys_chase.png"):
        picture = np.asarray(Image.open(tmp_path / name).convert("L"), dtype=float)
        assert picture.std() > 10.0  # a drawing, not a blank
    with Recording(tmp_path / "keys_flight.h5") as recorded:
        assert abs(recorded.frame_count - figures["frames"]) <= 1  # every frame flown is in the recording
