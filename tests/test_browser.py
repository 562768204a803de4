"""The viewer in a browser (``warpsim view SCENE --browser``): the server with a plain WebSocket client (its files,
origins and tokens, malformed messages, handovers, a hundred connections, a flight that waits for its page, bad
ports). The page in a real headless Chromium is in ``test_browser_page.py``.

The tests are skipped where aiohttp, Playwright or ``/usr/bin/chromium`` are missing, unless
``WARPSIM_REQUIRE_DISPLAY_TESTS=1`` (``.ci/run`` sets it and installs them), where a missing piece fails.
"""

from __future__ import annotations

import asyncio
import gc
import json
import os
import sys
import threading
import time
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from browser_support import _browser_viewer, _Flying, _require
from viewer_driver import Clock  # noqa: E402

"""Headless Chromium on a closed network: without the background-networking flags it keeps trying to reach
Google's hosts."""


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


@pytest.mark.slow
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
