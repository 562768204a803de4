"""``warpsim sweep``: run every combination of a few settings into a table."""

from __future__ import annotations

import contextlib
import sys
from pathlib import Path

from .._interrupt import interruptible
from .common import (
    EXIT_INTERRUPTED,
    UsageError,
    add_scene_options,
    check_device,
    load_scene,
    names_type,
    number_type,
    one_line,
    plural,
    same_file_check,
    scene_sources,
    window_type,
    world_count_type,
)


@contextlib.contextmanager
def _terminate_as_interrupt():
    """Inside the block, the first SIGTERM raises ``KeyboardInterrupt`` where Ctrl-C would (so that a sweep closes
    its cluster and writes its rows as it does on Ctrl-C, instead of dying with them unwritten); later ones are
    ignored, so that the clean-up itself is not cut short. Off the main thread, signals are left alone."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    raised = []

    def handle(signum, frame):
        if not raised:
            raised.append(signum)
            raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, handle)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def command(args) -> int:
    """Run a sweep into a table and say what it did."""
    from .. import sweeps
    from ..io import OutputPathError, check_output_path

    sweeps.require("distributed")  # a SweepError is exit 2 (main._exit_code)
    sweeps.require("pandas")
    if not args.scheduler:
        sweeps.require("cryptography")
    scene, _ = load_scene(args, worlds_from_vary=False)  # here --vary makes the sweep's axes
    where = scene.where
    kind = scene.kind
    if args.list_metrics:
        for name in sweeps.metrics_of(kind):
            unit, _, meaning = sweeps.METRICS[name]
            print(f"{name:<16} [{unit}]  {meaning}")
        return 0
    if not args.out:
        raise UsageError("--out OUT.parquet (or OUT.csv) is required: where the rows go")
    try:
        out = check_output_path(args.out, (".parquet", ".pq", ".csv"), "table")
    except OutputPathError as err:
        raise UsageError(f"--out {err}") from None
    if args.restart and args.resume:
        raise UsageError("--resume keeps the rows --out holds and --restart forgets them: give one")
    if args.resume and not (out.exists() or out.with_name(out.name + ".partial").exists()):
        raise UsageError(f"--resume: {out} holds no rows yet (run without --resume to start the sweep)")
    same_file_check(scene_sources(scene), {"--out": out}, "what the scene reads")
    if args.device != "cpu":
        check_device(args.device)
    axes = sweeps.parse_axes(scene, args.vary)
    plan = sweeps.SweepPlan(scene, axes, args.seconds, args.window, args.metrics)
    if not args.scheduler:
        sweeps.check_workers(args.workers)
    h5_dir = _check_h5_dir(args.h5_dir) if args.h5_dir and not args.scheduler else args.h5_dir
    if h5_dir and args.scheduler and Path(h5_dir).exists() and not Path(h5_dir).is_dir():
        raise UsageError(f"--h5-dir {h5_dir} is a file here, not a folder")
    h5_dir = Path(h5_dir) if h5_dir else None
    total = len(plan.cases)
    if not args.quiet:
        sizes = " x ".join(f"{len(a.values)} {a.name}" for a in plan.axes)
        print(
            f"{where}: {total} cases ({sizes}), {plan.seconds:g} s each, window {plan.window[0]:g}-{plan.window[1]:g} s"
        )
    progress = _sweep_progress if not args.quiet and sys.stderr.isatty() else None
    interruptible()  # the sweep's journal and table open inside
    try:
        with _terminate_as_interrupt():  # SIGTERM stops the sweep like Ctrl-C: workers stopped, rows written, 130
            outcome = sweeps.run_sweep(
                plan,
                out,
                args.workers,
                args.scheduler,
                args.chunk,
                args.device,
                h5_dir,
                args.restart,
                progress,
                threads=args.threads,
            )
    finally:
        sweeps.silence_dask()  # what a closing client says after the sweep (a scheduler gone) is not the user's
    if progress is not None:
        sys.stderr.write("\r" + " " * 70 + "\r")
    table = outcome.table
    unbuilt = int(table["blowup_reason"].astype(str).str.startswith("not built").sum()) if len(table) else 0
    blew = (int(table["blew_up"].sum()) if len(table) else 0) - unbuilt
    if not args.quiet:
        rate = outcome.ran / outcome.wall if outcome.wall > 0 else 0.0
        kept = f"{outcome.kept} already in {out}; " if outcome.kept else ""
        status = "failed" if outcome.failures else "interrupted" if outcome.interrupted else "done"
        ran = (
            f"{plural(outcome.ran, 'case')} run in {outcome.wall:.1f} s on {plural(outcome.workers, 'worker')} "
            f"({rate:.2f} cases/s)"
            if outcome.ran
            else "nothing left to run"
            if status == "done"
            else "no case finished"
        )
        not_built = f", {unbuilt} not built (their rows say why)" if unbuilt else ""
        print(f"{status}: {kept}{ran}; {plural(len(table), 'row')}, {blew} blew up{not_built}")
        print(f"  table: {out}")
    if outcome.failures:  # one line: the first failure's first line (a Dask error text runs over many)
        err = outcome.failures[0]
        text = (str(err).strip().splitlines() or [type(err).__name__])[0]
        more = f" (and {len(outcome.failures) - 1} more)" if len(outcome.failures) > 1 else ""
        log = f"; Dask's log: {outcome.log}" if outcome.log else ""
        sys.stderr.write(
            f"warpsim sweep: error: a task failed{more}: {one_line(text)}; the finished rows are kept{log}\n"
        )
        return 1
    return EXIT_INTERRUPTED if outcome.interrupted else 0


def _check_h5_dir(text: str) -> Path:
    """The ``--h5-dir`` of a local sweep, checked before anything runs: a folder (or one that can be made in the
    nearest folder that exists) that takes new files and has room (a full disk, a file in the way or a read-only
    folder ended in a Dask traceback once the workers tried)."""
    import os

    from ..io import OutputPathError, check_output_path

    h5_dir = Path(text)
    existing = h5_dir
    while not existing.exists() and existing != existing.parent and not existing.is_symlink():
        existing = existing.parent
    if not existing.is_dir():
        what = "is" if existing == h5_dir else f"lies under {existing}, which is"
        raise UsageError(f"--h5-dir {h5_dir} {what} not a folder")
    try:
        check_output_path(existing / "cases-000000-000000.h5", (".h5",), "HDF5")
    except OutputPathError:
        raise UsageError(f"--h5-dir {h5_dir}: recordings cannot be written in {existing}") from None
    info = os.statvfs(existing)
    if info.f_bavail * info.f_frsize < 1 << 20:
        raise UsageError(f"--h5-dir {h5_dir}: no space left on its disk (less than 1 MiB free)")
    return h5_dir


def _sweep_progress(done: int, total: int, wall: float) -> None:
    rate = done / wall if wall > 0 else 0.0
    eta = (total - done) / rate if rate > 0 else float("nan")
    sys.stderr.write(f"\r  {done}/{total} cases  {rate:6.2f} cases/s  ETA {eta:5.0f} s")
    sys.stderr.flush()


def add_parser(sub) -> None:
    """Add the ``sweep`` command to the subparsers ``sub``."""
    sweep = sub.add_parser(
        "sweep",
        help="run every combination of a few settings on every core (Dask) into a table",
        description="Run the cartesian product of the --vary axes (and of the scene's [sweep] table) and write "
        "one row per case, its swept values and its metrics, to a .parquet (or .csv) table. Cases run in chunks of "
        "batched worlds, one Dask task each, on a local cluster of one single-threaded worker process per core, "
        "or on a running Dask cluster (--scheduler). Running the same sweep again with the same --out runs only the "
        "cases the table does not hold yet; Ctrl-C keeps the finished rows. A case that blows up is a row saying "
        "when and why. Needs the sweep extra: pip install -e '.[sweep]'.",
        epilog="Metrics (see --list-metrics): window figures as NAME_mean/_min/_max over --window (default the "
        "second half of the run): altitude [m], airspeed [m/s], sink [m/s]; glider glide [-] and bank [deg]; kite "
        "line_angle [deg] and line_pull [N]; parachute radius [m] and swing [deg]; flag flap [m] and "
        "flap_frequency [Hz] (the mesh's without a resolved bending stiffness, the cloth's with one: the "
        "run's note says which); and airborne [-], ground_time [s], "
        "worst_stretch [%], window_frames, blew_up, blowup_time [s], blowup_reason. Exit codes: 0 done, 2 bad "
        "input, 1 a task failed for good (the finished rows are kept), 130 interrupted (the finished rows are kept).",
    )
    sweep.add_argument("scene", metavar="SCENE")
    sweep.add_argument(
        "--vary",
        action="append",
        default=[],
        metavar="KEY=VALUES",
        help="a swept key: START:STOP:COUNT (COUNT values, both ends included) or V1,V2,...; any key outside "
        "[scene], and wind.speed, e.g. --vary kite.tow_point=0.2:0.5:4 --vary wind.speed=4,8,12 (repeatable)",
    )
    sweep.add_argument("--out", metavar="OUT.parquet|OUT.csv", help="the results table (required)")
    sweep.add_argument(
        "--seconds", type=number_type("--seconds"), help="simulated time of every case [s] (default: scene's)"
    )
    sweep.add_argument(
        "--window",
        type=window_type,
        metavar="START:STOP",
        help="simulated seconds the window metrics cover (default: the second half of the run)",
    )
    sweep.add_argument(
        "--metrics", type=names_type, metavar="M1,M2", help="report only these metrics (default: all the object has)"
    )
    sweep.add_argument("--list-metrics", action="store_true", help="print the scene's metrics with units and stop")
    sweep.add_argument(
        "--workers", type=world_count_type, metavar="N", help="local worker processes (default: one per core)"
    )
    sweep.add_argument(
        "--scheduler",
        metavar="tcp://HOST:PORT",
        help="run on this running Dask scheduler's workers instead of a local cluster (see docs/sweeps.md)",
    )
    sweep.add_argument(
        "--chunk", type=world_count_type, metavar="N", help="cases per task (default: about 4 tasks per worker, <= 64)"
    )
    sweep.add_argument("--h5-dir", metavar="DIR", help="also write one recording per chunk into DIR")
    sweep.add_argument("--resume", action="store_true", help="require --out to hold rows of this sweep already")
    sweep.add_argument("--restart", action="store_true", help="forget the rows --out holds and run every case")
    sweep.add_argument("--quiet", action="store_true", help="print nothing but errors")
    add_scene_options(sweep, worlds=False)  # here --vary makes the sweep's axes
