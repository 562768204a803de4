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

import contextlib
import sys

import numpy as np

import warpsim.objects.glider_flight as glider_flight
from benchmarks.validation import handling

TRIM_SPEED = 12.0
"""Airspeed [m/s] at which the imposed twist is zero (the default glider trims at 11.97 m/s)."""


@contextlib.contextmanager
def imposed_twist(kappa: float, law: str):
    """Inside the block, the billow shift's struts also raise both trailing edges' washout at the tip by ``kappa``
    [deg] times the ``law``'s factor; yields the watcher for :func:`piloting.fly_piloted` that updates the factor
    from each decision's state."""
    factor = {"value": 0.0}
    original = glider_flight.billow_rest_lengths

    def twisted(rec, roll):
        return original(rec, roll, washout=kappa * factor["value"])

    def watch(sim, state):
        record = sim.model.objects[0]
        if law == "speed":
            ratio = (state["airspeed"] / TRIM_SPEED) ** 2
        else:  # the air force across the flight path over the weight
            triangles = np.concatenate([np.asarray(t) for t in record.tri_parts.values()]).astype(np.int64)
            air = 3.0 * sim.solver.tri_force.numpy()[triangles].sum(axis=0)
            air += sim.solver.particle_air.numpy()[record.particles].sum(axis=0)
            along = state["velocity"] / max(float(np.linalg.norm(state["velocity"])), 1e-9)
            weight = handling.GRAVITY * float(sim.model.particle_free_mass[record.particles].sum())
            ratio = float(np.linalg.norm(air - (air @ along) * along)) / weight
        factor["value"] = float(np.clip(ratio, 0.0, 4.0)) - 1.0

    glider_flight.billow_rest_lengths = twisted
    try:
        yield watch
    finally:
        glider_flight.billow_rest_lengths = original


def run(kappa: float, law: str = "speed", solver: dict | None = None) -> dict:
    """The dive's height lost [m], and the trim [m/s], glide over 10-20 s, phugoid period [s], Lanchester's [s] and
    damping, flown by :func:`handling.dive_flight` and :func:`handling.phugoid_flight` with the imposed twist."""
    scene = "scenes/hang_glider.toml"
    with imposed_twist(kappa, law) as watch:
        dive = handling.dive_flight(scene, solver, watch=watch)
        phugoid = handling.phugoid_flight(scene, solver, watch=watch)
    steady = [f for f in phugoid["history"] if 10.0 <= f["t"] <= 20.0]
    run_m = sum(float(np.hypot(*f["velocity"][:2])) * 0.1 for f in steady[1:])
    return {
        "dive": dive["height"],
        "trim": phugoid["trim"],
        "glide": run_m / (steady[0]["altitude"] - steady[-1]["altitude"]),
        "period": phugoid["period"],
        "lanchester": phugoid["lanchester"],
        "zeta": phugoid["zeta"],
    }


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
