"""Would one large object gain from splitting its particles across threads? A measurement, not a feature.

``python -m benchmarks.split_object [SIZES...]`` (default 32 64 128 256): for a square flag of each size, the
Jacobi constraint iterations (a gather over each particle's sticks, then the copy back: two kernels per iteration,
the shape of warpsim's scheme) replayed as one graph on one thread, against the same kernels cut into two
halves of the particles, each half replayed by its own thread with a barrier after every kernel (a graph cannot
hold a barrier, so each kernel is its own graph). The kernels here take an offset, which warpsim's do not; they
do the work of warpsim's gather scheme, not its exact arithmetic. Beside them, warpsim's own projection on one
thread: the fused scheme (the CPU default: one launch walks the sticks once) and the gather scheme. Prints ms per
55 iterations and the speed-up of the split over the fused scheme, what a split would have to beat.
"""

from __future__ import annotations

import sys
import threading
import time

import warp as wp

from warpsim.physics.projection import make_projector
from warpsim.run.simulation import Simulation

from .suite import flag

ITERATIONS = 55


@wp.kernel
def _gather(
    offset: int,
    q: wp.array(dtype=wp.vec3),
    start: wp.array(dtype=wp.int32),
    refs: wp.array(dtype=wp.int32),
    sticks: wp.array(dtype=wp.vec2i),
    rest: wp.array(dtype=wp.float32),
    inv_mass: wp.array(dtype=wp.float32),
    q_out: wp.array(dtype=wp.vec3),
):
    i = wp.tid() + offset
    x = q[i]
    total = wp.vec3(0.0)
    count = wp.float32(0.0)  # a variable the loop changes
    for k in range(start[i], start[i + 1]):
        ref = refs[k]
        ends = sticks[ref // 2]
        d = q[ends[1]] - q[ends[0]]
        length = wp.max(wp.length(d), 1.0e-9)
        c = (length - rest[ref // 2]) / length * 0.5 * d
        if ref % 2 == 0:
            total += c
        else:
            total -= c
        count += 1.0
    if count > 0.0 and inv_mass[i] > 0.0:
        x = x + total / count
    q_out[i] = x


@wp.kernel
def _copy(offset: int, q_in: wp.array(dtype=wp.vec3), q_out: wp.array(dtype=wp.vec3)):
    i = wp.tid() + offset
    q_out[i] = q_in[i]


def _launches(sim, q, q_tmp, first: int, count: int):
    """The two kernels of one iteration over particles ``[first, first + count)``."""
    m = sim.model
    inputs = [m.particle_stick_start, m.particle_stick_refs, m.stick_particles, sim.control.stick_rest]
    return (
        lambda: wp.launch(_gather, count, inputs=[first, q, *inputs, m.particle_inv_mass], outputs=[q_tmp]),
        lambda: wp.launch(_copy, count, inputs=[first, q_tmp], outputs=[q]),
    )


def _graph(launch):
    with wp.ScopedCapture(device="cpu") as capture:
        launch()
    return capture.graph


def measure(size: int, rounds: int = 5) -> dict:
    """ms per 55 iterations of a ``size`` x ``size`` flag, one thread (one graph) and two (a barrier per
    kernel), best of ``rounds`` alternating."""
    sim = Simulation(flag(size))
    q = sim.state.particle_q
    q_tmp = wp.empty_like(q)
    n = sim.model.particle_count
    whole = _launches(sim, q, q_tmp, 0, n)
    with wp.ScopedCapture(device="cpu") as capture:
        for _ in range(ITERATIONS):
            for launch in whole:
                launch()
    serial = capture.graph
    half = n // 2
    parts = [
        [_graph(launch) for launch in _launches(sim, q, q_tmp, 0, half)],
        [_graph(launch) for launch in _launches(sim, q, q_tmp, half, n - half)],
    ]
    barrier = threading.Barrier(2)

    def worker(graphs):
        for _ in range(ITERATIONS):
            for graph in graphs:
                wp.capture_launch(graph)
                barrier.wait()

    def split():
        other = threading.Thread(target=worker, args=(parts[1],))
        other.start()
        worker(parts[0])
        other.join()

    def timed(run, repeat: int) -> float:
        start = time.perf_counter()
        for _ in range(repeat):
            run()
        return (time.perf_counter() - start) / repeat * 1e3

    own = {}
    for scheme in ("fused", "gather"):
        projector = make_projector(sim.model, sim.settings.solver, scheme)
        projector.prepare(ITERATIONS)
        with wp.ScopedCapture(device="cpu") as capture:
            projector.project(sim.state, sim.control, ITERATIONS)
        own[scheme] = capture.graph

    repeat = max(1, int(0.3 / max(timed(lambda: wp.capture_launch(serial), 1) / 1e3, 1e-6)))
    times = {"fused": [], "gather": [], "1 thread": [], "2 threads": []}
    for _ in range(rounds):
        for scheme, graph in own.items():
            times[scheme].append(timed(lambda graph=graph: wp.capture_launch(graph), repeat))
        times["1 thread"].append(timed(lambda: wp.capture_launch(serial), repeat))
        times["2 threads"].append(timed(split, repeat))
    best = {name: min(t) for name, t in times.items()}
    return {"size": size, "particles": n, **best, "speedup": best["fused"] / best["2 threads"]}


def main(argv: list[str]) -> None:
    sizes = [int(a) for a in argv] or [32, 64, 128, 256]
    print(
        "| flag | particles | warpsim fused [ms] | warpsim gather [ms] | offset gather, 1 thread [ms] "
        "| offset gather, 2 threads + barriers [ms] | 2 threads / fused |"
    )
    print("|---|--:|--:|--:|--:|--:|--:|")
    for size in sizes:
        r = measure(size)
        print(
            f"| {size}x{size} | {r['particles']:,} | {r['fused']:.2f} | {r['gather']:.2f} | {r['1 thread']:.2f} | "
            f"{r['2 threads']:.2f} | {r['speedup']:.2f}x |",
            flush=True,
        )


if __name__ == "__main__":
    main(sys.argv[1:])
