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
import math
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
        b'{"type": "keys", "seq": 1, "held": ["UP"]}',  # a binary message, even of good JSON
    ]  # fmt: skip

    async def check():
        closed = []
        async with aiohttp.ClientSession() as session:
            pilot = await _connect(session, backend)
            for text in bad:
                ws = await _connect(session, backend)
                await (ws.send_bytes(text) if isinstance(text, bytes) else ws.send_str(text))
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


def test_a_pilot_who_hands_over_or_leaves_with_a_key_held_lets_it_go():
    """Keys held by a pilot who hands over, or whose page goes away, are let go at once (a held roll would
    otherwise steer on for ever) and the next pilot's keys messages are acknowledged by their own count."""
    _require("aiohttp")
    import aiohttp

    from warpsim.viewer.web import decode_frame

    viewer, backend = _browser_viewer("hang-glider")

    async def role(ws):
        async with asyncio.timeout(10):
            while True:
                message = await ws.receive()
                if message.type == aiohttp.WSMsgType.TEXT and json.loads(message.data)["type"] == "role":
                    return json.loads(message.data)

    def flown():
        return backend.applied_log[-1][1] if backend.applied_log else None

    async def until(test):
        async with asyncio.timeout(10):
            while not test():
                await asyncio.sleep(0.02)

    async def check():
        async with aiohttp.ClientSession() as session:
            first = await _connect(session, backend)
            second = await _connect(session, backend)
            assert (await role(second))["role"] == "spectator"
            await first.send_str(json.dumps({"type": "keys", "seq": 7, "held": ["RIGHT"]}))
            await until(lambda: flown() == ("RIGHT",))
            await first.send_str(json.dumps({"type": "handover"}))
            await until(lambda: backend.pilot == 2 and flown() == ())  # handed over: let go
            await second.send_str(json.dumps({"type": "keys", "seq": 1, "held": ["LEFT"]}))
            await until(lambda: flown() == ("LEFT",))
            acks = set()  # (pilot, ack) of the pictures seen since the test began
            async with asyncio.timeout(10):
                while (2, 1) not in acks:
                    _, ack, header, _ = decode_frame((await _pictures(second, 1))[0])
                    acks.add((header["pilot"], ack))
            await second.close()  # the pilot leaves with LEFT held
            await until(lambda: backend.pilot == 1 and flown() == ())  # gone: let go
            await first.close()
            return acks

    with _Flying(viewer):
        acks = asyncio.run(check())
    assert (1, 7) in acks and not {(2, a) for a in range(2, 8)} & acks  # each pilot's own count, never the other's
    assert [keys for _, keys, _ in backend.applied_log][-4:] == [("RIGHT",), (), ("LEFT",), ()]


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
            more = raw.recv(4096)
            if not more:
                break  # the server closed first
            got += more
        assert got.startswith(b"HTTP/1.1 101")
        # half a masked text frame of 100 bytes: the header and mask, then 10 bytes of the payload
        raw.sendall(bytes([0x81, 0x80 | 100]) + os.urandom(4) + os.urandom(10))
        raw.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))  # reset, mid-message


