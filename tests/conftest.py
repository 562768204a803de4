import contextlib
import os

import numpy as np
import pytest
import warp as wp
from hypothesis import settings

# CI explores the same examples on every run (a red CI names a reproducible input); locally each run explores anew
settings.register_profile("ci", derandomize=True, database=None)
if os.environ.get("CI"):
    settings.load_profile("ci")

wp.config.log_level = wp.LOG_WARNING

pytest_plugins = ["sweep_support"]  # the sweep tests' fixtures (a local Dask cluster, the reference rows)


def pytest_configure(config):
    """With worker processes (``-n auto``, pytest-xdist), the controller compiles every kernel module into Warp's
    cache before the workers start: on a cold cache the workers would otherwise compile the same modules side by
    side, inside tests that time a simulation's start-up."""
    if getattr(config, "workerinput", None) is not None or not config.getoption("numprocesses", default=None):
        return
    from warpsim.physics import kernels
    from warpsim.physics.kernels import frame
    from warpsim.physics.solver import load_modules

    load_modules((*kernels.MODULES, frame), "cpu")


DEVICES = ["cpu"] + (["cuda"] if wp.is_cuda_available() else [])
"""Every Warp device of this machine: tests taking ``device`` run on each (CUDA runs the gather scheme and graph
capture on a GPU)."""


@pytest.fixture(scope="session", params=DEVICES)
def device(request):
    return request.param


@pytest.fixture(scope="session")
def project():
    """``project(model, state, control, iterations, scheme=None, **settings)``: one Jacobi projection of
    ``iterations`` on ``state`` in place, with a :class:`warpsim.SolverConfig` made of ``settings`` (plain Jacobi,
    ``chebyshev=0``, unless given)."""
    from warpsim.physics.config import SolverConfig
    from warpsim.physics.projection import make_projector

    def run(model, state, control, iterations, scheme=None, **settings):
        config = SolverConfig(**{"chebyshev": 0.0, **settings})
        make_projector(model, config, scheme).project(state, control, iterations)

    return run


def worst_elongation(model, positions) -> float:
    """Largest relative lengthening of any stick."""
    return float(model.stick_stretch(positions).max())


@pytest.fixture
def rng():
    return np.random.default_rng(1234)


FUZZ_EXAMPLE_SECONDS = float(os.environ.get("WARPSIM_FUZZ_EXAMPLE_SECONDS", "20"))
"""Wall seconds one fuzz example may take before its watchdog interrupts it like Ctrl-C (a legitimate
`run hang-glider --seconds 1e9` drawn from the token lists ran for 49 minutes); six times as long ends the whole
test run with a stack dump of every thread (a hang that Ctrl-C cannot end)."""


class Watchdog:
    """What :func:`fuzz_watchdog` yields: ``fired`` is True once it interrupted the example."""

    fired = False


@contextlib.contextmanager
def fuzz_watchdog(seconds: float = FUZZ_EXAMPLE_SECONDS):
    """Bound one fuzz example: after ``seconds`` SIGINT reaches this process, as Ctrl-C would (a run stops after
    its frame and exits 130, a start-up raises ``KeyboardInterrupt``); after ``6 * seconds`` faulthandler dumps
    every thread's stack and exits. A ``KeyboardInterrupt`` the watchdog caused ends the block quietly; the caller
    treats an example the watchdog interrupted as one that ran too long, not as a failure (``Watchdog.fired``)."""
    import faulthandler
    import signal
    import threading

    dog = Watchdog()

    def fire():
        dog.fired = True
        os.kill(os.getpid(), signal.SIGINT)

    timer = threading.Timer(seconds, fire)
    timer.daemon = True
    faulthandler.dump_traceback_later(6 * seconds, exit=True)
    timer.start()
    try:
        try:
            yield dog
        finally:
            timer.cancel()
            timer.join()  # a SIGINT sent before the cancel is handled here at the latest
    except KeyboardInterrupt:
        if not dog.fired:
            raise
    finally:
        faulthandler.cancel_dump_traceback_later()
