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

COMMANDS = ("list", "info", "run", "view", "sweep", "plot", "convert", "render", "export", "schema")
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
        _silence_stdout()
        return 0


class StdoutWriteError(OSError):
    """Standard output could not take what a command printed (a full disk or an I/O error under a redirection)."""


class _Stdout:
    """Standard output for the length of a command: a failed write or flush (other than a closed pipe) becomes
    :class:`StdoutWriteError`, which the command line answers with one line and exit code 4."""

    def __init__(self, stream):
        self._stream = stream

    def _guard(self, call, *args):
        try:
            return call(*args)
        except BrokenPipeError:
            raise
        except OSError as err:
            raise StdoutWriteError(f"could not write to standard output ({err.strerror or err})") from None

    def write(self, text):
        return self._guard(self._stream.write, text)

    def flush(self):
        return self._guard(self._stream.flush)

    def __getattr__(self, name):
        return getattr(self._stream, name)


def _silence_stdout() -> None:
    """Point standard output at /dev/null, so that Python's own flush at exit raises no second error."""
    import os

    os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


def _main(argv: list[str] | None) -> int:
    parser = build_parser()
    if not (sys.argv[1:] if argv is None else argv):  # a bare `warpsim`: what it can do, and the usage's exit code
        parser.print_help()
        return EXIT_USAGE
    args = parser.parse_args(argv)
    from ..physics import _warp

    _warp.init()  # quietly: no banner, module load lines or CUDA-driver note on a CPU machine
    stdout, sys.stdout = sys.stdout, _Stdout(sys.stdout)
    try:
        code = _module(args.command).command(args)
        sys.stdout.flush()  # a full disk under a redirection shows here, not in Python's own flush at exit
        return code
    except Exception as err:  # noqa: BLE001 - only the errors _exit_code knows are answered; the rest re-raised
        code = _exit_code(err)
        if code is None:
            raise
        if isinstance(err, StdoutWriteError):
            _silence_stdout()
        sys.stderr.write(f"warpsim {args.command}: error: {one_line(str(err))}\n")
        return code
    finally:
        sys.stdout = stdout


def _exit_code(err: Exception) -> int | None:
    """The exit code of an error a command let through: 2 for a user's mistake (a bad scene, option, recording,
    table or output path; no display), 4 for an output (standard output too) that could not be written; None for
    anything else (a bug: its traceback is shown)."""
    from ..io import OutputPathError, OutputWriteError
    from ..io.hdf5 import RecordingError
    from ..scene.descriptor import DescriptorError
    from ..sweeps.metrics import SweepError
    from ..sweeps.plot import PlotError
    from ..viewer.backend import ViewerUnavailableError

    if isinstance(err, OutputWriteError | StdoutWriteError):
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
