"""``warpsim run``: simulate a scene (or continue or replay a recording), write its outputs, print its summary."""

from __future__ import annotations

import contextlib
import sys
from dataclasses import dataclass
from pathlib import Path

from .._interrupt import interruptible
from .common import (
    EXIT_BLOWUP,
    EXIT_INTERRUPTED,
    EXIT_OUTPUT,
    UsageError,
    add_scene_options,
    check_device,
    checked_output,
    load_scene,
    number_type,
    one_line,
    same_file_check,
)


class _StopRequests:
    """SIGINT (Ctrl-C) and SIGTERM ask a run to stop after the current frame, then the outputs are finished.

    Further signals change nothing: raising from a signal handler can land anywhere (inside a clean-up callback,
    inside the stage export) and lose what was being written; a frame takes well under a second, and SIGKILL
    still ends a run at once (the recording keeps its last checkpoint).
    """

    def __init__(self):
        import signal

        self.requested = False
        self.previous = {}
        for sig in (signal.SIGINT, signal.SIGTERM):
            try:
                self.previous[sig] = signal.signal(sig, self._handle)
            except ValueError:  # not the main thread (e.g. a test runner's worker): leave signals alone
                pass

    def _handle(self, signum, frame):
        self.requested = True

    def __call__(self) -> bool:
        return self.requested

    def restore(self) -> None:
        import signal

        for sig, handler in self.previous.items():
            signal.signal(sig, handler)


def command(args) -> int:
    """Run a scene (or continue a recording) and print the summary: check the options, resolve the scene, open
    the outputs, run, report."""
    from ..io import OutputWriteError
    from ..io.table import check_table_path, write_world_table
    from ..run.replay import RecordedControls
    from ..run.simulation import BlowUpError

    paths = _check_run_options(args)
    h5_path = paths["--h5"]
    table = checked_output(check_table_path, args.table, "--table")
    device = check_device(args.device)
    with contextlib.ExitStack() as outputs:
        lock = _claim_recording(outputs, args, h5_path)
        run = _resolve_run(args)
        sim = _start(run, device, args)
        stop = _StopRequests()
        outputs.callback(stop.restore)
        writer = _Outputs(outputs, sim, run, args, paths, lock, stop)
        figures = None if args.quiet and not table else _flight_figures(sim, run.seconds)
        on_frame = writer.on_frame if writer.any else None
        if figures is not None:
            on_frame = _both(figures, on_frame)
        blowup = None
        try:
            summary = sim.run(
                run.seconds,
                on_frame=on_frame,
                on_progress=_progress(sim) if not args.quiet else None,
                realtime=args.realtime,
                stop=stop,
                before=RecordedControls(sim, run.controls) if run.controls is not None else None,
            )
        except BlowUpError as err:
            blowup, summary = err, err.summary
        writer.close()
    if table is not None:
        try:
            write_world_table(table, figures)
        except OutputWriteError as err:
            writer.failures.append(err)
    return _report(args, run, summary, blowup, writer.failures, paths, figures, table)


def _flight_figures(sim, seconds: float):
    """The closing figures of a run of ``seconds`` [s] from the simulation's current time: each object's
    :data:`~warpsim.run.figures.FIGURES` over the second half of the run (the sweeps' default window)."""
    from ..run.figures import FlightFigures

    start = sim.state.time
    return FlightFigures(sim, start + 0.5 * seconds, start + seconds)


def _both(first, second):
    """A frame callback that calls ``first`` then ``second`` (None: only ``first``)."""
    if second is None:
        return first

    def on_frame(frame):
        first(frame)
        second(frame)

    return on_frame


