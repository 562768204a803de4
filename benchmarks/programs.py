"""The benchmark cases of whole programs: a run's start-up, cold and warm; the viewer's and the browser view's frame
rates; the model's build time as it grows; a sweep of 64 kites on a local Dask cluster; the kites' worlds on one
and two threads. Each returns a row as :mod:`benchmarks.suite`'s cases do, measured in the same run as its
baseline.
"""

from __future__ import annotations

import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable

import numpy as np

from warpsim import Scene
from warpsim.run.simulation import Simulation

from .suite import Options, flag, scene


def case_startup(opts: Options) -> dict:
    """`warpsim run hang-glider --seconds 1` in a fresh process: empty kernel cache (cold), then warm"""
    times = {}
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, WARP_CACHE_PATH=cache)
        script = shutil.which("warpsim", path=os.path.dirname(sys.executable)) or shutil.which("warpsim")
        launcher = [script] if script else [sys.executable, "-m", "warpsim"]
        command = [*launcher, "run", "hang-glider", "--seconds", "1", "--quiet"]
        command += ["--device", opts.device]
        for label in ("cold", "warm"):
            start = time.perf_counter()
            subprocess.run(command, env=env, check=True, capture_output=True)
            times[label] = time.perf_counter() - start
    return {"case": "startup", "cold_start_s": times["cold"], "warm_start_s": times["warm"], "device": opts.device}


def case_viewer(opts: Options) -> dict:
    """`warpsim view` of each built-in scene at 1280x720, real clock: pictures/s, real-time factor, step/draw share"""
    try:
        import pyglet  # noqa: F401
    except ImportError:
        return {"case": "viewer", "skipped": "needs pyglet (pip install -e '.[viewer]')"}
    import contextlib

    from warpsim.viewer.xvfb import VirtualDisplayError, virtual_display

    try:
        with contextlib.ExitStack() as stack:
            env = dict(os.environ) if os.environ.get("DISPLAY") else stack.enter_context(virtual_display())
            seconds = max(3.0, 3 * opts.min_time)
            result = subprocess.run(
                [sys.executable, "-m", "benchmarks.viewer", str(seconds), "1280x720"],
                env=env,
                capture_output=True,
                text=True,
                cwd=os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
            )
    except VirtualDisplayError as err:
        return {"case": "viewer", "skipped": f"no display ({err})"}
    if result.returncode != 0:
        raise RuntimeError(f"the viewer benchmark failed: {result.stderr.strip()[-2000:]}")
    import json

    return {"case": "viewer", "size": "1280x720", "scenes": json.loads(result.stdout.splitlines()[-1])}


def case_browser(opts: Options) -> dict:
    """`warpsim view --browser` watched in headless Chromium at 1280x720: the page's pictures/s, bytes/s, resolution"""
    import importlib.util
    import shutil

    if importlib.util.find_spec("playwright") is None or importlib.util.find_spec("aiohttp") is None:
        return {"case": "browser", "skipped": "needs aiohttp and playwright (pip install -e '.[test]')"}
    if not shutil.which("/usr/bin/chromium"):
        return {"case": "browser", "skipped": "needs Debian's chromium (apt-get install chromium)"}
    seconds = max(4.0, 4 * opts.min_time)
    result = subprocess.run(
        [sys.executable, "-m", "benchmarks.browser", str(seconds), "1280x720"],
        capture_output=True,
        text=True,
        cwd=os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
    )
    if result.returncode != 0:
        raise RuntimeError(f"the browser benchmark failed: {result.stderr.strip()[-2000:]}")
    import json

    return {"case": "browser", "size": "1280x720", "scenes": json.loads(result.stdout.splitlines()[-1])}


SWEEP_AXES = ("kite.tow_point=0.2:0.55:8", "wind.speed=4:11:8")  # 64 cases
SWEEP_SECONDS, SWEEP_CHUNK = 8.0, 8


def _warm_worker() -> None:
    """Run on each Dask worker before timing: Warp started and the kite's kernels loaded (a one-time cost per
    worker process, reported as the cluster's start-up)."""
    from warpsim.physics import _warp

    _warp.init()
    Simulation(scene("kite"))


