"""The validation table's row (:class:`Row`) and what every object's cases share: a hand-built bench, a pool
of processes, small closed forms.
"""

from __future__ import annotations

import math
import multiprocessing
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass

from warpsim.physics.builder import ModelBuilder
from warpsim.physics.config import AirConfig
from warpsim.physics.solver import SolverVerlet
from warpsim.run.simulation import available_cores


@dataclass
class Row:
    """One line of the validation table.

    Attributes:
        case: short name. compared: what is compared. expected: the reference value (text with unit).
        source: where the reference comes from. measured: warpsim's value (text with unit).
        band: what passes (text). ok: inside the band. model_limit: a miss the paper's model cannot avoid
        (explained in ``note``), reported, not counted as a failure. note: anything else to know.
    """

    case: str
    compared: str
    expected: str
    source: str
    measured: str
    band: str
    ok: bool
    model_limit: bool = False
    note: str = ""

    def __post_init__(self):
        self.ok, self.model_limit = bool(self.ok), bool(self.model_limit)

    @property
    def status(self) -> str:
        """``pass``, ``FAIL``, or ``model limit`` (outside the band for a stated reason)."""
        return "pass" if self.ok else "model limit" if self.model_limit else "FAIL"

    def as_dict(self) -> dict:
        """The row as plain values (JSON)."""
        return {**asdict(self), "status": self.status}


def _rel(measured: float, expected: float) -> float:
    return (measured - expected) / expected


def complete_elliptic_k(k: float) -> float:
    """Complete elliptic integral of the first kind ``K(k)`` (modulus ``k``), by the arithmetic-geometric mean."""
    a, b = 1.0, math.sqrt(1.0 - k * k)
    while abs(a - b) > 1e-15:
        a, b = 0.5 * (a + b), math.sqrt(a * b)
    return math.pi / (2.0 * a)


class _Bench:
    """A hand-built model stepped by the Verlet solver: no wind, flat ground far below."""

    def __init__(self, build: Callable[[ModelBuilder], None], dt=0.01, iterations=55, damping=0.0, air=None):
        b = ModelBuilder()
        build(b)
        self.model = b.finalize("cpu")
        self.dt = dt
        self.solver = SolverVerlet(self.model, iterations=iterations, damping=damping, air=air or AirConfig(scale=0.0))
        self.state = self.model.state(dt)
        self.control = self.model.control()

    def step(self, n=1):
        for _ in range(n):
            self.solver.step(self.state, self.control, self.dt)


def in_processes(function: Callable, jobs: dict, cost: Callable | None = None) -> dict:
    """``function(*jobs[name])`` for every ``name`` of ``jobs``, one process per core (a run's CPU kernels use one
    thread), the costliest first by ``cost(*args)``: the same results as one after another, in the order of
    ``jobs``. ``function`` must be importable (a module's top level)."""
    order = sorted(jobs, key=lambda name: -cost(*jobs[name])) if cost else list(jobs)
    workers = min(len(jobs), available_cores())
    if workers <= 1:
        return {name: function(*jobs[name]) for name in jobs}
    # spawned, not forked: a forked child would inherit the parent's Warp runtime mid-state
    pool = ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn"))
    try:
        futures = {name: pool.submit(function, *jobs[name]) for name in order}
        results = {name: futures[name].result() for name in jobs}
    except BaseException:  # one failed or Ctrl-C: the jobs not yet started are dropped, not waited for
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown()
    return results
