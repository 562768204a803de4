"""warpsim's step as a plain single-threaded C program (``step.c`` beside this file): the speed baseline.

:func:`export` writes a simulation's model and state in the program's binary layout, :func:`build` compiles it
with the system C compiler (``cc -O3 -march=native``, plain C), and :func:`run` steps it and returns its stepping
time and final positions. The program does the work of :class:`benchmarks.numpy_step.NumpyVerlet` at warpsim's
precision (float64 positions, float32 for everything measured from them); what it reads comes from that class,
so the two cannot read the model differently.
"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from warpsim.physics.kernels.aero import STALL_SHARPNESS, AeroModel
from warpsim.physics.kernels.collision import CollisionMode
from warpsim.run.simulation import Simulation

from ..numpy_step import F32, NumpyVerlet

SOURCE = Path(__file__).with_name("step.c")
FLAGS = ("-O3", "-march=native", "-std=c99", "-ffp-contract=off")
"""Plain C for this machine's CPU, as Warp compiles its CPU kernels (``-march=native``); no fused multiply-adds
(Warp's kernels have none, and the comparison is bit for bit), no OpenMP, no ``-ffast-math``."""


def compiler() -> str | None:
    """The system C compiler (``cc``, ``gcc`` or ``clang`` on the PATH), or None."""
    return next(filter(None, (shutil.which(name) for name in ("cc", "gcc", "clang"))), None)


def build(directory: Path) -> Path:
    """Compile ``step.c`` into ``directory``; returns the program. Raises ``RuntimeError`` without a compiler
    or when the build fails (with the compiler's message)."""
    cc = compiler()
    if cc is None:
        raise RuntimeError("no C compiler (cc, gcc or clang) on the PATH")
    program = Path(directory) / "step"
    done = subprocess.run([cc, *FLAGS, "-o", str(program), str(SOURCE), "-lm"], capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"{cc} failed: {done.stderr.strip()[:500]}")
    return program


def export(sim: Simulation, path: Path) -> None:
    """Write ``sim``'s model, controls and current state in ``step.c``'s layout. The wind is taken as it is now
    (no gusts, no shear: refused), per triangle and per drag body from its world."""
    ref = NumpyVerlet(sim)
    if ref.wind_profile.shear_exponent != 0.0:
        raise ValueError("the C reference has no wind shear: set wind.shear_exponent = 0")
    if ref.canopies:
        raise ValueError("the C reference has no whole-canopy air force: set parachute.canopy = paper")
    if ref.air.density <= 0.0:
        raise ValueError("the C reference has a fixed air density, not the standard atmosphere: set air.density")
    laws = {AeroModel.PAPER: 0, AeroModel.PLATE: 1, AeroModel.SAIL: 2}
    n = ref.n
    nail_of = np.full(n, -1, dtype=np.int32)
    nail_of[ref.nailed] = ref.nail_of
    ny, nx = ref.heights.shape
    ints = [n, len(ref.ends), len(ref.tris), len(ref.drag_particles), len(ref.omegas), ny, nx]
    ints += [laws[ref.air.model], 0 if ref.ground.collision == CollisionMode.NORMAL else 1, len(ref.nail_target)]
    ints += [len(ref.world_free)]
    floats = [ref.dt, ref.air.density, ref.air.scale, ref.relaxation, ref.damping, *ref.gravity, ref.ground.friction]
    floats += [*ref.origin[:2], *ref.cell[:2], STALL_SHARPNESS]
    i32, f32, f64 = np.int32, F32, np.float64  # positions and nail targets are double, as in warpsim
    arrays = [
        (ints, i32),
        (floats, f32),
        ([ref.base, *ref.origin[:2], *ref.cell[:2]], f64),  # the terrain's float64 base, origin and cell
        (ref.q, f64),
        (ref.q_prev, f64),
        (ref.inv_mass, f32),
        (nail_of, i32),
        (ref.nail_target, f64),
        (ref.ends, i32),
        (ref.coef, f32),
        (ref.rest, f32),
        (ref.alpha, f32),
        (ref.scale, f32),
        (ref.omegas, f32),
        (ref.tris, i32),
        (ref.tri_loading, f32),
        (ref.tri_sail, f32),
        (ref.tri_span, i32),
        (ref.wind[ref.tri_world], f32),
        (ref.drag_particles, i32),
        (ref.drag_area, f32),
        (ref.wind[ref.particle_world[ref.drag_particles]], f32),
        (ref.heights, f32),
        (ref.world_start, i32),
        (ref.world_particles[: ref.world_start[-1]], i32),
        (ref.world_free, i32),
    ]
    with open(path, "wb") as f:
        for a, kind in arrays:
            f.write(np.ascontiguousarray(a, dtype=kind).tobytes())


def run(program: Path, sim: Simulation, steps: int, parts: bool = False) -> tuple[float, np.ndarray, dict]:
    """Step ``sim``'s current state ``steps`` times with the C ``program``; returns the seconds the stepping
    loop took (reading and writing aside), the final float64 positions ``[n, 3]`` [m], and with ``parts`` the seconds
    spent in each part of the step (``air``, ``verlet``, ``constraints``, ``terrain``; else empty)."""
    with tempfile.TemporaryDirectory() as tmp:
        model, out = Path(tmp) / "model.bin", Path(tmp) / "out.bin"
        export(sim, model)
        command = [str(program), str(model), str(steps), str(out), *(["parts"] if parts else [])]
        done = subprocess.run(command, capture_output=True, text=True)
        if done.returncode != 0:
            raise RuntimeError(f"the C reference failed: {done.stderr.strip()[:500]}")
        words = done.stdout.split()
        spent = {name: float(value) for name, value in zip(words[2::2], words[3::2], strict=True)}
        return float(words[0]), np.fromfile(out, dtype=np.float64).reshape(-1, 3), spent
