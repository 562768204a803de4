"""Running a sweep: :func:`run_sweep` (a plan, its table, its cluster) and :func:`sweep`, the Python API."""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

from ..run.summary import available_cores
from ..scene.scene import Scene
from . import chunk as chunks
from . import cluster
from .metrics import SweepError, require
from .plan import MAX_CHUNK, SweepPlan, parse_axes
from .table import Results


@dataclass
class SweepOutcome:
    """What :func:`run_sweep` did. ``table``: the rows (pandas DataFrame); ``ran``: cases run now;
    ``kept``: cases already done before; ``wall``: seconds; ``workers``: worker threads used;
    ``interrupted``: stopped by Ctrl-C (the rows finished so far are kept); ``failures``: the exceptions of tasks
    that failed for good; ``log``: the file Dask's log lines went to, when there were any."""

    table: object
    ran: int
    kept: int
    wall: float
    workers: int
    interrupted: bool = False
    failures: list = field(default_factory=list)
    log: Path | None = None  # Dask's log of this sweep, when it logged anything (see dask_log)


def run_sweep(
    plan: SweepPlan,
    out: Path | None = None,
    workers: int | None = None,
    scheduler=None,
    chunk: int | None = None,
    device: str = "cpu",
    h5_dir: Path | None = None,
    restart: bool = False,
    on_progress: Callable[[int, int, float], None] | None = None,
    threads: int | None = None,
) -> SweepOutcome:
    """Run the cases of ``plan`` that ``out`` does not hold yet on a Dask cluster and keep their rows.

    Args:
        plan: the sweep. out: ``.parquet`` or ``.csv`` table (None: keep the rows in memory only).
        workers: worker processes of the local cluster (default: one per core); not with ``scheduler``.
        scheduler: address of a running Dask scheduler (``tcp://HOST:8786``) or a ``distributed.Client``.
        chunk: cases per task (default: about four tasks per worker, at most :data:`MAX_CHUNK`).
        device: Warp device of the workers. h5_dir: write one recording per chunk there.
        restart: forget the rows ``out`` holds and run every case again.
        on_progress: ``(cases done, cases to run, wall seconds)``, after every chunk.
        threads: threads stepping each chunk's worlds (default: on the local cluster, the cores per worker
            process, so that the workers' threads fill the cores; on a ``scheduler``'s cluster, 1).

    Ctrl-C (``KeyboardInterrupt``) stops the sweep: the finished rows are written and the outcome says
    ``interrupted``.
    """
    require("distributed")
    if scheduler is None:
        cluster.check_workers(workers)
    with _owning(out), cluster.dask_log(out.with_name(out.name + ".dask.log") if out is not None else None) as log:
        outcome = _run_owned(plan, out, workers, scheduler, chunk, device, h5_dir, restart, on_progress, log, threads)
    outcome.log = log if log is not None and log.exists() else None
    return outcome


@contextlib.contextmanager
def _owning(out: Path | None):
    """Hold ``out``'s :class:`~warpsim.io.OutputLock` inside the block (one sweep per table and journal: two sweeps
    on one ``--out`` each wrote the table, and the last to finish kept only its own rows)."""
    if out is None:
        yield
        return
    from ..io import OutputLock, OutputLockedError, reason

    try:
        lock = OutputLock(out)
    except OutputLockedError:
        raise SweepError(f"--out {out}: another warpsim sweep is writing this table; wait for it to end") from None
    except OSError as err:
        raise SweepError(f"--out {out}: cannot be locked for writing ({reason(err)})") from None
    try:
        yield
    finally:
        lock.release()


def recording_prefix(out) -> str:
    """The name the ``--h5-dir`` recordings of a sweep writing the table ``out`` start with: the table's name
    (``tour.parquet`` -> ``tour.parquet-cases``), or ``cases`` without a table."""
    return f"{Path(out).name}-cases" if out is not None else "cases"