def _run_with_clients(clients: int, frames: int):
    """Positions after ``frames`` frames of the glider flown on a test clock, with ``clients`` pages connecting,
    taking pictures, sending keys, drags and wheel turns and vanishing meanwhile, while a pilot that holds no key
    stays connected (so that they are spectators: none steers); and the Python memory held before and after."""
    import aiohttp

    viewer, backend = _browser_viewer("hang-glider")
    clock = Clock(viewer)

    async def churn():
        async with aiohttp.ClientSession() as session:
            pilot = await _connect(session, backend)
            for k in range(clients):
                if k % 2:
                    ws = await _connect(session, backend)
                    await ws.receive()  # the hello
                    for message in ({"type": "keys", "seq": 1, "held": ["RIGHT", "PLUS", "R"]},
                                    {"type": "drag", "dx": 40, "dy": 5}, {"type": "scroll", "clicks": 3}):  # fmt: skip
                        await ws.send_str(json.dumps(message))
                    await _pictures(ws, 1)
                    await ws.close()  # politely
                else:
                    _vanish(backend.port)
            await pilot.close()

    thread = threading.Thread(target=lambda: asyncio.run(churn()) if clients else None)
    gc.collect()
    tracemalloc.start()
    before = tracemalloc.take_snapshot()
    thread.start()
    for _ in range(frames):
        clock.ticks(1)
    viewer.paused = True  # then only pictures, until the pages are done
    deadline = time.monotonic() + 120
    while thread.is_alive() and time.monotonic() < deadline:
        clock.ticks(1)
        time.sleep(0.005)
    assert not thread.is_alive()
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
    assert connections == 101 and left == 0  # and the pilot
    assert np.array_equal(quiet, busy)  # bit for bit: watching changes nothing
    assert grown < 2_000_000, f"{grown} bytes more held after 100 pages came and went"


def test_while_no_page_is_connected_the_flight_waits():
    """The server's flight stands still while nobody watches (it flew on to the end of --seconds unseen), and
    goes on when a page comes back; what was printed says so."""
    _require("aiohttp")
    import contextlib
    import io

    import aiohttp

    from warpsim.cli.view import _serve

    viewer, backend = _browser_viewer("flag")
    printed = io.StringIO()

    async def look(seconds: float) -> float:
        async with aiohttp.ClientSession() as session:
            ws = await _connect(session, backend)
            await _pictures(ws, 3)
            await asyncio.sleep(seconds)
            await ws.close()
        return viewer.sim.state.time

    def serve():
        with contextlib.redirect_stdout(printed):
            _serve(viewer, backend, viewer.sim)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    time.sleep(0.5)
    assert viewer.sim.state.time == 0.0  # no page yet
    seen = asyncio.run(look(1.0))
    deadline = time.monotonic() + 10
    while backend.clients and time.monotonic() < deadline:
        time.sleep(0.02)
    time.sleep(0.3)
    gone = viewer.sim.state.time
    time.sleep(1.0)
    still = viewer.sim.state.time
    back = asyncio.run(look(0.5))
    viewer.quit = True
    thread.join(30)
    assert not thread.is_alive()
    assert 0.5 < seen and gone == still and back > still + 0.2
    out = printed.getvalue()
    assert "waiting for a page" in out and "no page connected: the flight waits for one" in out


@pytest.mark.parametrize(
    "extra, words",
    [
        (["--port", "70000"], "0 to 65535"),
        (["--port", "TAKEN"], "cannot listen"),
        (["--host", "no-such-host.invalid"], "--host no-such-host.invalid"),
    ],
)
def test_a_port_or_host_that_cannot_be_listened_on_is_one_line_before_the_model_is_built(
    extra, words, capsys, monkeypatch
):
    _require("aiohttp")
    import socket

    from warpsim.cli import main
    from warpsim.run import simulation

    def no_model(*args, **kwargs):
        raise AssertionError("the model was built first")

    monkeypatch.setattr(simulation, "Simulation", no_model)
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        argv = ["view", "kite", *[str(taken.getsockname()[1]) if a == "TAKEN" else a for a in extra]]
        try:
            code = main(argv)
        except SystemExit as exit:
            code = exit.code
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and words in err, err


def test_an_address_on_every_interface_is_printed_by_this_machines_name():
    import socket

    viewer, backend = _browser_viewer("flag", host="0.0.0.0")
    viewer.close()
    assert backend.url.startswith(f"http://{socket.gethostname()}:{backend.port}/?token=")


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


def _held_seconds(viewer, backend, key: str) -> float:
    """Simulated seconds ``key`` was held at frame starts, from the backend's log of what was flown."""
    log = backend.applied_log
    starts = [k for k, (_, keys, _) in enumerate(log) if key in keys]
    assert len(starts) == 1 and starts[0] + 1 < len(log), log
    k = starts[0]
    return (log[k + 1][0] - log[k][0]) * viewer.frame_interval


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
