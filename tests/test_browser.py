"""The viewer in a browser (``warpsim view SCENE --browser``): the server with a plain WebSocket client, and the page
in a real headless Chromium (Debian's ``chromium`` driven by Playwright for Python).

The browser tests are skipped where aiohttp, Playwright or ``/usr/bin/chromium`` are missing, unless
``WARPSIM_REQUIRE_DISPLAY_TESTS=1`` (``.ci/run`` sets it and installs them), where a missing piece fails.
"""

from __future__ import annotations

import asyncio
import gc
import importlib.util
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from warpsim.io.recording import Recording
from warpsim.run.simulation import Simulation
from warpsim.scene.descriptor import merge, resolve, to_toml
from warpsim.scene.dirs import scene_dirs
from warpsim.viewer import NullBackend, Viewer

sys.path.insert(0, str(Path(__file__).parent))
from viewer_driver import Clock  # noqa: E402

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = [
    "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
    "--disable-component-update", "--disable-sync",
]  # fmt: skip
"""Headless Chromium on a closed network: without the background-networking flags it keeps trying to reach
Google's hosts."""


def _require(*what: str) -> None:
    missing = [name for name in what if importlib.util.find_spec(name) is None]
    if "chromium" in what:
        missing = [m for m in missing if m != "chromium"] + ([] if shutil.which(CHROMIUM) else ["chromium"])
    if missing:
        if os.environ.get("WARPSIM_REQUIRE_DISPLAY_TESTS") == "1":
            pytest.fail(f"browser tests need {', '.join(missing)} (WARPSIM_REQUIRE_DISPLAY_TESTS=1)")
        pytest.skip(f"needs {', '.join(missing)}")


def _sim(scene: str, **overrides) -> tuple[Simulation, str, str]:
    descriptor, _, where = resolve(scene, scene_dirs())
    if overrides:
        descriptor = merge("test", descriptor, overrides)
    return Simulation(descriptor), to_toml(descriptor), where


def _browser_viewer(scene: str, seconds=None, record=None, host="127.0.0.1", **overrides):
    from warpsim.viewer.web import BrowserBackend

    sim, text, where = _sim(scene, **overrides)
    backend = BrowserBackend(host, 0)
    viewer = Viewer(sim, backend, f"warpsim: {where}", record, text, where, seconds=seconds, say=lambda line: None)
    return viewer, backend


class _Flying:
    """A viewer flown at wall-clock pace on its own thread (as ``warpsim view --browser`` flies it)."""

    def __init__(self, viewer):
        self.viewer = viewer
        self.thread = threading.Thread(target=viewer.run, daemon=True)

    def __enter__(self):
        self.thread.start()
        return self

    def __exit__(self, *exc):
        self.viewer.quit = True
        self.thread.join(30)
        assert not self.thread.is_alive()


# ------------------------------------------------------------------------------------------ a WebSocket client


async def _connect(session, backend, origin=True, token=None, path="/ws"):
    url = f"http://127.0.0.1:{backend.port}{path}" + (f"?token={token}" if token else "")
    headers = (
        {"Origin": f"http://127.0.0.1:{backend.port}"} if origin is True else ({"Origin": origin} if origin else {})
    )
    return await session.ws_connect(url, headers=headers)


async def _pictures(ws, count: int, timeout: float = 20.0) -> list[bytes]:
    """The next ``count`` binary messages from ``ws`` (text ones skipped)."""
    import aiohttp

    out = []
    async with asyncio.timeout(timeout):
        while len(out) < count:
            message = await ws.receive()
            if message.type == aiohttp.WSMsgType.BINARY:
                out.append(message.data)
            elif message.type in (aiohttp.WSMsgType.CLOSE, aiohttp.WSMsgType.CLOSED, aiohttp.WSMsgType.ERROR):
                raise ConnectionError(f"closed: {message.extra}")
    return out


def test_a_frame_keeps_millimetres_10_km_out():
    from warpsim.viewer.web import decode_frame, encode_frame

    points = np.array([[10000.0, -7000.0, 300.0], [10000.0012, -7000.0034, 300.0056]])
    picture, ack, header, back = decode_frame(
        encode_frame(7, 3, points, {"view": {"target": [10000.0, -7000.0, 300.0], "eye": [0, 0, 0], "fov": 50.0}})
    )
    assert (picture, ack, header["count"]) == (7, 3, 2)
    assert np.abs(back - points).max() < 1e-6


