"""The browser view's rates: ``warpsim view SCENE --browser`` watched by a page in headless Chromium.

Run by the ``browser`` benchmark case in a subprocess (Debian's ``chromium`` driven by Playwright for Python)::

    python -m benchmarks.browser SECONDS WIDTHxHEIGHT [SCENE ...]

prints one JSON object: per scene (glider, kite, parachute, flag-64, 16 kites), the pictures the page drew and
received per wall second, the bytes it received per second, the share of its pixels it drew at (the page lowers
its resolution when it cannot draw every picture), the server's pictures per second and real-time factor, and
the WebGL renderer. The simulation, the server and Chromium share the machine's cores, as they do for a user
running all three on one computer.
"""

from __future__ import annotations

import json
import sys
import threading
import time

from warpsim.physics import _warp
from warpsim.run.simulation import Simulation
from warpsim.viewer.core import Viewer
from warpsim.viewer.web import BrowserBackend

from .suite import flag, scene

CHROMIUM = "/usr/bin/chromium"
ARGS = [
    "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
    "--disable-component-update", "--disable-sync",
]  # fmt: skip

SCENES = {
    "hang-glider": lambda: scene("hang-glider"),
    "kite": lambda: scene("kite"),
    "parachute": lambda: scene("parachute"),
    "flag-64": lambda: flag(64),
    "kites-16": lambda: scene("kite", {"worlds": {"count": 16}}),
}


def measure(browser, name: str, seconds: float, size: tuple[int, int], warm_up: float = 6.0) -> dict:
    """Serve ``name`` and watch it in a new page of ``browser`` for ``seconds`` of wall time after ``warm_up``
    seconds (first pictures, kernel builds, the page settling its resolution); the rates."""
    sim = Simulation(SCENES[name]())
    backend = BrowserBackend("127.0.0.1", 0)
    viewer = Viewer(sim, backend, f"warpsim benchmark {name}", say=lambda line: None)
    thread = threading.Thread(target=viewer.run, daemon=True)
    thread.start()
    page = browser.new_page(viewport={"width": size[0], "height": size[1]})
    try:
        page.goto(backend.url)
        page.wait_for_function("window.warpsim && window.warpsim.drawn > 0", timeout=60000)
        time.sleep(warm_up)
        read = "[warpsim.pictures, warpsim.drawn, warpsim.bytes, performance.now()]"
        p0, d0, b0, w0 = page.evaluate(read)
        t0, pictures0 = sim.state.time, viewer.pictures
        start = time.perf_counter()
        time.sleep(seconds)
        p1, d1, b1, w1 = page.evaluate(read)
        wall = time.perf_counter() - start
        t1, pictures1 = sim.state.time, viewer.pictures
        renderer = page.evaluate(
            "(() => { const g = document.createElement('canvas').getContext('webgl2');"
            " const i = g && g.getExtension('WEBGL_debug_renderer_info');"
            " return i ? g.getParameter(i.UNMASKED_RENDERER_WEBGL) : 'unknown'; })()"
        )
        page_wall = (w1 - w0) / 1000.0
        return {
            "page_fps": (d1 - d0) / page_wall,
            "received_fps": (p1 - p0) / page_wall,
            "bytes_per_s": (b1 - b0) / page_wall,
            "resolution": page.evaluate("warpsim.resolution"),
            "server_fps": (pictures1 - pictures0) / wall,
            "realtime_factor": (t1 - t0) / wall,
            "points": int(len(viewer.points)),
            "renderer": renderer,
        }
    finally:
        page.close()
        viewer.quit = True
        thread.join(30)


def main(argv: list[str]) -> dict:
    from playwright.sync_api import sync_playwright

    seconds = float(argv[0])
    width, height = (int(v) for v in argv[1].split("x"))
    names = argv[2:] or list(SCENES)
    _warp.init()
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        try:
            return {name: measure(browser, name, seconds, (width, height)) for name in names}
        finally:
            browser.close()


if __name__ == "__main__":
    print(json.dumps(main(sys.argv[1:])))
