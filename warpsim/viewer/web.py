"""The viewer in a browser: a :class:`~warpsim.viewer.backend.Backend` that serves a page and talks to it over a
WebSocket (the ``browser`` extra: ``pip install -e '.[browser]'``, aiohttp).

The simulation stays here, paced by the wall clock as in the window (:class:`~warpsim.viewer.core.Viewer` runs
unchanged on this backend); the page only draws and reads keys. The server runs on its own thread with its own
asyncio loop, so a slow or vanished client never holds up a step.

Protocol (one WebSocket per page, at ``/ws``):

- On connecting, the page gets one text message, ``{"type": "hello", ...}``: what does not move (the draw list's
  meshes, curves, tubes and spheres by point index, the terrain as base64 float32/int32 arrays), the page's role
  (``pilot`` or ``spectator``), its id and the key map.
- Then one binary message per picture drawn: ``b"WSF1"``, then little-endian uint32 ``picture``, uint32 ``ack``
  (the number of the last keys message whose held keys were applied at a frame start, counted by the page the
  JSON's ``pilot`` names: each pilot counts its own from 1), uint32 ``n`` (bytes of JSON that follow: heads-up
  lines, overlay, view, origin, pilot), the JSON padded with spaces to 4 bytes, then
  ``points`` float32 ``[P, 3]``: the drawn points [m] minus ``origin`` (float64 in the JSON, so that a flight
  10 km out keeps its millimetres). A client that has not taken the last picture gets only the newest: the
  ones in between are dropped, never queued.
- The page sends text messages, each a JSON object of at most :data:`MAX_MESSAGE` bytes:
  ``{"type": "keys", "seq": N, "held": [KEY, ...]}`` whenever the set of held keys changes (key names as in
  :mod:`warpsim.viewer.backend`; the page ignores the browser's auto-repeat), ``{"type": "drag", "dx": .., "dy": ..}``
  [pixels], ``{"type": "scroll", "clicks": ..}`` and ``{"type": "handover"}`` (the pilot gives the keys to the
  longest-waiting spectator). Only the pilot's messages steer; a spectator's keys are ignored. A message that is not
  one of these (bad JSON, unknown type or key, a number that is not finite, too long) closes that one connection.

Safety: the server binds ``127.0.0.1`` by default. Bound to any other address it asks for a token (printed once
with the address, compared in constant time) on the page and the WebSocket; the WebSocket's ``Origin`` must be
the page's own; only the page's own files are served.
"""

from __future__ import annotations

import asyncio
import base64
import hmac
import ipaddress
import json
import math
import secrets
import socket
import struct
import threading
import time
from collections import deque
from importlib import resources

import numpy as np

from .._extras import install_hint
from .backend import Backend, DrawList, View, ViewerUnavailableError

MAX_MESSAGE = 4096
"""[bytes] the longest message a page may send; a longer one closes its connection."""

KEY_NAMES = frozenset(
    ["UP", "DOWN", "LEFT", "RIGHT", "SPACE", "ESCAPE", "PLUS", "MINUS", "[", "]", ".", "?"]
    + [chr(c) for c in range(ord("A"), ord("Z") + 1)]
)
"""The key names a page may send (those of :mod:`warpsim.viewer.backend`)."""

FILES = {
    "/": ("index.html", "text/html"),
    "/app.js": ("app.js", "text/javascript"),
    "/three.min.js": ("three.min.js", "text/javascript"),
    "/three.LICENSE": ("three.LICENSE", "text/plain"),
}
"""Everything the server serves besides ``/ws``: the page's own files (``warpsim/viewer/web/``), nothing else."""

MAGIC = b"WSF1"


def _aiohttp():
    try:
        import aiohttp
        from aiohttp import web
    except ImportError:
        raise ViewerUnavailableError(f"the browser view needs aiohttp: {install_hint('browser')}") from None
    return aiohttp, web


