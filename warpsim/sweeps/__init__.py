"""Sweeps: every combination of a few settings of one scene, run over every core and over machines with Dask.

A *case* is one combination of the swept values (the cartesian product of the axes, first axis slowest). Cases
are cut into *chunks*; a chunk runs as one :class:`~warpsim.run.simulation.Simulation` whose worlds are its cases (the
batched worlds of ``--worlds``, one launch for all), and each chunk is one Dask task. The cluster is a
``LocalCluster`` of single-threaded worker processes, one per core, unless a running scheduler is given.

Every case gives one row: its swept values and its metrics (:data:`METRICS`, from the same
:class:`warpsim.run.figures.Figures` the viewer's heads-up display reads). Worlds never touch each other
and each world's gusts are seeded by its own ``wind.gust_seed``, so a case's row is bit for bit the same
whatever the chunk size, the number of workers or the order they finish in. A case that blows up stops being
measured at that frame and is a row saying when and why; the other cases of its chunk go on.

Rows are kept as they come: with an output file, every finished chunk is appended to a journal beside it
(``OUT.partial``, JSON lines) and the output is written when the sweep ends, is interrupted (Ctrl-C) or fails;
running the same sweep again with the same output runs only the cases it does not hold yet.

Modules: :mod:`.metrics` (the catalogue), :mod:`.plan` (axes, cases, chunks), :mod:`.chunk` (one task),
:mod:`.table` (rows, journal, table), :mod:`.cluster` (Dask: only it imports Dask), :mod:`.run` (:func:`sweep`,
:func:`run_sweep`), :mod:`.plot`. pandas and pyarrow come with Dask in the ``[sweep]`` extra.
"""

from .chunk import run_chunk
from .cluster import ONE_THREAD, WORKER_BYTES, check_workers, max_local_workers, silence_dask
from .metrics import METRICS, SweepError, metrics_of, require
from .plan import Axis, ChunkTask, SweepPlan, parse_axes
from .run import SweepOutcome, run_sweep, sweep
from .table import read_csv

__all__ = [
    "METRICS",
    "ONE_THREAD",
    "WORKER_BYTES",
    "Axis",
    "ChunkTask",
    "SweepError",
    "SweepOutcome",
    "SweepPlan",
    "check_workers",
    "max_local_workers",
    "metrics_of",
    "parse_axes",
    "read_csv",
    "require",
    "run_chunk",
    "run_sweep",
    "silence_dask",
    "sweep",
]
