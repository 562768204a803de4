"""How much a model may take: the memory a machine can still give, and the check made before a model is built
(too many particles for one model, or for the memory available)."""

from __future__ import annotations

import os

BYTES_PER_PARTICLE = 2048
"""Memory [bytes] one particle takes to build and run, with its share of sticks and triangles (measured peak:
1.4 kB on a 200,000-particle flag, 2.5 sticks per particle)."""


def available_memory() -> int | None:
    """Memory [bytes] this machine can still give (``MemAvailable``), or None where it cannot be read."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


MAX_MODEL_PARTICLES = 1024 * 1024
"""Most particles one model may hold: building is done particle by particle in Python (about a minute for this many;
the ``build-scaling`` benchmark), and a 256 x 256 flag already steps at only a few steps per second on the CPU."""


def check_memory(particles: float, what: str) -> None:
    """Raise ``ValueError`` before building when ``particles`` exceed :data:`MAX_MODEL_PARTICLES` or would need
    more than 80 % of the memory available (``what`` names them: ``"256 worlds of 136 particles"``)."""
    if particles > MAX_MODEL_PARTICLES:
        raise ValueError(
            f"{what} ({particles:,.0f} particles) is more than the {MAX_MODEL_PARTICLES:,} one model may hold "
            "(building them would take minutes): use fewer worlds or a coarser object"
        )
    need = particles * BYTES_PER_PARTICLE
    available = available_memory()
    if available is not None and need > 0.8 * available:
        raise ValueError(
            f"{what} ({particles:,.0f} particles) would need about {need / 1e9:.1f} GB to build and run; this "
            f"machine has {available / 1e9:.1f} GB available: use fewer worlds or a coarser object"
        )
