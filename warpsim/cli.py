"""The ``warpsim`` command: list, info, run, view, sweep, plot, convert, render.

Every error a user can cause ends with one line ``warpsim <command>: error: ...`` and exit code 2; a run that
blows up (NaN/Inf, or a stick past ``solver.max_stretch``) ends with exit code 3 and keeps its outputs up to the
last good frame; an output that cannot be written part-way (disk full, I/O error) ends with exit code 4 and one
line naming the file and what it keeps; a sweep whose Dask task failed for good ends with 1 (its finished rows
kept); an interrupted run ends with 130.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
from dataclasses import dataclass
from pathlib import Path

from . import __version__
from ._interrupt import interruptible

EXIT_USAGE = 2
EXIT_BLOWUP = 3
EXIT_OUTPUT = 4
EXIT_INTERRUPTED = 130


class UsageError(Exception):
    """A user mistake: printed as one line, exit code 2."""


MAX_LINE = 600  # characters of an error line; a hostile value must not fill the terminal


def one_line(message: str) -> str:
    """``message`` with every control or line-breaking character escaped (``\\n``, ``\\r``...), so that text a
    user typed cannot break an error line apart, and cut to about ``MAX_LINE`` characters (a value of megabytes
    is not echoed whole)."""
    if len(message) > MAX_LINE:
        message = f"{message[: MAX_LINE - 120]} [... {len(message) - MAX_LINE + 100:,} characters ...] {message[-100:]}"
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in message)


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):  # one line, no usage dump
        self.exit(EXIT_USAGE, f"{self.prog}: error: {one_line(message)} (see {self.prog} --help)\n")


def _number(name: str, what: str = "a positive finite number", low: float = 0.0, high: float = math.inf, closed=False):
    """argparse type for ``name``: a finite float above ``low`` (``closed``: or equal to it) and at most ``high``;
    the error says it must be ``what``."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be a number, got {text!r}") from None
        above = value >= low if closed else value > low
        if not (above and value <= high and math.isfinite(value)):
            raise argparse.ArgumentTypeError(f"{name} must be {what}, got {text}")
        return value

    return parse


def _iterations(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--iterations must be a whole number >= 1, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"--iterations must be a whole number >= 1, got {value}")
    return value


