"""An OpenGL 3.3 window for the viewer, with pyglet (the ``viewer`` extra: ``pip install -e '.[viewer]'``).

Meshes are drawn from one vertex buffer each (position, normal, colour), rewritten from NumPy every frame;
the terrain is uploaded once. Cloth is lit from both sides with a sun and sky light; the terrain gets a 10 m
grid so that motion over it can be seen and fades into haze with distance; ropes and lines are lines 2 pixels wide
(a kite's line shows at any distance); tubes (a glider's keel and control frame, the pilot's body, a flag's pole)
are capped 8-sided cylinders and balls are spheres, placed every frame; the sky goes from haze at the horizon to
blue overhead and the ground beyond the terrain is hazy to the horizon. The heads-up text is on a dark semi-opaque
panel and the view's centre is the middle of the picture below it. Text (heads-up and overlay) is pyglet's. Runs
on Mesa's software renderer (llvmpipe), as on a virtual X screen, and on GPUs.
"""

from __future__ import annotations

import ctypes

import numpy as np

from .._extras import install_hint
from .backend import Backend, DrawList, View, ViewerUnavailableError
from .geometry import sphere, tube_mesh, tube_points, vertex_normals, view_matrix

_VERTEX = """
#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec3 colour;
uniform mat4 view_projection;
out vec3 v_normal;
out vec3 v_colour;
out vec3 v_world;
void main() {
    gl_Position = view_projection * vec4(position, 1.0);
    v_normal = normal;
    v_colour = colour;
    v_world = position;
}
"""

_FRAGMENT = """
#version 330 core
in vec3 v_normal;
in vec3 v_colour;
in vec3 v_world;
uniform int mode;  // 0: lit both sides, 1: unlit, 2: lit terrain with a 10 m grid, 3: sky (v_normal: the ray)
uniform vec3 sun;
uniform vec3 eye;  // [m]
uniform float eye_height;  // above the ground under the eye [m]
uniform vec3 ground;  // the terrain's colour, lit from straight above
const vec3 horizon = vec3(0.86, 0.91, 0.96);
const vec3 zenith = vec3(0.42, 0.62, 0.90);
const float haze_distance = 2500.0;  // [m]: the ground's colour halfway to the haze's at 0.69 times this
out vec4 colour;
void main() {
    vec3 c = v_colour;
    if (mode == 3) {  // sky above the horizon, hazy ground below it (where the terrain does not reach)
        vec3 d = normalize(v_normal);
        if (d.z >= 0.0) {
            c = mix(horizon, zenith, sqrt(d.z));
        } else {
            float reach = max(eye_height, 0.5) * length(d.xy) / max(-d.z, 1e-4);
            c = mix(ground, 0.92 * horizon, 1.0 - exp(-reach / haze_distance));
        }
        colour = vec4(c, 1.0);
        return;
    }
    if (mode != 1) {
        vec3 n = normalize(v_normal);
        float light = 0.35 + 0.65 * abs(dot(n, sun));
        c = c * light;
    }
    if (mode == 2) {
        vec2 g = v_world.xy / 10.0;
        vec2 d = abs(fract(g + 0.5) - 0.5) / max(fwidth(g), vec2(1e-6));  // distance to a line in pixels
        float line = (1.0 - min(min(d.x, d.y), 1.0)) * (1.0 - smoothstep(0.05, 0.5, max(fwidth(g).x, fwidth(g).y)));
        c = mix(c, c * 0.82, line);  // grid lines fade out where they would be closer than 2 pixels
        c = mix(c, 0.92 * horizon, 1.0 - exp(-length(v_world.xy - eye.xy) / haze_distance));
    }
    colour = vec4(c, 1.0);
}
"""

_KEYS = {
    "UP": "UP",
    "DOWN": "DOWN",
    "LEFT": "LEFT",
    "RIGHT": "RIGHT",
    "SPACE": "SPACE",
    "ESCAPE": "ESCAPE",
}
"""Keys that are held or are not characters, by pyglet's symbol name (letters too, see ``_name``): the viewer's
name for each, pressed and released."""

_TEXT_KEYS = {"+": "PLUS", "=": "PLUS", "-": "MINUS", "?": "?", "/": "?", "[": "[", "]": "]", ".": "."}
"""The character keys, which act once per press, read from the text typed (pyglet's ``on_text``): on X, pyglet
misses every press of a shifted key after the first (shift+= for '+', shift+/ for '?') when shift is let go
before the key, as xdotool and quick fingers do, because it takes the key's release, reported unshifted, for
another key's; the typed text comes every time, once for the keypad's + and - too."""


