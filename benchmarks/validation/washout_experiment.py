"""Issue 34's washout experiment: would a flex wing's nose-up moment that grows with speed (its sail twisting more
as the air load grows, the m_u > 0 of published flex-wing derivatives) bring the hands-off phugoid and dive
recovery into their bands? Not part of the model: the twist is imposed from outside, through the billow shift's
washout struts, and its size is a free parameter.

``python -m benchmarks.validation.washout_experiment KAPPA [LAW] [dt iterations]`` flies the default glider's
hands-off dive (released from rest, nose 60 deg down) and its phugoid pulse (as :mod:`.handling` does) with both
trailing edges' washout at the tip raised by ``KAPPA`` degrees times

* ``speed`` (the default): ``(V / 12 m/s)^2 - 1``, the dynamic pressure over the trim's, at the sail's airspeed V;
* ``load``: ``n - 1``, the air force across the flight path over the weight;

and prints the dive's height lost, the trim, the glide over 10-20 s, and the phugoid's period against
Lanchester's and its damping ratio. The struts' rest lengths are set every decision step (0.02 s in the dive,
0.1 s in the phugoid) and move at the solver's control rate.
"""

from __future__ import annotations

import math
import sys

import numpy as np

import warpsim.objects.glider_flight as glider_flight
from benchmarks.validation import handling
from warpsim.objects.hang_glider import flight_state
from warpsim.run.simulation import Simulation

TRIM_SPEED = 12.0
"""Airspeed [m/s] at which the imposed twist is zero (the default glider trims at 11.97 m/s)."""


def fly(d: dict, seconds: float, kappa: float, law: str, pilot=None, every: float = 0.02) -> list[dict]:
    """Fly descriptor ``d`` for ``seconds`` [s] with the imposed washout (``kappa`` [deg], ``law``), ``pilot``
    deciding the bar every ``every`` seconds; the flight state at each decision, with ``t`` [s] and ``n``."""
    sim = Simulation(d)
    record = sim.model.objects[0]
    steps = max(1, int(round(every / sim.dt)))
    weight = handling.GRAVITY * float(sim.model.particle_free_mass[record.particles].sum())
    triangles = np.concatenate([np.asarray(t) for t in record.tri_parts.values()]).astype(np.int64)
    factor = {"value": 0.0}
    original = glider_flight.billow_rest_lengths

    def twisted(rec, roll):
        extra = np.radians(rec.billow_shift) * roll * -rec.billow_side + np.radians(kappa) * factor["value"]
        target = rec.billow_points + np.outer(rec.billow_rise * extra, (0.0, 0.0, 1.0))
        return np.linalg.norm(target - rec.billow_anchors, axis=1)

    glider_flight.billow_rest_lengths = twisted
    history, controls = [], {"pitch": 0.0, "roll": 0.0}
    try:
        for i in range(int(round(seconds / every))):
            sim.step(steps)
            state = flight_state(record, sim.state.positions(), sim.state.particle_q_prev.numpy(), sim.dt, (0, 0, 0))
            state["t"] = (i + 1) * steps * sim.dt
            air = 3.0 * sim.solver.tri_force.numpy()[triangles].sum(axis=0)
            air += sim.solver.particle_air.numpy()[record.particles].sum(axis=0)
            along = state["velocity"] / max(float(np.linalg.norm(state["velocity"])), 1e-9)
            state["n"] = float(np.linalg.norm(air - (air @ along) * along)) / weight
            ratio = (state["airspeed"] / TRIM_SPEED) ** 2 if law == "speed" else state["n"]
            factor["value"] = float(np.clip(ratio, 0.0, 4.0)) - 1.0
            controls.update((pilot(state) if pilot else None) or {})
            sim.set_controls(**controls)  # every step: the struts follow the twist
            history.append({**state, **controls})
    finally:
        glider_flight.billow_rest_lengths = original
    return history


def run(kappa: float, law: str = "speed", solver: dict | None = None) -> dict:
    """The dive's height lost [m], and the trim [m/s], glide, phugoid period [s], Lanchester's [s] and damping."""
    scene = "scenes/hang_glider.toml"
    dive = fly(handling.scene_descriptor(scene, solver, {"speed": 0.0, "nose_up": -60.0}), 12.0, kappa, law)
    moving = next(f["t"] for f in dive if f["velocity"][2] < -1.0)
    level = next((f["t"] for f in dive if f["t"] >= moving and f["velocity"][2] >= 0.0), math.inf)
    height = dive[0]["altitude"] - min(f["altitude"] for f in dive if f["t"] <= level)

    def pulse(state):
        if abs(state["t"] - 20.0) < 1e-6:
            return {"pitch": 0.3}
        if abs(state["t"] - 22.0) < 1e-6:
            return {"pitch": 0.0}
        return None

    flight = fly(handling.scene_descriptor(scene, solver), 60.0, kappa, law, pulse, every=0.1)
    steady = [f for f in flight if 10.0 <= f["t"] <= 20.0]
    trim = float(np.mean([f["airspeed"] for f in steady]))
    run_m = sum(float(np.hypot(*f["velocity"][:2])) * 0.1 for f in steady[1:])
    glide = run_m / (steady[0]["altitude"] - steady[-1]["altitude"])
    after = [f for f in flight if f["t"] >= 23.0 - 1e-9]
    dv = np.array([f["airspeed"] for f in after]) - trim
    troughs = [i for i in range(1, len(dv) - 1) if dv[i] < dv[i - 1] and dv[i] <= dv[i + 1] and dv[i] < -0.2]
    period = zeta = math.nan
    if len(troughs) >= 2:
        period = (after[troughs[-1]]["t"] - after[troughs[0]]["t"]) / (len(troughs) - 1)
        decrement = math.log(dv[troughs[0]] / dv[troughs[-1]]) / (len(troughs) - 1)
        zeta = decrement / math.hypot(2.0 * math.pi, decrement)
    lanchester = math.pi * math.sqrt(2.0) * trim / handling.GRAVITY
    return {"dive": height, "trim": trim, "glide": glide, "period": period, "lanchester": lanchester, "zeta": zeta}


if __name__ == "__main__":
    kappa = float(sys.argv[1]) if len(sys.argv) > 1 else 10.0
    law = sys.argv[2] if len(sys.argv) > 2 else "speed"
    solver = {"dt": float(sys.argv[3]), "iterations": int(sys.argv[4])} if len(sys.argv) > 4 else None
    r = run(kappa, law, solver)
    longer = 100.0 * (r["period"] / r["lanchester"] - 1.0)
    print(
        f"kappa {kappa:g} deg ({law}), solver {solver or 'defaults'}: dive {r['dive']:.1f} m; "
        f"trim {r['trim']:.2f} m/s, glide {r['glide']:.2f}; phugoid {r['period']:.2f} s ({longer:+.0f} % of "
        f"Lanchester's {r['lanchester']:.2f} s), damping {r['zeta']:.3f}"
    )
