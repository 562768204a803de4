"""The Dask side of a sweep: the local cluster (TLS, single-threaded workers that ignore Ctrl-C), a running
scheduler's client, the limits on local workers, Dask's log kept off the terminal, and the loop that submits the
chunks and keeps their rows as they finish. This package's only Dask imports are here."""

from __future__ import annotations

import contextlib
import math
import os
import stat
import time
from pathlib import Path

from ..run.summary import available_cores
from .chunk import run_chunk
from .metrics import SweepError
from .plan import ChunkTask
from .table import Results

ONE_THREAD = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}


def _ignore_interrupt_plugin(log: Path | None = None):
    """A worker plugin for the local cluster: Ctrl-C in the terminal reaches every process of its group, the
    workers included; they ignore it, and the sweep itself stops them cleanly. With ``log``, what the worker's Dask
    logs goes there (see :func:`dask_log`) instead of the terminal."""
    from dask.distributed import WorkerPlugin

    class IgnoreInterrupt(WorkerPlugin):
        name = "warpsim-ignore-interrupt"

        def __init__(self, log: str | None):
            self.log = log

        def setup(self, worker):
            import signal
            import threading

            if threading.current_thread() is threading.main_thread():
                signal.signal(signal.SIGINT, signal.SIG_IGN)
            if self.log:
                _log_to(self.log)

    return IgnoreInterrupt(str(log) if log else None)


_DASK_LOGGERS = ("distributed", "tornado", "asyncio")


def _log_to(path) -> list:
    """Send what Dask and its network layers log in this process to ``path`` (appended; a link there is never
    followed) instead of the terminal; returns what to give back to :func:`_restore_logging`."""
    import logging

    flags = os.O_WRONLY | os.O_CREAT | os.O_APPEND | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
    # non-blocking: a FIFO planted there would block the open (the sweep holding its table's lock) until a reader came
    with contextlib.suppress(FileNotFoundError):
        if not stat.S_ISREG(os.lstat(path).st_mode):
            raise SweepError(f"{path}: is not a regular file (a pipe or a device); remove it, Dask's log goes there")
    try:
        fd = os.open(path, flags | os.O_NONBLOCK, 0o666)
    except OSError as err:
        raise SweepError(f"{path}: Dask's log cannot be written there ({err.strerror or err})") from None
    if not stat.S_ISREG(os.fstat(fd).st_mode):
        os.close(fd)
        raise SweepError(f"{path}: is not a regular file (a pipe or a device); remove it, Dask's log goes there")
    os.set_blocking(fd, True)
    handler = logging.StreamHandler(open(fd, "a", encoding="utf-8"))  # noqa: SIM115
    handler.setFormatter(logging.Formatter("%(asctime)s %(process)d %(name)s %(levelname)s: %(message)s"))
    handler.setLevel(logging.WARNING)  # what went wrong; a worker's routine "Stopping worker" lines left a log behind
    saved = []
    for logger in dask_loggers():
        saved.append((logger, logger.handlers[:], logger.propagate))
        logger.handlers = [handler]
        logger.propagate = False
    return [handler, saved]


def dask_loggers() -> list:
    """Dask's loggers and those of its network layers: the top ones, and every one below them that Dask gave a
    handler of its own (``distributed.client`` has one)."""
    import logging

    names = set(_DASK_LOGGERS)
    for name, logger in list(logging.root.manager.loggerDict.items()):
        if name.split(".")[0] in _DASK_LOGGERS and getattr(logger, "handlers", None):
            names.add(name)
    return [logging.getLogger(name) for name in sorted(names)]


def silence_dask() -> None:
    """Turn off Dask's logging in this process for good: for a command whose sweep is over, whose client may still
    be tearing down connections (a killed scheduler gave 36 lines of tracebacks after the sweep had ended)."""
    for logger in dask_loggers():
        logger.disabled = True


def _restore_logging(state: list) -> None:
    handler, saved = state
    for logger, handlers, propagate in saved:
        logger.handlers, logger.propagate = handlers, propagate
    handler.close()


