"""The browser view's page in a real headless Chromium (Debian's ``chromium`` driven by Playwright for Python): keys
held in the page against the null backend, the wind's keys, physical keys and blur, a second tab and the handover,
and the command serving a recording to SIGTERM.

The tests are skipped where aiohttp, Playwright or ``/usr/bin/chromium`` are missing, unless
``WARPSIM_REQUIRE_DISPLAY_TESTS=1`` (``.ci/run`` sets it and installs them), where a missing piece fails.
"""

from __future__ import annotations

import math
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from warpsim.io.recording import Recording
from warpsim.viewer import NullBackend, Viewer

sys.path.insert(0, str(Path(__file__).parent))
from browser_support import CHROMIUM, CHROMIUM_ARGS, _browser_viewer, _Flying, _require, _sim
from viewer_driver import Clock  # noqa: E402


@pytest.fixture(scope="module")
def chromium():
    _require("aiohttp", "playwright", "chromium")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        yield browser
        browser.close()


def _page(chromium, url: str, size=(960, 540)):
    page = chromium.new_page(viewport={"width": size[0], "height": size[1]})
    errors: list[str] = []
    page.on("pageerror", lambda err: errors.append(str(err)))
    page.goto(url)
    page.wait_for_function("window.warpsim && window.warpsim.drawn > 2", timeout=30000)
    page.errors = errors
    return page


def _replayed(scene: str, log, frames: int) -> Viewer:
    """The scene flown on the null backend with the keys the browser's pilot held, frame by frame (``log``:
    ``BrowserBackend.applied_log``)."""
    sim, text, where = _sim(scene)
    keys = NullBackend()
    viewer = Viewer(sim, keys, "replay", say=lambda line: None)
    clock = Clock(viewer)
    changes = {frame: set(held) for frame, held, _ in log}
    held: set[str] = set()
    for frame in range(1, frames + 1):
        if frame in changes:
            for key in held - changes[frame]:
                keys.release(key)
            for key in changes[frame] - held:
                keys.press(key)
            keys.events()  # what changed is in held(); presses of these keys mean nothing
            held = changes[frame]
        clock.ticks(1)
    return viewer


@pytest.mark.slow
def test_arrow_right_held_3_s_in_the_page_banks_the_glider_as_the_null_backend_does(chromium):
    from warpsim.objects.hang_glider import bank

    viewer, backend = _browser_viewer("hang-glider", seconds=6.0)
    with _Flying(viewer) as flying:
        page = _page(chromium, backend.url)
        assert page.evaluate("warpsim.role") == "pilot"
        page.keyboard.down("ArrowRight")
        time.sleep(3.0)
        page.keyboard.up("ArrowRight")
        flying.thread.join(60)
        page.wait_for_timeout(300)
        shot = page.screenshot()
        hud = page.inner_text("#hud")
        acked, sent = page.evaluate("[warpsim.ack, warpsim.sentSeq]")
        assert not page.errors
        page.close()
    flown = [(f, keys) for f, keys, _ in backend.applied_log]
    assert [keys for _, keys in flown] == [(), ("RIGHT",), ()]
    held_frames = (flown[2][0] - flown[1][0]) * viewer.frame_interval
    assert 2.0 < held_frames < 4.0  # 3 s of wall time, at about real time
    assert acked == sent == 2
    frames = viewer.sim.steps_taken // viewer.sim.steps_per_frame
    again = _replayed("hang-glider", backend.applied_log, frames)
    assert np.array_equal(again.frame.positions, viewer.frame.positions)
    banked = bank(viewer.model.objects[0], viewer.frame.positions)
    assert banked > 5.0
    assert again.hud()[1] == viewer.hud()[1] == hud.splitlines()[1].rstrip()  # the page shows the same figures
    import io

    from PIL import Image

    picture = np.asarray(Image.open(io.BytesIO(shot)).convert("RGB")).astype(int)
    sail = (picture[..., 2] > picture[..., 0] + 60) & (picture[..., 2] > 120)  # the blue sail
    assert sail.sum() > 400, "no glider in the picture"


def _held_seconds(viewer, backend, key: str) -> float:
    """Simulated seconds ``key`` was held at frame starts, from the backend's log of what was flown."""
    log = backend.applied_log
    starts = [k for k, (_, keys, _) in enumerate(log) if key in keys]
    assert len(starts) == 1 and starts[0] + 1 < len(log), log
    k = starts[0]
    return (log[k + 1][0] - log[k][0]) * viewer.frame_interval


@pytest.mark.slow
def test_plus_held_in_the_page_ramps_the_wind_and_never_blows_the_kite_up(chromium):
    """+ held 1.5 s, then 3 s more: the wind rises at WIND_RATE while held, ends 1 to 2 m/s above where it was at
    the release (WIND_LEAD), never past the kite's limit; then + held 6 s stops at the limit (12 m/s)."""
    viewer, backend = _browser_viewer("kite")  # 6 m/s
    with _Flying(viewer):
        page = _page(chromium, backend.url)
        page.keyboard.down("+")
        time.sleep(1.5)
        page.keyboard.up("+")
        time.sleep(2.5)
        wind = float(np.linalg.norm(viewer.sim.controls["wind"]))
        held = _held_seconds(viewer, backend, "PLUS")
        shown = float(re.search(r"wind ([\d.]+) m/s", page.inner_text("#hud")).group(1))
        page.keyboard.down("+")
        time.sleep(6.0)
        page.keyboard.up("+")
        time.sleep(0.5)
        top = float(np.linalg.norm(viewer.sim.controls["wind"]))
        blew_up = viewer.blew_up
        page.close()
    assert 0.8 < held < 2.2
    at_release = 6.0 + viewer.WIND_RATE * held
    assert at_release + 1.0 - 0.2 <= wind <= at_release + viewer.WIND_LEAD + 0.2
    assert shown == pytest.approx(wind, abs=0.06)  # the page shows it (to its one decimal)
    assert top == pytest.approx(viewer.wind_limit) == 12.0 and not blew_up


