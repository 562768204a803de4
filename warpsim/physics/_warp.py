"""Warp, started quietly: the default device is the CPU, so Warp's banner, its per-module load lines and its
"Could not find or load the NVIDIA CUDA driver" warning (printed by its C library on every machine without a
GPU) are kept off the user's terminal. ``WARPSIM_VERBOSE=1`` shows them all.

Any other message Warp prints while starting is passed on to stderr unchanged.
"""

from __future__ import annotations

import os
import sys
import tempfile

import warp as wp

DRIVER_NOTE = "Could not find or load the NVIDIA CUDA driver"


def verbose() -> bool:
    """True when ``WARPSIM_VERBOSE`` asks for Warp's own messages."""
    return os.environ.get("WARPSIM_VERBOSE", "").strip() not in ("", "0")


def init() -> None:
    """Initialise Warp once (a no-op afterwards), quietly unless :func:`verbose`."""
    import warp._src.context as context

    if context.runtime is not None:
        return
    if verbose():
        wp.init()
        return
    if wp.config.log_level < wp.LOG_WARNING:  # banner and "Module ... load" lines are INFO
        wp.config.log_level = wp.LOG_WARNING
    sys.stderr.flush()
    try:
        saved = os.dup(2)
    except OSError:  # no stderr to protect
        wp.init()
        return
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), 2)
        try:
            wp.init()
        finally:
            os.dup2(saved, 2)
            os.close(saved)
        sink.seek(0)
        printed = sink.read().decode("utf-8", "replace")
    rest = "".join(line for line in printed.splitlines(keepends=True) if DRIVER_NOTE not in line)
    if rest:
        sys.stderr.write(rest)