@contextlib.contextmanager
def dask_log(path: Path | None):
    """Inside the block, Dask's log lines (a lost worker, "Couldn't gather keys", a scheduler gone: dozens of lines
    and tracebacks) go to ``path`` beside the table, not the terminal; yields ``path`` (None without one). The file is
    removed when nothing was logged. Without ``path`` logging is left as it is."""
    if path is None:
        yield None
        return
    with contextlib.suppress(FileNotFoundError):
        if os.path.islink(path):
            path.unlink()
    state = _log_to(path)
    try:
        yield path
    finally:
        _restore_logging(state)
        with contextlib.suppress(OSError):
            if os.path.getsize(path) == 0:
                path.unlink()


WORKER_BYTES = 384 << 20
"""Memory [bytes] one local worker process takes: about 220 MB at rest (Python, Warp, NumPy, Dask, pandas;
measured RSS of a worker running kite chunks on the CPU) and room for a chunk of up to :data:`MAX_CHUNK` worlds."""


WORKERS_PER_CORE = 4
"""Most local worker processes per core: each is single-threaded and CPU-bound, so more only time-slice."""


def max_local_workers() -> int:
    """Most worker processes a local cluster may start here: :data:`WORKERS_PER_CORE` per core, and no more than
    80 % of the available memory holds at :data:`WORKER_BYTES` each (at least 1)."""
    from ..physics.memory import available_memory

    limit = WORKERS_PER_CORE * available_cores()
    available = available_memory()
    if available is not None:
        limit = min(limit, int(0.8 * available) // WORKER_BYTES)
    return max(1, limit)


def check_workers(workers: int | None) -> None:
    """Raise :class:`SweepError` when ``workers`` local processes are more than :func:`max_local_workers` (a
    thousand workers took more than 10 GB within a minute; 64 ended in Dask tracebacks)."""
    if workers is None:
        return
    limit = max_local_workers()
    if workers > limit:
        raise SweepError(
            f"--workers {workers} is more than this machine can run ({limit}: {WORKERS_PER_CORE} per core on "
            f"{available_cores()} cores, about {WORKER_BYTES >> 20} MB each of the memory available); use --workers "
            f"{limit} or fewer, or a --scheduler with workers on more machines"
        )


def connect(scheduler, workers: int | None):
    """``(client, whether this sweep made it, worker threads)`` for a running ``scheduler``; ``(None, False,
    worker processes to start)`` for the local cluster."""
    if scheduler is None:
        if workers is not None:
            return None, False, workers
        return None, False, min(available_cores(), max_local_workers())
    from dask.distributed import Client

    if workers is not None:
        raise SweepError("--workers sizes the local cluster; a --scheduler's cluster has the workers it has")
    if isinstance(scheduler, Client):
        return scheduler, False, sum(scheduler.nthreads().values())
    try:
        client = Client(scheduler, timeout="5s")
    except (OSError, TimeoutError, ValueError) as err:
        raise SweepError(f"--scheduler {scheduler}: cannot connect ({err})") from None
    return client, True, sum(client.nthreads().values())


def local_cluster(count: int, log: Path | None = None):
    """A ``LocalCluster`` of ``count`` single-threaded worker processes (NumPy/BLAS on one thread each), and
    its client (``log``: where the workers' Dask logs go, see :func:`dask_log`). Nobody else can join it: every
    connection is TLS with mutual authentication by temporary credentials made for this cluster
    (``Security.temporary()``), which only this process and its workers hold; without them any local process could
    connect to the scheduler on 127.0.0.1 and run its own code on a worker as the sweep's user."""
    import logging

    from dask.distributed import Client, LocalCluster
    from distributed.security import Security

    security = Security.temporary()  # needs `cryptography` (the [sweep] extra)
    cluster = LocalCluster(
        n_workers=count,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        protocol="tls://",
        security=security,
        dashboard_address="127.0.0.1:0",  # the HTTP server always starts: on a free port
        silence_logs=logging.ERROR,
        env=ONE_THREAD,
    )
    client = Client(cluster, security=security)
    client.register_plugin(_ignore_interrupt_plugin(log))
    return client, cluster


POLL = 0.02
"""[s] how long a running sweep waits, when no chunk has finished, before it looks again (Ctrl-C wakes it)."""

NO_WORKER_GRACE = 60.0
"""[s] how long a sweep waits with no worker in its cluster (killed again and again, out of memory) before it
stops: a nanny restarts a killed worker within seconds, so a minute without one is a cluster that will not come
back."""

WATCH_INTERVAL = 1.0
"""[s] between two looks at the cluster's workers."""


class NoWorkerError(Exception):
    """The cluster had no worker for :data:`NO_WORKER_GRACE` seconds."""


def _watch_workers(client, state: dict) -> None:
    """Raise :class:`NoWorkerError` when ``client``'s cluster has had no worker for :data:`NO_WORKER_GRACE` seconds
    (looked at every :data:`WATCH_INTERVAL`; ``state`` keeps the times between calls)."""
    now = time.monotonic()
    if now - state.get("looked", -math.inf) < WATCH_INTERVAL:
        return
    state["looked"] = now
    try:
        workers = len(client.nthreads())
    except Exception:  # noqa: BLE001 - a scheduler that does not answer has no worker for us either
        workers = 0
    if workers:
        state.pop("since", None)
        return
    since = state.setdefault("since", now)
    if now - since >= NO_WORKER_GRACE:
        raise NoWorkerError(
            f"the cluster has had no worker for {NO_WORKER_GRACE:g} s (its workers died: killed, or out of memory)"
        )


def run_tasks(client, tasks: list[ChunkTask], results: Results, total: int, started: float, on_progress) -> None:
    import uuid

    from dask.distributed import as_completed

    token = uuid.uuid4().hex[:8]  # task keys unique on a shared scheduler
    futures = [
        client.submit(run_chunk, task, key=f"warpsim-cases-{task.cases[0]}-{task.cases[-1]}-{token}", retries=2)
        for task in tasks
    ]
    finished, done = as_completed(futures), 0
    watch: dict = {}
    try:
        with _ctrl_c_flag() as stop:
            while not finished.is_empty():
                batch = finished.next_batch(block=False)
                for future in batch:  # rows that are done are kept, even when Ctrl-C came meanwhile
                    try:
                        rows = future.result()
                    except Exception as err:
                        raise TaskFailedError() from err
                    results.add(rows)
                    done += len(rows)
                    if on_progress is not None:
                        on_progress(done, total, time.perf_counter() - started)
                if stop.is_set():
                    raise KeyboardInterrupt
                if not batch:
                    try:
                        _watch_workers(client, watch)
                    except NoWorkerError as err:
                        raise TaskFailedError() from err
                    stop.wait(POLL)
    finally:
        client.cancel(futures)


@contextlib.contextmanager
def _ctrl_c_flag():
    """While inside, Ctrl-C (SIGINT) or SIGTERM sets the event this yields instead of raising ``KeyboardInterrupt``
    wherever the main thread happens to be (inside Dask's client code it could be lost); the sweep's loop raises it
    when it looks next, at once if it was waiting. Off the main thread (where no signal lands) the event is never
    set."""
    import signal
    import threading

    stop = threading.Event()
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return
    # SIGTERM too: a sweep asked to end (by a scheduler, `kill`) stops like Ctrl-C and keeps its rows
    previous = {sig: signal.signal(sig, lambda *_: stop.set()) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield stop
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


class TaskFailedError(Exception):
    """A Dask task failed for good; its cause is the task's exception."""


def close(client, cluster) -> None:
    """Close this sweep's client and local cluster (quietly: they may be half gone after Ctrl-C)."""
    if client is not None:
        with contextlib.suppress(Exception):
            client.close(timeout=5)
    if cluster is not None:
        with contextlib.suppress(Exception):
            cluster.close(timeout=10)