def _check_run_options(args) -> dict[str, Path | None]:
    """The checked path of every output (:data:`~warpsim.io.outputs.OUTPUTS`), by flag (None where not given); a
    contradictory or bad option is a usage error."""
    from ..io.outputs import OUTPUTS

    given = [
        flag for flag, value in (("SCENE", args.scene), ("--resume", args.resume), ("--replay", args.replay)) if value
    ]
    if len(given) > 1:
        raise UsageError(f"give one of SCENE, --resume REC.h5 and --replay REC.h5, not both {' and '.join(given)}")
    if not given:
        raise UsageError("missing SCENE (a built-in object, a scene name or a .toml path), or --resume/--replay REC.h5")
    if args.resume and args.h5:
        raise UsageError("--resume appends to its recording; --h5 is not needed")
    for flag, source in (("--resume", args.resume), ("--replay", args.replay)):
        if source:
            for name in ("set", "dt", "iterations", "fps", "worlds", "vary"):
                if getattr(args, name):
                    raise UsageError(f"--{name} cannot change a {flag} run; it uses the recording's settings")
            if not Path(source).is_file():
                raise UsageError(f"{flag} {source}: no such file")
    paths = {kind.flag: checked_output(kind.check, getattr(args, kind.dest), kind.flag) for kind in OUTPUTS}
    if args.scene:
        same_file_check(args.scene, paths)
    if args.replay:
        same_file_check(args.replay, paths, "the recording replayed")
    return paths


def _claim_recording(outputs, args, h5_path: Path | None):
    """Take the writer's lock of the ``--h5`` or ``--resume`` recording before anything else happens (another
    run writing it is a usage error); released when ``outputs`` closes. Returns the lock or None."""
    from ..io.h5format import signals_held
    from ..io.hdf5 import RecordingError, check_recording_path, claim

    if not (h5_path or args.resume):
        return None
    if args.resume:
        checked_output(check_recording_path, args.resume, "--resume")
    flag, path = ("--h5", h5_path) if h5_path else ("--resume", args.resume)
    interruptible()  # from here on Ctrl-C must close what is opened
    # SIGINT and SIGTERM held from the file's creation until its removal is arranged: one landing in between left
    # an empty file that every reader called 'not an HDF5 file' (a loaded suite run hit it); held, it lands just after
    with signals_held():
        try:
            lock = claim(path, create=bool(h5_path))  # held to the end: nobody else writes it meanwhile
        except RecordingError as err:
            raise UsageError(f"{flag} {err}") from None
        outputs.callback(lock.release, remove_created=True)  # a no-op once the recorder has released it
    return lock


@dataclass
class _RunInputs:
    """What ``warpsim run`` runs: the scene (a :class:`~warpsim.scene.scene.Scene`, named where it came from), how
    long (None: the scene's own time), and the checkpoint it continues (with that checkpoint's frame) when
    resuming."""

    scene: object
    seconds: float | None
    checkpoint: object = None
    frame: int = -1
    controls: list | None = None  # --replay: the recorded controls of each frame
    terrain: object = None  # --resume/--replay: the recording's own terrain (a Heightfield; None: the descriptor's)

    def __post_init__(self):
        if self.seconds is None:
            self.seconds = self.scene.seconds

    @property
    def where(self) -> str:
        """Where the scene came from (named in errors and in the run's first line)."""
        return self.scene.where


def _resolve_run(args) -> _RunInputs:
    """The scene of the command line, or the one a ``--resume`` recording holds with its checkpoint."""
    from ..io.hdf5 import RecordingError
    from ..io.recording import Recording

    if args.replay:
        try:
            with Recording(args.replay) as recording:
                if recording.frame_count == 0:
                    raise RecordingError(f"{args.replay}: the recording has no frames")
                controls = recording.controls()
                scene = recording.recorded_scene(f"{args.replay} (replayed)")
                length, terrain = float(recording.time[-1]), recording.terrain()
        except RecordingError as err:
            raise UsageError(f"--replay {err}") from None
        seconds = args.seconds if args.seconds is not None else length
        return _RunInputs(scene, seconds, controls=controls, terrain=terrain)
    if not args.resume:
        return _RunInputs(load_scene(args)[0], None)
    try:
        with Recording(args.resume, owner=True) as recording:
            checkpoint, frame = recording.checkpoint(), recording.checkpoint_frame
            where = f"{args.resume} (resumed)"
            scene, terrain = recording.recorded_scene(where), recording.terrain()
    except RecordingError as err:
        raise UsageError(f"--resume {err}") from None
    return _RunInputs(scene, args.seconds, checkpoint, frame, terrain=terrain)


