"""Ctrl-C from the first moment the ``warpsim`` command runs.

While the command loads its modules and builds its model it has opened and written nothing, so Ctrl-C there ends
it at once with one line and exit code 130 (:func:`exit_at_once`): a ``KeyboardInterrupt`` raised in the middle of an
import (NumPy, Warp, h5py, pandas) surfaced as a traceback or an ``ImportError``, or, inside a finaliser, as
"Exception ignored ... KeyboardInterrupt" and was lost. Just before a command first creates a file it calls
:func:`interruptible`: from then on Ctrl-C raises ``KeyboardInterrupt`` (except inside a finaliser, where it is
delivered again when the finaliser has returned), which the command turns into closed outputs and exit 130.
"""

from __future__ import annotations

import os
import signal
import threading


def exit_at_once(signum, frame) -> None:
    """SIGINT handler while nothing is open: one line on stderr, exit 130, no clean-up needed."""
    os.write(2, b"warpsim: interrupted\n")
    os._exit(130)


def _raise_outside_finalisers(signum, frame) -> None:
    inside = frame
    while inside is not None:
        if inside.f_code.co_name == "__del__":  # an exception here could only be printed and lost
            again = threading.Timer(0.005, os.kill, (os.getpid(), signal.SIGINT))
            again.daemon = True
            again.start()
            return
        inside = inside.f_back
    raise KeyboardInterrupt


def interruptible() -> None:
    """Called by a command just before it first creates or opens an output: when :func:`exit_at_once` handles
    Ctrl-C (the ``warpsim`` process), Ctrl-C and SIGTERM raise ``KeyboardInterrupt`` from now on, so that the
    outputs are closed or removed (SIGTERM's default ended the process at once and left a just-created recording
    empty); in any other caller (a test calling :func:`warpsim.cli.main`) nothing changes."""
    if threading.current_thread() is threading.main_thread() and signal.getsignal(signal.SIGINT) is exit_at_once:
        signal.signal(signal.SIGINT, _raise_outside_finalisers)
        if signal.getsignal(signal.SIGTERM) == signal.SIG_DFL:
            signal.signal(signal.SIGTERM, _raise_outside_finalisers)
