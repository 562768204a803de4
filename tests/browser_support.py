"""What test_browser.py and test_browser_page.py share: the browser viewer of a scene on a free port, a flight
stepped in a thread, and the check that aiohttp, Playwright and Chromium are here (or a skip, or a failure in CI)."""

from __future__ import annotations

import importlib.util
import os
import shutil
import sys
import threading
from pathlib import Path

import pytest

from warpsim.run.simulation import Simulation
from warpsim.scene.descriptor import merge, resolve, to_toml
from warpsim.scene.dirs import scene_dirs
from warpsim.viewer import Viewer

sys.path.insert(0, str(Path(__file__).parent))


CHROMIUM = "/usr/bin/chromium"


CHROMIUM_ARGS = [
    "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
    "--disable-component-update", "--disable-sync",
]  # fmt: skip


def _require(*what: str) -> None:
    missing = [name for name in what if importlib.util.find_spec(name) is None]
    if "chromium" in what:
        missing = [m for m in missing if m != "chromium"] + ([] if shutil.which(CHROMIUM) else ["chromium"])
    if missing:
        if os.environ.get("WARPSIM_REQUIRE_DISPLAY_TESTS") == "1":
            pytest.fail(f"browser tests need {', '.join(missing)} (WARPSIM_REQUIRE_DISPLAY_TESTS=1)")
        pytest.skip(f"needs {', '.join(missing)}")


def _sim(scene: str, **overrides) -> tuple[Simulation, str, str]:
    descriptor, _, where = resolve(scene, scene_dirs())
    if overrides:
        descriptor = merge("test", descriptor, overrides)
    return Simulation(descriptor), to_toml(descriptor), where


def _browser_viewer(scene: str, seconds=None, record=None, host="127.0.0.1", **overrides):
    from warpsim.viewer.web import BrowserBackend

    sim, text, where = _sim(scene, **overrides)
    backend = BrowserBackend(host, 0)
    viewer = Viewer(sim, backend, f"warpsim: {where}", record, where, seconds=seconds, say=lambda line: None)
    return viewer, backend


class _Flying:
    """A viewer flown at wall-clock pace on its own thread (as ``warpsim view --browser`` flies it)."""

    def __init__(self, viewer):
        self.viewer = viewer
        self.thread = threading.Thread(target=viewer.run, daemon=True)

    def __enter__(self):
        self.thread.start()
        return self

    def __exit__(self, *exc):
        self.viewer.quit = True
        self.thread.join(30)
        assert not self.thread.is_alive()
