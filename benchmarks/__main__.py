"""``python -m benchmarks``: run the benchmark cases, print a table, write JSON.

Examples::

    python -m benchmarks                       # every case, about 2-4 minutes on 2 CPU cores
    python -m benchmarks -k flag -k glider     # the cases whose names contain "flag" or "glider"
    python -m benchmarks --list                # the case names and what each measures
    python -m benchmarks --device cuda --json gpu.json
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time

import numpy as np
import warp as wp

wp.config.log_level = wp.LOG_WARNING  # before Warp initialises: no per-module load lines

from . import programs, suite  # noqa: E402
from .suite import Options, constraint_rate  # noqa: E402

CASES = {**suite.CASES, **programs.CASES}

DEFAULT_JSON = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results.json")
"""Where a whole run writes its results."""


def machine() -> dict:
    """Where the numbers were measured: CPU, cores, Python, NumPy and Warp versions, the Warp device."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            cpu = next((line.split(":", 1)[1].strip() for line in f if line.startswith("model name")), cpu)
    except OSError:
        pass
    import warpsim

    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "system": platform.platform(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "warp": wp.__version__,
        "warpsim": warpsim.__version__,
    }


def _fmt(value, digits: int = 0) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:,.{digits}f}"
    return str(value)


def table(rows: list[dict]) -> str:
    """A Markdown table of the rows: the case, its rate, ms/step, real-time factor, sizes and comparison."""
    lines = [
        "| case | steps/s | ms/step | real-time | particles | sticks | iters | constraint-iters/s | compared with "
        "| theirs, steps/s | ratio |",
        "|---|--:|--:|--:|--:|--:|--:|--:|---|--:|--:|",
    ]
    for r in rows:
        if "skipped" in r:
            lines.append(f"| {r['case']} | skipped: {r['skipped']} ||||||||||")
            continue
        if r["case"] == "startup":
            lines.append(
                f"| startup | cold {r['cold_start_s']:.2f} s, warm {r['warm_start_s']:.2f} s "
                "(`warpsim run hang-glider --seconds 1`, fresh process) ||||||||||"
            )
            continue
        if r["case"] == "viewer":
            scenes = "; ".join(
                f"{name} {v['fps']:.0f} fps, {v['realtime_factor']:.2f}x real time, stepping "
                f"{100 * v['step_share']:.0f}% / drawing {100 * v['draw_share']:.0f}% of the wall time"
                for name, v in r["scenes"].items()
            )
            renderer = next(iter(r["scenes"].values()))["renderer"]
            lines.append(f"| viewer | `warpsim view` at {r['size']} on {renderer}: {scenes} ||||||||||")
            continue
        if r["case"] == "browser":
            scenes = "; ".join(
                f"{name} {v['page_fps']:.0f} fps drawn of {v['received_fps']:.0f} received at "
                f"{100 * v['resolution']:.0f}% resolution, {v['bytes_per_s'] / 1e3:.0f} kB/s, "
                f"{v['realtime_factor']:.2f}x real time"
                for name, v in r["scenes"].items()
            )
            renderer = next(iter(r["scenes"].values()))["renderer"]
            lines.append(
                f"| browser | `warpsim view --browser` at {r['size']}, headless Chromium on {renderer}: "
                f"{scenes} ||||||||||"
            )
            continue
        if r["case"] == "sweep-kites-64":
            lines.append(
                f"| sweep-kites-64 | `warpsim sweep` of {r['cases']} kite cases ({r['seconds_per_case']:g} s each, "
                f"{r['tasks']} tasks): {r['workers_1_cases_per_s']:.2f} cases/s with 1 worker, "
                f"{r['workers_2_cases_per_s']:.2f} with 2 ({r['speedup_2_workers']:.2f}x); the same chunks in one "
                f"process {r['in_process_cases_per_s']:.2f} cases/s, so Dask costs {r['overhead_per_task_pct']:.1f}% "
                f"({r['overhead_per_task_ms']:.0f} ms per task); cluster start "
                f"{r['cluster_startup_s']['1']:.1f} s / {r['cluster_startup_s']['2']:.1f} s (1 / 2 workers) ||||||||||"
            )
            continue
        if r["case"] == "build-scaling":
            sizes = ", ".join(f"{k}: {v:.1f} us" for k, v in r["us_per_particle"].items())
            worlds = ", ".join(f"x{k}: {v:.1f} ms" for k, v in r["ms_per_kite_world"].items())
            lines.append(
                f"| build-scaling | model build per particle, {sizes}; growth {r['growth']:.2f}x per 4x particles "
                f"(1 = linear); batched kites per world, {worlds}; growth {r['world_growth']:.2f}x per 4x worlds "
                "||||||||||"
            )
            continue
        if r["case"] == "threads-kites":
            parts = []
            for count, v in r["worlds"].items():
                one, two = v["steps_per_s_1_thread"], v["steps_per_s_2_threads"]
                parts.append(
                    f"x{count}: {max(one):.1f} steps/s with 1 thread ({min(one):.1f}-{max(one):.1f}), "
                    f"{max(two):.1f} with 2 ({min(two):.1f}-{max(two):.1f}), {v['speedup_best']:.2f}x best to best "
                    f"(rounds {', '.join(f'{x:.2f}' for x in v['speedup_per_round'])}), "
                    f"{v['constraint_iterations_per_s_2_threads']:.3g} constraint-iters/s"
                )
            lines.append(
                f"| threads-kites | batched kites, `warpsim run --threads 1` vs `--threads 2`, {r['rounds']} "
                f"alternating rounds: {'; '.join(parts)} ||||||||||"
            )
            continue
        rt = r.get("realtime_factor")
        lines.append(
            "| "
            + " | ".join(
                [
                    r["case"],
                    _fmt(r["steps_per_s"], 1 if r["steps_per_s"] < 100 else 0),
                    _fmt(r["ms_per_step"], 3),
                    f"{rt:,.1f}x" if rt is not None else "-",
                    _fmt(r.get("particles")),
                    _fmt(r.get("sticks")),
                    _fmt(r.get("iterations")),
                    f"{r['constraint_iterations_per_s']:.3g}" if r.get("constraint_iterations_per_s") else "-",
                    r.get("baseline", ""),
                    _fmt(r.get("baseline_steps_per_s"), 1) if "baseline" in r else "",
                    f"{r['ratio']:,.1f}x" if "ratio" in r else "",
                ]
            )
            + " |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Run the selected cases; returns the exit code."""
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks",
        description="warpsim's benchmark suite: steps per second of each case, and comparisons measured in the "
        "same run (the paper's figure, a plain NumPy step, Newton's XPBD, Euler against Verlet, batched worlds).",
    )
    parser.add_argument(
        "-k",
        dest="select",
        action="append",
        default=[],
        metavar="TEXT",
        help="run only the cases whose name contains TEXT (repeatable)",
    )
    parser.add_argument("--list", action="store_true", help="list the cases and exit")
    parser.add_argument(
        "--min-time",
        type=float,
        default=1.0,
        metavar="S",
        help="measure each timing over at least S wall seconds (default 1)",
    )
    parser.add_argument("--device", default="cpu", help="Warp device (default cpu)")
    parser.add_argument(
        "--json",
        metavar="PATH",
        default=None,
        help="where to write the results (default: benchmarks/results.json for a whole run; a run of a few cases "
        "(-k) writes none unless given one, so that it cannot replace the whole run's file with its subset)",
    )
    args = parser.parse_args(argv)
    if args.list:
        for name, case in CASES.items():
            print(f"{name:20s} {case.__doc__}")
        return 0
    names = [n for n in CASES if not args.select or any(s in n for s in args.select)]
    if not names:
        parser.error(f"no case matches {' / '.join(args.select)}; see --list")
    if not args.min_time > 0:
        parser.error("--min-time must be positive")
    try:
        wp.get_device(args.device)
    except (ValueError, RuntimeError):
        parser.error(f"--device {args.device} is not available here")
    opts = Options(min_time=args.min_time, device=args.device)
    info = machine()
    print(
        f"# {info['cpu']}, {info['cores']} cores; Warp {info['warp']} on {args.device}; {time.strftime('%Y-%m-%d')}",
        file=sys.stderr,
    )
    rows = []
    for name in names:
        start = time.perf_counter()
        print(f"  {name} ...", end="", flush=True, file=sys.stderr)
        row = CASES[name](opts)
        if "steps_per_s" in row:
            row["constraint_iterations_per_s"] = constraint_rate(row)
        rows.append(row)
        print(f" {time.perf_counter() - start:.1f} s", file=sys.stderr)
    print(table(rows))
    if args.json is None and not args.select:
        args.json = DEFAULT_JSON
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump(
                {"machine": info, "device": args.device, "date": time.strftime("%Y-%m-%d"), "results": rows},
                f,
                indent=1,
            )
        print(f"results written to {args.json}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
