"""The live viewer (``warpsim view``): its logic with the null backend (keys, wind, pause, restart, the camera,
the heads-up text, blow-ups, recordings and takes). The real window is in ``test_viewer_window.py``."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from warpsim.cli import main
from warpsim.io.recording import Recording
from warpsim.objects.hang_glider import bank
from warpsim.run.simulation import Simulation
from warpsim.scene.descriptor import merge, resolve
from warpsim.scene.dirs import scene_dirs
from warpsim.viewer import NullBackend, Viewer

sys.path.insert(0, str(Path(__file__).parent))
from viewer_driver import Clock  # noqa: E402  (the wall clock the window driver gives too)


def _viewer(scene: str, record=None, **overrides) -> tuple[Viewer, NullBackend]:
    descriptor, _, where = resolve(scene, scene_dirs())
    if overrides:
        descriptor = merge("test", descriptor, overrides)
    backend = NullBackend()
    viewer = Viewer(Simulation(descriptor), backend, record=record, where=where)
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


def test_an_interrupt_inside_a_frame_leaves_the_viewer_able_to_step_on():
    """Ctrl-C (or any error) inside a frame's stepping ends the frame iterator the viewer steps by; the next step
    starts a new one from the state as it is, frame by frame as before."""
    viewer, backend = _viewer("hang-glider")
    assert viewer.advance()
    held, calls = backend.held, {"n": 0}

    def interrupted():
        calls["n"] += 1
        if calls["n"] == 1:
            raise KeyboardInterrupt
        return held()

    backend.held = interrupted
    with pytest.raises(KeyboardInterrupt):
        viewer.advance()
    before = viewer.sim.steps_taken
    assert viewer.advance() and viewer.advance()
    assert viewer.sim.steps_taken == before + 2 * viewer.sim.steps_per_frame
    assert viewer.frame.steps == viewer.sim.steps_taken and viewer.frame.finite