def test_the_pages_keys_are_the_physical_keys_once_each_and_let_go_on_blur(chromium):
    """A key let go after Shift is still the key pressed (by event.code: '[' pressed, then Shift, then '[' let go
    once stayed held as '{'); the browser's auto-repeat sends nothing more; leaving the page lets every key go."""
    viewer, backend = _browser_viewer("kite")
    with _Flying(viewer):
        page = _page(chromium, backend.url)
        page.keyboard.down("BracketLeft")
        page.keyboard.down("Shift")
        page.keyboard.up("BracketLeft")
        page.keyboard.up("Shift")
        page.keyboard.down("Shift")
        page.keyboard.down("Equal")  # '+'
        page.keyboard.up("Shift")
        page.keyboard.up("Equal")  # '='
        assert page.evaluate("warpsim.held") == [] and page.evaluate("warpsim.sentSeq") == 4
        for _ in range(5):
            page.keyboard.down("KeyW")  # a held key's auto-repeat
        assert page.evaluate("[warpsim.sentSeq, warpsim.held]") == [5, ["W"]]
        time.sleep(0.5)
        page.evaluate("window.dispatchEvent(new Event('blur'))")
        assert page.evaluate("[warpsim.sentSeq, warpsim.held]") == [6, []]
        page.wait_for_function("warpsim.ack === 6")
        time.sleep(1.5)
        w = np.array(viewer.sim.controls["wind"])
        flown = [keys for _, keys, _ in backend.applied_log]
        assert not page.errors
        page.close()
    assert math.degrees(math.atan2(w[1], w[0])) == pytest.approx(viewer.WIND_TURN)  # one '[' press
    assert np.linalg.norm(w) == pytest.approx(7.0)  # one '+' press
    assert flown[-1] == () and ("W",) in flown and "anchor" in viewer.sim.controls


@pytest.mark.slow
def test_a_second_tab_watches_and_the_pilot_hands_over(chromium):
    viewer, backend = _browser_viewer("hang-glider")
    with _Flying(viewer):
        pilot = _page(chromium, backend.url)
        watcher = _page(chromium, backend.url)
        watcher.wait_for_function("warpsim.role === 'spectator'")
        pilot.wait_for_function("warpsim.watchers === 1")
        seen = watcher.evaluate("warpsim.pictures")
        watcher.keyboard.down("ArrowLeft")  # a spectator's keys steer nothing
        time.sleep(1.0)
        watcher.keyboard.up("ArrowLeft")
        assert watcher.evaluate("warpsim.pictures") > seen + 10  # it sees the flight live
        assert all("LEFT" not in keys for _, keys, _ in backend.applied_log)
        assert "watching" in watcher.inner_text("#role")
        pilot.click("#handover")
        watcher.wait_for_function("warpsim.role === 'pilot'")
        pilot.wait_for_function("warpsim.role === 'spectator'")
        watcher.keyboard.down("ArrowLeft")
        time.sleep(0.8)
        watcher.keyboard.up("ArrowLeft")
        time.sleep(0.3)
        assert any("LEFT" in keys for _, keys, _ in backend.applied_log)
        watcher.wait_for_function("warpsim.ack === warpsim.sentSeq")  # its own keys messages, acknowledged
        assert pilot.evaluate("warpsim.ack") <= pilot.evaluate("warpsim.sentSeq")
        watcher.close()  # the pilot leaves: the keys go to the page connected longest
        pilot.wait_for_function("warpsim.role === 'pilot'")
        pilot.close()


def test_the_command_serves_records_and_stops_on_sigterm_with_the_recording_closed(chromium, tmp_path):
    out = tmp_path / "flight.h5"
    proc = subprocess.Popen(
        [sys.executable, "-m", "warpsim", "view", "hang_glider", "--browser", "--port", "0", "--h5", str(out)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        line = proc.stdout.readline()
        url = re.search(r"(http://127\.0\.0\.1:\d+/)", line).group(1)
        page = _page(chromium, url)
        # a second and a half simulated (45 frames at 30 a second), read from the HUD's clock: the pictures are
        # drawn per tick whether or not a frame was stepped, so their count says little about the frames recorded
        page.wait_for_function(
            "warpsim.header !== null && parseFloat(warpsim.header.hud[0].split('=')[1]) > 1.5", timeout=60000
        )
        proc.send_signal(signal.SIGTERM)
        stdout, stderr = proc.communicate(timeout=60)
        page.wait_for_function("warpsim.closed !== ''", timeout=10000)
        page.close()
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, stderr
    assert "sent" in stdout and f"recording: {out}" in stdout
    with Recording(out) as recording:
        assert recording.frame_count > 30