def scene_dirs() -> list[Path]:
    """Where scene files are looked up: ./scenes, then the scenes/ folder beside the package."""
    dirs = [Path.cwd() / "scenes", Path(__file__).resolve().parent.parent / "scenes"]
    seen, out = set(), []
    for d in dirs:
        if d.is_dir() and d.resolve() not in seen:
            seen.add(d.resolve())
            out.append(d)
    return out


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``warpsim`` command."""
    parser = _Parser(
        prog="warpsim",
        description="Simulate flying fabric objects (flag, hang glider, delta kite, parachute) with Verlet "
        "particles and Jacobi-averaged distance constraints, in NVIDIA Warp kernels.",
        epilog="SCENE is a built-in object name (see `warpsim list`), a scene name found in ./scenes, "
        "or a path to a .toml descriptor. Exit codes: 0 done, 2 bad input (one error line), 3 the simulation "
        "blew up (outputs kept up to the last good frame), 4 an output could not be written (disk full, I/O error; "
        "one line says what it keeps), 1 a sweep's task failed for good (its finished rows kept), 130 interrupted "
        "(outputs kept).",
    )
    parser.add_argument("--version", action="version", version=f"warpsim {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True

    sub.add_parser(
        "list",
        help="built-in objects and the scene files found",
        description="List built-in objects and the scene files found in ./scenes and the project's scenes/ folder.",
    )

    info = sub.add_parser(
        "info",
        help="counts, masses and settings of a scene",
        description="Print a scene's particle/stick/triangle counts, masses and settings.",
    )
    info.add_argument("scene", metavar="SCENE")
    info.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a descriptor value, e.g. --set flag.resolution=8 (repeatable)",
    )
    _world_arguments(info)

    run = sub.add_parser(
        "run",
        help="simulate a scene",
        description="Simulate a scene and print a summary: "
        "simulated time, steps, wall time, steps per second, real-time factor, worst stick "
        "stretch. Shows progress on a terminal; Ctrl-C stops cleanly.",
    )
    run.add_argument("scene", metavar="SCENE", nargs="?", help="the scene (not with --resume or --replay)")
    run.add_argument(
        "--seconds",
        type=_number("--seconds"),
        help="simulated time [s] (default: scene's); with --resume, the time to add",
    )
    _scene_arguments(run)
    run.add_argument("--realtime", action="store_true", help="pace the run to the wall clock")
    run.add_argument("--quiet", action="store_true", help="print nothing but errors")
    run.add_argument(
        "--usd",
        metavar="OUT",
        help="write an animated USD stage (.usda text, .usdc binary, .usdz package), one time sample per frame; "
        "written when the run ends, also on Ctrl-C",
    )
    run.add_argument(
        "--h5",
        metavar="OUT.h5",
        help="stream a recording (positions, diagnostics, topology, descriptor) frame by frame; "
        "an interrupted run keeps every completed frame",
    )
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

    view = sub.add_parser(
        "view",
        help="fly a scene in a live 3-D window (keyboard control, real time)",
        description="Open a window and fly the scene at wall-clock pace: arrows steer the hang glider (held keys "
        "ramp pitch/roll to +-1, release ramps back), W/A/S/D walk the kite's anchor, +/- and [/] change the wind, "
        "Space pauses, '.' steps one frame, R restarts, C cycles the camera, H shows every key, Esc quits. "
        "Needs the viewer extra (pip install -e '.[viewer]') and a display (on a remote machine: ssh -X, or "
        "xvfb-run with --screenshot).",
    )
    view.add_argument("scene", metavar="SCENE")
    _scene_arguments(view)
    view.add_argument(
        "--h5",
        metavar="OUT.h5",
        help="record what is flown, with the controls as applied (replay: warpsim run --replay OUT.h5); after a "
        "restart the next take goes to OUT.take2.h5, ...",
    )
    view.add_argument(
        "--seconds", type=_number("--seconds"), help="close after this much simulated time (default: when you quit)"
    )
    view.add_argument("--screenshot", metavar="OUT.png", help="save the last picture drawn as a PNG when closing")
    view.add_argument("--size", type=_size, default=(1280, 720), metavar="WxH", help="window size (default 1280x720)")

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
        "line_angle [deg] and line_pull [N]; parachute radius [m]; and airborne [-], ground_time [s], "
        "worst_stretch [-], window_frames, blew_up, blowup_time [s], blowup_reason. Exit codes: 0 done, 2 bad "
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
        "--seconds", type=_number("--seconds"), help="simulated time of every case [s] (default: scene's)"
    )
    sweep.add_argument(
        "--window",
        type=_window,
        metavar="START:STOP",
        help="simulated seconds the window metrics cover (default: the second half of the run)",
    )
    sweep.add_argument(
        "--metrics", type=_names, metavar="M1,M2", help="report only these metrics (default: all the object has)"
    )
    sweep.add_argument("--list-metrics", action="store_true", help="print the scene's metrics with units and stop")
    sweep.add_argument(
        "--workers", type=_world_count, metavar="N", help="local worker processes (default: one per core)"
    )
    sweep.add_argument(
        "--scheduler",
        metavar="tcp://HOST:PORT",
        help="run on this running Dask scheduler's workers instead of a local cluster (see docs/sweeps.md)",
    )
    sweep.add_argument(
        "--chunk", type=_world_count, metavar="N", help="cases per task (default: about 4 tasks per worker, <= 64)"
    )
    sweep.add_argument("--h5-dir", metavar="DIR", help="also write one recording per chunk into DIR")
    sweep.add_argument("--resume", action="store_true", help="require --out to hold rows of this sweep already")
    sweep.add_argument("--restart", action="store_true", help="forget the rows --out holds and run every case")
    sweep.add_argument("--quiet", action="store_true", help="print nothing but errors")
    _scene_arguments(sweep, worlds=False)  # here --vary makes the sweep's axes

    plot = sub.add_parser(
        "plot",
        help="draw a metric of a sweep's table as a line or a heat map, or a recording's against time (PNG)",
        description="Draw a sweep's metric against one swept key (a line per combination of the other keys) or "
        "two (a heat map; the other keys fixed with --where). Blown-up cases are left out and counted in the "
        "title. A recording (REC.h5): its objects' figures against simulated time, one panel per --metric. "
        "Needs matplotlib (the sweep extra).",
    )
    plot.add_argument("table", metavar="SWEEP.parquet|SWEEP.csv|REC.h5")
    plot.add_argument("output", metavar="OUT.png")
    plot.add_argument("--x", metavar="KEY", help="swept key on the horizontal axis (a sweep's table: required)")
    plot.add_argument("--y", metavar="KEY", help="second swept key: draw a heat map")
    plot.add_argument(
        "--metric",
        required=True,
        metavar="M",
        help="the metric to draw, e.g. line_angle_mean; of a recording, against time, one or more: "
        "altitude,airspeed,sink (warpsim.io.plot.recording_metrics)",
    )
    plot.add_argument(
        "--where",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="keep only the cases with this value of a swept key (repeatable)",
    )

    convert = sub.add_parser(
        "convert",
        help="turn a recording into a USD stage",
        description="Write the frames of an HDF5 recording as an animated USD stage (same layout as run --usd).",
    )
    convert.add_argument("recording", metavar="REC.h5")
    convert.add_argument("output", metavar="OUT.usda|.usdc|.usdz")

    render = sub.add_parser(
        "render",
        help="draw a recording as a picture (.png, one frame) or an animation (.gif)",
        description="Draw a recording with a small built-in renderer (needs Pillow: pip install -e '.[render]'): "
        "OUT.png shows one frame (default the last), OUT.gif the whole run at simulated speed. The camera looks "
        "from the side and a little above, under the sky, at the distance that frames the objects, and follows them.",
    )
    render.add_argument("recording", metavar="REC.h5")
    render.add_argument("output", metavar="OUT.png|OUT.gif")
    render.add_argument("--frame", type=int, help="frame to draw in a .png (default: the last; -1 = last)")
    render.add_argument("--size", type=_size, default=(960, 540), metavar="WxH", help="pixels (default 960x540)")
    render.add_argument(
        "--azimuth",
        type=_number("--azimuth", "an angle in degrees from -360 to 360", -360.0, 360.0, closed=True),
        default=-60.0,
        help="view direction about +z [deg] (default -60)",
    )
    render.add_argument(
        "--elevation",
        type=_number("--elevation", "an angle in degrees from -90 to 90", -90.0, 90.0, closed=True),
        default=12.0,
        help="view height above the horizon [deg], -90..90 (default 12)",
    )
    render.add_argument(
        "--wide", action="store_true", help="frame the ropes and lines too (a kite's line down to its anchor)"
    )
    return parser


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        w = h = 0
    if not (16 <= w <= 8192 and 16 <= h <= 8192):
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT in pixels (16..8192), e.g. 960x540, got {text!r}")
    return w, h


def _window(text: str) -> tuple[float, float]:
    try:
        start, stop = (float(v) for v in text.split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected START:STOP in simulated seconds, e.g. 10:30, got {text!r}"
        ) from None
    if not (math.isfinite(start) and math.isfinite(stop) and 0.0 <= start <= stop):
        raise argparse.ArgumentTypeError(f"expected 0 <= START <= STOP, got {text!r}")
    return start, stop


def _names(text: str) -> list[str]:
    names = [n.strip() for n in text.split(",") if n.strip()]
    if not names:
        raise argparse.ArgumentTypeError(f"expected names separated by commas, got {text!r}")
    return names


def _scene_arguments(parser, worlds: bool = True) -> None:
    """The options that change the scene a command simulates: time step, iterations, frame rate, device,
    ``--set`` and (``worlds``) ``--worlds``/``--vary``."""
    parser.add_argument(
        "--dt", type=_number("--dt"), help="time step [s] (default: the scene's; `warpsim info SCENE` shows it)"
    )
    parser.add_argument("--iterations", type=_iterations, help="constraint iterations per step (default 55)")
    parser.add_argument("--fps", type=_number("--fps"), help="output frames per simulated second")
    parser.add_argument("--device", default="cpu", help="Warp device: cpu (default) or cuda[:N]")
    parser.add_argument(
        "--threads",
        type=_world_count,
        metavar="N",
        help="threads stepping the worlds, each a group of them, on the CPU (default: every core this process may "
        "use; in a sweep, the cores per worker process); the frames are the same, bit for bit, for any N",
    )
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a descriptor value, e.g. --set wind.velocity=[8,0,0] (repeatable)",
    )
    if worlds:
        _world_arguments(parser)


def _world_arguments(parser) -> None:
    parser.add_argument(
        "--worlds",
        type=_world_count,
        metavar="N",
        help="simulate N copies of the scene in one model, stepped by the same launches (default: scene's, 1)",
    )
    parser.add_argument(
        "--vary",
        action="append",
        default=[],
        metavar="KEY=VALUES",
        help="a value that differs between worlds: START:STOP spread over the N worlds, or one value per "
        "world, e.g. --vary wind.speed=4:12, --vary wind.gust_seed=0:255, --vary kite.rope_length=20,30 "
        "(keys of [wind] or of the object's section; repeatable)",
    )


def _load(args, worlds_from_vary: bool = True) -> tuple[dict, str, str]:
    """The scene of ``args`` with its ``--set``, ``--dt``, ``--iterations``, ``--fps``, ``--seconds`` and (with
    ``worlds_from_vary``) ``--worlds``/``--vary`` applied: ``(descriptor, source text, where)``."""
    from .descriptor import merge, parse_override, parse_vary, resolve

    descriptor, text, where = resolve(args.scene, scene_dirs())
    for item in args.set:
        descriptor = merge(f"--set {item}", descriptor, parse_override(item))
    count = getattr(args, "worlds", None)
    worlds: dict = {}
    for item in getattr(args, "vary", []) if worlds_from_vary else []:
        section, key, values = parse_vary(item, count)
        count = count or len(values)
        worlds.setdefault(section, {})[key] = values
    if count is not None:
        worlds["count"] = count
    if worlds:
        flags = " ".join([f"--worlds {count}"] + [f"--vary {v}" for v in args.vary])
        descriptor = merge(flags, descriptor, {"worlds": worlds})
    overrides = {
        ("solver", "dt", "--dt"): getattr(args, "dt", None),
        ("solver", "iterations", "--iterations"): getattr(args, "iterations", None),
        ("scene", "fps", "--fps"): getattr(args, "fps", None),
        ("scene", "seconds", "--seconds"): getattr(args, "seconds", None),
    }
    for (section, key, flag), value in overrides.items():
        if value is not None:  # checked against the descriptor's bounds like any other value
            descriptor = merge(f"{flag} {value:g}", descriptor, {section: {key: value}})
    return descriptor, text, where


def _world_count(text: str) -> int:
    from .descriptor import MAX_WORLDS

    try:
        value = int(text)
    except ValueError:
        value = 0
    if not 1 <= value <= MAX_WORLDS:
        raise argparse.ArgumentTypeError(f"must be a whole number from 1 to {MAX_WORLDS}, got {text!r}")
    return value


def _check_device(name: str) -> str:
    import warp as wp

    available = ", ".join(str(d) for d in wp.get_devices())
    # without a CUDA driver, asking Warp for a cuda device prints two raw driver errors first: say it in one line
    if name.startswith("cuda") and not wp.is_cuda_available():
        raise UsageError(f"--device {name} is not available here (no CUDA driver); available: {available}")
    try:
        wp.get_device(name)
    except (ValueError, RuntimeError):
        raise UsageError(f"--device {name} is not available here; available: {available}") from None
    return name


def cmd_list(args) -> int:
    """Print built-in objects and scene files."""
    from .objects import registry

    print("built-in objects:")
    for name, spec in registry.OBJECTS.items():
        print(f"  {name:<12} {spec.summary}")
    for directory in scene_dirs():
        files = sorted(directory.glob("*.toml"))
        if files:
            print(f"scenes in {directory}:")
            for f in files:
                print(f"  {f.stem:<22} {f}")
    return 0


def cmd_info(args) -> int:
    """Print counts, masses and settings of a scene."""
    import numpy as np

    from .descriptor import to_toml
    from .scene import build_model

    descriptor, _, where = _load(args)
    model = build_model(descriptor, "cpu", where)
    kind = descriptor["scene"]["object"]
    print(f"scene: {where} (object: {kind})")
    print(
        f"  particles {model.particle_count}, sticks {model.stick_count}, triangles {model.tri_count}, "
        f"nails {model.nail_count}"
    )
    for record in model.objects:
        mass = model.particle_mass[record.particles]
        print(f"  {record.name}: total mass {mass[mass != float('inf')].sum():.3f} kg (nailed particles excluded)")
        earlier: set[int] = set()  # parts may share particles (the flag's pole column is cloth too)
        for part, ids in record.parts.items():
            pm = model.particle_mass[ids]
            finite = pm[pm != float("inf")]
            shared = len(earlier.intersection(int(i) for i in ids))
            nailed = int(np.isinf(pm).sum())
            notes = ([f"{shared} also in a part above"] if shared else []) + ([f"{nailed} nailed"] if nailed else [])
            note = f" ({', '.join(notes)})" if notes else ""
            print(f"    part {part:<10} {len(ids):5d} particles, {finite.sum():9.3f} kg{note}")
            earlier.update(int(i) for i in ids)
        paper = record.paper_counts
        if paper:
            print(
                f"  the paper's model: particles {paper['particles']}, sticks {paper['sticks']}, "
                f"triangles {paper['triangles']} (see docs/objects.md)"
            )
    print(f"  terrain: {model.terrain}")
    print("settings:")
    print("  " + to_toml(descriptor).replace("\n", "\n  ").rstrip())
    return 0


def _checked_output(check, value: str | None, flag: str) -> Path | None:
    """``check(value)`` for an output option given as ``flag``; a bad path becomes a usage error."""
    from .io import OutputPathError

    if not value:
        return None
    try:
        return check(value)
    except OutputPathError as err:
        raise UsageError(f"{flag} {err}") from None


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


def _on_display_lost(viewer, backend, shot):
    """Install an Xlib I/O error handler for when the X server goes away under the viewer (Xlib's own printed two
    lines and exited 1 with the recording open and no screenshot): close the recording with every frame flown, save
    the screenshot, say so in one line and exit 130. Returns the handler (keep it referenced), or None without
    Xlib."""
    import os

    try:
        from pyglet.libs.x11 import xlib
    except Exception:  # noqa: BLE001 - not X11 (or no pyglet): nothing to watch
        return None

    def lost(display):
        try:
            viewer.close_recording()
            saved = ""
            if shot is not None:
                from .io.render import save_png

                saved = f"; screenshot: {save_png(shot, backend.screenshot())}"
            kept = f"; recording: {', '.join(str(p) for p in viewer.takes)}" if viewer.takes else ""
            sys.stderr.write(
                f"warpsim view: error: the display went away (its X server ended) at t = {viewer.sim.state.time:.2f} s"
                f"{kept}{saved}\n"
            )
            sys.stderr.flush()
        finally:
            os._exit(EXIT_INTERRUPTED)  # Xlib exits the process once this returns; nothing more can be drawn
        return 0

    handler = xlib.XIOErrorHandler(lost)
    xlib.XSetIOErrorHandler(handler)
    return handler


@contextlib.contextmanager
def _signals_quit(viewer):
    """Inside the block SIGINT and SIGTERM ask ``viewer`` to quit (its ``quit`` flag, read between frames), as Esc
    does. Off the main thread, signals are left alone."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handle(signum, frame):
        viewer.quit = True

    previous = {sig: signal.signal(sig, handle) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def _same_file_check(scene: str, outputs: dict, what: str = "the scene file") -> None:
    """Refuse an output that would overwrite the scene file being run."""
    from .io import same_file

    if not Path(scene).is_file():
        return
    for flag, path in outputs.items():
        if path is not None and Path(path).exists() and same_file(scene, path):
            raise UsageError(f"{flag} {path} is {what} itself; choose another output name")


def cmd_run(args) -> int:
    """Run a scene (or continue a recording) and print the summary: check the options, resolve the scene, open
    the outputs, run, report."""
    from .runner import BlowUpError, RecordedControls

    usd_path, h5_path = _check_run_options(args)
    from .io import OutputWriteError
    from .io.table import check_table_path, write_world_table

    table = _checked_output(check_table_path, args.table, "--table")
    device = _check_device(args.device)
    with contextlib.ExitStack() as outputs:
        lock = _claim_recording(outputs, args, h5_path)
        run = _resolve_run(args)
        sim = _start(run, device, args)
        stop = _StopRequests()
        outputs.callback(stop.restore)
        writer = _Outputs(outputs, sim, run, args, h5_path, usd_path, lock, stop)
        figures = None if args.quiet and not table else _flight_figures(sim, run.seconds)
        on_frame = writer.on_frame if writer.any else None
        if figures is not None:
            on_frame = _both(figures, on_frame)
        blowup = None
        try:
            summary = sim.run(
                run.seconds,
                on_frame=on_frame,
                on_progress=_progress(sim) if not args.quiet and sys.stderr.isatty() else None,
                realtime=args.realtime,
                stop=stop,
                before=RecordedControls(sim, run.controls) if run.controls is not None else None,
            )
        except BlowUpError as err:
            blowup, summary = err, err.summary
        writer.close()
    if table is not None:
        try:
            write_world_table(table, figures, sim.descriptor)
        except OutputWriteError as err:
            writer.failures.append(err)
    return _report(args, run, summary, blowup, writer.failures, h5_path, usd_path, figures, table)


def _flight_figures(sim, seconds: float):
    """The closing figures of a run of ``seconds`` [s] from the simulation's current time: each object's
    :data:`~warpsim.diagnostics.FIGURES` over the second half of the run (the sweeps' default window)."""
    from .diagnostics import FlightFigures

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


def _check_run_options(args) -> tuple[Path | None, Path | None]:
    """The checked ``--usd`` and ``--h5`` paths; a contradictory or bad option is a usage error."""
    from .io import check_stage_path
    from .io.hdf5 import check_recording_path

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
    usd_path = _checked_output(check_stage_path, args.usd, "--usd")
    h5_path = _checked_output(check_recording_path, args.h5, "--h5")
    if args.scene:
        _same_file_check(args.scene, {"--h5": h5_path, "--usd": usd_path})
    if args.replay:
        _same_file_check(args.replay, {"--h5": h5_path, "--usd": usd_path}, "the recording replayed")
    return usd_path, h5_path


def _claim_recording(outputs, args, h5_path: Path | None):
    """Take the writer's lock of the ``--h5`` or ``--resume`` recording before anything else happens (another
    run writing it is a usage error); released when ``outputs`` closes. Returns the lock or None."""
    from .io.hdf5 import RecordingError, check_recording_path, claim

    if not (h5_path or args.resume):
        return None
    if args.resume:
        _checked_output(check_recording_path, args.resume, "--resume")
    flag, path = ("--h5", h5_path) if h5_path else ("--resume", args.resume)
    interruptible()  # from here on Ctrl-C must close what is opened
    try:
        lock = claim(path, create=bool(h5_path))  # held to the end: nobody else writes it meanwhile
    except RecordingError as err:
        raise UsageError(f"{flag} {err}") from None
    outputs.callback(lock.release, remove_created=True)  # a no-op once the recorder has released it
    return lock


@dataclass
class _RunInputs:
    """What ``warpsim run`` runs: the descriptor, where it came from, how long, and the checkpoint it continues
    (with that checkpoint's frame) when resuming."""

    descriptor: dict
    where: str
    seconds: float
    checkpoint: object = None
    frame: int = -1
    controls: list | None = None  # --replay: the recorded controls of each frame
    terrain: object = None  # --resume/--replay: the recording's own terrain (a Heightfield; None: the descriptor's)


def _resolve_run(args) -> _RunInputs:
    """The scene of the command line, or the one a ``--resume`` recording holds with its checkpoint."""
    from .io.hdf5 import Recording, RecordingError

    if args.replay:
        try:
            with Recording(args.replay) as recording:
                if recording.frame_count == 0:
                    raise RecordingError(f"{args.replay}: the recording has no frames")
                controls = recording.controls()
                descriptor = recording.descriptor(f"{args.replay} (replayed)")
                length, terrain = float(recording.time[-1]), recording.terrain()
        except RecordingError as err:
            raise UsageError(f"--replay {err}") from None
        seconds = args.seconds if args.seconds is not None else length
        return _RunInputs(descriptor, f"{args.replay} (replayed)", seconds, controls=controls, terrain=terrain)
    if not args.resume:
        descriptor, _, where = _load(args)
        return _RunInputs(descriptor, where, descriptor["scene"]["seconds"])
    try:
        with Recording(args.resume, owner=True) as recording:
            checkpoint, frame = recording.checkpoint(), recording.checkpoint_frame
            where = f"{args.resume} (resumed)"
            descriptor, terrain = recording.descriptor(where), recording.terrain()
    except RecordingError as err:
        raise UsageError(f"--resume {err}") from None
    seconds = args.seconds if args.seconds is not None else descriptor["scene"]["seconds"]
    return _RunInputs(descriptor, where, seconds, checkpoint, frame, terrain=terrain)


def _start(run: _RunInputs, device: str, args):
    """The :class:`~warpsim.runner.Simulation` of ``run`` (restored from its checkpoint), announced unless
    ``--quiet``."""
    from .runner import Simulation, available_cores

    sim = Simulation(
        run.descriptor,
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
    if not args.quiet:
        m = sim.model
        print(
            f"{run.where}: {m.particle_count} particles, {m.stick_count} sticks, {m.tri_count} triangles; "
            f"dt {sim.dt:g} s, {run.descriptor['solver']['method']}, device {device}"
            + (f", {sim.threads} threads" if sim.threads > 1 else "")
            + (f"; from t = {sim.state.time:.3f} s, frame {run.frame}" if run.checkpoint is not None else "")
        )
    return sim


def _progress(sim):
    """A progress line on stderr, rewritten in place."""

    def progress(t, total, steps, wall):
        rate = steps / wall if wall > 0 else 0.0
        sys.stderr.write(f"\r  t = {t:8.2f} s  ({100 * steps * sim.dt / total:5.1f}%)  {rate:10,.0f} steps/s")
        sys.stderr.flush()

    return progress


class _Outputs:
    """The recording and the stage of a run, opened now and closed (always) by :meth:`close`; a write that fails
    stops the run at that frame, and its error is kept in ``failures``."""

    def __init__(self, stack, sim, run: _RunInputs, args, h5_path, usd_path, lock, stop):
        from .descriptor import to_toml
        from .io.hdf5 import H5Recorder, RecordingError

        self.stop, self.failures = stop, []
        self.recorder = self.usd = None
        stack.callback(self.close)
        try:
            if args.resume or h5_path:
                self.recorder = H5Recorder(
                    args.resume or h5_path,
                    sim.model,
                    run.descriptor,
                    sim.checkpoint,
                    "" if args.resume else to_toml(run.descriptor),
                    "" if args.resume else run.where,
                    resume=bool(args.resume),
                    lock=lock,
                )
        except RecordingError as err:
            raise UsageError(str(err)) from None
        if usd_path:
            from .io.usd import UsdWriter  # USD loads here, after Ctrl-C no longer raises (see _StopRequests)

            self.usd = UsdWriter(usd_path, sim.model, sim.steps_per_frame * sim.dt)
        self.any = bool(self.recorder or self.usd)

    def on_frame(self, frame) -> None:
        """Write ``frame`` to every output."""
        from .io import OutputWriteError

        if self.recorder and not self.failures:
            try:
                self.recorder.write(frame)
            except OutputWriteError as err:  # stop at this frame; the outputs keep what they have
                self.failures.append(err)
                self.stop.requested = True
        if self.usd:
            self.usd.write(frame.time, frame.positions)

    def close(self) -> None:
        """Finish every output (safe to call twice); a failure joins ``failures``."""
        from .io import OutputWriteError

        for name in ("recorder", "usd"):
            output = getattr(self, name)
            setattr(self, name, None)
            if output is not None:
                try:
                    output.close()
                except OutputWriteError as err:
                    if err not in self.failures:
                        self.failures.append(err)


def _report(args, run: _RunInputs, summary, blowup, failures, h5_path, usd_path, figures=None, table=None) -> int:
    """Print the summary, the flight figures, the outputs and any error line; return the exit code."""
    if not args.quiet and sys.stderr.isatty():
        sys.stderr.write("\r" + " " * 70 + "\r")
    if not args.quiet:
        print(summary.text())
        for line in figures.lines() if figures is not None else ():
            print(line)
        for label, path in (("recording", args.resume or h5_path), ("USD stage", usd_path), ("table", table)):
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
            if run.descriptor["solver"]["method"] == "euler"
            else "try a smaller --dt or more --iterations"
        )
        sys.stderr.write(f"warpsim run: error: {one_line(str(blowup))}\n  ({hint}; see docs/outputs.md: Blow-ups)\n")
        return EXIT_BLOWUP
    return EXIT_INTERRUPTED if summary.interrupted else 0


def cmd_convert(args) -> int:
    """Write a recording's frames as a USD stage."""
    from .io import OutputPathError
    from .io.hdf5 import RecordingError
    from .io.usd import recording_to_stage

    interruptible()  # the output's temporary is made next
    try:
        path = recording_to_stage(args.recording, args.output)
    except (RecordingError, OutputPathError) as err:
        raise UsageError(str(err)) from None
    print(f"{args.recording} -> {path}")
    return 0


def cmd_render(args) -> int:
    """Draw a recording as a PNG or an animated GIF."""
    from .io import OutputPathError
    from .io.hdf5 import RecordingError
    from .io.render import render_recording

    interruptible()  # the output's temporary is made next
    try:
        path = render_recording(
            args.recording, args.output, args.frame, args.size, args.azimuth, args.elevation, wide=args.wide
        )
    except (RecordingError, OutputPathError, RuntimeError) as err:
        raise UsageError(str(err)) from None
    print(f"{args.recording} -> {path}")
    return 0


def cmd_sweep(args) -> int:
    """Run a sweep into a table and say what it did."""
    from . import sweeps
    from .io import OutputPathError, check_output_path

    try:
        sweeps.require("distributed")
        sweeps.require("pandas")
        if not args.scheduler:
            sweeps.require("cryptography")
    except sweeps.SweepError as err:
        raise UsageError(str(err)) from None
    descriptor, _, where = _load(args, worlds_from_vary=False)  # here --vary makes the sweep's axes
    kind = descriptor["scene"]["object"]
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
    _same_file_check(args.scene, {"--out": out})
    if args.device != "cpu":
        _check_device(args.device)
    try:
        axes = sweeps.parse_axes(descriptor, args.vary)
        plan = sweeps.SweepPlan(descriptor, axes, args.seconds, args.window, args.metrics)
        if not args.scheduler:
            sweeps.check_workers(args.workers)
    except sweeps.SweepError as err:
        raise UsageError(str(err)) from None
    h5_dir = _check_h5_dir(args.h5_dir) if args.h5_dir and not args.scheduler else args.h5_dir
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
    except sweeps.SweepError as err:
        raise UsageError(str(err)) from None
    finally:
        sweeps.silence_dask()  # what a closing client says after the sweep (a scheduler gone) is not the user's
    if progress is not None:
        sys.stderr.write("\r" + " " * 70 + "\r")
    table = outcome.table
    blew = int(table["blew_up"].sum()) if len(table) else 0
    if not args.quiet:
        rate = outcome.ran / outcome.wall if outcome.wall > 0 else 0.0
        kept = f"{outcome.kept} already in {out}; " if outcome.kept else ""
        where_run = _count(outcome.workers, "worker") if outcome.ran else "nothing to run"
        status = "failed" if outcome.failures else "interrupted" if outcome.interrupted else "done"
        print(
            f"{status}: {kept}{_count(outcome.ran, 'case')} run in {outcome.wall:.1f} s on {where_run} "
            f"({rate:.2f} cases/s); {_count(len(table), 'row')}, {blew} blew up"
        )
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

    from .io import OutputPathError, check_output_path

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


def cmd_plot(args) -> int:
    """Draw a sweep's metric as a PNG."""
    from .io.plot import PlotError, plot_recording, plot_sweep

    recording = args.table.lower().endswith(".h5")
    if recording and (args.x or args.y or args.where):
        raise UsageError("a recording is drawn against time: --x, --y and --where are for a sweep's table")
    if not recording and not args.x:
        raise UsageError("--x KEY: the swept key on the horizontal axis of a sweep's table")
    interruptible()  # the output's temporary is made next
    try:
        if recording:
            path = plot_recording(args.table, args.output, args.metric.split(","))
        else:
            path = plot_sweep(args.table, args.output, args.x, args.metric, args.y, args.where)
    except PlotError as err:
        raise UsageError(str(err)) from None
    print(f"{args.table} -> {path}")
    return 0


def cmd_view(args) -> int:
    """Fly a scene in a window until the user quits (or --seconds); print where the outputs went."""
    from .descriptor import to_toml
    from .io.hdf5 import RecordingError, check_recording_path
    from .io.render import check_picture_path
    from .runner import Simulation, available_cores
    from .viewer.core import Viewer
    from .viewer.gl import PygletBackend

    h5_path = _checked_output(check_recording_path, args.h5, "--h5")
    shot = _checked_output(check_picture_path, args.screenshot, "--screenshot")
    if shot is not None:
        from .io.render import require_pillow

        try:
            require_pillow()
        except RuntimeError as err:
            raise UsageError(f"--screenshot: {err}") from None
    device = _check_device(args.device)
    descriptor, _, where = _load(args)
    _same_file_check(args.scene, {"--h5": h5_path, "--screenshot": shot})
    from .viewer import gl

    gl.check_display()  # a missing extra or display is said before the model is built
    sim = Simulation(descriptor, device=device, where=where, threads=args.threads or available_cores())
    backend = PygletBackend(args.size, keep_pictures=shot is not None)
    interruptible()  # the recording opens next
    try:
        viewer = Viewer(sim, backend, f"warpsim: {where}", h5_path, to_toml(descriptor), where, seconds=args.seconds)
    except RecordingError as err:
        raise UsageError(f"--h5 {err}") from None
    lost = _on_display_lost(viewer, backend, shot)  # kept referenced: Xlib holds only a C pointer to it
    # Ctrl-C in the terminal, or SIGTERM, quits like Esc, between two frames: the recording closed with every frame
    # flown (an interrupt raised between a step and its write once cost the frames since the last checkpoint), the
    # screenshot saved
    with _signals_quit(viewer), contextlib.suppress(KeyboardInterrupt):
        viewer.run()  # closes the recording and the window, however it ends
    if shot is not None:
        from .io.render import save_png

        print(f"screenshot: {save_png(shot, backend.screenshot())}")
    del lost
    print(f"simulated {sim.state.time:.2f} s; drew {viewer.pictures} pictures")
    for path in viewer.takes:
        print(f"recording: {path}")
    return EXIT_BLOWUP if viewer.blew_up else 0


def main(argv: list[str] | None = None) -> int:
    """The ``warpsim`` command line (``argv``: its arguments; default ``sys.argv[1:]``); returns the exit code."""
    try:
        return _main(argv)
    except KeyboardInterrupt:  # Ctrl-C before a run's own handling starts (start-up, model building)
        sys.stderr.write("warpsim: interrupted\n")
        return EXIT_INTERRUPTED
    except BrokenPipeError:  # the reader went away (`warpsim list | head`): nothing more to say
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no second error when Python flushes
        return 0


def _count(n: int, noun: str) -> str:
    """``n`` and ``noun``, plural unless ``n`` is 1 ("1 case", "2 cases")."""
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def _main(argv: list[str] | None) -> int:
    parser = build_parser()
    if not (sys.argv[1:] if argv is None else argv):  # a bare `warpsim`: what it can do, not an error
        parser.print_help()
        return 0
    args = parser.parse_args(argv)
    from . import _warp

    _warp.init()  # quietly: no banner, module load lines or CUDA-driver note on a CPU machine
    from .descriptor import DescriptorError
    from .io import OutputWriteError
    from .viewer.backend import ViewerUnavailableError

    commands = {
        "list": cmd_list,
        "info": cmd_info,
        "run": cmd_run,
        "view": cmd_view,
        "convert": cmd_convert,
        "render": cmd_render,
        "sweep": cmd_sweep,
        "plot": cmd_plot,
    }
    try:
        return commands[args.command](args)
    except (DescriptorError, UsageError, ViewerUnavailableError) as err:
        sys.stderr.write(f"warpsim {args.command}: error: {one_line(str(err))}\n")
        return EXIT_USAGE
    except OutputWriteError as err:
        sys.stderr.write(f"warpsim {args.command}: error: {one_line(str(err))}\n")
        return EXIT_OUTPUT


if __name__ == "__main__":
    sys.exit(main())
