"""``python -m benchmarks.validation``: the validation table, the convergence plot and the hour-long kite run.

Prints a Markdown table; the whole run (no ``-k``) also writes ``benchmarks/validation/results.md`` and
``results.json`` and the plot ``docs/convergence.svg``. Exit code 1 when a row misses its band without a stated
model limit.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import h5py
import numpy as np
import warp as wp

from warpsim.io.recording import Recording, RecordingError
from warpsim.run.simulation import BlowUpError, Simulation
from warpsim.scene import descriptor

from .cases import CASES
from .common import Row
from .svg import loglog_panels

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent


def worst_stretch_after(d: dict, seconds: float, settle: float = 1.0) -> float:
    """The worst stick stretch over the frames after ``settle`` seconds of a ``seconds`` run (NaN if it blew up)."""
    d = descriptor.merge("convergence", d, {"solver": {"max_stretch": 0.0}, "scene": {"fps": 50.0}})
    sim = Simulation(d)
    worst = [0.0]

    def on_frame(frame):
        if frame.time >= settle - 1e-9:
            worst[0] = max(worst[0], frame.worst_stretch)

    try:
        sim.run(seconds, on_frame=on_frame)
    except BlowUpError:
        return math.nan
    return worst[0]


ITERATIONS = (1, 2, 3, 5, 8, 13, 20, 30, 40, 55, 70, 100)
TIME_STEPS = (0.02, 0.01, 0.005, 0.0025, 0.00125)


def convergence(seconds: float = 4.0) -> dict:
    """Worst stretch (after the first second) against iterations at the object's default dt (glider 5 ms, kite
    2.5 ms) and against dt at its default iterations (glider 55, kite 45), for the hang glider and the kite at their
    defaults."""
    out = {}
    for kind in ("hang-glider", "kite"):
        base = descriptor.defaults(kind)
        by_iterations = [
            worst_stretch_after(descriptor.merge("k", base, {"solver": {"iterations": k}}), seconds) for k in ITERATIONS
        ]
        by_dt = [
            worst_stretch_after(descriptor.merge("dt", base, {"solver": {"dt": dt}}), seconds) for dt in TIME_STEPS
        ]
        out[kind] = {
            "iterations": list(ITERATIONS),
            "by_iterations": by_iterations,
            "dt": list(TIME_STEPS),
            "by_dt": by_dt,
        }
    return out


def plot_convergence(data: dict, path: Path) -> Path:
    """The convergence data as a two-panel log-log SVG."""
    pct = lambda values: [100 * v for v in values]  # noqa: E731
    return loglog_panels(
        [
            {
                "title": "worst stretch vs iterations (default dt)",
                "xlabel": "constraint iterations per step",
                "ylabel": "worst stick stretch [%]",
                "series": [(k, v["iterations"], pct(v["by_iterations"])) for k, v in data.items()],
            },
            {
                "title": "worst stretch vs time step (default iterations)",
                "xlabel": "dt [s]",
                "ylabel": "worst stick stretch [%]",
                "series": [(k, v["dt"], pct(v["by_dt"])) for k, v in data.items()],
            },
        ],
        path,
    )


def _rss_kib(pid: int) -> int | None:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    except OSError:
        return None
    return None


def long_run(seconds: float = 3600.0, fps: float = 1.0, poll: float = 1.0) -> tuple[list[Row], dict]:
    """Run ``kite_gusty.toml`` for ``seconds`` in a child ``warpsim run --h5``, reading the recording from this
    process while it grows (SWMR) and sampling the child's resident memory."""
    with tempfile.TemporaryDirectory() as tmp:
        rec = Path(tmp) / "hour.h5"
        cmd = [
            sys.executable,
            "-m",
            "warpsim",
            "run",
            str(ROOT / "scenes" / "kite_gusty.toml"),
            "--seconds",
            f"{seconds:g}",
        ]
        cmd += ["--fps", f"{fps:g}", "--h5", str(rec), "--quiet"]
        start = time.perf_counter()
        child = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        reads, rss = [], []
        while child.poll() is None:
            time.sleep(poll)
            kib = _rss_kib(child.pid)
            if kib:
                rss.append((time.perf_counter() - start, kib))
            try:  # as a user reads it: only frames a checkpoint covers (each dataset grows on its own under SWMR)
                with Recording(rec) as f:
                    n = f.frame_count
                    if n:
                        reads.append((n, float(f.time[n - 1]), bool(np.isfinite(f.positions(n - 1)).all())))
            except (OSError, KeyError, RecordingError):
                pass  # not created yet, or not yet in SWMR mode
        _, err = child.communicate()
        wall = time.perf_counter() - start
        with h5py.File(rec, "r") as f:
            times = f["time"][:]
            stretch = f["diagnostics/worst_stretch"][:]
    half = len(stretch) // 2
    first, second = float(stretch[1:half].max()), float(stretch[half:].max())
    grew = [b[0] > a[0] for a, b in zip(reads, reads[1:], strict=False)]
    early = [k for t, k in rss if t >= 0.1 * wall] or [k for _, k in rss]
    growth_mib = (early[-1] - early[0]) / 1024 if early else math.nan
    info = {
        "seconds": seconds,
        "wall_s": wall,
        "exit_code": child.returncode,
        "stderr": err.decode()[-500:],
        "frames": len(times),
        "reads_while_running": len(reads),
        "worst_stretch_first_half": first,
        "worst_stretch_second_half": second,
        "rss_kib": rss,
    }
    minutes = seconds / 60
    rows = [
        Row(
            "long run: stretch",
            f"worst stick stretch over {minutes:g} simulated minutes of the gusty kite (first half, second half)",
            "bounded: second half ≤ 1.5 × first half, and under solver.max_stretch",
            "no drift: the solver must not accumulate error",
            f"{100 * first:.1f} %, {100 * second:.1f} %",
            "second ≤ 1.5 × first, both < 100 %",
            child.returncode == 0 and second <= 1.5 * first and max(first, second) < 1.0,
            note=f"{len(times)} frames at {fps:g} fps, {wall:.0f} s wall",
        ),
        Row(
            "long run: memory",
            "resident memory of the running process, from 10 % of the run to its end",
            "flat",
            "a run streams its frames to disk and keeps none",
            f"{growth_mib:+.1f} MiB (of {early[-1] / 1024 if early else math.nan:.0f} MiB)",
            "grows less than 10 MiB",
            abs(growth_mib) < 10.0,
        ),
        Row(
            "long run: live reading",
            "another process opens the recording while it is written (h5py SWMR) and sees it grow",
            "every read succeeds and sees finite positions",
            "HDF5 single-writer/multiple-reader mode",
            f"{len(reads)} reads, {sum(grew)} saw new frames",
            "≥ 5 reads, all finite, frames grow",
            len(reads) >= 5 and all(r[2] for r in reads) and sum(grew) >= len(reads) // 2,
        ),
    ]
    return rows, info


