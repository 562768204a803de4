"""Drive the real viewer window on an X display, as a person would, and report what happened as JSON.

Run by tests/test_viewer.py in a subprocess with ``DISPLAY`` set to a virtual X screen (so that an X server
going away never takes the test process with it). Keys are injected with xdotool (XTEST events to the
focused window); the wall clock is the test's own (one frame interval per tick), so that what is stepped
does not depend on how fast the machine draws.

    python tests/viewer_driver.py glider|kite OUT_DIR
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

from warpsim import _warp
from warpsim.cli import scene_dirs
from warpsim.descriptor import resolve, to_toml
from warpsim.objects.hang_glider import bank
from warpsim.runner import Simulation
from warpsim.viewer.core import Viewer
from warpsim.viewer.gl import PygletBackend, view_matrix

SIZE = (640, 360)


def xdotool(*args: str) -> str:
    return subprocess.run(["xdotool", *args], check=True, capture_output=True, text=True, timeout=20).stdout


def open_viewer(scene: str, title: str, record: Path | None):
    descriptor, _, where = resolve(scene, scene_dirs())
    sim = Simulation(descriptor)
    backend = PygletBackend(SIZE, keep_pictures=True)
    viewer = Viewer(sim, backend, title, record, to_toml(descriptor), where, say=lambda line: None)
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


if __name__ == "__main__":
    _warp.init()
    scenario, out = sys.argv[1], Path(sys.argv[2])
    result = {"glider": glider, "kite": kite}[scenario](out)
    (out / f"{scenario}.json").write_text(json.dumps(result))
