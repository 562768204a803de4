"""Make the viewer's screenshots in docs/ on a virtual X screen (needs Xvfb and the viewer extra).

    python docs/screenshots.py [NAME ...]      # default: every one; NAME as in SHOTS

Each opens ``warpsim view``'s window (PygletBackend) on its own Xvfb, flies the scene hands off for the seconds
given on a clock of one frame interval per tick (so what is shown does not depend on the machine's speed), sets
the camera (and the orbit's angles and distance) and saves the last picture as docs/viewer_NAME.png ("turn":
the glider flown with the right arrow held from 4 to 7 s, then hands off, at 8 s, chase camera, as
docs/viewer.png).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent

SHOTS = {
    # name: (scene, seconds, camera, orbit (azimuth [deg], elevation [deg], distance factor) or None, settings)
    "hang_glider": ("hang-glider", 3.0, "orbit", (-125.0, -5.0, 0.8), {}),
    "kite": ("kite", 8.0, "ground", None, {}),
    "flag": ("flag", 3.0, "orbit", None, {}),
    "parachute": ("parachute", 3.0, "orbit", None, {}),
    "turn": ("hang-glider", 8.0, "chase", None, {}),
    "worlds": (
        "kite",
        8.0,
        "orbit",
        (-150.0, 8.0, 0.7),
        {"worlds": {"count": 4, "wind": {"speed": [4.0, 6.0, 8.0, 10.0]}}},
    ),
}
KEYS = {"turn": [(4.0, "on_key_press", "RIGHT"), (7.0, "on_key_release", "RIGHT")]}
"""Keys pressed and released in a shot's window at a simulated time [s]: the turn is flown with the right arrow,
through the window's own key handlers, as a pilot at the keyboard flies it."""
OUTPUT = {"turn": "viewer.png"}  # the others: viewer_NAME.png
SIZE = (1280, 720)


def shoot(name: str) -> Path:
    """Fly shot ``name`` in a window on the current display and save its last picture."""
    import pyglet

    from warpsim.io.render import save_png
    from warpsim.physics import _warp
    from warpsim.run.simulation import Simulation
    from warpsim.scene.descriptor import merge, resolve
    from warpsim.scene.dirs import scene_dirs
    from warpsim.viewer.core import Viewer
    from warpsim.viewer.gl import PygletBackend

    _warp.init()
    scene, seconds, camera, angles, extra = SHOTS[name]
    descriptor, _, where = resolve(scene, scene_dirs())
    if extra:
        descriptor = merge("screenshot", descriptor, extra)
    backend = PygletBackend(SIZE, keep_pictures=True)
    viewer = Viewer(Simulation(descriptor), backend, f"warpsim: {where}", None, where)
    viewer.camera = camera
    if angles is not None:
        viewer.orbit["azimuth"], viewer.orbit["elevation"], zoom = angles
        viewer.orbit["distance"] *= zoom
    keys = list(KEYS.get(name, []))
    now = 0.0
    viewer.tick(now)
    for _ in range(int(round(seconds / viewer.frame_interval))):
        now += viewer.frame_interval
        while keys and keys[0][0] <= now + 1e-9:
            _, event, key = keys.pop(0)
            backend.window.dispatch_event(event, getattr(pyglet.window.key, key), 0)
        viewer.tick(now)
    out = save_png(HERE / OUTPUT.get(name, f"viewer_{name}.png"), backend.screenshot())
    viewer.close()
    return out


if __name__ == "__main__":
    names = sys.argv[1:] or list(SHOTS)
    if os.environ.get("WARPSIM_SCREENSHOT_CHILD"):
        for name in names:
            print(shoot(name))
    else:
        from warpsim.viewer.xvfb import virtual_display

        with virtual_display(SIZE) as env:
            env = {**env, "WARPSIM_SCREENSHOT_CHILD": "1"}
            subprocess.run([sys.executable, __file__, *names], env=env, check=True)
