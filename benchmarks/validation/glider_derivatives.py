"""The lateral-directional derivatives of a flying glider's own shape under the vortex law (issue 53).

The glider is flown hands off for ``settle`` seconds; its particles are then held rigid in that flying shape and
moved through still air at the mass centre's speed and angle of attack, with a sideslip, a roll rate or a yaw
rate added, and the lattice's forces (:func:`warpsim.physics.kernels.vortex.vortex_air_force`, the section polar
included; the drag bodies left out) are summed into moments about the mass centre. Axes are stability axes: ``x``
along the flight path, ``z`` across it in the plane of the keel and the sail's normal, ``y`` to the left tip.
Signs: sideslip ``beta > 0`` moves the glider towards its left tip (the air comes from the left); ``p > 0`` drops
the right tip; ``r > 0`` yaws the nose left. ``Cn > 0`` yaws the nose left, ``Cl > 0`` drops the right tip;
moments on ``q S b``, the side force on ``q S``.

``python -m benchmarks.validation.glider_derivatives [SCENE]`` prints them (default: the lattice glider).
"""

from __future__ import annotations

import math
import sys

import numpy as np
import warp as wp

from benchmarks.validation.piloting import body_frame
from warpsim.physics.config import WindConfig
from warpsim.physics.kernels.vortex import VortexScratch, vortex_air_force
from warpsim.run.simulation import Simulation
from warpsim.scene import descriptor


def derivatives(scene: str = "scenes/hang_glider_lattice.toml", settle: float = 8.0, step: float = 0.05) -> dict:
    """``C_n_beta``, ``C_l_beta``, ``C_Y_beta`` [1/rad], ``C_n_p``, ``C_l_p``, ``C_n_r``, ``C_l_r`` (per unit of
    ``p b / 2V``, ``r b / 2V``) and ``CL`` of the flying shape of ``scene`` after ``settle`` [s], from differences
    of 5 degrees of sideslip and of ``step`` in ``p b / 2V`` and ``r b / 2V``; ``speed`` [m/s] and ``alpha`` [deg]
    (the keel's) of the flight they were taken from."""
    d = descriptor.resolve(scene)[0]
    if d["air"]["model"] != "vortex":
        raise ValueError(f"{scene}: the derivatives are the vortex law's; set air.model = vortex")
    sim = Simulation(d)
    sim.step(int(round(settle / sim.dt)))
    m, rec, dt = sim.model, sim.model.objects[0], sim.dt
    q = sim.state.positions().astype(np.float64)
    mass = m.particle_free_mass
    cg = mass @ q / mass.sum()
    v = mass @ (q - sim.state.particle_q_prev.numpy()) / (mass.sum() * dt)
    keel, left, normal = body_frame(rec, q)
    speed = float(np.linalg.norm(v))
    alpha = math.atan2(-float(v @ normal), float(v @ keel))
    x = math.cos(alpha) * keel - math.sin(alpha) * normal  # stability axes
    z = math.sin(alpha) * keel + math.cos(alpha) * normal
    area, span = rec_area_span(q, rec)
    qd = 0.5 * float(sim.control.air_density.numpy()[0]) * speed * speed
    sim.control.wind.assign(np.zeros((m.world_count, 3), dtype=np.float32))

    def loads(beta: float = 0.0, p: float = 0.0, r: float = 0.0) -> np.ndarray:
        velocity = speed * (math.cos(beta) * x + math.sin(beta) * left)
        rate = (p * x + r * z) * 2.0 * speed / span
        moving = velocity + np.cross(rate, q - cg)
        sim.state.particle_q.assign(q)
        sim.state.particle_q_prev.assign(q - moving * dt)
        tri = wp.zeros(m.tri_count, dtype=wp.vec3, device=m.device)
        part = wp.zeros(m.particle_count, dtype=wp.vec3, device=m.device)
        vortex_air_force(m, sim.state, sim.control, dt, sim.solver.air, WindConfig(), VortexScratch(m), tri, part)
        f = part.numpy().astype(np.float64)
        np.add.at(f, m.tri_indices_np.reshape(-1), np.repeat(tri.numpy().astype(np.float64), 3, axis=0))
        moment = np.cross(q - cg, f).sum(0)
        force = f.sum(0)
        return np.array(
            [
                moment @ z / (qd * area * span),  # Cn
                moment @ x / (qd * area * span),  # Cl (x forward: a positive rotation lifts the left tip)
                force @ left / (qd * area),  # CY
                force @ np.cross(x, left) / (qd * area),  # CL
            ]
        )

    base = loads()
    slip = math.radians(5.0)
    beta = (loads(beta=slip) - base) / slip
    roll = (loads(p=step) - base) / step
    yaw = (loads(r=step) - base) / step
    return {
        "speed": speed,
        "alpha": math.degrees(alpha),
        "CL": float(base[3]),
        "C_n_beta": float(beta[0]),
        "C_l_beta": float(beta[1]),
        "C_Y_beta": float(beta[2]),
        "C_n_p": float(roll[0]),
        "C_l_p": float(roll[1]),
        "C_n_r": float(yaw[0]),
        "C_l_r": float(yaw[1]),
    }


def rec_area_span(q: np.ndarray, rec) -> tuple[float, float]:
    """The reference area [m^2] (the planform triangle of the nose and the tips) and span [m] (tip to tip) of the
    hang glider ``rec`` at positions ``q`` [m]."""
    nose, tip_l, tip_r = q[rec.nose], q[rec.tips[0]], q[rec.tips[1]]
    return 0.5 * float(np.linalg.norm(np.cross(tip_l - nose, tip_r - nose))), float(np.linalg.norm(tip_l - tip_r))


if __name__ == "__main__":
    figures = derivatives(*(sys.argv[1:2] or []))
    for key, value in figures.items():
        print(f"{key:9s} {value:+.4f}")
