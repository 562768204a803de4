"""A virtual X screen (Debian's ``xvfb``) for the viewer's tests and benchmark on machines without a display."""

from __future__ import annotations

import contextlib
import os
import shutil
import socket
import subprocess
import time


class VirtualDisplayError(RuntimeError):
    """Xvfb is missing or did not start."""


def _answers(number: str, server: subprocess.Popen, timeout: float = 10.0) -> bool:
    """Wait until display ``number`` accepts connections on its socket; False when the server exits first."""
    path = f"/tmp/.X11-unix/X{number}"
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if server.poll() is not None:
            return False
        with contextlib.suppress(OSError), socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
            s.connect(path)
            time.sleep(0.05)  # let a server that is about to fail on start-up do so
            return server.poll() is None
        time.sleep(0.05)
    return False


@contextlib.contextmanager
def virtual_display(size: tuple[int, int] = (1920, 1080), attempts: int = 3):
    """Start Xvfb on a free display number; yields the environment (``os.environ`` with ``DISPLAY`` set) and
    stops the server afterwards. Tries ``attempts`` times (a server started right after another one stopped
    sometimes exits at once). Raises :class:`VirtualDisplayError` when Xvfb is missing or never starts."""
    if shutil.which("Xvfb") is None:
        raise VirtualDisplayError("no Xvfb (apt install xvfb)")
    for _ in range(attempts):
        read, write = os.pipe()
        server = subprocess.Popen(
            ["Xvfb", "-displayfd", str(write), "-screen", "0", f"{size[0]}x{size[1]}x24", "-nolisten", "tcp"],
            pass_fds=(write,),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        os.close(write)
        number = b""
        with os.fdopen(read, "rb") as pipe:
            while not number.endswith(b"\n"):
                chunk = pipe.read(1)
                if not chunk:
                    break
                number += chunk
        number = number.decode().strip()
        if number and _answers(number, server):
            try:
                yield {**os.environ, "DISPLAY": f":{number}"}
            finally:
                server.terminate()
                server.wait(timeout=10)
            return
        server.kill()
        server.wait(timeout=10)
    raise VirtualDisplayError(f"Xvfb did not start in {attempts} attempts")