def test_only_the_pages_own_files_are_served():
    _require("aiohttp")
    import aiohttp

    viewer, backend = _browser_viewer("flag")

    async def check():
        async with aiohttp.ClientSession() as session:
            base = f"http://127.0.0.1:{backend.port}"
            got = {}
            for path in ("/", "/app.js", "/three.min.js", "/three.LICENSE", "/web.py", "/../pyproject.toml",
                         "/%2e%2e/web.py", "/static/app.js", "/favicon.ico"):  # fmt: skip
                async with session.get(base + path) as response:
                    got[path] = (response.status, await response.read())
            return got

    try:
        got = asyncio.run(check())
    finally:
        viewer.close()
    assert [p for p, (status, _) in got.items() if status == 200] == ["/", "/app.js", "/three.min.js", "/three.LICENSE"]
    assert b"MIT License" in got["/three.LICENSE"][1] and b"three.min.js" in got["/app.js"][1]
    assert all(status == 404 for status, _ in list(got.values())[4:])


def test_a_strangers_origin_a_strange_host_and_a_missing_token_are_refused():
    _require("aiohttp")
    import aiohttp

    viewer, backend = _browser_viewer("flag")
    assert backend.token is None and backend.url.startswith("http://127.0.0.1:")

    async def loopback():
        async with aiohttp.ClientSession() as session:
            with pytest.raises(aiohttp.WSServerHandshakeError) as refused:
                await _connect(session, backend, origin="http://evil.example")
            statuses = [refused.value.status]
            async with session.get(f"http://127.0.0.1:{backend.port}/", headers={"Host": "evil.example"}) as r:
                statuses.append(r.status)  # a DNS-rebound name is not this machine's
            ws = await _connect(session, backend)
            hello = json.loads((await ws.receive()).data)
            await ws.close()
            return statuses, hello

    try:
        statuses, hello = asyncio.run(loopback())
    finally:
        viewer.close()
    assert statuses == [403, 403] and hello["type"] == "hello"

    viewer, backend = _browser_viewer("flag", host="0.0.0.0")  # any address: a token is asked for
    token = backend.token
    assert token and len(token) >= 16 and backend.url.endswith(f"?token={token}")

    async def remote():
        out = []
        async with aiohttp.ClientSession() as session:
            for given in (None, "wrong", token[:-1], token):
                async with session.get(f"http://127.0.0.1:{backend.port}/" + (f"?token={given}" if given else "")) as r:
                    out.append(r.status)
            async with session.get(f"http://127.0.0.1:{backend.port}/app.js") as r:
                out.append(r.status)  # the page's scripts load without the token (the page asks for none)
            for given in (None, "wrong"):
                with pytest.raises(aiohttp.WSServerHandshakeError) as refused:
                    await _connect(session, backend, token=given)
                out.append(refused.value.status)
            ws = await _connect(session, backend, token=token)
            out.append(json.loads((await ws.receive()).data)["type"])
            await ws.close()
        return out

    try:
        got = asyncio.run(remote())
    finally:
        viewer.close()
    assert got == [403, 403, 403, 200, 200, 403, 403, "hello"]
    assert backend.refused >= 5


