"""The ``warpsim`` command: list, info, run, view, sweep, plot, convert, render, schema (one module each here).

Every error a user can cause ends with one line ``warpsim <command>: error: ...`` and exit code 2; a run that
blows up (NaN/Inf, or a stick past ``solver.max_stretch``) ends with exit code 3 and keeps its outputs up to the
last good frame; an output that cannot be written part-way (disk full, I/O error) ends with exit code 4 and one
line naming the file and what it keeps; a sweep whose Dask task failed for good ends with 1 (its finished rows
kept); an interrupted run ends with 130. The errors are mapped to exit codes here, once (:func:`_exit_code`).
"""

from __future__ import annotations

import argparse
import importlib
import sys

from .._version import __version__
from .common import EXIT_INTERRUPTED, EXIT_OUTPUT, EXIT_USAGE, Parser, UsageError, one_line

COMMANDS = ("list", "info", "run", "view", "sweep", "plot", "convert", "render", "schema")
"""The commands, in the order ``--help`` lists them; each is the module of that name in this package, with
``add_parser(sub)`` and ``command(args) -> exit code``."""


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``warpsim`` command."""
    parser = Parser(
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
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    sub.required = True
    for name in COMMANDS:
        _module(name).add_parser(sub)
    return parser


def _module(name: str):
    return importlib.import_module(f".{name}", __package__)


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


def _main(argv: list[str] | None) -> int:
    parser = build_parser()
    if not (sys.argv[1:] if argv is None else argv):  # a bare `warpsim`: what it can do, not an error
        parser.print_help()
        return 0
    args = parser.parse_args(argv)
    from ..physics import _warp

    _warp.init()  # quietly: no banner, module load lines or CUDA-driver note on a CPU machine
    try:
        return _module(args.command).command(args)
    except Exception as err:  # noqa: BLE001 - only the errors _exit_code knows are answered; the rest re-raised
        code = _exit_code(err)
        if code is None:
            raise
        sys.stderr.write(f"warpsim {args.command}: error: {one_line(str(err))}\n")
        return code


def _exit_code(err: Exception) -> int | None:
    """The exit code of an error a command let through: 2 for a user's mistake (a bad scene, option, recording,
    table or output path; no display), 4 for an output that could not be written; None for anything else (a bug:
    its traceback is shown)."""
    from ..io import OutputPathError, OutputWriteError
    from ..io.hdf5 import RecordingError
    from ..scene.descriptor import DescriptorError
    from ..sweeps.metrics import SweepError
    from ..sweeps.plot import PlotError
    from ..viewer.backend import ViewerUnavailableError

    if isinstance(err, OutputWriteError):
        return EXIT_OUTPUT
    usage = (
        DescriptorError,
        UsageError,
        ViewerUnavailableError,
        RecordingError,
        OutputPathError,
        SweepError,
        PlotError,
    )
    return EXIT_USAGE if isinstance(err, usage) else None


if __name__ == "__main__":
    sys.exit(main())
