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
    from warpsim.config import SolverConfig
    from warpsim.kernels.constraints import make_projector

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
