"""Drive the real viewer window on an X display, as a person would, and report what happened as JSON.

Run by tests/test_viewer.py in a subprocess with ``DISPLAY`` set to a virtual X screen (so that an X server
going away never takes the test process with it). Keys are injected with xdotool (XTEST events to the
focused window); the wall clock is the test's own (one frame interval per tick), so that what is stepped
does not depend on how fast the machine draws.

    python tests/viewer_driver.py glider|kite|typed|pictures OUT_DIR
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

from warpsim.objects.hang_glider import bank
from warpsim.physics import _warp
from warpsim.run.simulation import Simulation
from warpsim.scene.descriptor import resolve
from warpsim.scene.dirs import scene_dirs
from warpsim.viewer.core import Viewer
from warpsim.viewer.gl import PygletBackend, view_matrix

SIZE = (640, 360)


def xdotool(*args: str) -> str:
    return subprocess.run(["xdotool", *args], check=True, capture_output=True, text=True, timeout=20).stdout


def open_viewer(scene: str, title: str, record: Path | None):
    descriptor, _, where = resolve(scene, scene_dirs())
    sim = Simulation(descriptor)
    backend = PygletBackend(SIZE, keep_pictures=True)
    viewer = Viewer(sim, backend, title, record, where, say=lambda line: None)
    window = xdotool("search", "--sync", "--name", title).split()[0]
    xdotool("windowfocus", "--sync", window)
    return viewer, backend


class Clock:
    """The wall clock the viewer is given: one frame interval per tick."""

    def __init__(self, viewer):
        self.viewer, self.now = viewer, 0.0
        viewer.tick(self.now)

    def ticks(self, count: int) -> None:
        for _ in range(count):
            self.now += self.viewer.frame_interval
            self.viewer.tick(self.now)

    def seconds(self, simulated: float) -> None:
        self.ticks(int(round(simulated / self.viewer.frame_interval)))


def projected(viewer, point: np.ndarray) -> list[float]:
    """Pixel (column, row from the top) of a world point in the viewer's current view (below the heads-up panel)."""
    w, h = SIZE
    clip = view_matrix(viewer.view(), w, h, viewer.backend.hud_fraction) @ np.append(point, 1.0)
    x, y = clip[:2] / clip[3]
    return [float((x + 1) / 2 * w), float((1 - y) / 2 * h)]


def glider(out: Path) -> dict:
    viewer, backend = open_viewer("hang-glider", "warpsim-test-glider", out / "flown.h5")
    clock = Clock(viewer)
    from PIL import Image

    Image.fromarray(backend.screenshot()).save(out / "first.png")
    glider = viewer.model.objects[0]
    sail = glider.parts["sail"]
    result = {"sail_pixel": projected(viewer, viewer.frame.positions[sail].mean(axis=0))}
    initial = viewer.frame.positions.copy()
    xdotool("keydown", "Right")
    held = []
    for _ in range(int(2.0 / viewer.frame_interval + 1e-9)):
        clock.ticks(1)
        held.append((viewer.sim.state.time, viewer.sim.controls.get("roll", 0.0), bank(glider, viewer.frame.positions)))
    xdotool("keyup", "Right")
    clock.ticks(10)
    result["held"] = held
    result["roll_after_release"] = viewer.sim.controls.get("roll", 0.0)
    xdotool("key", "space")
    clock.ticks(1)
    paused_at = viewer.sim.state.time
    clock.ticks(20)
    result["paused"] = [paused_at, viewer.sim.state.time, viewer.paused]
    xdotool("key", "period")
    clock.ticks(1)
    result["one_frame"] = viewer.sim.state.time - paused_at
    xdotool("key", "r")
    clock.ticks(1)
    result["restart_time"] = viewer.sim.state.time
    result["restart_same"] = bool(np.array_equal(viewer.frame.positions, initial))
    result["takes"] = sorted(p.name for p in out.glob("flown*.h5"))
    result["takes_said"] = [p.name for p in viewer.takes]
    xdotool("key", "Escape")
    result["closed"] = not viewer.tick(clock.now + 0.1)
    viewer.close()
    return result


def kite(out: Path) -> dict:
    viewer, _ = open_viewer("kite", "warpsim-test-kite", None)
    clock = Clock(viewer)
    start = np.array(viewer._anchor())
    xdotool("keydown", "w")
    clock.ticks(int(round(1.0 / viewer.frame_interval)))
    xdotool("keyup", "w")
    clock.ticks(1)
    kite_xy = viewer.frame.positions[viewer.model.objects[0].parts["sail"]].mean(axis=0)[:2]
    result = {"anchor_start": start.tolist(), "anchor_end": list(viewer._anchor()), "kite": kite_xy.tolist()}
    result["time"] = viewer.sim.state.time
    viewer.close()
    return result


