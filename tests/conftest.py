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


@pytest.fixture(scope="session")
def device():
    """Tests run on Warp's CPU device (the default everywhere); CUDA is checked separately when present."""
    return "cpu"


def worst_elongation(model, positions) -> float:
    """Largest relative lengthening of any stick."""
    return float(model.stick_stretch(positions).max())


@pytest.fixture
def rng():
    return np.random.default_rng(1234)