def _pyglet():
    try:
        import pyglet
    except ImportError:
        raise ViewerUnavailableError(
            f"the viewer needs pyglet: {install_hint('viewer')} (or fly it in a web page: --browser)"
        ) from None
    pyglet.options["debug_gl"] = False  # no glGetError after every call: it halves the frame rate
    return pyglet


NO_DISPLAY_HINT = (
    "on a machine without a screen: --browser (and ssh -L 8765:127.0.0.1:8765 to open it from yours), ssh -X, or "
    "xvfb-run -a warpsim view ... --seconds S --screenshot OUT.png"
)


def _window_library():
    """pyglet (:func:`_pyglet`), its ``gl`` module and its ``Shader`` and ``ShaderProgram`` classes;
    :class:`ViewerUnavailableError` when its window library cannot start (a missing libGL or X library, an X server
    that does not answer)."""
    pyglet = _pyglet()
    try:
        import pyglet.window
        from pyglet import gl
        from pyglet.graphics.shader import Shader, ShaderProgram
    except Exception as err:  # noqa: BLE001 - a missing libGL or X library, an X server that does not answer
        raise ViewerUnavailableError(f"the viewer's window library cannot start ({err}); {NO_DISPLAY_HINT}") from None
    return pyglet, gl, Shader, ShaderProgram


def check_display() -> None:
    """Raise :class:`ViewerUnavailableError` when the viewer cannot work here: pyglet missing, or (on Linux and
    other X11 systems) no ``DISPLAY`` to open a window on."""
    import os
    import sys

    _pyglet()
    if sys.platform.startswith(("linux", "freebsd", "openbsd")) and not os.environ.get("DISPLAY"):
        raise ViewerUnavailableError(f"no display to open a window on (DISPLAY is not set); {NO_DISPLAY_HINT}")


class _Buffer:
    """One vertex array: interleaved position, normal, colour (9 floats) and optional indices."""

    def __init__(self, gl, vertices: int, indices: np.ndarray | None, mode):
        self.gl, self.mode, self.count = gl, mode, vertices
        self.vao, self.vbo = gl.GLuint(), gl.GLuint()
        gl.glGenVertexArrays(1, ctypes.byref(self.vao))
        gl.glBindVertexArray(self.vao)
        gl.glGenBuffers(1, ctypes.byref(self.vbo))
        gl.glBindBuffer(gl.GL_ARRAY_BUFFER, self.vbo)
        gl.glBufferData(gl.GL_ARRAY_BUFFER, max(vertices, 1) * 36, None, gl.GL_DYNAMIC_DRAW)
        for location in range(3):
            gl.glEnableVertexAttribArray(location)
            gl.glVertexAttribPointer(location, 3, gl.GL_FLOAT, gl.GL_FALSE, 36, ctypes.c_void_p(12 * location))
        self.index_count = 0
        if indices is not None:
            indices = np.ascontiguousarray(indices, dtype=np.uint32).ravel()
            self.ebo = gl.GLuint()
            gl.glGenBuffers(1, ctypes.byref(self.ebo))
            gl.glBindBuffer(gl.GL_ELEMENT_ARRAY_BUFFER, self.ebo)
            gl.glBufferData(
                gl.GL_ELEMENT_ARRAY_BUFFER, indices.nbytes, indices.ctypes.data_as(ctypes.c_void_p), gl.GL_STATIC_DRAW
            )
            self.index_count = len(indices)
        gl.glBindVertexArray(0)

    def update(self, points: np.ndarray, normals: np.ndarray, colours: np.ndarray) -> None:
        data = np.ascontiguousarray(np.hstack([points, normals, colours]), dtype=np.float32)
        gl = self.gl
        gl.glBindBuffer(gl.GL_ARRAY_BUFFER, self.vbo)
        gl.glBufferSubData(gl.GL_ARRAY_BUFFER, 0, data.nbytes, data.ctypes.data_as(ctypes.c_void_p))

    def draw(self) -> None:
        gl = self.gl
        gl.glBindVertexArray(self.vao)
        if self.index_count:
            gl.glDrawElements(self.mode, self.index_count, gl.GL_UNSIGNED_INT, None)
        else:
            gl.glDrawArrays(self.mode, 0, self.count)
        gl.glBindVertexArray(0)


