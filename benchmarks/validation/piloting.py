"""A scripted pilot for the hang glider's flights, measured from the particles: the scene with its solver and
glider keys, the flight flown with a pilot, the body's frame and angles (pitch, bank, sideslip, the keel's angle
of attack) and a pilot that holds a bank.

A *pilot* here is a function of the flight state (:func:`warpsim.objects.hang_glider.flight_state`, with its
time ``t`` [s]) that returns the controls to set (or ``None`` to keep them), called every ``every`` seconds.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from warpsim.run.simulation import Simulation
from warpsim.scene import descriptor

Pilot = Callable[[dict], dict | None]


def scene_descriptor(scene: str | dict, solver: dict | None = None, glider: dict | None = None) -> dict:
    """The descriptor of ``scene`` with ``solver`` (e.g. ``{"dt": 0.005, "iterations": 110}``) and ``glider``
    (``[hang_glider]`` keys) merged over it."""
    d = scene if isinstance(scene, dict) else descriptor.resolve(scene)[0]
    over = {}
    if solver:
        over["solver"] = solver
    if glider:
        over["hang_glider"] = glider
    return descriptor.merge("handling", d, over) if over else d


def fly_piloted(
    d: dict,
    seconds: float,
    pilot: Pilot | None = None,
    every: float = 0.05,
    slew: float = 2.0,
    stop: Callable[[dict], bool] | None = None,
    watch: Callable[[Simulation, dict], None] | None = None,
) -> list[dict]:
    """Fly the hang glider of descriptor ``d`` for ``seconds`` [s] with ``pilot`` deciding the controls every
    ``every`` seconds; the flight state at each decision, with ``t`` [s], the air's ``density`` [kg/m^3] and the
    ``roll``/``pitch`` then set.

    The bar moves at most ``slew`` per second (2: from centre to a stop in 0.5 s, as a pilot's arms do; a step of
    the arms' lengths jerks the frame). ``watch(sim, state)``, if given, sees each decision's state first and may
    change what the controls write (an experiment's imposed twist): the controls are then written at every
    decision, not only when they move."""
    from warpsim.objects.hang_glider import flight_state

    sim = Simulation(d)
    record = sim.model.objects[0]
    steps = max(1, int(round(every / sim.dt)))
    inv = sim.model.particle_inv_mass.numpy()[record.particles]
    mass = np.where(inv > 0, 1.0 / np.where(inv > 0, inv, 1.0), 0.0)
    history, wanted, controls = [], {"pitch": 0.0, "roll": 0.0}, {"pitch": 0.0, "roll": 0.0}
    step_most = slew * steps * sim.dt
    for i in range(int(round(seconds / every))):
        sim.step(steps)
        state = flight_state(record, sim.state.positions(), sim.state.particle_q_prev.numpy(), sim.dt, (0, 0, 0))
        state["t"] = (i + 1) * steps * sim.dt
        state["density"] = float(sim.control.air_density.numpy()[0])  # [kg/m^3] the air it flies in
        q, q_prev = sim.state.positions()[record.particles], sim.state.particle_q_prev.numpy()[record.particles]
        state["cg_velocity"] = mass @ (q - q_prev) / (mass.sum() * sim.dt)
        state["cg_speed"] = float(np.linalg.norm(state["cg_velocity"]))
        if watch is not None:
            watch(sim, state)
        wanted.update((pilot(state) if pilot else None) or {})
        moved = {k: controls[k] + float(np.clip(v - controls[k], -step_most, step_most)) for k, v in wanted.items()}
        if moved != controls or watch is not None:
            controls.update(moved)
            sim.set_controls(**controls)
        state.update(controls)
        history.append(state)
        if stop is not None and stop(state):
            break
    return history


def body_frame(record, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A hang glider's body axes at positions ``q`` [m], unit vectors: ``fwd`` along the keel from the tail to the
    nose, ``up`` across the keel and the tip-to-tip line (the sail's normal), ``left`` = ``up x fwd`` (towards the
    left tip)."""
    fwd = q[record.nose] - q[record.keel[-1]]
    fwd /= np.linalg.norm(fwd)
    up = np.cross(fwd, q[record.tips[0]] - q[record.tips[1]])
    up /= np.linalg.norm(up)
    return fwd, np.cross(up, fwd), up


def body_angles(sim: Simulation, state: dict) -> None:
    """Add to ``state`` (a :func:`fly_piloted` decision's) the mass centre's sideslip ``beta`` [deg] (the angle of
    its velocity out of the plane of the keel and the sail's normal, positive towards the left tip) and the keel's
    angle of attack ``alpha`` [deg] (of that velocity below the keel, in that plane; beyond ±90° the keel flies tail
    first), in the glider's :func:`body_frame`."""
    fwd, left, up = body_frame(sim.model.objects[0], sim.state.positions())
    v = state["cg_velocity"] / max(float(np.linalg.norm(state["cg_velocity"])), 1e-9)
    state["beta"] = math.degrees(math.asin(float(np.clip(v @ left, -1.0, 1.0))))
    state["alpha"] = math.degrees(math.atan2(-float(v @ up), float(v @ fwd)))


def crossing(history: list[dict], t0: float, test: Callable[[dict], bool]) -> float:
    """First time [s] at or after ``t0`` when ``test`` holds (inf if never)."""
    return next((f["t"] for f in history if f["t"] >= t0 and test(f)), math.inf)


def bank_holder(
    target: Callable[[float], float | None], gain: float = 0.05, integral: float = 0.005, near: float = 3.0
) -> Pilot:
    """A pilot holding the bank at ``target(t)`` [deg] (None: hands off, bar centred): roll = gain * error +
    integral * (the error integrated over time while within ``near`` degrees of the target) [per deg, per deg s],
    clipped to [-1, 1]."""
    last = {"sum": 0.0}

    def pilot(s):
        want = target(s["t"])
        dt = s["t"] - last.get("t", s["t"])
        last["t"] = s["t"]
        if want is None:
            last["sum"] = 0.0
            return {"roll": 0.0}
        error = want - s["bank_deg"]
        if abs(error) < near:
            last["sum"] += error * dt
        return {"roll": float(np.clip(gain * error + integral * last["sum"], -1.0, 1.0))}

    return pilot


def path_angle(velocity) -> float:
    """Path angle [rad] of ``velocity`` above the horizontal."""
    return math.atan2(velocity[2], math.hypot(velocity[0], velocity[1]))


def wing_loading(scene: str | dict) -> float:
    """Total mass over the sail's planform area (span x chord / 2) [kg/m^2]."""
    g = scene_descriptor(scene)["hang_glider"]
    return (g["glider_mass"] + g["pilot_mass"] + g["control_frame_mass"]) / (0.5 * g["span"] * g["chord"])
