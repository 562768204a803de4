"""Make docs/browser.png: the hang glider as the browser view's page draws it, in headless Chromium at 1280x720.

    python docs/browser_screenshot.py

The glider is flown by the viewer on a clock of one frame interval per tick (so the picture does not depend on the
machine's speed): the right arrow held from 2 to 4 s, as the page sends it, then hands off to 5 s, chase camera.
The page is opened and shown the last frame, then photographed (needs the browser extra, Playwright for Python
and Debian's chromium).
"""

from __future__ import annotations

import sys
from pathlib import Path

from playwright.sync_api import sync_playwright

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

from viewer_driver import Clock  # noqa: E402

from warpsim.run.simulation import Simulation  # noqa: E402
from warpsim.scene.descriptor import resolve  # noqa: E402
from warpsim.viewer.core import Viewer  # noqa: E402
from warpsim.viewer.web import BrowserBackend  # noqa: E402

ARGS = [
    "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
    "--disable-component-update", "--disable-sync",
]  # fmt: skip


def main() -> Path:
    backend = BrowserBackend("127.0.0.1", 0)
    viewer = Viewer(Simulation(resolve("hang-glider")[0]), backend, "warpsim: hang-glider", say=lambda line: None)
    clock = Clock(viewer)
    viewer.camera = "chase"
    clock.seconds(2.0)
    backend._held = frozenset({"RIGHT"})  # what a page's held right arrow sets
    clock.seconds(2.0)
    backend._held = frozenset()
    clock.seconds(1.0)
    out = HERE / "browser.png"
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path="/usr/bin/chromium", args=ARGS)
        page = browser.new_page(viewport={"width": 1280, "height": 720})
        page.goto(backend.url)
        page.wait_for_function("window.warpsim && window.warpsim.role === 'pilot'")
        clock.ticks(1)  # one more frame, drawn for the page
        page.wait_for_function("window.warpsim.drawn > 0")
        page.wait_for_timeout(500)
        page.screenshot(path=str(out))
        browser.close()
    viewer.close()
    return out


if __name__ == "__main__":
    print(main())