def _start(run: _RunInputs, device: str, args):
    """The :class:`~warpsim.run.simulation.Simulation` of ``run`` (restored from its checkpoint), announced unless
    ``--quiet``."""
    from ..run.simulation import Simulation, available_cores

    sim = Simulation(
        run.scene,
        device=device,
        where=run.where,
        terrain=run.terrain,
        threads=args.threads or available_cores(),
    )
    if run.checkpoint is not None:
        try:
            sim.restore(run.checkpoint)
        except ValueError as err:
            raise UsageError(f"--resume {args.resume}: its checkpoint does not fit its scene ({err})") from None
    unknown = sorted({name for frame in run.controls or () for name in frame} - set(sim.control_names()))
    if unknown:  # a recording whose stored controls are not its scene's (edited): one line, not a KeyError
        raise UsageError(
            f"--replay {args.replay}: its frames set {', '.join(unknown)}, which its scene has no control for "
            f"(it has {', '.join(sim.control_names())})"
        )
    if not args.quiet:
        m = sim.model
        print(
            f"{run.where}: {m.particle_count} particles, {m.stick_count} sticks, {m.tri_count} triangles; "
            f"dt {sim.dt:g} s, {sim.settings.solver.method}, device {device}"
            + (f", {sim.threads} threads" if sim.threads > 1 else "")
            + (f"; from t = {sim.state.time:.3f} s, frame {run.frame}" if run.checkpoint is not None else "")
        )
    return sim


LOG_PROGRESS_INTERVAL = 10.0
"""Wall seconds between two progress lines when stderr is not a terminal (a log file, CI, ``| tee``)."""


def _progress(sim):
    """Progress on stderr: one line rewritten in place on a terminal; elsewhere a new line every
    :data:`LOG_PROGRESS_INTERVAL` wall seconds (a log shows the run is alive without a line per frame)."""
    tty = sys.stderr.isatty()
    last = {"wall": 0.0}

    def progress(t, total, steps, wall):
        rate = steps / wall if wall > 0 else 0.0
        text = f"  t = {t:8.2f} s  ({100 * steps * sim.dt / total:5.1f}%)  {rate:10,.0f} steps/s"
        if tty:
            sys.stderr.write("\r" + text)
        elif wall - last["wall"] >= LOG_PROGRESS_INTERVAL:
            last["wall"] = wall
            sys.stderr.write(text + "\n")
        sys.stderr.flush()

    return progress


class _Outputs:
    """The outputs of a run (its recording, then its stage; each an :class:`~warpsim.io.protocol.Output`), opened
    now and closed (always) by :meth:`close`; a write that fails stops the run at that frame, and its error is kept
    in ``failures``."""

    def __init__(self, stack, sim, run: _RunInputs, args, paths: dict, lock, stop):
        from ..io.outputs import OUTPUTS, RunOutputs

        self.stop, self.failures = stop, []
        self.outputs: list = []
        self._failed: set[int] = set()
        stack.callback(self.close)
        opened = RunOutputs(
            run.scene,
            "" if args.resume else run.where,
            resume=bool(args.resume),
            lock=lock,
        )
        # in the table's order, the recording first; USD loads here, after Ctrl-C no longer raises (_StopRequests);
        # a RecordingError is exit 2 (main._exit_code)
        for kind in OUTPUTS:
            path = args.resume if kind.flag == "--h5" and args.resume else paths[kind.flag]
            if path:
                self.outputs.append(kind.open(path, sim, opened))
        self.any = bool(self.outputs)

    def on_frame(self, frame) -> None:
        """Write ``frame`` to every output that has not failed."""
        from ..io import OutputWriteError
        from ..io.protocol import write_frame

        for k, output in enumerate(self.outputs):
            if k in self._failed:
                continue
            try:
                write_frame(output, frame)
            except OutputWriteError as err:  # stop at this frame; the outputs keep what they have
                self._failed.add(k)
                self.failures.append(err)
                self.stop.requested = True

    def close(self) -> None:
        """Finish every output (safe to call twice); a failure joins ``failures``."""
        from ..io import OutputWriteError

        outputs, self.outputs = self.outputs, []
        for output in outputs:
            try:
                output.close()
            except OutputWriteError as err:
                if err not in self.failures:
                    self.failures.append(err)