def _run_owned(
    plan, out, workers, scheduler, chunk, device, h5_dir, restart, on_progress, log, threads=None
) -> SweepOutcome:
    """:func:`run_sweep` once ``out`` is this sweep's own."""
    from ..io import OutputWriteError

    failed_write = None
    results = Results(out, plan, restart)
    todo = [i for i in range(len(plan.cases)) if not results.done(i)]
    started = time.perf_counter()
    interrupted, failures = False, []
    client = local = None
    own_client, used = False, 0
    try:
        if todo:
            client, own_client, used = cluster.connect(scheduler, workers)
            size = chunk or max(1, min(MAX_CHUNK, math.ceil(len(todo) / (4 * max(used, 1)))))
            prefix = recording_prefix(out)
            tasks = plan.chunks(size, set(range(len(plan.cases))) - set(todo), device, h5_dir, prefix)
            chunks.check_recordings_free(tasks)
            if threads is None:
                threads = 1 if scheduler is not None else max(1, available_cores() // max(used, 1))
            tasks = [replace(task, threads=threads) for task in tasks]
            if client is None:  # the local cluster: kernels compiled once, here, then the workers start
                chunks.warm_kernels(tasks, device)
                client, local = cluster.local_cluster(used, log)
                own_client = True
            cluster.run_tasks(client, tasks, results, len(todo), started, on_progress)
    except KeyboardInterrupt:
        interrupted = True
    except cluster.TaskFailedError as err:  # e.g. a task that killed its workers again and again
        failures.append(err.__cause__)
    except OutputWriteError as err:  # the journal could not be written (disk full): stop, keep what is kept
        failed_write = err
    finally:
        if own_client:
            cluster.close(client, local)
        try:
            table = results.finish()
        except OutputWriteError as err:
            raise (failed_write or err) from None
    if failed_write is not None:
        raise failed_write
    ran = sum(1 for i in todo if results.done(i))
    wall = time.perf_counter() - started
    return SweepOutcome(table, ran, len(plan.cases) - len(todo), wall, used, interrupted, failures)


def sweep(
    scene: str | Path | Scene,
    axes: dict | Sequence[str] = (),
    *,
    seconds: float | None = None,
    window: tuple[float, float] | None = None,
    metrics: Sequence[str] | None = None,
    out: str | Path | None = None,
    workers: int | None = None,
    scheduler=None,
    chunk: int | None = None,
    device: str = "cpu",
    h5_dir: str | Path | None = None,
    restart: bool = False,
):
    """Sweep a scene over every combination of ``axes`` and return one row per case (a pandas DataFrame).

    Args:
        scene: a built-in object name, a scene name or ``.toml`` path, or a :class:`~warpsim.scene.scene.Scene`
            (:meth:`~warpsim.scene.scene.Scene.of`).
        axes: ``{"section.key": [values] or "START:STOP:COUNT"}`` or ``--vary`` texts
            (``"kite.tow_point=0.2:0.5:4"``); added to the scene's ``[sweep]`` table.
        seconds: simulated time of every case [s] (default: the scene's).
        window: ``(start, stop)`` [s] of simulated time the window metrics cover (default: the second half).
        metrics: metric names (default: all, see :data:`METRICS`).
        out: ``.parquet`` / ``.csv`` file that keeps the rows; cases it already holds are not run again.
        workers, scheduler, chunk, device, h5_dir, restart: see :func:`run_sweep`.

    Example: ``warpsim.sweep("kite", {"kite.tow_point": "0.2:0.5:4", "wind.speed": [4, 8, 12]}, seconds=20)``.
    Raises :class:`SweepError` or :class:`~warpsim.scene.descriptor.DescriptorError` for a sweep that cannot run, and
    ``KeyboardInterrupt`` after keeping the finished rows when interrupted.
    """
    scene = Scene.of(scene)  # a name or path is found as warpsim run finds it
    plan = SweepPlan(scene, parse_axes(scene, axes), seconds, window, metrics)
    outcome = run_sweep(plan, Path(out) if out else None, workers, scheduler, chunk, device, h5_dir, restart)
    if outcome.interrupted:
        raise KeyboardInterrupt
    if outcome.failures:
        raise outcome.failures[0]
    return outcome.table