def table(rows: list[Row]) -> str:
    """The rows as a Markdown table."""
    lines = [
        "| case | compared | expected | source | measured | band | status | note |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        cells = [r.case, r.compared, r.expected, r.source, r.measured, r.band, f"**{r.status}**", r.note]
        lines.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Entry point: run the chosen parts and print them; a whole run also writes the results."""
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.validation",
        description="The validation table, the convergence plot and the hour-long kite run. The whole run rewrites "
        "benchmarks/validation/results.md, results.json and docs/convergence.svg; exit code 1 when a row misses "
        "its band without a stated model limit.",
    )
    parser.add_argument(
        "-k", action="append", default=[], help="run only the parts whose name contains this (prints; writes nothing)"
    )
    parser.add_argument("--list", action="store_true", help="list the parts and exit")
    parser.add_argument("--long-seconds", type=float, default=3600.0, help="simulated time of the long run [s]")
    parser.add_argument("--no-write", action="store_true", help="print only; do not rewrite the results files")
    args = parser.parse_args(argv)
    wp.config.log_level = wp.LOG_WARNING
    parts = [*CASES, "convergence", "long-run"]
    if args.list:
        print("\n".join(parts))
        return 0
    chosen = [p for p in parts if not args.k or any(k in p for k in args.k)]
    if not chosen:
        parser.error(f"no part matches {' or '.join(repr(k) for k in args.k)}; the parts: {', '.join(parts)}")
    # the results files and the convergence picture are the whole run's: a part alone only prints
    write = not args.no_write and not args.k
    rows: list[Row] = []
    extra: dict = {}
    for name in chosen:
        t = time.perf_counter()
        if name == "convergence":
            data = convergence()
            extra["convergence"] = data
            if write:
                plot_convergence(data, ROOT / "docs" / "convergence.svg")
            for kind, v in data.items():
                at55 = v["by_iterations"][ITERATIONS.index(55)]
                print(
                    f"  convergence {kind}: "
                    + ", ".join(f"{k}: {100 * s:.2f}%" for k, s in zip(ITERATIONS, v["by_iterations"], strict=True))
                )
                print(
                    f"  convergence {kind} dt: "
                    + ", ".join(f"{d:g}: {100 * s:.2f}%" for d, s in zip(TIME_STEPS, v["by_dt"], strict=True))
                )
                rows.append(
                    Row(
                        f"convergence ({kind})",
                        "worst stretch after the first second, 55 iterations vs 13 (the object's default dt)",
                        "falls as iterations grow",
                        "Jacobi iterations converge (docs/convergence.svg)",
                        f"{100 * v['by_iterations'][ITERATIONS.index(13)]:.2f} % → {100 * at55:.2f} %",
                        "55 iterations below 13",
                        at55 < v["by_iterations"][ITERATIONS.index(13)],
                    )
                )
        elif name == "long-run":
            long_rows, info = long_run(args.long_seconds)
            rows += long_rows
            extra["long_run"] = {k: v for k, v in info.items() if k != "rss_kib"}
        else:
            rows += CASES[name]()
        print(f"{name}: {time.perf_counter() - t:.1f} s", file=sys.stderr)
    text = table(rows)
    machine = f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, Warp {wp.config.version}, cpu"
    print(text)
    print(f"\n{machine}")
    if args.k and not args.no_write:
        print("(a part alone: results.md, results.json and docs/convergence.svg are left as they are)")
    if write and rows:
        (HERE / "results.md").write_text(f"{text}\n\n{machine}; `python -m benchmarks.validation`\n", encoding="utf-8")
        payload = {"machine": machine, "rows": [r.as_dict() for r in rows], **extra}
        (HERE / "results.json").write_text(json.dumps(payload, indent=1) + "\n", encoding="utf-8")
    failed = [r.case for r in rows if r.status == "FAIL"]
    if failed:
        print(f"FAILED: {', '.join(failed)}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
