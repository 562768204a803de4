"""What test_recording_safety.py and test_recording_refusals.py share: the command line started in a subprocess
with SIGINT held until warpsim handles it, waits for its handler and its frames, and its one error line."""

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

from warpsim.io.recording import Recording

ROOT = Path(__file__).resolve().parent.parent


CUDA_NOTE = "Warp CUDA warning"  # printed by Warp on machines without a GPU driver; not ours


def _start(*args, cwd=None):
    """``python -m warpsim ARGS`` with SIGINT ignored until warpsim's first line installs its own handler (Python's
    start-up, before that line, is no code of warpsim's: see :func:`_wait_for_sigint_handler`)."""
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    return subprocess.Popen(
        [sys.executable, "-m", "warpsim", *map(str, args)],
        cwd=cwd or ROOT,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN),  # noqa: PLW1509 - no threads here
    )


def _wait_for_sigint_handler(proc, timeout=60.0) -> None:
    """Wait until ``proc`` (started by :func:`_start`, SIGINT ignored) catches SIGINT (Linux: its ``SigCgt`` mask in
    /proc), i.e. warpsim's first line has run: before it, Python's own start-up would handle Ctrl-C, which no code of
    warpsim's can reach. On a loaded machine that window lasted past the tests' first delays and made them flaky
    (issue 55)."""
    status = Path(f"/proc/{proc.pid}/status")
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and proc.poll() is None:
        try:
            caught = next(line for line in status.read_text().splitlines() if line.startswith("SigCgt:"))
        except (OSError, StopIteration):
            return  # not Linux, or gone: nothing to wait for
        if int(caught.split()[1], 16) & (1 << (signal.SIGINT - 1)):
            return
        time.sleep(0.002)


def _wait_for_frames(path, count, proc, timeout=120.0) -> int:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        assert proc.poll() is None, proc.communicate()
        if path.exists():
            try:
                with Recording(path) as rec:
                    if rec.frame_count >= count:
                        return rec.frame_count
            except Exception:  # noqa: BLE001 - not yet switched to SWMR
                pass
        time.sleep(0.1)
    raise AssertionError(f"no {count} frames in {path} after {timeout} s")


PROGRESS = re.compile(r"^\s+t =\s+\S+ s\s+\(")


def _one_error_line(err: list[str], *words: str) -> str:
    err = [line for line in err if not PROGRESS.match(line)]
    assert len(err) == 1, err
    assert err[0].startswith("warpsim ") and "error:" in err[0], err
    for word in words:
        assert word in err[0], err
    assert "Traceback" not in err[0]
    return err[0]
