"""The viewer's logic, apart from any window: pacing, keyboard controls, camera, heads-up text, restarts.

One :meth:`Viewer.tick` reads the window's events, steps as many frames as wall time asks (each through
:meth:`warpsim.run.simulation.Simulation.advance`, the keyboard's controls set at the frame start through
:meth:`~warpsim.run.simulation.Simulation.set_controls`), records them, and draws one picture. Controls change only
at frame starts and depend only on which keys were held there, so a recording of what was flown replays
bit for bit (``warpsim run --replay``).
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np

from ..objects.keys import WalkKeys
from ..objects.registry import OBJECTS
from ..objects.style import COLOURS
from ..run.diagnostics import Frame
from ..run.figures import Figures
from ..run.simulation import BlowUpError, Simulation
from . import camera, hud
from .backend import Backend, DrawList, View

CAMERAS = ("orbit", "chase", "ground")


def draw_list(model, terrain_samples: int = 129) -> DrawList:
    """What to draw of ``model``: part meshes with the outputs' colours, curves, spheres, tubes (the pictures'
    :class:`warpsim.io.render.Scene`: a batch's worlds side by side), and the terrain resampled to at most
    ``terrain_samples`` per side (heights from the model's heightfield)."""
    from ..io.render import Scene

    scene = Scene(model)
    hf = model.terrain
    ny, nx = hf.heights.shape
    stride = max(1, math.ceil((max(nx, ny) - 1) / (terrain_samples - 1)))
    ix, iy = np.arange(0, nx, stride), np.arange(0, ny, stride)
    if ix[-1] != nx - 1:
        ix = np.append(ix, nx - 1)
    if iy[-1] != ny - 1:
        iy = np.append(iy, ny - 1)
    gx, gy = np.meshgrid(hf.origin[0] + ix * hf.cell[0], hf.origin[1] + iy * hf.cell[1])
    gz = hf.heights[np.ix_(iy, ix)]
    points = np.stack([gx, gy, gz], axis=-1).reshape(-1, 3).astype(np.float32)
    w = len(ix)
    cells = np.arange((len(iy) - 1) * w).reshape(len(iy) - 1, w)[:, :-1].ravel()
    triangles = np.concatenate(
        [np.stack([cells, cells + 1, cells + w + 1], 1), np.stack([cells, cells + w + 1, cells + w], 1)]
    ).astype(np.int32)
    low, high = float(gz.min()), float(gz.max())
    s = ((gz - low) / (high - low) if high > low else np.zeros_like(gz)).reshape(-1, 1)
    grass, rock = np.asarray(COLOURS["terrain"]), np.array([0.55, 0.50, 0.42])
    colours = (grass * (1 - s) + rock * s).astype(np.float32)
    return DrawList(
        meshes=scene.triangles,
        curves=scene.curves,
        spheres=scene.discs,
        tubes=scene.tubes,
        place=scene.place,
        terrain_points=points,
        terrain_triangles=triangles,
        terrain_colours=colours,
        drawn=scene.drawn,
        focus=scene.focus,
    )


def bindings(model) -> tuple[list, object, object]:
    """The keys that steer ``model``'s objects, from their :attr:`~warpsim.objects.registry.ObjectSpec.keys`:
    ``(axis bindings, one per control, walk binding or None, the record it walks or None)``. A control shared by
    several objects is steered by one binding (the first object's); the first object with a walkable anchor is
    the one whose anchor walks."""
    axes, walk, walked = {}, None, None
    for record in model.objects:
        for b in OBJECTS[record.kind].keys:
            if isinstance(b, WalkKeys):
                if walk is None and b.nail(record) >= 0:
                    walk, walked = b, record
            elif b.active is None or b.active(record):
                axes.setdefault(b.control, b)
    return list(axes.values()), walk, walked


def _towards(value: float, target: float, step: float) -> float:
    """``value`` moved by at most ``step`` towards ``target``."""
    return min(value + step, target) if target > value else max(value - step, target)


class Viewer:
    """Fly a :class:`~warpsim.run.simulation.Simulation` in a window.

    Args:
        sim: the scene, at its start. backend: the window (:class:`~warpsim.viewer.backend.Backend`).
        title: window title. record: path of an ``.h5`` recording of what is flown (None: no recording);
            after a restart (``R``) the next take goes to ``NAME.take2.h5`` and so on.
        where: where the scene came from, stored in the recording.
        seconds: quit after this much simulated time (None: when the user quits).
        say: where messages go (one line each; stderr by default).

    Attributes:
        paused, camera (one of :data:`CAMERAS`), axes (the keyboard's pitch and roll, each in [-1, 1]),
        frame (the last :class:`~warpsim.run.diagnostics.Frame`), error (the last blow-up or output message),
        behind (wall time ran ahead of what the machine could simulate in the last second),
        step_time and draw_time (wall seconds spent stepping and drawing), pictures (drawn so far).
    """

    RAMP = 2.0  # [1/s] of simulated time: a held arrow takes pitch or roll from 0 to 1 in 0.5 s, release back
    WIND_STEP = 1.0  # [m/s] per + or - press
    WIND_RATE = 2.0  # [m/s per simulated second]: how fast the wind moves to what + and - asked for
    WIND_LEAD = 2.0  # [m/s]: what + and - ask for runs at most this far ahead of the wind (a key's auto-repeat
    # adds nothing beyond it: holding + raises the wind at WIND_RATE, and at most WIND_LEAD more once let go)
    WIND_HOLD = 0.4  # [s] of simulated time: a + or - held longer than this (a page's held key) keeps asking
    WIND_TURN = 15.0  # [deg] per [ or ] press
    BUDGET = 0.05  # [s] of wall time stepping per tick at most, so that the window keeps answering
    MAX_FPS = 60.0  # pictures per wall second at most: the rest of the time is left to stepping or idle

    def __init__(
        self,
        sim: Simulation,
        backend: Backend,
        title: str = "warpsim",
        record: str | Path | None = None,
        where: str = "",
        *,
        seconds: float | None = None,
        say=None,
    ):
        self.sim, self.backend, self.title = sim, backend, title
        self.say = say or (lambda line: print(line, file=sys.stderr))
        self.seconds = seconds
        self.model = sim.model
        self.frame_interval = sim.steps_per_frame * sim.dt
        self.axis_keys, self.walk_keys, self.walked = bindings(self.model)
        self.draw_list = draw_list(self.model)
        self.figures = Figures(self.model)
        self.initial = sim.checkpoint()
        self._frames = sim.frames(before=self._controls_at_frame_start)  # the flight's frames, stepped by tick
        self.frame: Frame = next(self._frames)  # the current state, checked
        self.points = self.draw_list.place(self.frame.positions)  # the frame as drawn [m]
        self.axes = {b.control: 0.0 for b in self.axis_keys}
        self.paused = False
        self.show_help = False
        self.camera = "orbit"
        self.quit = False
        self.error = ""
        self.blew_up = False  # the last frame stepped blew up (cleared by a restart)
        self.behind = False
        self.step_time = self.draw_time = 0.0
        self.pictures = 0
        focus = self.draw_list.focus
        size = np.ptp(self.points[focus], axis=0) if len(focus) else np.ones(3)
        self.orbit = {"azimuth": -120.0, "elevation": 20.0, "distance": float(max(1.25 * np.linalg.norm(size), 6.0))}
        self._chase_heading = np.array([1.0, 0.0])
        self._ground_eye = camera.ground_point(self)
        self._debt = 0.0  # simulated seconds owed to the wall clock
        self._last = None  # wall time of the last tick
        self._rate = []  # (wall time, simulated time, steps) of the last ticks, for the rates shown
        self._pending_wind = None
        self._wind_goal: float | None = None  # [m/s] the wind speed + and - asked for, reached at WIND_RATE
        self._held_frames = {"PLUS": 0, "MINUS": 0}  # frame starts at which each has been held in a row
        self._initial_heading = self._wind_heading = self._heading(sim.settings.wind.velocity, 0.0)
        self.wind_limit = max(
            min(OBJECTS[r.kind].wind_limit for r in self.model.objects),
            float(np.linalg.norm(sim.settings.wind.velocity[:2])),
        )  # [m/s] + stops here: the strongest wind the scene's objects are made for (or the scene's own)
        self._one_frame = False
        self._restarted = False
        self.recorder = None
        self._record_path = Path(record) if record else None
        self.takes: list[Path] = []  # the recordings made: NAME.h5, then NAME.take2.h5, ... after each restart
        self._where = where
        self.backend.open(self.draw_list, title, hud.key_map(self))
        if self._record_path is not None:
            try:
                self._open_recorder(self._record_path)
            except BaseException:
                self.backend.close()
                raise

    # ------------------------------------------------------------------ recording
    def _open_recorder(self, path: Path) -> None:
        from ..io.outputs import open_recording
        from ..io.protocol import write_frame

        self.recorder = open_recording(path, self.sim, self._where)
        write_frame(self.recorder, self.frame)
        self.takes.append(path)
        self.say(f"recording to {path}")

    def _write(self, frame: Frame) -> None:
        if self.recorder is None:
            return
        from ..io import OutputWriteError
        from ..io.protocol import write_frame

        try:
            write_frame(self.recorder, frame)
        except OutputWriteError as err:
            self.recorder = None
            self._fail(str(err))

    def _close_recorder(self) -> None:
        from ..io import OutputWriteError

        recorder, self.recorder = self.recorder, None
        if recorder is not None:
            try:
                recorder.close()
            except OutputWriteError as err:
                self._fail(str(err))

    def _fail(self, message: str) -> None:
        self.error = message
        self.paused = True
        self.say(f"warpsim view: error: {message}")

    # ------------------------------------------------------------------ controls
    def _held_axis(self, held, minus: str, plus: str) -> float:
        return float((plus in held) - (minus in held))

    def _controls_at_frame_start(self, index: int) -> None:
        """Set the keyboard's controls for the frame about to be stepped (see Simulation.advance)."""
        held = self.backend.held()
        self.backend.applied(index, held)
        values: dict = {}
        for b in self.axis_keys:
            value = _towards(self.axes[b.control], self._held_axis(held, b.minus, b.plus), b.rate * self.frame_interval)
            if value != self.axes[b.control]:  # keys that do not move an axis leave a schedule's value alone
                self.axes[b.control] = value
                values[b.control] = value
        if self.walk_keys is not None:
            b = self.walk_keys
            forward = self._held_axis(held, b.back, b.forward)
            right = self._held_axis(held, b.left, b.right)
            if forward or right:
                anchor = np.asarray(self._anchor(), dtype=np.float64)
                ahead = self._bearing(anchor)
                side = np.array([ahead[1], -ahead[0]])
                move = (forward * ahead + right * side) * b.speed * self.frame_interval
                values[b.control] = tuple(float(v) for v in anchor + move)
        for key, sign in (("PLUS", 1.0), ("MINUS", -1.0)):
            # a press asks once (its event, :meth:`_handle`); a key held on (a page's: the window's + comes as
            # repeated presses) keeps asking once held longer than WIND_HOLD, as a keyboard's auto-repeat would
            self._held_frames[key] = self._held_frames[key] + 1 if key in held else 0
            if self._held_frames[key] * self.frame_interval > self.WIND_HOLD + 1e-9:
                self._nudge_wind(sign)
        if self._wind_goal is not None:
            w = np.asarray(self._pending_wind if self._pending_wind is not None else self.wind(), dtype=np.float64)
            speed = float(np.hypot(w[0], w[1]))
            heading = self._heading(w)
            speed = _towards(speed, self._wind_goal, self.WIND_RATE * self.frame_interval)
            if abs(speed - self._wind_goal) < 1e-9:
                self._wind_goal = None
            self._pending_wind = (speed * math.cos(heading), speed * math.sin(heading), float(w[2]))
        if self._pending_wind is not None:
            values["wind"], self._pending_wind = self._pending_wind, None
        if values:
            self.sim.set_controls(**values)

    def _anchor(self) -> tuple[float, float]:
        """Where the walked line is anchored now (x, y) [m] (see :class:`~warpsim.objects.keys.WalkKeys`)."""
        if self.walk_keys.control in self.sim.controls:
            return self.sim.controls[self.walk_keys.control]
        target = self.sim.control.nail_target.numpy()[self.walk_keys.nail(self.walked)]
        return float(target[0]), float(target[1])

    def _bearing(self, anchor: np.ndarray) -> np.ndarray:
        """Unit horizontal vector from the anchor towards the walked object (downwind when right above it)."""
        d = self.frame.positions[self.walk_keys.towards(self.walked)].mean(axis=0)[:2] - anchor
        if np.linalg.norm(d) < 1e-3:
            d = self.wind()[:2]
        n = np.linalg.norm(d)
        return d / n if n > 1e-9 else np.array([1.0, 0.0])

    def wind(self) -> np.ndarray:
        """The wind the scene blows now (the mean, with gusts) [m/s]."""
        if "wind" in self.sim.controls:
            return np.asarray(self.sim.controls["wind"], dtype=np.float64)
        return np.asarray(self.sim.settings.wind.velocity, dtype=np.float64)

    def _heading(self, wind, default: float | None = None) -> float:
        """The direction [rad, anticlockwise from +x] ``wind`` blows towards; a calm keeps the last one seen (or
        ``default``), so that the wind comes back from where it was."""
        x, y = float(wind[0]), float(wind[1])
        if math.hypot(x, y) > 1e-9:
            self._wind_heading = math.atan2(y, x)
            return self._wind_heading
        return self._wind_heading if default is None else default

    def _nudge_wind(self, sign: float) -> None:
        """+ (``sign`` 1) or - (-1): ask for WIND_STEP more or less wind, unless what is asked for already runs
        WIND_LEAD ahead of the wind; never below calm, and + never above :attr:`wind_limit` (nor lowers a wind a
        schedule took beyond it)."""
        w = self._pending_wind if self._pending_wind is not None else self.wind()
        speed = float(np.hypot(w[0], w[1]))
        goal = speed if self._wind_goal is None else self._wind_goal
        if sign * (goal - speed) + self.WIND_STEP <= self.WIND_LEAD + 1e-9:
            limit = max(self.wind_limit, goal)
            self._wind_goal = min(max(goal + sign * self.WIND_STEP, 0.0), limit)

    def _change_wind(self, turn: float = 0.0) -> None:
        """Turn the wind by ``turn`` [deg] (anticlockwise seen from above) at the next frame start."""
        w = self._pending_wind if self._pending_wind is not None else tuple(self.wind())
        x, y, z = w
        speed = math.hypot(x, y)
        heading = self._heading(w) + math.radians(turn)
        self._wind_heading = heading  # kept through a calm
        self._pending_wind = (speed * math.cos(heading), speed * math.sin(heading), z)

    # ------------------------------------------------------------------ events
    def _handle(self, event: tuple) -> None:
        kind = event[0]
        if kind == "close":
            self.quit = True
        elif kind == "drag":
            self.camera = "orbit"
            self.orbit["azimuth"] -= 0.3 * event[1]
            self.orbit["elevation"] = min(max(self.orbit["elevation"] - 0.3 * event[2], -5.0), 89.0)
        elif kind == "scroll":
            self.orbit["distance"] = min(max(self.orbit["distance"] * 0.9 ** event[1], 1.0), 5000.0)
        elif kind == "press":
            key = event[1]
            if key in ("ESCAPE", "Q"):
                self.quit = True
            elif key == "SPACE":
                self.paused = not self.paused
                self._debt = 0.0
            elif key == ".":
                self.paused = True
                self._one_frame = True
            elif key == "R":
                self.restart()
            elif key == "C":
                self.camera = CAMERAS[(CAMERAS.index(self.camera) + 1) % len(CAMERAS)]
            elif key in ("H", "?"):
                self.show_help = not self.show_help
            elif key == "PLUS":
                self._nudge_wind(1.0)
            elif key == "MINUS":
                self._nudge_wind(-1.0)
            elif key == "[":
                self._change_wind(turn=self.WIND_TURN)
            elif key == "]":
                self._change_wind(turn=-self.WIND_TURN)

    def restart(self) -> None:
        """Back to the initial state and controls; a recording goes on in a new take file."""
        if self._record_path is not None:
            self._close_recorder()  # before the state goes back: its checkpoint is of the last frame flown
        self.sim.restore(self.initial)
        self._frames = self.sim.frames(before=self._controls_at_frame_start)
        self.frame = next(self._frames)
        self.axes = {b.control: 0.0 for b in self.axis_keys}
        self._pending_wind = self._wind_goal = None
        self._held_frames = dict.fromkeys(self._held_frames, 0)
        self._wind_heading = self._initial_heading
        self._debt, self.error, self.paused, self.blew_up = 0.0, "", False, False
        self._restarted = True  # the wall time of the tick that restarts is not owed to the new run
        if self._record_path is not None:
            p, take = self._record_path, len(self.takes) + 1
            try:
                self._open_recorder(p.with_name(f"{p.stem}.take{take}{p.suffix}"))
            except Exception as err:  # noqa: BLE001 - shown, and flying goes on without a recording
                self._fail(f"cannot record take {take}: {err}")

    # ------------------------------------------------------------------ stepping
    def advance(self) -> bool:
        """Step one frame with the keyboard's controls, record it; False (and paused) after a blow-up."""
        started = time.perf_counter()
        try:
            if self._frames is None:  # after a blow-up or an error: on from the state as it is
                self._frames = self.sim.frames(before=self._controls_at_frame_start)
                next(self._frames)
            self.frame = next(self._frames)
        except BlowUpError as err:
            self._frames = None  # the iterator has ended with it: the next frame comes from a new one
            self.frame = self.sim.frame(err.last_good_frame)
            self.blew_up = True
            self._fail(f"{err}; press R to restart")
            return False
        except BaseException:  # Ctrl-C, an error of the keys: the same, and it goes on up
            self._frames = None
            raise
        finally:
            self.step_time += time.perf_counter() - started
        self._write(self.frame)
        if self.seconds is not None and self.sim.state.time >= self.seconds - 1e-9:
            self.quit = True
        return True

    def tick(self, now: float | None = None) -> bool:
        """Read events, step what wall time asks (all of it within :attr:`BUDGET`, else fall behind and say
        so), draw. ``now``: the wall clock [s] (default ``time.perf_counter()``; tests pass their own).
        Returns False once the viewer should close."""
        now = time.perf_counter() if now is None else now
        elapsed = 0.0 if self._last is None else max(now - self._last, 0.0)
        self._last = now
        self._restarted = False
        for event in self.backend.events():
            self._handle(event)
        if self._restarted:
            elapsed = 0.0
        if self.backend.closed:
            self.quit = True
        if self.quit:
            return False
        if self.paused:
            if self._one_frame:
                self.advance()
            self._one_frame = False
            self._debt = 0.0
        else:
            self._debt += elapsed
            started = time.perf_counter()
            while self._debt >= self.frame_interval * (1 - 1e-6) and not self.quit:
                if not self.advance():
                    break
                self._debt -= self.frame_interval
                if time.perf_counter() - started > self.BUDGET:
                    break
            self.behind = self._debt > 2 * self.frame_interval
            if self.behind:
                self._debt = 0.0  # slow down instead of owing ever more: simulated time falls behind the wall
        self._rate.append((now, self.sim.state.time, self.sim.steps_taken))
        while len(self._rate) > 2 and now - self._rate[0][0] > 1.0:
            self._rate.pop(0)
        started = time.perf_counter()
        self.points = self.draw_list.place(self.frame.positions)
        self.backend.draw(self.points, self.view(), self.hud(), self.overlay())
        self.draw_time += time.perf_counter() - started
        self.pictures += 1
        return not self.quit

    def hold_clock(self) -> None:
        """The wall time until the next tick is not owed to the flight (after a wait in which nothing was to be
        flown: the browser view with no page connected)."""
        self._last = None

    def paced_tick(self) -> bool:
        """:meth:`tick` on the wall clock, then sleep what is left of a picture's share (:attr:`MAX_FPS`)."""
        started = time.perf_counter()
        going = self.tick()
        spare = 1.0 / self.MAX_FPS - (time.perf_counter() - started)
        if going and spare > 0:
            time.sleep(spare)
        return going

    def run(self) -> None:
        """Tick until the user quits (or ``seconds`` have been simulated), then close the recording and window."""
        try:
            while self.paced_tick():
                pass
        finally:
            self.close()

    def close_recording(self) -> None:
        """Close the recording now (its frames are kept), leaving the window alone: what is left to do when the
        display itself has gone (the window can no longer be closed)."""
        self._close_recorder()

    def close(self) -> None:
        """Close the recording (its frames are kept) and the window."""
        self._close_recorder()
        self.backend.close()

    # ------------------------------------------------------------------ camera and text
    def centre(self) -> np.ndarray:
        """Centre of the bounding box of the particles the camera frames [m] (``DrawList.focus``)."""
        return camera.centre(self)

    def view(self) -> View:
        """The camera of the current mode."""
        return camera.view(self)

    def rates(self) -> tuple[float, float]:
        """(real-time factor, steps per wall second) over the last second of ticks."""
        return hud.rates(self)

    def hud(self) -> list[str]:
        """The heads-up lines: time and rates, each object's flight figures, the controls in force."""
        return hud.hud_lines(self)

    def overlay(self) -> list[str]:
        """The lines shown in the middle: an error, else the key map while help is on."""
        return hud.overlay_lines(self)
