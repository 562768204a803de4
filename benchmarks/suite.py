"""The benchmark cases: each measures steps per second of one configuration, and comparisons measure
their baseline in the same run so that the ratio is fair.

Every case returns a row (a dict) with at least ``case``, ``steps_per_s``, ``ms_per_step``; scene cases add
the real-time factor at the scene's ``dt``, counts, iterations and device, and the runner adds
``constraint_iterations_per_s`` (sticks x iterations x steps/s: what GPU cloth papers report) to each;
comparisons add ``baseline``, ``baseline_steps_per_s`` and ``ratio`` (warpsim / baseline, except where
``baseline`` says otherwise).
Timings replay the captured step graph (the way ``warpsim run`` steps) after one warm-up step that
compiles and captures, and repeat until at least ``min_time`` seconds of wall time have been measured.
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import warp as wp

from warpsim.physics.config import AIR_DENSITY
from warpsim.run.simulation import BlowUpError, Simulation
from warpsim.scene import descriptor

PAPER_HANG_GLIDER_STEPS_PER_S = 100.0  # the paper's figure: 100 steps/s on a 2 GHz Pentium 4 (Section 9)
FLAG_SIZES = (16, 32, 64, 128, 256)


@dataclass
class Options:
    """How long and where to measure: ``min_time`` [s] of wall time per timing, Warp ``device``."""

    min_time: float = 1.0
    device: str = "cpu"


def time_steps(step: Callable[[int], None], min_time: float, sync: Callable[[], None] = lambda: None) -> float:
    """Steps per second of ``step(n)`` (takes ``n`` steps), measured over at least ``min_time`` seconds."""
    step(1)  # warm-up: compile, capture
    sync()
    n, steps, elapsed = 1, 0, 0.0
    while elapsed < min_time:
        start = time.perf_counter()
        step(n)
        sync()
        elapsed += time.perf_counter() - start
        steps += n
        n = min(n * 2, 1 << 16)
    return steps / elapsed


def scene(name: str, overrides: dict | None = None) -> dict:
    """A validated descriptor: built-in ``name`` with ``overrides`` (sections of keys) merged in."""
    desc = descriptor.resolve(name)[0]
    return descriptor.merge(f"benchmark {name}", desc, overrides or {})


PAPER_SOLVER = {"dt": 0.01, "iterations": 55}
"""The paper's step and iterations, which the flag benchmarks keep (the paper flag scene's own are 1.25 ms and 110)."""

PAPER_FLAG = {"design": "paper"}
"""The paper's cloth (rigid sticks, no bending), which the flag benchmarks fly: the C, NumPy and Newton references
step the same model."""


def flag(size: int, **solver) -> dict:
    """A square paper flag (:data:`PAPER_FLAG`) of ``size`` x ``size`` particles (the pole along one side) at the
    paper's dt 0.01 s and 55 iterations (``solver`` overrides them and adds keys)."""
    return scene(
        "flag",
        {"flag": {**PAPER_FLAG, "resolution": size, "height": 2.0, "width": 2.0}, "solver": {**PAPER_SOLVER, **solver}},
    )


def _row(case: str, sim: Simulation, rate: float) -> dict:
    m = sim.model
    return {
        "case": case,
        "steps_per_s": rate,
        "ms_per_step": 1e3 / rate,
        "realtime_factor": rate * sim.dt,
        "dt": sim.dt,
        "particles": m.particle_count,
        "sticks": m.stick_count,
        "triangles": m.tri_count,
        "worlds": m.world_count,
        "iterations": sim.solver.config.iterations if sim.solver.config.method == "verlet" else None,
        "method": sim.descriptor["solver"]["method"],
        "device": str(m.device),
    }


def constraint_rate(row: dict) -> float | None:
    """Constraint iterations per second of a row: sticks x iterations x steps/s (every stick solved once per
    Jacobi iteration), the unit GPU cloth reports (Ten Minute Physics: 1.35e9/s on a GPU); None without
    iterations (the Euler integrator) or counts."""
    if not row.get("sticks") or not row.get("iterations") or not row.get("steps_per_s"):
        return None
    return row["sticks"] * row["iterations"] * row["steps_per_s"]


def measure(case: str, desc: dict, opts: Options) -> dict:
    """Steps per second of a scene, stepping only (no frames, no outputs)."""
    sim = Simulation(desc, device=opts.device)
    rate = time_steps(sim.step, opts.min_time, lambda: wp.synchronize_device(sim.model.device))
    return _row(case, sim, rate)


