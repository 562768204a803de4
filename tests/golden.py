"""Digests of every shipped scene's positions after 1,000 solver steps, flown through ``Simulation.run`` frame by
frame: the guard that a change of the house (the frame loop, the scene's types, the outputs) leaves every flight the
same, bit for bit (issue 54). ``tests/test_golden.py`` compares them with ``tests/data/golden_positions.json``.

Warp compiles the CPU kernels for the machine's own instruction set (``-march=native``), and fused multiply-adds
round differently from a multiply and an add, so the digests hold on the kind of CPU that made them, which the file
names (:func:`machine`). A change that means to move a flight writes them again, and says why in its commit:

    python -m tests.golden     # from the repository's root: writes tests/data/golden_positions.json
"""

from __future__ import annotations

import hashlib
import json
import platform
import sys
from pathlib import Path

import numpy as np

STEPS = 1000
"""Solver steps each scene flies."""
FILE = Path(__file__).resolve().parent / "data" / "golden_positions.json"
SCENES = Path(__file__).resolve().parents[1] / "warpsim" / "scene" / "files"
FEATURES = ("avx512f", "avx2", "fma", "sse4_2", "neon", "asimd")
"""The CPU features that change how the kernels are compiled."""


def machine() -> str:
    """The kind of machine the digests hold on: its architecture, its vector and FMA features, Warp's version."""
    import warp as wp

    flags = set()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith(("flags", "Features")):
                flags = set(line.split(":", 1)[1].split())
                break
    except OSError:
        pass
    have = [f for f in FEATURES if f in flags]
    return f"{platform.machine()} {'+'.join(have) or 'no-flags'} warp {wp.__version__}"


def digest(array: np.ndarray) -> str:
    """The sha256 of ``array``'s bytes (C order), as hex."""
    return hashlib.sha256(np.ascontiguousarray(array).tobytes()).hexdigest()


def fly(name: str) -> dict:
    """Scene ``name``'s digests: its final positions and every frame's, after ``STEPS`` steps of ``Simulation.run``."""
    from warpsim.run.simulation import Simulation
    from warpsim.scene import descriptor

    sim = Simulation(descriptor.resolve(str(SCENES / f"{name}.toml"))[0])
    frames = hashlib.sha256()

    def keep(frame) -> None:
        frames.update(np.ascontiguousarray(frame.positions).tobytes())

    sim.run(STEPS * sim.dt, on_frame=keep)
    assert sim.steps_taken == STEPS, (name, sim.steps_taken)
    return {"final": digest(sim.state.positions()), "frames": frames.hexdigest()}


def names() -> list[str]:
    """The shipped scenes."""
    return sorted(p.stem for p in SCENES.glob("*.toml"))


def main() -> None:
    scenes = {}
    for name in names():
        scenes[name] = fly(name)
        print(name, scenes[name]["final"][:12], flush=True)
    FILE.parent.mkdir(exist_ok=True)
    FILE.write_text(json.dumps({"machine": machine(), "steps": STEPS, "scenes": scenes}, indent=1) + "\n")
    print(f"wrote {FILE}", file=sys.stderr)


if __name__ == "__main__":
    main()