def typed(out: Path) -> dict:
    """The wind and help keys typed as a person types them: '+' is shift+= (shift let go first, as xdotool does),
    three times in a row, then '=', the keypad's + and -, '-' twice, '?' twice, '/', '[' and ']' twice; the wind
    speed, whether help shows and the wind's heading [deg] after each."""
    viewer, _ = open_viewer("flag", "warpsim-test-typed", None)
    clock = Clock(viewer)
    steps = []
    keys = ("plus", "plus", "plus", "equal", "KP_Add", "minus", "minus", "KP_Subtract", "question", "question")
    for key in (*keys, "slash", "bracketleft", "bracketright", "bracketright"):
        xdotool("key", key)
        clock.seconds(0.6)  # + and - move the wind 1 m/s in 0.5 s (Viewer.WIND_RATE)
        wind = viewer.wind()
        heading = float(np.degrees(np.arctan2(wind[1], wind[0])))
        steps.append([key, float(np.linalg.norm(wind[:2])), viewer.show_help, heading])
    viewer.close()
    return {"steps": steps}


def _fly(scene: str, title: str, seconds: float, camera: str, overrides: dict | None = None):
    """A viewer of ``scene`` flown hands off for ``seconds`` on the test's clock, with ``camera``."""
    from warpsim.scene.descriptor import merge

    descriptor, _, where = resolve(scene, scene_dirs())
    if overrides:
        descriptor = merge("test", descriptor, overrides)
    backend = PygletBackend(SIZE, keep_pictures=True)
    viewer = Viewer(Simulation(descriptor), backend, title, None, where, say=lambda line: None)
    viewer.camera = camera
    Clock(viewer).seconds(seconds)
    return viewer, backend


def pictures(out: Path) -> dict:
    """Screenshots of what the viewer draws besides cloth, with where the drawn parts project (pixels)."""
    from PIL import Image

    from warpsim.objects.drawing import BODY

    result = {}

    def save(name, viewer, backend, **points):
        Image.fromarray(backend.screenshot()).save(out / f"{name}.png")
        result[name] = {key: projected(viewer, np.asarray(p, dtype=float)) for key, p in points.items()}
        result[name]["panel_height"] = backend.hud_fraction * SIZE[1]
        viewer.close()

    viewer, backend = _fly("flag", "warpsim-test-flag", 1.0, "orbit")
    pole = viewer.model.objects[0].parts["pole"]
    q = viewer.points
    foot = q[pole].mean(axis=0) * [1, 1, 0]  # the terrain under the flag is flat at 0
    save("flag", viewer, backend, pole_low=foot + [0, 0, 0.5], pole_mid=foot + [0, 0, 1.5])

    viewer, backend = _fly("kite", "warpsim-test-kite-ground", 3.0, "ground")
    kite = viewer.model.objects[0]
    q = viewer.points
    rope = kite.curves["rope"][0]
    points = {f"line_{k}": q[rope[int(k * (len(rope) - 1) / 10)]] for k in range(2, 9)}
    save("kite", viewer, backend, sail=q[kite.parts["sail"]].mean(axis=0), horizon=viewer.view().eye + [1e4, 0, 0],
         **points)  # fmt: skip

    viewer, backend = _fly("hang-glider", "warpsim-test-glider-side", 0.5, "orbit")
    viewer.orbit.update(azimuth=-100.0, elevation=-3.0)
    viewer.tick(viewer._last)  # draw again from the side (no time passes)
    glider = viewer.model.objects[0]
    q = viewer.points
    hang, left, _ = glider.parts["control_frame"]
    fwd = q[glider.nose] - q[glider.keel[-1]]
    fwd /= np.linalg.norm(fwd)
    upright = {f"upright_{k}": q[hang] + k / 10 * (q[left] - q[hang]) for k in range(3, 9)}
    save("glider", viewer, backend, head=q[glider.pilot] + BODY["head"] * fwd,
         harness=q[glider.pilot] - 0.25 * fwd, **upright)  # fmt: skip

    viewer, backend = _fly("flag", "warpsim-test-worlds", 1.0, "orbit", {"worlds": {"count": 2}})
    q = viewer.points
    centres = {
        f"world_{w}": q[np.flatnonzero(viewer.model.particle_world_np == w)].mean(axis=0)
        for w in range(viewer.model.world_count)
    }
    save("worlds", viewer, backend, **centres)
    return result


if __name__ == "__main__":
    _warp.init()
    scenario, out = sys.argv[1], Path(sys.argv[2])
    result = {"glider": glider, "kite": kite, "typed": typed, "pictures": pictures}[scenario](out)
    (out / f"{scenario}.json").write_text(json.dumps(result))