def _compare(row: dict, baseline: str, baseline_rate: float, ratio: float | None = None, **extra) -> dict:
    """Add a baseline to ``row``; ``ratio`` defaults to warpsim's steps/s over the baseline's."""
    ratio = row["steps_per_s"] / baseline_rate if ratio is None else ratio
    row.update(baseline=baseline, baseline_steps_per_s=baseline_rate, ratio=ratio, **extra)
    return row


# ---------------------------------------------------------------------------------------------- cases
def case_object(name: str) -> Callable[[Options], dict]:
    def run(opts: Options) -> dict:
        row = measure(name, scene(name), opts)
        if name == "hang-glider":
            _compare(row, "paper (2 GHz Pentium 4)", PAPER_HANG_GLIDER_STEPS_PER_S)
        return row

    run.__doc__ = f"the {name} at its default settings (the flying design where it has one)"
    return run


def case_flag(size: int) -> Callable[[Options], dict]:
    def run(opts: Options) -> dict:
        return measure(f"flag-{size}", flag(size), opts)

    run.__doc__ = f"a {size}x{size} flag of the paper's cloth at 55 iterations"
    return run


def case_numpy(name: str) -> Callable[[Options], dict]:
    def run(opts: Options) -> dict:
        from .numpy_step import NumpyVerlet

        desc = flag(256) if name == "flag-256" else scene(name)
        row = measure(f"numpy-{name}", desc, opts)
        sim = Simulation(desc, device="cpu")
        ref = NumpyVerlet(sim)

        def step(n):
            for _ in range(n):
                ref.step()

        return _compare(row, "plain NumPy, same step", time_steps(step, opts.min_time))

    run.__doc__ = f"warpsim against the plain NumPy step on the {name}"
    return run


def largest_stable_dt(desc: dict, device: str, seconds: float = 2.0, max_stretch: float = 0.1) -> float | None:
    """The largest of dt = 1/25 ... 1/6400 s at which ``seconds`` of the scene stay finite with every stick
    within ``max_stretch`` (the run's blow-up detection with that limit)."""
    for divisor in (25, 50, 100, 200, 400, 800, 1600, 3200, 6400):
        change = {"solver": {"dt": 1.0 / divisor, "max_stretch": max_stretch}, "scene": {"fps": 25.0}}
        sim = Simulation(descriptor.merge("stability search", desc, change), device=device)
        try:
            sim.run(seconds)
        except BlowUpError:
            continue
        return 1.0 / divisor
    return None


def case_euler_vs_verlet(opts: Options) -> dict:
    """the paper's flag comparison (slide 15): wall time per simulated second, each at its largest stable dt"""
    results = {}
    for method in ("verlet", "euler"):
        desc = scene("flag", {"flag": PAPER_FLAG, "solver": {**PAPER_SOLVER, "method": method}})
        dt = largest_stable_dt(desc, opts.device)
        row = measure(f"flag-{method}", descriptor.merge("dt", desc, {"solver": {"dt": dt}}), opts)
        row["cost_per_simulated_s"] = 1.0 / (row["steps_per_s"] * dt)
        results[method] = row
    verlet, euler = results["verlet"], results["euler"]
    row = dict(verlet, case="euler-vs-verlet")
    return _compare(
        row,
        f"Euler mass-spring at its dt 1/{1 / euler['dt']:.0f} s (Verlet's: 1/{1 / verlet['dt']:.0f} s); "
        "ratio = Euler's wall time per simulated second / Verlet's",
        euler["steps_per_s"],
        ratio=euler["cost_per_simulated_s"] / verlet["cost_per_simulated_s"],
        euler_dt=euler["dt"],
        euler_cost_per_simulated_s=euler["cost_per_simulated_s"],
    )


def case_batched(count: int, gpu_only: bool = False) -> Callable[[Options], dict]:
    def run(opts: Options) -> dict:
        if gpu_only and opts.device == "cpu":
            return {"case": f"kites-x{count}", "skipped": "a GPU row: python -m benchmarks --device cuda"}
        single = measure("kite", scene("kite"), opts)
        speeds = list(np.linspace(4.0, 12.0, count))
        row = measure(f"kites-x{count}", scene("kite", {"worlds": {"count": count, "wind": {"speed": speeds}}}), opts)
        row["world_steps_per_s"] = row["steps_per_s"] * count
        return _compare(
            row,
            "one kite alone; ratio = world-steps/s (worlds x steps/s) / its steps/s",
            single["steps_per_s"],
            ratio=row["world_steps_per_s"] / single["steps_per_s"],
        )

    run.__doc__ = f"{count} kites (wind 4-12 m/s) as batched worlds against one kite"
    return run


