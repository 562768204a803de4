"""The viewer's own rate: ``warpsim view`` as a user gets it (real clock, 60 fps cap), per built-in scene.

Run by the ``viewer`` benchmark case in a subprocess on an X display (a virtual one when the machine has
none)::

    python -m benchmarks.viewer SECONDS WIDTHxHEIGHT [SCENE WORLDS THREADS]

prints one JSON object: per scene (every built-in one, or SCENE with WORLDS batched worlds stepped by THREADS
threads), pictures per wall second, real-time factor (simulated / wall seconds), the
shares of the wall time spent stepping and drawing, and the OpenGL renderer.
"""

from __future__ import annotations

import json
import sys
import time

from warpsim.physics import _warp
from warpsim.run.simulation import Simulation
from warpsim.scene.descriptor import merge, resolve
from warpsim.viewer.core import Viewer
from warpsim.viewer.gl import PygletBackend

SCENES = ("flag", "hang-glider", "kite", "parachute")


def measure(scene: str, seconds: float, size: tuple[int, int], worlds: int = 1, threads: int = 1) -> dict:
    """Fly ``scene`` (``worlds`` batched worlds stepped by ``threads`` threads) hands off for ``seconds`` of wall
    time after one warm-up second; the rates."""
    desc = resolve(scene)[0]
    if worlds > 1:
        desc = merge("benchmark", desc, {"worlds": {"count": worlds}})
    sim = Simulation(desc, threads=threads)
    viewer = Viewer(sim, PygletBackend(size), f"warpsim benchmark {scene}", say=lambda line: None)
    try:
        end = time.perf_counter() + 1.0
        while time.perf_counter() < end:  # warm-up: first pictures, graph capture
            viewer.paced_tick()
        t0, pictures0, step0, draw0 = sim.state.time, viewer.pictures, viewer.step_time, viewer.draw_time
        start = time.perf_counter()
        while time.perf_counter() - start < seconds:
            viewer.paced_tick()  # as `warpsim view` ticks
        wall = time.perf_counter() - start
        from pyglet import gl

        return {
            "fps": (viewer.pictures - pictures0) / wall,
            "realtime_factor": (sim.state.time - t0) / wall,
            "step_share": (viewer.step_time - step0) / wall,
            "draw_share": (viewer.draw_time - draw0) / wall,
            "renderer": gl.gl_info.get_renderer(),
        }
    finally:
        viewer.close()


if __name__ == "__main__":
    _warp.init()
    seconds = float(sys.argv[1])
    width, height = (int(v) for v in sys.argv[2].split("x"))
    if len(sys.argv) > 3:
        scene, worlds, threads = sys.argv[3], int(sys.argv[4]), int(sys.argv[5])
        print(json.dumps({scene: measure(scene, seconds, (width, height), worlds, threads)}))
    else:
        print(json.dumps({scene: measure(scene, seconds, (width, height)) for scene in SCENES}))