def _report(args, run: _RunInputs, summary, blowup, failures, paths: dict, figures=None, table=None) -> int:
    """Print the summary, the flight figures, the outputs and any error line; return the exit code."""
    from ..io.outputs import OUTPUTS

    if not args.quiet and sys.stderr.isatty():
        sys.stderr.write("\r" + " " * 70 + "\r")
    if not args.quiet:
        print(summary.text())
        for line in figures.lines() if figures is not None else ():
            print(line)
        written = [(k.label, args.resume if k.flag == "--h5" and args.resume else paths[k.flag]) for k in OUTPUTS]
        written = [(label, path) for label, path in written if path and Path(path).exists()]  # a picture of no frame
        for label, path in [*written, ("table", table)]:
            if path and not any(str(path) in str(err) for err in failures):
                print(f"  {label}: {path}")
    for err in failures:
        sys.stderr.write(f"warpsim run: error: {one_line(str(err))}\n")
    if failures:
        return EXIT_OUTPUT
    if blowup is not None:
        hint = (
            "try a smaller --dt (explicit Euler springs need dt well below sqrt(mass / solver.spring_stiffness)), "
            "or solver.method=verlet"
            if run.scene.settings.solver.method == "euler"
            else "try a smaller --dt or more --iterations"
        )
        sys.stderr.write(f"warpsim run: error: {one_line(str(blowup))}\n  ({hint}; see docs/outputs.md: Blow-ups)\n")
        return EXIT_BLOWUP
    return EXIT_INTERRUPTED if summary.interrupted else 0


def add_parser(sub) -> None:
    """Add the ``run`` command to the subparsers ``sub``."""
    from ..io.outputs import OUTPUTS

    run = sub.add_parser(
        "run",
        help="simulate a scene",
        description="Simulate a scene and print a summary: "
        "simulated time, steps, wall time, steps per second, real-time factor, worst stick "
        "stretch. Shows progress on a terminal (in a log or a pipe, a line every 10 s); Ctrl-C stops cleanly.",
    )
    run.add_argument("scene", metavar="SCENE", nargs="?", help="the scene (not with --resume or --replay)")
    run.add_argument(
        "--seconds",
        type=number_type("--seconds"),
        help="simulated time [s] (default: scene's); with --resume, the time to add",
    )
    add_scene_options(run)
    run.add_argument("--realtime", action="store_true", help="pace the run to the wall clock")
    run.add_argument("--quiet", action="store_true", help="print nothing but errors")
    for kind in OUTPUTS:  # warpsim.io.outputs: one line there per format
        run.add_argument(kind.flag, metavar=kind.metavar, help=kind.help)
    run.add_argument(
        "--table",
        metavar="OUT.parquet|OUT.csv",
        help="write the closing figures, one row per world (the sweep's columns; warpsim.io.table)",
    )
    run.add_argument(
        "--resume",
        metavar="REC.h5",
        help="continue a recording from its last frame, appending to it (scene and settings come from it)",
    )
    run.add_argument(
        "--replay",
        metavar="REC.h5",
        help="run a recording's scene again from the start with the controls recorded in it (a flight flown in "
        "`warpsim view`), for as long as it lasts (or --seconds); the frames come out bit for bit the same",
    )