def is_loopback(host: str) -> bool:
    """True for an address only this machine can reach (``127.0.0.1``, ``::1``, ``localhost``)."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def _b64(array: np.ndarray, dtype) -> str:
    return base64.b64encode(np.ascontiguousarray(array, dtype=dtype).tobytes()).decode("ascii")


def topology(draw_list: DrawList, title: str, keys) -> dict:
    """What the page is sent once: the parts by point index with their colours, the terrain, the key map."""

    def colour(c) -> list[float]:
        return [round(float(v), 4) for v in c]

    return {
        "title": title,
        "meshes": [{"triangles": _b64(t, np.int32), "rgb": colour(c)} for t, c in draw_list.meshes],
        "curves": [{"chain": np.asarray(ch, dtype=np.int64).tolist(), "rgb": colour(c)} for ch, c in draw_list.curves],
        "spheres": [{"point": int(p), "radius": float(r), "rgb": colour(c)} for p, r, c in draw_list.spheres],
        "tubes": [{"a": int(a), "b": int(b), "radius": float(r), "rgb": colour(c)} for a, b, r, c in draw_list.tubes],
        "terrain": {
            "points": _b64(draw_list.terrain_points, np.float32),
            "triangles": _b64(draw_list.terrain_triangles, np.int32),
            "colours": _b64(draw_list.terrain_colours, np.float32),
        },
        "keys": [list(k) for k in keys],
    }


def encode_frame(picture: int, ack: int, points: np.ndarray, header: dict) -> bytes:
    """One picture as the binary message of the protocol (module notes); ``points`` ``[P, 3]`` [m]."""
    p = np.asarray(points, dtype=np.float64)
    origin = np.asarray(header.get("view", {}).get("target", p.mean(axis=0) if len(p) else np.zeros(3)), float)
    header = dict(header, origin=[float(v) for v in origin], count=len(p))
    text = json.dumps(header, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    return MAGIC + struct.pack("<III", picture, ack, len(text)) + text + (p - origin).astype("<f4").tobytes()


def decode_frame(message: bytes) -> tuple[int, int, dict, np.ndarray]:
    """The inverse of :func:`encode_frame`: (picture, ack, header, points [P, 3] [m], float64)."""
    if message[:4] != MAGIC:
        raise ValueError("not a warpsim frame")
    picture, ack, n = struct.unpack_from("<III", message, 4)
    header = json.loads(message[16 : 16 + n])
    points = np.frombuffer(message, dtype="<f4", offset=16 + n).reshape(-1, 3).astype(np.float64)
    return picture, ack, header, points + np.asarray(header["origin"])


class _Client:
    """One page: its socket, its id, the newest picture not yet sent to it, and the keys it holds."""

    def __init__(self, ws, ident: int):
        self.ws, self.id = ws, ident
        self.latest: bytes | None = None
        self.ready = asyncio.Event()
        self.sent = 0  # pictures sent
        self.dropped = 0  # pictures replaced by a newer one before they could be sent


class BrowserBackend(Backend):
    """Serve the viewer to browsers: ``open`` starts the server, ``draw`` sends a picture to every page,
    ``events``/``held`` are the pilot page's keys and mouse.

    Args:
        host: the address to bind (``127.0.0.1``: this machine only). Any other needs the ``token``.
        port: the port (0: any free one; :attr:`port` says which after :meth:`open`).
        token: the token the address carries (None: a fresh random one when ``host`` is not a loopback address,
            none asked for on loopback).
        size: the picture size the heads-up text is laid out for [pixels] (the page draws at its own size).

    Attributes:
        url: the page's address (with ``?token=`` when one is asked for), set by :meth:`open`.
        clients: pages connected now. pilot: the id of the page that steers (None when none is connected).
        applied_log: ``[(frame index, sorted held keys, seq)]`` each time the held keys read at a frame start
            changed (what was flown, key by key, for tests and replays).
        connections: pages connected since :meth:`open`. refused: connections refused (origin, token, host).
    """

    def __init__(self, host: str = "127.0.0.1", port: int = 8765, token: str | None = None, size=(1280, 720)):
        self.host, self.port, self.size = host, int(port), size
        self.token = token if token is not None else (None if is_loopback(host) else secrets.token_urlsafe(16))
        self.closed = False
        self.url = ""
        self.clients: dict[int, _Client] = {}
        self.pilot: int | None = None
        self.applied_log: list[tuple[int, tuple[str, ...], int]] = []
        self.connections = self.refused = 0
        self._lock = threading.Lock()
        self._events: deque = deque()
        self._held: frozenset[str] = frozenset()
        self._seq = 0  # of the pilot's last keys message (each page counts its own: 0 again at a new pilot)
        self._ack = 0  # of the last keys message read at a frame start
        self._read_seq = 0  # of the keys message held() last returned
        self._read_pilot: int | None = None  # whose it was
        self._ack_pilot: int | None = None  # the page whose keys message the pictures acknowledge
        self._tasks: set = set()  # background sends, referenced until done
        self._last_applied: tuple[str, ...] | None = None
        self._picture = 0
        self._next_id = 1
        self._hello: str = ""
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._runner = None
        self._stopped = threading.Event()

    @classmethod
    def check(cls, host: str = "127.0.0.1", port: int = 8765, **options) -> None:
        """The ``browser`` extra is there and ``host:port`` can be listened on (not taken, in range, an address of
        this machine), or :class:`ViewerUnavailableError` says which in one line."""
        _aiohttp()
        check_listen(host, port)

    # ------------------------------------------------------------------ server
    def open(self, draw_list: DrawList, title: str, keys: tuple = ()) -> None:

        _aiohttp()
        self.draw_list, self.title = draw_list, title
        self._hello = json.dumps({"type": "hello", **topology(draw_list, title, keys)}, separators=(",", ":"))
        started = threading.Event()
        failure: list[BaseException] = []
        self._thread = threading.Thread(target=self._serve, args=(started, failure), name="warpsim-web", daemon=True)
        self._thread.start()
        if not started.wait(30.0):
            self.close()
            raise ViewerUnavailableError(f"cannot serve on {self.host}:{self.port}: the server did not start in 30 s")
        if failure:
            raise ViewerUnavailableError(f"cannot serve on {self.host}:{self.port}: {failure[0]}") from None

    def _serve(self, started: threading.Event, failure: list) -> None:
        _, web = _aiohttp()
        loop = self._loop = asyncio.new_event_loop()
        asyncio.set_event_loop(loop)
        app = web.Application(client_max_size=MAX_MESSAGE)
        app.router.add_get("/ws", self._websocket)
        for path in FILES:
            app.router.add_get(path, self._file)
        self._runner = web.AppRunner(app, access_log=None, handle_signals=False)
        try:
            loop.run_until_complete(self._runner.setup())
            site = web.TCPSite(self._runner, self.host, self.port)
            loop.run_until_complete(site.start())
            self.port = site._server.sockets[0].getsockname()[1]
            self.url = self._address()
        except BaseException as err:  # noqa: BLE001 - said by open()
            failure.append(err)
            started.set()
            loop.run_until_complete(self._runner.cleanup())
            loop.close()
            return
        started.set()
        try:
            loop.run_forever()
        finally:
            loop.run_until_complete(self._shutdown())
            loop.close()
            self._stopped.set()

    def _address(self) -> str:
        """The page's address: an address bound to every interface (``0.0.0.0``, ``::``) is shown by this machine's
        name, which others can type (the bound address itself reaches nothing)."""
        host = self.host
        try:
            if ipaddress.ip_address(host).is_unspecified:
                host = socket.gethostname()
        except ValueError:
            pass
        shown = f"[{host}]" if ":" in host else host
        return f"http://{shown}:{self.port}/" + (f"?token={self.token}" if self.token else "")

    async def _shutdown(self) -> None:
        for client in list(self.clients.values()):
            await client.ws.close(code=1001, message=b"the flight ended")
        await self._runner.cleanup()

    def _refusal(self, request) -> str:
        """Why a request is refused ("" when it is not): a missing or wrong token (when one is asked for), or on a
        loopback server a Host that is not a loopback name; counts what it refuses."""
        why = ""
        if self.token is not None:
            given = request.query.get("token", "")
            if not hmac.compare_digest(given.encode(), self.token.encode()):
                why = "a token is needed: use the address warpsim printed"
        elif request.url.host not in ("localhost", "127.0.0.1", "::1", self.host):
            # a loopback server answers only to loopback names (no DNS rebinding)
            why = f"this server answers to {self.host} only, not to {request.url.host}"
        if why:
            self.refused += 1
        return why

    async def _file(self, request):
        _, web = _aiohttp()
        # the page's scripts and licence are public code: only the page itself (and /ws) ask for the token, so that the
        # scripts it loads without one are served
        why = self._refusal(request) if request.path == "/" else ""
        if why:
            return web.Response(status=403, text=why + "\n")
        name, kind = FILES[request.path]
        body = resources.files(__package__).joinpath("web", name).read_bytes()
        headers = {"Cache-Control": "no-store", "X-Content-Type-Options": "nosniff"}
        return web.Response(body=body, content_type=kind, headers=headers)

    async def _websocket(self, request):
        aiohttp, web = _aiohttp()
        why = self._refusal(request)
        if why:
            return web.Response(status=403, text=why + "\n")
        origin = request.headers.get("Origin")
        if origin is not None and origin != f"{request.scheme}://{request.host}":
            self.refused += 1
            return web.Response(status=403, text="this page's own origin only\n")
        ws = web.WebSocketResponse(max_msg_size=MAX_MESSAGE, heartbeat=20.0)
        await ws.prepare(request)
        client = _Client(ws, self._next_id)
        self._next_id += 1
        with self._lock:
            self.clients[client.id] = client
            if self.pilot is None:
                self.pilot = client.id
        self.connections += 1
        sender = asyncio.get_running_loop().create_task(self._send_pictures(client))
        try:
            await ws.send_str(self._hello)
            await self._send_roles()
            async for message in ws:
                if message.type != aiohttp.WSMsgType.TEXT or not self._take(client, message.data):
                    await ws.close(code=1008, message=b"malformed message")  # binary ones too
                    break
        except (ConnectionError, asyncio.CancelledError, RuntimeError):
            pass
        finally:
            sender.cancel()
            self._leave(client)
            await self._send_roles()
        return ws

    async def _send_pictures(self, client: _Client) -> None:
        """Send ``client`` the newest picture whenever there is one it has not had (older ones are dropped)."""
        try:
            while not client.ws.closed:
                await client.ready.wait()
                client.ready.clear()
                message, client.latest = client.latest, None
                if message is not None:
                    await client.ws.send_bytes(message)
                    client.sent += 1
        except (ConnectionError, RuntimeError, asyncio.CancelledError):
            pass

    async def _send_roles(self) -> None:
        with self._lock:
            pilot, ids = self.pilot, list(self.clients)
        for ident in ids:
            client = self.clients.get(ident)
            if client is None or client.ws.closed:
                continue
            role = {"type": "role", "id": ident, "role": "pilot" if ident == pilot else "spectator",
                    "watchers": len(ids) - 1}  # fmt: skip
            try:
                await client.ws.send_str(json.dumps(role))
            except (ConnectionError, RuntimeError):
                pass

    def _leave(self, client: _Client) -> None:
        """A page went away: its keys are let go, and the keys pass to the page connected longest."""
        with self._lock:
            self.clients.pop(client.id, None)
            if self.pilot == client.id:
                for key in sorted(self._held):
                    self._events.append(("release", key))
                self._new_pilot(min(self.clients) if self.clients else None)

    def _new_pilot(self, ident: int | None) -> None:
        """The keys pass to page ``ident`` (None: no page): nothing held, and its own keys messages counted from 0
        (under the lock)."""
        self._held, self.pilot, self._seq = frozenset(), ident, 0

    def _take(self, client: _Client, text: str) -> bool:
        """Apply one message from ``client``; False when it is malformed (its connection is then closed)."""
        if len(text) > MAX_MESSAGE:
            return False
        try:
            message = json.loads(text)
        except ValueError:
            return False
        if not isinstance(message, dict):
            return False
        kind = message.get("type")
        with self._lock:
            steering = client.id == self.pilot
            if kind == "keys":
                held, seq = message.get("held"), message.get("seq")
                if not isinstance(held, list) or len(held) > len(KEY_NAMES) or not _is_count(seq):
                    return False
                if not all(isinstance(k, str) and k in KEY_NAMES for k in held):
                    return False
                if steering:
                    new = frozenset(held)
                    for key in sorted(new - self._held):
                        self._events.append(("press", key))
                    for key in sorted(self._held - new):
                        self._events.append(("release", key))
                    self._held, self._seq = new, int(seq)
            elif kind == "drag":
                dx, dy = message.get("dx"), message.get("dy")
                if not (_is_number(dx) and _is_number(dy)):
                    return False
                if steering:
                    self._events.append(("drag", float(dx), float(dy)))
            elif kind == "scroll":
                clicks = message.get("clicks")
                if not _is_number(clicks):
                    return False
                if steering:
                    self._events.append(("scroll", float(clicks)))
            elif kind == "handover":
                if steering:
                    waiting = [i for i in self.clients if i != client.id]
                    if waiting:
                        for key in sorted(self._held):
                            self._events.append(("release", key))
                        self._new_pilot(min(waiting))
                        task = asyncio.get_running_loop().create_task(self._send_roles())
                        self._tasks.add(task)
                        task.add_done_callback(self._tasks.discard)
            else:
                return False
        return True

    # ------------------------------------------------------------------ the viewer's side
    def wait_for_page(self, timeout: float | None = None, stop=lambda: False) -> bool:
        """Block until a page is connected (True at once if one is), ``timeout`` seconds pass or ``stop()`` is true
        (False)."""
        started = time.monotonic()
        while not self.clients:
            if stop() or (timeout is not None and time.monotonic() - started > timeout):
                return False
            time.sleep(0.05)
        return True

    def events(self) -> list[tuple]:
        with self._lock:
            out = list(self._events)
            self._events.clear()
        return out

    def held(self) -> frozenset[str]:
        with self._lock:
            self._read_seq, self._read_pilot = self._seq, self.pilot  # what applied() acknowledges
            return self._held

    def applied(self, frame: int, held: frozenset[str]) -> None:
        """Frame ``frame`` is steered by ``held``: the next pictures acknowledge the keys message it came from, and
        :attr:`applied` logs it when it differs from the last frame's."""
        with self._lock:
            self._ack, self._ack_pilot = self._read_seq, self._read_pilot
            keys = tuple(sorted(held))
            if keys != self._last_applied:
                self.applied_log.append((frame, keys, self._ack))
                self._last_applied = keys

    def draw(self, positions: np.ndarray, view: View, hud: list[str], overlay: list[str]) -> None:
        if self._loop is None or self.closed:
            return
        self._picture += 1
        header = {
            "hud": list(hud),
            "overlay": list(overlay),
            "pilot": self._ack_pilot,  # the page whose keys message ``ack`` counts
            "view": {"eye": [float(v) for v in view.eye], "target": [float(v) for v in view.target],
                     "fov": float(view.fov)},
        }  # fmt: skip
        message = encode_frame(self._picture, self._ack, positions, header)
        self._loop.call_soon_threadsafe(self._publish, message)

    def _publish(self, message: bytes) -> None:
        for client in list(self.clients.values()):
            if client.latest is not None:
                client.dropped += 1
            client.latest = message
            client.ready.set()

    def screenshot(self) -> np.ndarray:
        """The browser draws the pictures; here there are none (a black picture of :attr:`size`)."""
        return np.zeros((self.size[1], self.size[0], 3), dtype=np.uint8)

    def close(self) -> None:
        """Stop the server: every page is told the flight ended (safe to call twice)."""
        if self.closed:
            return
        self.closed = True
        if self._loop is not None and self._thread is not None and self._thread.is_alive():
            self._loop.call_soon_threadsafe(self._loop.stop)
            self._stopped.wait(5.0)


def check_listen(host: str, port: int) -> None:
    """Raise :class:`ViewerUnavailableError` when ``host:port`` cannot be listened on: a port out of range, a host
    name that does not resolve, an address taken or not of this machine."""
    if not 0 <= port <= 65535:
        raise ViewerUnavailableError(f"--port {port}: a port is 0 to 65535 (0: any free one)")
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    except (OSError, UnicodeError) as err:
        raise ViewerUnavailableError(f"--host {host}: {err}") from None
    family, kind, proto, _, address = infos[0]
    with socket.socket(family, kind, proto) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as the server binds
        try:
            probe.bind(address)
        except OSError as err:
            raise ViewerUnavailableError(f"cannot listen on {host}:{port}: {err.strerror or err}") from None


def _is_number(value) -> bool:
    if not isinstance(value, int | float) or isinstance(value, bool):
        return False
    try:
        return math.isfinite(value) and abs(value) < 1e6
    except OverflowError:  # an integer of hundreds of digits
        return False


def _is_count(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and 0 <= value < 2**32