class PygletBackend(Backend):
    """The viewer's window: ``size`` (width, height) [pixels], ``visible`` False for an off-screen window on
    an X display (still needs one), ``keep_pictures`` to read each picture back for :meth:`screenshot`."""

    def __init__(self, size: tuple[int, int] = (1280, 720), visible: bool = True, keep_pictures: bool = False):
        self.size = tuple(size)
        self.visible = visible
        self.closed = False
        self.window = None
        self.keep_pictures = keep_pictures  # read every picture back (for screenshot()); a few ms a picture
        self._events: list[tuple] = []
        self._held: set[str] = set()

    # ------------------------------------------------------------------ window
    @classmethod
    def check(cls, **options) -> None:
        check_display()

    def open(self, draw_list: DrawList, title: str, keys: tuple = ()) -> None:
        pyglet, gl, Shader, ShaderProgram = _window_library()
        self._open_window(pyglet, gl, title)
        self.gl, self.pyglet = gl, pyglet
        self.window.switch_to()
        self._program = ShaderProgram(Shader(_VERTEX, "vertex"), Shader(_FRAGMENT, "fragment"))
        self.draw_list = draw_list
        self._make_buffers(draw_list)
        self._make_text()
        self._bind_events()
        self.window.dispatch_events()

    def _open_window(self, pyglet, gl, title: str) -> None:
        """Open ``self.window``, ``self.size`` [pixels] and resizable, titled ``title``, double-buffered with a 24-bit
        depth buffer on OpenGL 3.3, without vsync; :class:`ViewerUnavailableError` when it cannot (no display, no
        GLX, no OpenGL 3.3)."""
        try:
            config = gl.Config(double_buffer=True, depth_size=24, major_version=3, minor_version=3)
            self.window = pyglet.window.Window(
                *self.size, caption=title, config=config, visible=self.visible, vsync=False, resizable=True
            )
        except Exception as err:  # noqa: BLE001 - no display, no GLX, no OpenGL 3.3
            reason = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
            raise ViewerUnavailableError(f"cannot open a window ({reason}); {NO_DISPLAY_HINT}") from None

    def _make_buffers(self, d: DrawList) -> None:
        """The vertex buffers of the draw list ``d``: the terrain (uploaded here, once), each mesh (its particles and
        their triangles renumbered), the curves' line segments, the spheres, the tubes and the sky; and the colour of
        the hazy ground beyond the terrain."""
        gl = self.gl
        self._terrain = _Buffer(gl, len(d.terrain_points), d.terrain_triangles, gl.GL_TRIANGLES)
        self._terrain.update(d.terrain_points, vertex_normals(d.terrain_points, d.terrain_triangles), d.terrain_colours)
        self._meshes = []
        for triangles, rgb in d.meshes:
            ids, local = np.unique(np.asarray(triangles).ravel(), return_inverse=True)
            local = local.reshape(-1, 3).astype(np.int32)
            colours = np.tile(np.asarray(rgb, dtype=np.float32), (len(ids), 1))
            self._meshes.append((ids, local, colours, _Buffer(gl, len(ids), local, gl.GL_TRIANGLES)))
        ends, colours = [np.zeros(0, np.int64)], [np.zeros((0, 3), np.float32)]
        for chain, rgb in d.curves:  # each chain as line segments: vertex pairs (k, k + 1)
            ends.append(np.stack([chain[:-1], chain[1:]], 1).ravel())
            colours.append(np.tile(np.asarray(rgb, np.float32), (2 * max(len(chain) - 1, 0), 1)))
        self._segments, self._segment_colours = np.concatenate(ends), np.concatenate(colours)
        self._lines = _Buffer(gl, len(self._segments), None, gl.GL_LINES)
        self._make_sphere_buffer(d)
        self._make_tube_buffer(d)
        self._sky_corners = np.array([[-1, -1, 0.999], [1, -1, 0.999], [1, 1, 0.999], [-1, 1, 0.999]], np.float32)
        self._sky = _Buffer(gl, 4, np.array([0, 1, 2, 0, 2, 3]), gl.GL_TRIANGLES)
        from ..objects.style import COLOURS

        self._ground_colour = tuple(float(c) * 0.95 for c in COLOURS["terrain"])

    def _make_sphere_buffer(self, d: DrawList) -> None:
        """One buffer for every sphere of ``d`` (``self._spheres``, None without any): the unit sphere scaled by each
        radius [m] as offsets from its particle, their normals and colours; only the centres move."""
        self._spheres = None
        if d.spheres:
            gl = self.gl
            unit, sphere_triangles = sphere()
            n, count = len(unit), len(d.spheres)
            triangles = np.concatenate([sphere_triangles + k * n for k in range(count)])
            self._spheres = _Buffer(gl, n * count, triangles, gl.GL_TRIANGLES)
            self._sphere_offsets = np.concatenate([unit * radius for _, radius, _ in d.spheres])
            self._sphere_particles = np.repeat([p for p, _, _ in d.spheres], n)
            self._sphere_normals = np.tile(unit, (count, 1))
            self._sphere_colours = np.concatenate([np.tile(np.asarray(c, np.float32), (n, 1)) for *_, c in d.spheres])

    def _make_tube_buffer(self, d: DrawList) -> None:
        """One buffer for every tube of ``d`` (``self._tubes``, None without any), with the tubes' end particles,
        radii [m] and colours; the ends move with their points."""
        self._tubes = None
        if d.tubes:
            gl = self.gl
            count = len(d.tubes)
            self._tube_ends = np.array([(a, b) for a, b, _, _ in d.tubes], dtype=np.int64)
            self._tube_radii = np.array([r for _, _, r, _ in d.tubes], dtype=np.float64)
            per = len(tube_points(np.zeros((1, 3)), np.ones((1, 3)), np.ones(1))[0])
            self._tube_colours = np.repeat(np.array([c for *_, c in d.tubes], np.float32), per, axis=0)
            self._tubes = _Buffer(gl, per * count, tube_mesh(count), gl.GL_TRIANGLES)

    def _make_text(self) -> None:
        """The heads-up text (top left, on its dark panel) and the overlay's (centred, on its shade), pyglet's labels
        in a smaller font in a window under 1000 pixels wide."""
        pyglet = self.pyglet
        small = self.size[0] < 1000

        def label(font_size: int, colour: tuple, **place):
            return pyglet.text.Label(
                "", multiline=True, font_name="DejaVu Sans Mono", font_size=font_size, color=colour, **place
            )

        width, height = self.size
        white = (255, 255, 255, 255)
        self._hud = label(7 if small else 11, white, x=14, y=height - 12, anchor_y="top", width=width - 28)
        self._panel = pyglet.shapes.Rectangle(0, 0, 1, 1, color=(20, 25, 35, 185))  # under the heads-up text
        self.hud_fraction = 0.0  # the share of the height the heads-up panel covers (the view slides below it)
        self._overlay = label(
            8 if small else 12, (255, 255, 255, 255), x=width // 2, y=height // 2, anchor_x="center",
            anchor_y="center", width=int(width * 0.8),
        )  # fmt: skip
        self._shade = pyglet.shapes.Rectangle(0, 0, 1, 1, color=(20, 25, 35, 200))

    def _bind_events(self) -> None:
        """Queue the window's input for :meth:`events`: keys pressed and released (held until then, or until the
        window loses the focus), the character keys typed, mouse drags [pixels] and scrolls, and the window's
        closing; a resize moves the text with the window's size."""
        w = self.window

        @w.event
        def on_key_press(symbol, modifiers):
            key = self._name(symbol)
            if key:
                self._held.add(key)
                self._events.append(("press", key))
            return True  # pyglet's default closes the window on Esc: the viewer decides

        @w.event
        def on_text(text):
            key = _TEXT_KEYS.get(text)
            if key:
                self._events.append(("press", key))

        @w.event
        def on_key_release(symbol, modifiers):
            key = self._name(symbol)
            if key:
                self._held.discard(key)
                self._events.append(("release", key))

        @w.event
        def on_mouse_drag(x, y, dx, dy, buttons, modifiers):
            self._events.append(("drag", dx, dy))

        @w.event
        def on_mouse_scroll(x, y, scroll_x, scroll_y):
            self._events.append(("scroll", scroll_y))

        @w.event
        def on_close():
            self._events.append(("close",))
            self.closed = True
            return True

        @w.event
        def on_deactivate():  # keys released while another window has the focus would stay held
            for key in list(self._held):
                self._events.append(("release", key))
            self._held.clear()

        @w.event
        def on_resize(width, height):
            self.size = (max(width, 1), max(height, 1))
            self._hud.y, self._hud.width = height - 12, max(width - 28, 10)
            self._overlay.x, self._overlay.y = width // 2, height // 2
            self._overlay.width = max(int(width * 0.8), 10)

    def _name(self, symbol: int) -> str | None:
        name = self.pyglet.window.key.symbol_string(symbol)
        if name in _KEYS:
            return _KEYS[name]
        return name if len(name) == 1 and name.isalpha() else None

    def events(self) -> list[tuple]:
        if self.window is not None and not self.closed:
            self.window.dispatch_events()
        out, self._events = self._events, []
        return out

    def held(self) -> frozenset[str]:
        return frozenset(self._held)

    # ------------------------------------------------------------------ drawing
    def draw(self, positions: np.ndarray, view: View, hud: list[str], overlay: list[str]) -> None:
        if self.window is None or self.closed:
            return
        gl, q = self.gl, np.asarray(positions, dtype=np.float32)
        self.window.switch_to()
        width, height = self.window.get_framebuffer_size()
        gl.glViewport(0, 0, width, height)
        gl.glClearColor(0.6, 0.75, 0.92, 1.0)
        gl.glClear(gl.GL_COLOR_BUFFER_BIT | gl.GL_DEPTH_BUFFER_BIT)
        program = self._program
        program.use()
        self._hud.text = "\n".join(hud)  # laid out first: the view goes below the panel it needs
        self._panel.height = self._hud.content_height + 16
        self.hud_fraction = (self._panel.height + 4) / max(height, 1)
        matrix = view_matrix(view, width, height, self.hud_fraction)
        eye = np.asarray(view.eye, dtype=np.float64)
        far = np.linalg.inv(matrix) @ np.hstack([self._sky_corners, np.ones((4, 1))]).T  # the corners' rays
        rays = (far[:3] / far[3]).T - eye
        gl.glDisable(gl.GL_DEPTH_TEST)
        program["view_projection"] = tuple(np.eye(4).T.ravel())
        program["mode"] = 3
        program["eye"] = tuple(float(v) for v in eye)
        under = float(self.draw_list.terrain_points[:, 2].mean()) if len(self.draw_list.terrain_points) else 0.0
        program["eye_height"] = float(eye[2] - under)
        sun = np.array([0.35, -0.25, 0.9]) / np.linalg.norm([0.35, -0.25, 0.9])
        program["ground"] = tuple(c * (0.35 + 0.65 * sun[2]) for c in self._ground_colour)
        self._sky.update(self._sky_corners, rays.astype(np.float32), np.zeros_like(self._sky_corners))
        self._sky.draw()
        gl.glEnable(gl.GL_DEPTH_TEST)
        program["view_projection"] = tuple(matrix.T.ravel())
        program["sun"] = tuple(sun)
        program["mode"] = 2
        self._terrain.draw()
        program["mode"] = 0
        for ids, local, colours, buffer in self._meshes:
            p = q[ids]
            buffer.update(p, vertex_normals(p, local), colours)
            buffer.draw()
        if self._spheres is not None:
            self._spheres.update(
                self._sphere_offsets + q[self._sphere_particles], self._sphere_normals, self._sphere_colours
            )
            self._spheres.draw()
        if self._tubes is not None:
            ends = q[self._tube_ends].astype(np.float64)
            points, normals = tube_points(ends[:, 0], ends[:, 1], self._tube_radii)
            self._tubes.update(points, normals, self._tube_colours)
            self._tubes.draw()
        if len(self._segments):  # ropes and lines 2 pixels wide at any distance
            program["mode"] = 1
            p = q[self._segments]
            self._lines.update(p, np.zeros_like(p), self._segment_colours)
            gl.glLineWidth(2.0)
            self._lines.draw()
            gl.glLineWidth(1.0)
        program.stop()
        gl.glDisable(gl.GL_DEPTH_TEST)
        self._panel.x, self._panel.width = 4, min(self._hud.content_width + 20, width - 8)
        self._panel.y = height - 4 - self._panel.height
        self._panel.draw()
        self._hud.draw()
        if overlay:
            self._overlay.text = "\n".join(overlay)
            h = self._overlay.content_height + 30
            w = min(self._overlay.content_width + 40, width)
            self._shade.x, self._shade.y = (width - w) / 2, (height - h) / 2
            self._shade.width, self._shade.height = w, h
            self._shade.draw()
            self._overlay.draw()
        if self.keep_pictures:
            self._picture = self._read()
        self.window.flip()

    def _read(self) -> np.ndarray:
        gl = self.gl
        width, height = self.window.get_framebuffer_size()
        buffer = (ctypes.c_ubyte * (width * height * 3))()
        gl.glPixelStorei(gl.GL_PACK_ALIGNMENT, 1)
        gl.glReadPixels(0, 0, width, height, gl.GL_RGB, gl.GL_UNSIGNED_BYTE, buffer)
        return np.frombuffer(buffer, np.uint8).reshape(height, width, 3)[::-1].copy()

    def screenshot(self) -> np.ndarray:
        return getattr(self, "_picture", np.zeros((self.size[1], self.size[0], 3), dtype=np.uint8))

    def close(self) -> None:
        if self.window is not None:
            window, self.window = self.window, None
            self.closed = True
            window.close()