def case_newton(size: int) -> Callable[[Options], dict]:
    def run(opts: Options) -> dict:
        try:
            import newton
        except ImportError:
            return {"case": f"newton-flag-{size}", "skipped": "Newton is not installed (pip install -e '.[bench]')"}
        desc = flag(size, chebyshev=0.0)
        row = measure(f"newton-flag-{size}", desc, opts)
        sim = Simulation(desc, device=opts.device)
        m = sim.model
        builder = newton.ModelBuilder(up_axis=newton.Axis.Z, gravity=(0.0, 0.0, -9.80665))
        inv = m.particle_inv_mass.numpy()
        for p, w in zip(m.particle_q0, inv, strict=True):
            builder.add_particle(tuple(p), (0.0, 0.0, 0.0), mass=0.0 if w == 0 else 1.0 / float(w), radius=0.0)
        for i, j in m.stick_particles_np:
            builder.add_spring(int(i), int(j), ke=1.0e6, kd=0.0, control=0.0)
        model = builder.finalize(device=opts.device)
        solver = newton.solvers.SolverXPBD(model, iterations=sim.solver.config.iterations)
        s0, s1, control = model.state(), model.state(), model.control()
        solver.step(s0, s1, control, None, sim.dt)
        with wp.ScopedCapture(device=model.device) as capture:
            solver.step(s0, s1, control, None, sim.dt)
            solver.step(s1, s0, control, None, sim.dt)

        def step(n):
            for _ in range((n + 1) // 2):
                wp.capture_launch(capture.graph)

        rate = time_steps(step, opts.min_time, lambda: wp.synchronize_device(model.device))
        return _compare(row, f"Newton {newton.__version__} SolverXPBD, {sim.solver.config.iterations} iterations", rate)

    run.__doc__ = f"warpsim against Newton's SolverXPBD on a {size}x{size} grid of the same sticks"
    return run


def case_c_reference(name: str) -> Callable[[Options], dict]:
    def run(opts: Options) -> dict:
        from . import c_reference

        case = f"c-reference-{name}"
        if c_reference.compiler() is None:
            return {"case": case, "skipped": "no C compiler (cc, gcc or clang) on the PATH"}
        desc = flag(int(name.split("-")[1])) if name.startswith("flag-") else scene(name)
        # the C has a fixed density (the paper's) and the per-triangle laws, not the vortex lattice
        air = {"density": AIR_DENSITY, **({"model": "sail"} if desc["air"]["model"] == "vortex" else {})}
        desc = descriptor.merge("c", desc, {"air": air})
        row = measure(case, desc, opts)
        sim = Simulation(desc, device="cpu")
        with tempfile.TemporaryDirectory() as tmp:
            program = c_reference.build(Path(tmp))
            q = c_reference.run(program, sim, 3)[1]  # does the C do the same work? 3 steps, before chaos
            steps, seconds = 1, 0.0
            while seconds < opts.min_time:  # as time_steps does: grow the run until it lasts min_time
                steps *= 4 if seconds < opts.min_time / 8 else 2
                seconds = c_reference.run(program, sim, steps)[0]
            # this machine's rate drifts over minutes: alternate warpsim and C, best of 3 each
            c_rates, rates = [steps / seconds], [row["steps_per_s"]]
            for _ in range(2):
                rates.append(measure(case, desc, opts)["steps_per_s"])
                c_rates.append(steps / c_reference.run(program, sim, steps)[0])
            spent = c_reference.run(program, sim, steps, parts=True)[2]
        row.update(steps_per_s=max(rates), ms_per_step=1e3 / max(rates), realtime_factor=max(rates) * sim.dt)
        sim.step(3)
        total = sum(spent.values())
        # the C steps the same model, so warpsim/C per stick is warpsim/C per step (the ratio)
        return _compare(
            row,
            f"plain C, single thread (cc {' '.join(c_reference.FLAGS)}), the same step; best of 3 alternating",
            max(c_rates),
            c_profile=", ".join(f"{part} {100 * t / total:.0f} %" for part, t in spent.items()),
            c_differs_after_3_steps_m=float(np.abs(q - sim.state.positions()).max()),
        )

    run.__doc__ = f"warpsim against the same step in plain C on the {name} (skipped without a C compiler)"
    return run


def case_run_vs_raw(name: str, rounds: int = 3) -> Callable[[Options], dict]:
    def run(opts: Options) -> dict:
        desc = scene(name)
        row = measure(f"run-{name}", desc, opts)  # raw stepping (first round)
        raw_rates = [row["steps_per_s"]]
        sim = Simulation(desc, device=opts.device)
        sim.run(1.0)  # warm-up: compile, capture, first frames
        seconds = 1.0
        while sim.run(seconds).wall_time < opts.min_time:  # what `warpsim run` does per frame, no outputs
            seconds *= 2.0
        run_rates = []
        # this machine's rate drifts by a third over minutes: alternate the two, best of each
        for k in range(rounds):
            summary = sim.run(seconds)
            run_rates.append(summary.steps / summary.wall_time)
            if k < rounds - 1:
                raw_rates.append(measure(f"run-{name}", desc, opts)["steps_per_s"])
        rate, raw = max(run_rates), max(raw_rates)
        row.update(steps_per_s=rate, ms_per_step=1e3 / rate, realtime_factor=rate * sim.dt)
        return _compare(
            row, f"raw stepping of the same scene, best of {rounds} alternating rounds; target ratio >= 0.9", raw
        )

    run.__doc__ = f"Simulation.run (frames, diagnostics, checks) against raw stepping on the {name}"
    return run


VORTEX_OVERRIDES = {"hang-glider": {}, "kite": {"kite": {"tow_point": 0.35}}}
"""What each object flies with under the vortex law (the kite's bridle moved to where the lattice's centre of
pressure lets it fly)."""


def case_vortex(name: str, rounds: int = 3) -> Callable[[Options], dict]:
    def run(opts: Options) -> dict:
        sims = {
            law: Simulation(
                scene(name, {"air": {"model": law}, **(VORTEX_OVERRIDES[name] if law == "vortex" else {})}),
                device=opts.device,
            )
            for law in ("sail", "vortex")
        }
        rates = {law: [] for law in sims}
        for _ in range(rounds):  # alternating rounds: the machine's drift falls on both laws alike
            for law, sim in sims.items():
                rates[law].append(
                    time_steps(sim.step, opts.min_time, lambda s=sim: wp.synchronize_device(s.model.device))
                )
        sail, vortex = (float(np.median(rates[law])) for law in ("sail", "vortex"))
        row = _row(f"vortex-{name.removeprefix('hang-')}", sims["vortex"], vortex)
        lattice = sims["vortex"].model.lattice
        return _compare(
            row,
            "the sail law, same run",
            sail,
            panels=lattice.panel_count,
            interval_s=float(sims["vortex"].solver.air.vortex_interval),
        )

    run.__doc__ = f"the {name} on the vortex law against the sail law, {rounds} alternating rounds"
    return run


AIR_SETTINGS = {
    "steady": {"air": {"density": AIR_DENSITY}},
    "isa": {"air": {"density": 0.0}},
    "turbulence": {"wind": {"turbulence_intensity": 0.15}},
}
"""The kite's air in the ``air-kite`` case: the paper's constant density and a steady wind (the baseline), the standard
atmosphere, frozen turbulence."""


def case_air(rounds: int = 3) -> Callable[[Options], dict]:
    def run(opts: Options) -> dict:
        sims = {name: Simulation(scene("kite", extra), device=opts.device) for name, extra in AIR_SETTINGS.items()}
        rates = {name: [] for name in sims}
        for _ in range(rounds):  # alternating rounds: the machine's drift falls on every setting alike
            for name, sim in sims.items():
                rates[name].append(
                    time_steps(sim.step, opts.min_time, lambda s=sim: wp.synchronize_device(s.model.device))
                )
        median = {name: float(np.median(r)) for name, r in rates.items()}
        row = _row("air-kite", sims["turbulence"], median["turbulence"])
        return _compare(row, "the kite in steady air, same run", median["steady"], isa_steps_per_s=median["isa"])

    run.__doc__ = f"the kite in frozen turbulence (and in the standard atmosphere) against steady air, {rounds} rounds"
    return run


CASES: dict[str, Callable[[Options], dict]] = {
    "flag": case_object("flag"),
    "hang-glider": case_object("hang-glider"),
    "kite": case_object("kite"),
    "parachute": case_object("parachute"),
    **{f"flag-{n}": case_flag(n) for n in FLAG_SIZES},
    "euler-vs-verlet": case_euler_vs_verlet,
    "kites-x256": case_batched(256),
    "kites-x1024": case_batched(1024, gpu_only=True),
    "numpy-hang-glider": case_numpy("hang-glider"),
    "numpy-flag-256": case_numpy("flag-256"),
    **{f"newton-flag-{n}": case_newton(n) for n in FLAG_SIZES},
    **{f"c-reference-{n}": case_c_reference(n) for n in ("hang-glider", "flag-32", "flag-256")},
    **{f"run-{n}": case_run_vs_raw(n) for n in ("hang-glider", "kite", "parachute")},
    "vortex-glider": case_vortex("hang-glider"),
    "vortex-kite": case_vortex("kite"),
    "air-kite": case_air(),
}