def case_sweep(opts: Options) -> dict:
    """64-case kite sweep (8 tow points x 8 winds, 8 s each, 8 chunks of 8 worlds) on Dask with 1 and 2 local
    workers: cases/s, against the same chunks run one after another in this process (task overhead); two
    rounds, alternating, best of each"""
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        return {"case": "sweep-kites-64", "skipped": "needs Dask (pip install -e '.[sweep]')"}
    import logging

    import pandas as pd

    from warpsim import sweeps

    d = scene("kite")
    plan = sweeps.SweepPlan(Scene(d), sweeps.parse_axes(Scene(d), list(SWEEP_AXES)), SWEEP_SECONDS)
    tasks = plan.chunks(SWEEP_CHUNK, device=opts.device)
    sweeps.run_chunk(tasks[0])  # kernels loaded, caches warm
    best = {"in process": math.inf, 1: math.inf, 2: math.inf}
    startup = {}
    reference = None
    clusters = {}
    try:
        for workers in (1, 2):
            start = time.perf_counter()
            cluster = LocalCluster(
                n_workers=workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address="127.0.0.1:0",
                silence_logs=logging.ERROR,
                env=sweeps.ONE_THREAD,
            )
            clusters[workers] = (cluster, Client(cluster))
            clusters[workers][1].run(_warm_worker)
            startup[str(workers)] = time.perf_counter() - start
        for _ in range(2):
            start = time.perf_counter()
            rows = [row for task in tasks for row in sweeps.run_chunk(task)]
            best["in process"] = min(best["in process"], time.perf_counter() - start)
            reference = pd.DataFrame(rows, columns=plan.columns)
            for workers, (_, client) in clusters.items():
                start = time.perf_counter()
                outcome = sweeps.run_sweep(plan, scheduler=client, chunk=SWEEP_CHUNK, device=opts.device)
                best[workers] = min(best[workers], time.perf_counter() - start)
                pd.testing.assert_frame_equal(outcome.table, reference, check_exact=True)  # the same rows
    finally:
        for cluster, client in clusters.values():
            client.close()
            cluster.close()
    cases = len(plan.cases)
    return {
        "case": "sweep-kites-64",
        "cases": cases,
        "tasks": len(tasks),
        "seconds_per_case": SWEEP_SECONDS,
        "in_process_cases_per_s": cases / best["in process"],
        "workers_1_cases_per_s": cases / best[1],
        "workers_2_cases_per_s": cases / best[2],
        "speedup_2_workers": best[1] / best[2],
        "overhead_per_task_pct": 100.0 * (best[1] / best["in process"] - 1.0),
        "overhead_per_task_ms": 1e3 * (best[1] - best["in process"]) / len(tasks),
        "cluster_startup_s": startup,
        "device": opts.device,
    }


THREAD_WORLDS = (64, 256)


def case_threads(opts: Options, rounds: int = 3) -> dict:
    """64 and 256 batched kites (wind 4-12 m/s) run by 1 and by 2 threads (`warpsim run --threads`: frames,
    checks), alternating rounds in one run: steps/s, best and spread of each, and the speed-up of 2 threads"""
    if opts.device != "cpu":
        return {"case": "threads-kites", "skipped": "threads step worlds on the CPU only"}
    out = {"case": "threads-kites", "rounds": rounds, "device": opts.device, "worlds": {}}
    for count in THREAD_WORLDS:
        desc = scene("kite", {"worlds": {"count": count, "wind": {"speed": list(np.linspace(4.0, 12.0, count))}}})
        sims = {threads: Simulation(desc, device=opts.device, threads=threads) for threads in (1, 2)}
        seconds = 0.25
        while sims[1].run(seconds).wall_time < opts.min_time:  # warm-up, and a run that lasts min_time
            seconds *= 2.0
        sims[2].run(seconds)
        rates = {1: [], 2: []}
        for _ in range(rounds):  # the machine's speed drifts and is shared: alternate, keep every round
            for threads, sim in sims.items():
                summary = sim.run(seconds)
                rates[threads].append(summary.steps / summary.wall_time)
        m = sims[1].model
        best = {threads: max(r) for threads, r in rates.items()}
        out["worlds"][str(count)] = {
            "particles": m.particle_count,
            "sticks": m.stick_count,
            "iterations": sims[1].solver.config.iterations,
            "steps_per_s_1_thread": rates[1],
            "steps_per_s_2_threads": rates[2],
            "speedup_best": best[2] / best[1],
            "speedup_per_round": [b / a for a, b in zip(rates[1], rates[2], strict=True)],
            "constraint_iterations_per_s_2_threads": m.stick_count * sims[1].solver.config.iterations * best[2],
            "startup_s": {str(threads): sim.startup_time for threads, sim in sims.items()},
        }
    return out


BUILD_SIZES = (32, 64, 128, 256, 512)
BUILD_WORLDS = (16, 64, 256)


def case_build_scaling(opts: Options) -> dict:
    """model build time of square flags from 32^2 to 512^2 particles (microseconds per particle) and of batches of
    16 to 256 kites (milliseconds per world): linear = flat"""
    per_particle, per_world = {}, {}
    for n in BUILD_SIZES:
        desc = flag(n)
        start = time.perf_counter()
        model = Simulation(desc, device=opts.device).model
        per_particle[n] = (time.perf_counter() - start) / model.particle_count * 1e6
    for n in BUILD_WORLDS:
        desc = scene("kite", {"worlds": {"count": n, "wind": {"gust_seed": list(range(n))}}})
        start = time.perf_counter()
        Simulation(desc, device=opts.device)
        per_world[n] = (time.perf_counter() - start) / n * 1e3
    return {
        "case": "build-scaling",
        "us_per_particle": {f"{n}x{n}": round(v, 2) for n, v in per_particle.items()},
        "growth": per_particle[BUILD_SIZES[-1]] / per_particle[BUILD_SIZES[-2]],  # ~1 when the build is linear
        "ms_per_kite_world": {str(n): round(v, 2) for n, v in per_world.items()},
        "world_growth": per_world[BUILD_WORLDS[-1]] / per_world[BUILD_WORLDS[-2]],
        "device": opts.device,
    }


CASES: dict[str, Callable[[Options], dict]] = {
    "startup": case_startup,
    "viewer": case_viewer,
    "browser": case_browser,
    "build-scaling": case_build_scaling,
    "sweep-kites-64": case_sweep,
    "threads-kites": case_threads,
}
"""The programs' cases, after :data:`benchmarks.suite.CASES` in the table."""