def test_a_malformed_message_closes_that_connection_only():
    _require("aiohttp")
    import aiohttp

    viewer, backend = _browser_viewer("hang-glider")
    bad = [
        "not json", "[1, 2]", json.dumps({"type": "keys", "seq": 1, "held": ["F13"]}),
        json.dumps({"type": "keys", "seq": -1, "held": []}), json.dumps({"type": "drag", "dx": "1e400", "dy": 0}),
        '{"type": "scroll", "clicks": 1e999}', '{"type": "drag", "dx": ' + "9" * 400 + ', "dy": 0}',
        json.dumps({"type": "launch"}), json.dumps({"type": "keys", "seq": 1, "held": ["UP"] * 10000}),
    ]  # fmt: skip

    async def check():
        closed = []
        async with aiohttp.ClientSession() as session:
            pilot = await _connect(session, backend)
            for text in bad:
                ws = await _connect(session, backend)
                await ws.send_str(text)
                async with asyncio.timeout(10):
                    ends = (aiohttp.WSMsgType.CLOSE, aiohttp.WSMsgType.CLOSED)
                    while (await ws.receive()).type not in ends:
                        pass
                closed.append(ws.close_code)
            await pilot.send_str(json.dumps({"type": "keys", "seq": 1, "held": ["RIGHT"]}))
            await asyncio.sleep(0.5)
            pictures = await _pictures(pilot, 3)
            await pilot.close()
            return closed, pictures

    with _Flying(viewer):
        closed, pictures = asyncio.run(check())
        held_right = any("RIGHT" in keys for _, keys, _ in backend.applied_log)
    assert closed == [1008] * len(bad) or all(code in (1008, 1009) for code in closed)
    assert len(pictures) == 3 and held_right  # the pilot, connected throughout, still flies and steers
    assert not viewer.error


def _vanish(port: int) -> None:
    """A page that opens the WebSocket, takes part of what is sent and vanishes (its socket reset, no close)."""
    import base64
    import socket
    import struct

    with socket.create_connection(("127.0.0.1", port), timeout=10) as raw:
        key = base64.b64encode(os.urandom(16)).decode()
        raw.sendall(
            f"GET /ws HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
            f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\nOrigin: http://127.0.0.1:{port}\r\n\r\n".encode()
        )
        got = b""
        while len(got) < 2000:
            got += raw.recv(4096)
        assert got.startswith(b"HTTP/1.1 101")
        raw.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))  # reset, mid-message


def _run_with_clients(clients: int, frames: int):
    """Positions after ``frames`` frames of the glider flown on a test clock, with ``clients`` pages connecting,
    taking pictures and vanishing meanwhile (none steers); and the Python memory held before and after."""
    import aiohttp

    viewer, backend = _browser_viewer("hang-glider")
    clock = Clock(viewer)

    async def churn():
        async with aiohttp.ClientSession() as session:
            for k in range(clients):
                if k % 2:
                    ws = await _connect(session, backend)
                    await ws.receive()  # the hello
                    await ws.close()  # politely
                else:
                    _vanish(backend.port)

    thread = threading.Thread(target=lambda: asyncio.run(churn()) if clients else None)
    gc.collect()
    tracemalloc.start()
    before = tracemalloc.take_snapshot()
    thread.start()
    for _ in range(frames):
        clock.ticks(1)
    thread.join(60)
    deadline = time.monotonic() + 10
    while backend.clients and time.monotonic() < deadline:
        time.sleep(0.05)
    gc.collect()
    after = tracemalloc.take_snapshot()
    tracemalloc.stop()
    grown = sum(s.size_diff for s in after.compare_to(before, "filename"))
    positions = viewer.frame.positions.copy()
    left = len(backend.clients)
    viewer.close()
    return positions, grown, left, backend.connections


def test_a_hundred_connects_and_disconnects_leave_the_flight_and_memory_unchanged():
    _require("aiohttp")
    quiet, _, _, _ = _run_with_clients(0, 120)
    busy, grown, left, connections = _run_with_clients(100, 120)
    assert connections == 100 and left == 0
    assert np.array_equal(quiet, busy)  # bit for bit: watching changes nothing
    assert grown < 2_000_000, f"{grown} bytes more held after 100 pages came and went"


# ------------------------------------------------------------------------------------------ the page in Chromium


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


def test_plus_held_2_s_in_the_page_does_not_blow_the_kite_up(chromium):
    viewer, backend = _browser_viewer("kite")
    with _Flying(viewer):
        page = _page(chromium, backend.url)
        page.keyboard.down("+")
        time.sleep(2.0)
        page.keyboard.up("+")
        time.sleep(2.5)
        hud = page.inner_text("#hud")
        page.close()
        wind = float(re.search(r"wind ([\d.]+) m/s", hud).group(1))
        blew_up = viewer.blew_up
    assert not blew_up
    assert 6.0 + 2.0 < wind <= 6.0 + 4.5 * viewer.WIND_RATE / 2 + viewer.WIND_LEAD  # about 2 m/s a second held


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
        page.wait_for_function("warpsim.pictures > 60", timeout=30000)
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
