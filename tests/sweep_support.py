"""What the sweep tests share: the gusty kite's 2 x 3 sweep, its plan and command line, a local Dask cluster and
the rows of every case run in this process (the reference the cluster's rows must equal bit for bit). Its
fixtures (``cluster``, ``reference``) reach every test module through ``tests/conftest.py``'s plugins."""

from __future__ import annotations

import sys

import pytest

from warpsim import Scene, sweeps
from warpsim.scene import descriptor as desc_mod

SECONDS = 12.0  # each case; the window is its second half

AXES = ["wind.gust_seed=1,2", "kite.tow_point=0.25,0.3,0.35"]  # 2 x 3 cases, gusty: each case its own gusts


def _scene() -> dict:
    return desc_mod.merge("test", desc_mod.defaults("kite"), {"wind": {"gust_intensity": 0.25}})


def _plan(seconds: float = SECONDS) -> sweeps.SweepPlan:
    d = _scene()
    return sweeps.SweepPlan(Scene(d), sweeps.parse_axes(Scene(d), AXES), seconds)


@pytest.fixture(scope="module")
def cluster():
    """A local Dask cluster of two single-threaded worker processes (a nanny restarts one that dies)."""
    import logging

    from dask.distributed import Client, LocalCluster

    with (
        LocalCluster(
            n_workers=2,
            threads_per_worker=1,
            processes=True,
            dashboard_address="127.0.0.1:0",
            silence_logs=logging.CRITICAL,
        ) as local,
        Client(local) as client,
    ):
        yield client


@pytest.fixture(scope="module")
def reference():
    """The 6 rows, every case run in this process as one chunk of 6 worlds (no Dask)."""
    import pandas as pd

    plan = _plan()
    (task,) = plan.chunks(6)
    return pd.DataFrame(sweeps.run_chunk(task), columns=plan.columns)


def _same(table, reference):
    import pandas as pd

    pd.testing.assert_frame_equal(
        table.reset_index(drop=True), reference.reset_index(drop=True), check_exact=True, check_dtype=False
    )


def _cli(tmp_path, *extra, workers: int = 2) -> list[str]:
    vary = sum((["--vary", a] for a in AXES), [])
    return [
        sys.executable,
        "-m",
        "warpsim",
        "sweep",
        "kite",
        "--set",
        "wind.gust_intensity=0.25",
        *vary,
        "--seconds",
        str(SECONDS),
        "--workers",
        str(workers),
        "--chunk",
        "1",
        "--out",
        str(tmp_path / "s.parquet"),
        *extra,
    ]
