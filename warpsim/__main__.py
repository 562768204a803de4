"""``python -m warpsim`` is the ``warpsim`` command (the console script calls :func:`console` too)."""

import os
import signal


def _exit_at_once(signum, frame):
    """Ctrl-C before :mod:`warpsim._interrupt` is loaded: nothing is open; one line, exit 130."""
    os.write(2, b"warpsim: interrupted\n")
    os._exit(130)


signal.signal(signal.SIGINT, _exit_at_once)  # first of all: the imports below take a while on a loaded machine

import sys  # noqa: E402

from ._interrupt import exit_at_once  # noqa: E402


def console() -> int:
    """Run the ``warpsim`` command line; returns its exit code.

    Ctrl-C ends the command at once while it has nothing open (see :mod:`warpsim._interrupt`); once the command has
    its exit code, a late Ctrl-C is ignored, so that it cannot interrupt the interpreter's own shut-down
    ("Exception ignored ... KeyboardInterrupt")."""
    signal.signal(signal.SIGINT, exit_at_once)
    from .cli.main import main

    code = main()
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    return code


if __name__ == "__main__":
    sys.exit(console())
