"""How far the shipped defaults' headline figures lie from their converged values, and what it costs to come closer.

    python -m benchmarks.validation.convergence_table [--only kite] [--json out.json]

Each headline figure is measured from the particles at the scene's own step ``dt`` and iterations ``n`` and on two
ladders: halving the step with the iterations doubled (``dt/2, 2n``; ``dt/4, 4n``: the iterations scaled with the
step, so the constraint solve converges as the step does) and halving it with the iterations kept (``dt/2, n``;
``dt/4, n``: Müller's "small steps", more substeps instead of more iterations). The converged value is the
Richardson extrapolation of the first ladder from its three rungs, ``f4 + (f4 - f2)^2 / ((f2 - f1) - (f4 - f2))`` when
the differences shrink (their ratio over 1.5), else the finest rung (said so). Each setting's cost is its
steps x iterations per simulated second against the defaults', and its real-time factor is measured alone.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from collections.abc import Callable

import numpy as np

from warpsim.objects.kite import anchor_elevation, anchor_pull
from warpsim.objects.parachute import descent_and_swing
from warpsim.run.simulation import Simulation
from warpsim.scene import descriptor


def _fly(d: dict, seconds: float, measure: Callable) -> tuple[dict, float]:
    sim = Simulation(d)
    started = time.perf_counter()
    figures = measure(sim, seconds)
    return figures, seconds / (time.perf_counter() - started)


def _kite(sim, seconds: float) -> dict:
    record, mass = sim.model.objects[0], sim.model.particle_free_mass
    angle, pull = [], []

    def keep(frame) -> None:
        if frame.time >= seconds / 2:
            angle.append(anchor_elevation(record, frame.positions))
            pull.append(anchor_pull(record, frame.positions, mass))

    sim.run(seconds, on_frame=keep)
    return {"line angle [deg]": float(np.mean(angle)), "line pull [N]": float(np.nanmean(pull))}


def _glider(sim, seconds: float) -> dict:
    record = sim.model.objects[0]
    times, centre = [], []

    def keep(frame) -> None:
        if frame.time >= seconds / 2:
            times.append(frame.time)
            q, m = frame.positions[record.particles], sim.model.particle_free_mass[record.particles]
            centre.append((q * m[:, None]).sum(axis=0) / m.sum())

    sim.run(seconds, on_frame=keep)
    c, t = np.array(centre), np.array(times)
    v = np.diff(c, axis=0) / np.diff(t)[:, None]
    horizontal, sink = np.linalg.norm(v[:, :2], axis=1).mean(), -v[:, 2].mean()
    return {"glide ratio": float(horizontal / sink), "trim speed [m/s]": float(np.linalg.norm(v, axis=1).mean())}


def _parachute(sim, seconds: float) -> dict:
    descent, swing, rms = descent_and_swing(sim, seconds)
    return {"descent [m/s]": descent, "largest swing [deg]": swing, "rms swing [deg]": rms}


OBJECTS = {
    "kite": ("kite", {}, 40.0, _kite),
    "kite-10": ("kite", {"wind": {"velocity": [10.0, 0.0, 0.0]}}, 40.0, _kite),
    "hang-glider": ("hang-glider", {}, 30.0, _glider),
    "parachute": ("scenes/parachute.toml", {"wind": {"gust_intensity": 0.0}}, 60.0, _parachute),
}
"""Name -> (scene, overrides, seconds, measure): the objects whose figures the README and the tour quote (the
parachute in its scene's breeze without its gusts, so that every rung meets the same air)."""


def richardson(f1: float, f2: float, f4: float) -> tuple[float, str]:
    """The extrapolated value of a figure from rungs at h, h/2, h/4, and how it was found."""
    d1, d2 = f2 - f1, f4 - f2
    if d2 == 0.0:
        return f4, "converged"
    ratio = d1 / d2
    if ratio > 1.5:
        return f4 + d2 / (ratio - 1.0), f"Richardson (order {math.log2(ratio):.1f})"
    return f4, "the finest rung (the differences do not shrink)"


def table(name: str) -> list[dict]:
    """The convergence rows of object ``name`` (:data:`OBJECTS`): one per figure."""
    scene, overrides, seconds, measure = OBJECTS[name]
    base = descriptor.merge("convergence", descriptor.resolve(scene)[0], overrides)
    dt, n = float(base["solver"]["dt"]), int(base["solver"]["iterations"])
    settings = {
        "defaults": (dt, n),
        "dt/2, 2n": (dt / 2, 2 * n),
        "dt/4, 4n": (dt / 4, 4 * n),
        "dt/2, n": (dt / 2, n),
        "dt/4, n": (dt / 4, n),
    }
    results, speed = {}, {}
    for label, (step, iterations) in settings.items():
        solver = {"solver": {"dt": step, "iterations": iterations}}
        results[label], speed[label] = _fly(descriptor.merge("c", base, solver), seconds, measure)
        print(f"  {name} {label}: {results[label]} ({speed[label]:.1f}x real time)", flush=True)
    rows = []
    for figure in results["defaults"]:
        values = {label: results[label][figure] for label in settings}
        converged, how = richardson(values["defaults"], values["dt/2, 2n"], values["dt/4, 4n"])
        rows.append(
            {
                "object": name,
                "figure": figure,
                "converged": converged,
                "how": how,
                **{label: v for label, v in values.items()},
                **{f"{label} error %": 100.0 * (v / converged - 1.0) for label, v in values.items()},
                **{f"{label} cost": (dt / s) * (i / n) for label, (s, i) in settings.items()},
                **{f"{label} real time": speed[label] for label in settings},
            }
        )
    return rows


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", action="append", choices=sorted(OBJECTS), help="these objects (default: all)")
    parser.add_argument("--json", help="write the rows here")
    args = parser.parse_args(argv)
    rows = []
    for name in args.only or OBJECTS:
        rows += table(name)
    for r in rows:
        errors = ", ".join(f"{label} {r[f'{label} error %']:+.1f} %" for label in ("defaults", "dt/2, 2n", "dt/2, n"))
        print(f"{r['object']} {r['figure']}: converged {r['converged']:.4g} ({r['how']}); {errors}")
    if args.json:
        with open(args.json, "w") as out:
            json.dump(rows, out, indent=1)


if __name__ == "__main__":
    main()
