"""What the viewer asks of a window: the :class:`Backend` interface, what to draw, and a backend that draws nothing.

Key names are plain strings: ``"UP" "DOWN" "LEFT" "RIGHT"`` (arrows), letters ``"A"``..``"Z"``, ``"SPACE"``,
``"ESCAPE"``, ``"PLUS"``, ``"MINUS"``, ``"["``, ``"]"``, ``"."`` and ``"?"``. Events are tuples:
``("press", key)``, ``("release", key)``, ``("drag", dx, dy)`` [pixels], ``("scroll", clicks)`` and
``("close",)``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


class ViewerUnavailableError(RuntimeError):
    """The window cannot open (the ``viewer`` extra is missing, or there is no display); a one-line reason."""


@dataclass
class DrawList:
    """What a scene draws, fixed when it is built; positions come with every frame.

    Attributes:
        meshes: ``(triangles [t, 3] particle indices, rgb)`` per object part (sail, keel, canopy, cloth).
        curves: ``(particle chain [n], rgb)`` per rope or line.
        spheres: ``(point, radius [m], rgb)`` per ball (a parachutist's head, a pole's finial).
        tubes: ``(point a, point b, radius [m], rgb)`` per tube drawn from a to b (a glider's keel and control frame,
            the pilot's body and arms, a flag's pole: :mod:`warpsim.objects.drawing`).
        terrain_points: ``[v, 3]`` terrain vertices [m]. terrain_triangles: ``[t, 3]`` vertex indices.
        terrain_colours: ``[v, 3]`` rgb per terrain vertex.
        drawn: indices of the points drawn.
        focus: the points the camera frames: those of the meshes, spheres and tubes (a rope's ground end is
            not what one watches), else every drawn one.
        place: ``positions [P, 3] -> points [P + added, 3]`` [m]: the particles as drawn (the worlds of a batch
            side by side) followed by the points the tubes and spheres add; indices above refer to these points.

    The backend is given placed points (:meth:`Backend.draw`).
    """

    meshes: list = field(default_factory=list)
    curves: list = field(default_factory=list)
    spheres: list = field(default_factory=list)
    tubes: list = field(default_factory=list)
    terrain_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), np.float32))
    terrain_triangles: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), np.int32))
    terrain_colours: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), np.float32))
    drawn: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    focus: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    place: object = field(default=lambda q: q)


@dataclass
class View:
    """A perspective camera: ``eye`` and ``target`` [m], vertical field of view ``fov`` [deg]; Z is up."""

    eye: np.ndarray
    target: np.ndarray
    fov: float = 50.0


class Backend:
    """A window the viewer draws into and reads keys from.

    Attributes: ``size`` (width, height) [pixels]; ``closed``: the user closed the window.
    """

    size: tuple[int, int] = (1280, 720)
    closed: bool = False

    @classmethod
    def check(cls, **options) -> None:
        """Raise :class:`ViewerUnavailableError` (one line) when this backend cannot work here with ``options`` (the
        arguments its constructor will be given): said before the scene is built. The base accepts anything."""

    def open(self, draw_list: DrawList, title: str, keys: tuple = ()) -> None:
        """Open the window and upload what does not move (terrain, topology); ``keys``: the scene's key map,
        ``(keys, what they do)`` lines, for a backend that shows its own help."""
        raise NotImplementedError

    def events(self) -> list[tuple]:
        """The input events since the last call (see the module notes)."""
        raise NotImplementedError

    def held(self) -> frozenset[str]:
        """Keys held down now."""
        raise NotImplementedError

    def applied(self, frame: int, held: frozenset[str]) -> None:
        """The viewer read ``held`` (from :meth:`held`) at the start of frame ``frame`` and steers that frame by it
        (a backend that acknowledges inputs, or logs what was flown, overrides this)."""

    def draw(self, positions: np.ndarray, view: View, hud: list[str], overlay: list[str]) -> None:
        """Draw one picture: the points ``positions`` ``[P + added, 3]`` [m] (``DrawList.place`` of the particles)
        seen from ``view``, the ``hud`` lines on a panel in a corner and ``overlay`` lines (help, errors) in the
        middle when not empty; then show it."""
        raise NotImplementedError

    def screenshot(self) -> np.ndarray:
        """The last picture drawn, ``[height, width, 3]`` uint8, top row first."""
        raise NotImplementedError

    def close(self) -> None:
        """Close the window (safe to call twice)."""


BACKENDS = {
    "window": "warpsim.viewer.gl:PygletBackend",
    "browser": "warpsim.viewer.web:BrowserBackend",
    "null": "warpsim.viewer.backend:NullBackend",
}
"""The backends by name (``module:class``, imported when asked for, so that a missing extra costs nothing until
then): the pyglet window, the web page, and the null backend of the tests."""


def backend_class(name: str) -> type[Backend]:
    """The backend class called ``name`` in :data:`BACKENDS` (a ``ValueError`` for another name)."""
    import importlib

    if name not in BACKENDS:
        raise ValueError(f"no viewer backend {name!r}: one of {', '.join(BACKENDS)}")
    module, cls = BACKENDS[name].split(":")
    return getattr(importlib.import_module(module), cls)


def make_backend(name: str, **options) -> Backend:
    """Check (:meth:`Backend.check`) and make the backend called ``name`` with ``options``, before the scene is
    built: what cannot work here is said in one line first."""
    cls = backend_class(name)
    cls.check(**options)
    return cls(**options)


class NullBackend(Backend):
    """A backend without a window: tests press and release keys with :meth:`press` and :meth:`release`;
    :meth:`draw` keeps what it was given (``last_hud``, ``last_overlay``, ``last_view``) and counts pictures."""

    def __init__(self, size: tuple[int, int] = (320, 180)):
        self.size = size
        self.closed = False
        self._events: list[tuple] = []
        self._held: set[str] = set()
        self.pictures = 0
        self.last_hud: list[str] = []
        self.last_overlay: list[str] = []
        self.last_view: View | None = None

    def open(self, draw_list: DrawList, title: str, keys: tuple = ()) -> None:
        self.draw_list, self.title, self.keys = draw_list, title, tuple(keys)

    def press(self, key: str) -> None:
        """Press ``key`` (held until :meth:`release`)."""
        self._held.add(key)
        self._events.append(("press", key))

    def release(self, key: str) -> None:
        """Release ``key``."""
        self._held.discard(key)
        self._events.append(("release", key))

    def tap(self, key: str) -> None:
        """Press and release ``key`` (both seen by the next tick)."""
        self.press(key)
        self.release(key)

    def send(self, *event) -> None:
        """Queue any event, e.g. ``send("drag", 10, 0)``."""
        self._events.append(tuple(event))

    def events(self) -> list[tuple]:
        out, self._events = self._events, []
        return out

    def held(self) -> frozenset[str]:
        return frozenset(self._held)

    def draw(self, positions, view, hud, overlay) -> None:
        self.pictures += 1
        self.last_hud, self.last_overlay, self.last_view = list(hud), list(overlay), view

    def screenshot(self) -> np.ndarray:
        return np.zeros((self.size[1], self.size[0], 3), dtype=np.uint8)

    def close(self) -> None:
        self.closed = True
