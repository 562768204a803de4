"""How the hang glider handles (issue 34), measured from the particles: roll, turns, dive recovery, phugoid.

Each function flies a scene once (a built-in name, a scene file or a descriptor; ``solver`` overrides the time
step and iterations) and returns several figures of that one flight, so a test or a validation row reuses it.
A *pilot* here is a function of the flight state (:func:`warpsim.objects.hang_glider.flight_state`, with its
time ``t`` [s]) that returns the controls to set (or ``None`` to keep them), called every ``every`` seconds.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from warpsim.physics.atmosphere import scene_density
from warpsim.physics.model import AIR_DENSITY, GRAVITY
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
    ``every`` seconds; the flight state at each decision, with ``t`` [s] and the ``roll``/``pitch`` then set.

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


def _crossing(history: list[dict], t0: float, test: Callable[[dict], bool]) -> float:
    """First time [s] at or after ``t0`` when ``test`` holds (inf if never)."""
    return next((f["t"] for f in history if f["t"] >= t0 and test(f)), math.inf)


def roll_flight(
    scene: str | dict, solver: dict | None = None, level: float = 10.0, steady: float = 8.0, hold: float = 20.0
) -> dict:
    """Full weight shift from level flight, a reversal from a steady turn, and the bar centred in a turn.

    From level trimmed flight at ``level`` [s], ``roll = -1`` until 30° of left bank; a pilot (:func:`bank_holder`)
    then holds 30° left for ``steady`` [s]; then ``roll = +1`` until 30° of right bank (the reversal), and the bar is
    centred for ``hold`` [s]. Returns ``time_to_30`` [s] (level to -30°), ``reversal`` [s] (from the full weight
    shift right in the steady left turn to +30°), ``bank_after_hold`` [deg] (the bank ``hold`` seconds after
    centring), ``bank_min``/``bank_max`` [deg] over the hold, the largest sideslip [deg] at the mass centre
    (:func:`body_angles`) over the roll-in (``beta_roll_in``: level to -30°) and over the reversal (``beta_reversal``),
    the largest keel angle of attack [deg] from the roll-in on (``alpha_max``; beyond 90° the keel flies tail
    first), ``history``.
    """
    phase = {"name": "level"}
    holder = bank_holder(lambda t: -30.0)

    def pilot(s):
        name = phase["name"]
        if name == "level" and s["t"] >= level - 1e-9:
            phase.update(name="left", t=s["t"])
            return {"roll": -1.0}
        if name == "left" and s["bank_deg"] <= -30.0:
            phase.update(name="steady", t_left=s["t"])
        if phase["name"] == "steady":
            if s["t"] < phase["t_left"] + steady - 1e-9:
                return holder(s)
            phase.update(name="right", t_reverse=s["t"])
            return {"roll": 1.0}
        if name == "right" and s["bank_deg"] >= 30.0:
            phase.update(name="hold", t_right=s["t"])
            return {"roll": 0.0}
        return None

    done = lambda s: phase["name"] == "hold" and s["t"] >= phase["t_right"] + hold - 1e-9  # noqa: E731
    history = fly_piloted(
        scene_descriptor(scene, solver), level + steady + 60.0 + hold, pilot, stop=done, watch=body_angles
    )
    t_right = phase.get("t_right", math.inf)
    held = [f for f in history if t_right <= f["t"]]

    def largest_beta(t0: float, t1: float) -> float:
        return max((abs(f["beta"]) for f in history if t0 - 1e-9 <= f["t"] <= t1 + 1e-9), default=math.nan)

    return {
        "beta_roll_in": largest_beta(level, phase.get("t_left", math.inf)),
        "beta_reversal": largest_beta(phase.get("t_reverse", math.inf), t_right),
        "alpha_max": max(abs(f["alpha"]) for f in history if f["t"] >= level - 1e-9),
        "time_to_30": phase.get("t_left", math.inf) - level,
        "reversal": t_right - phase.get("t_reverse", math.inf),
        "history": history,
        "bank_after_hold": held[-1]["bank_deg"] if held and held[-1]["t"] >= t_right + hold - 0.06 else math.nan,
        "bank_min": min((f["bank_deg"] for f in held), default=math.nan),
        "bank_max": max((f["bank_deg"] for f in held), default=math.nan),
    }


def held_shift_flight(
    scene: str | dict, solver: dict | None = None, roll: float = 0.5, level: float = 10.0, seconds: float = 20.0
) -> dict:
    """Weight shift ``roll`` held ``seconds`` [s] from level trimmed flight at ``level`` [s]: the largest sideslip
    [deg] at the mass centre and keel angle of attack [deg] (:func:`body_angles`) while it is held, the bank [deg]
    and airspeed [m/s] at its end and the fastest airspeed [m/s] on the way, and the ``history``."""
    history = fly_piloted(
        scene_descriptor(scene, solver),
        level + seconds,
        lambda s: {"roll": roll} if s["t"] >= level - 1e-9 else None,
        watch=body_angles,
    )
    held = [f for f in history if f["t"] >= level - 1e-9]
    return {
        "beta": max(abs(f["beta"]) for f in held),
        "alpha": max(abs(f["alpha"]) for f in held),
        "bank": held[-1]["bank_deg"],
        "airspeed": held[-1]["airspeed"],
        "fastest": max(f["airspeed"] for f in held),
        "history": history,
    }


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


def turn_circle(frames: list[dict]) -> dict:
    """The steady turn over ``frames``: mean bank [deg], airspeed [m/s], horizontal speed [m/s], turn rate [deg/s],
    radius V_h / rate [m] and the coordinated turn's V^2 / (g tan bank) [m] (V the airspeed)."""
    heading = np.unwrap([math.atan2(f["velocity"][1], f["velocity"][0]) for f in frames])
    rate = (heading[-1] - heading[0]) / (frames[-1]["t"] - frames[0]["t"])
    bank = float(np.mean([f["bank_deg"] for f in frames]))
    airspeed = float(np.mean([f["airspeed"] for f in frames]))
    horizontal = float(np.mean([np.hypot(*f["velocity"][:2]) for f in frames]))
    return {
        "bank": bank,
        "airspeed": airspeed,
        "rate": math.degrees(rate),
        "radius": horizontal / abs(rate),
        "expected": airspeed**2 / (GRAVITY * math.tan(math.radians(abs(bank)))),
    }


def turn_flight(scene: str | dict, solver: dict | None = None, banks=(20.0, 40.0), settle=10.0, hold=10.0) -> dict:
    """Steady turns held by :func:`bank_holder` at each of ``banks`` [deg] in turn (from 10 s, ``settle`` + ``hold``
    seconds each); :func:`turn_circle` over each ``hold``, keyed by the bank."""
    start = 10.0
    span = settle + hold

    def target(t):
        k = int((t - start) // span)
        return None if t < start or k >= len(banks) else banks[k]

    history = fly_piloted(scene_descriptor(scene, solver), start + span * len(banks), bank_holder(target))
    out = {"history": history}
    for k, b in enumerate(banks):
        t0 = start + k * span + settle
        out[b] = turn_circle([f for f in history if t0 <= f["t"] <= t0 + hold + 1e-9])
    return out


def dive_flight(
    scene: str | dict,
    solver: dict | None = None,
    nose_down: float = 60.0,
    seconds: float = 12.0,
    bar: float = 0.0,
    watch: Callable[[Simulation, dict], None] | None = None,
) -> dict:
    """Released from rest with the nose ``nose_down`` [deg] below the horizon (R.T. Jones 1977), the bar at
    ``bar`` from the release (0: hands off; -1: pushed full out, the pilot pulling out at the highest lift, as
    Jones's constant-C_L analysis assumes; it reaches the stop in 0.5 s, the arms' slew): the height [m] lost
    until the flight path is level again (the sail's mean vertical velocity back to 0), the time [s] it takes,
    the fastest airspeed [m/s] and the lowest pitch [deg] on the way."""
    d = scene_descriptor(scene, solver, {"speed": 0.0, "nose_up": -nose_down})
    history = fly_piloted(d, seconds, pilot=(lambda state: {"pitch": bar}) if bar else None, every=0.02, watch=watch)
    start = history[0]["altitude"]
    moving = [f for f in history if f["velocity"][2] < -1.0]
    t_level = _crossing(history, moving[0]["t"] if moving else 0.0, lambda f: f["velocity"][2] >= 0.0)
    lowest = min((f for f in history if f["t"] <= t_level), key=lambda f: f["altitude"])
    return {
        "height": start - lowest["altitude"],
        "time": t_level,
        "fastest": max(f["airspeed"] for f in history if f["t"] <= t_level),
        "lowest_pitch": min(f["pitch_deg"] for f in history if f["t"] <= t_level),
        "history": history,
    }


def jones_recovery_height(wing_loading: float, lift_coefficient: float, density: float = AIR_DENSITY) -> float:
    """Height [m] a glider released from rest loses before its path is level again, after R.T. Jones (1977):
    without drag and at a constant lift coefficient C_L, energy gives V^2 = 2 g z after a drop z, and the path's
    curvature ``V dgamma/dt = (rho S C_L / 2m) V^2 - g cos gamma`` integrates (Lanchester's phugoid) to
    ``cos gamma = (2/3) (rho C_L / (2 m/S)) 2 z``, from a vertical start: level (cos gamma = 1) at
    ``z = 3 (m/S) / (rho C_L)``, whatever the nose's start attitude. ``wing_loading`` m/S [kg/m^2], ``density`` rho
    [kg/m^3]."""
    return 3.0 * wing_loading / (density * lift_coefficient)


def point_mass_recovery(
    wing_loading: float,
    lift_coefficient: float,
    glide_ratio: float,
    density: float = AIR_DENSITY,
    step: float = 1e-3,
    lag: float = 0.0,
) -> float:
    """Height [m] lost from rest until the path is level, integrating Jones's point mass with drag: the
    ``lift_coefficient`` across the path and drag ``lift / glide_ratio`` along it (midpoint rule, ``step`` [s]);
    ``wing_loading`` [kg/m^2], ``density`` [kg/m^3].

    ``lag`` (``c`` of :func:`lag_ratio`, 0: Jones's constant C_L) is a tailless wing's pitch-damping lag: hands off,
    its C_L falls to ``C_L - a k dgamma/dt / V`` while its path turns (``k`` [m], :func:`delta_pitch_lag`). With
    ``V dgamma/dt = L/m - g cos gamma`` the lift per unit mass is
    then ``(K V^2 + c g cos gamma) / (1 + c)`` (``K = rho C_L / (2 m/S)``): the path turns ``1 + c`` times slower.
    Without drag this levels at ``z = (3 + 2c) (m/S) / (rho C_L)`` (:func:`jones_recovery_height` at ``c = 0``)."""
    k = density * lift_coefficient / (2.0 * wing_loading)  # lift per unit mass over V^2 [1/m]

    def accel(v):
        speed = math.hypot(*v)
        # lift per unit mass, divided by V: along the unit normal (-v_y, v_x) / V and against v / V for the drag
        lift = (k * speed * speed + lag * GRAVITY * v[0] / speed) / ((1.0 + lag) * speed)
        return np.array([-lift * v[1] - lift * v[0] / glide_ratio, lift * v[0] - lift * v[1] / glide_ratio - GRAVITY])

    v, z = np.array([0.0, -1e-3]), 0.0
    while not (v[1] >= 0.0 and v[0] > 0.0):
        half = v + 0.5 * step * accel(v)
        z -= step * half[1]
        v = v + step * accel(half)
    return z


def lag_ratio(lag_length: float, lift_slope: float, wing_loading: float, density: float = AIR_DENSITY) -> float:
    """The pitch-damping lag ``c = rho a k / (2 m/S)`` (dimensionless) of a wing whose C_L falls ``a k dgamma/dt / V``
    below trim while its path turns: ``lag_length`` k [m], ``lift_slope`` a [1/rad], ``wing_loading`` m/S [kg/m^2],
    ``density`` rho [kg/m^3]. Its path turns ``1 + c`` times slower than a point mass's at the trim C_L
    (:func:`point_mass_recovery`); its phugoid's period is ``sqrt(1 + c)`` times Lanchester's
    (:func:`lagged_period`)."""
    return density * lift_slope * lag_length / (2.0 * wing_loading)


def lagged_period(speed: float, lag: float = 0.0) -> float:
    """Lanchester's phugoid period ``pi sqrt(2) V / g`` [s] at ``speed`` V [m/s], times ``sqrt(1 + c)`` for the lag
    ``c`` (:func:`lag_ratio`). Linearised about trim (speed V + u, path angle gamma): ``du/dt = -g gamma`` and
    ``V dgamma/dt = 2 g u / V - a k (rho V^2 S / 2m) dgamma/dt / V``, so ``(1 + c) V dgamma/dt = 2 g u / V`` and
    ``omega^2 = 2 g^2 / (V^2 (1 + c))``."""
    return math.pi * math.sqrt(2.0) * speed / GRAVITY * math.sqrt(1.0 + lag)


def inertial_phugoid(
    speed: float,
    glide_ratio: float,
    lag: float = 0.0,
    static_margin: float = math.inf,
    inertia_per_mass: float = 0.0,
) -> dict:
    """The phugoid of a wing with drag, pitch damping and pitch inertia: its damped ``period`` [s], damping ratio
    ``zeta`` and ``tau`` [s], at ``speed`` V [m/s] and ``glide_ratio`` L/D, with the lag ``c`` (:func:`lag_ratio`),
    the ``static_margin`` SM [m] and the pitch inertia over the mass I/m [m^2] (:func:`pitch_inertia`).

    Linearised about trim (speed V + u, path angle gamma, the pitch rate the path's, q = dgamma/dt): the pitch
    equation ``I dq/dt = -M_alpha dalpha - M_q q`` with ``M_alpha = L_alpha SM`` makes the lift change by
    ``L_alpha dalpha = -(I / SM) d^2gamma/dt^2 - c m V dgamma/dt``: the wing's angle of attack must fall to
    accelerate its pitch. With ``m V dgamma/dt = 2 m g u / V + L_alpha dalpha`` and ``du/dt = -g gamma - d u``
    (``d = 2 g / (V L/D)``, drag ~ V^2) the modes are the roots of
    ``(tau s^2 + (1 + c) s) (s + d) + 2 g^2 / V^2 = 0``, ``tau = (I/m) / (SM V)``. Without inertia
    (``tau = 0``) this is Lanchester's phugoid with the lag: ``zeta = sqrt(1 + c) / (sqrt(2) L/D)``, period
    ``sqrt(1 + c)`` times his (:func:`lagged_period`). Inertia lowers the damping by about
    ``tau omega / (2 (1 + c))`` (``omega = sqrt(2) g / (V sqrt(1 + c))``): the lift that accelerates the pitch is in
    phase with the speed's rate of change and feeds the oscillation."""
    d = 2.0 * GRAVITY / (speed * glide_ratio)
    tau = inertia_per_mass / (static_margin * speed)
    roots = np.roots([tau, (1.0 + lag) + tau * d, (1.0 + lag) * d, 2.0 * GRAVITY**2 / speed**2])
    mode = roots[np.argmax(np.abs(roots.imag))]
    return {"period": 2.0 * math.pi / abs(mode.imag), "zeta": -mode.real / abs(mode), "tau": tau}


def pitch_inertia(scene: str | dict, solver: dict | None = None, settle: float = 15.0) -> dict:
    """The flying object's (the glider with its pilot and control frame) ``mass`` [kg] and pitch inertia about its
    centre of mass over that mass, ``inertia_per_mass`` [m^2], after ``settle`` [s] hands off: the particles' masses
    times their squared distances from the horizontal axis through the centre of mass across the flight path."""
    sim = Simulation(scene_descriptor(scene, solver))
    sim.step(max(1, int(round(settle / sim.dt))))
    record = sim.model.objects[0]
    q = sim.state.positions()[record.particles]
    q_prev = sim.state.particle_q_prev.numpy()[record.particles]
    inv = sim.model.particle_inv_mass.numpy()[record.particles]
    mass = np.where(inv > 0, 1.0 / np.where(inv > 0, inv, 1.0), 0.0)
    centre = mass @ q / mass.sum()
    axis = np.cross(mass @ (q - q_prev), (0.0, 0.0, 1.0))
    axis /= np.linalg.norm(axis)
    r = q - centre
    across = r - np.outer(r @ axis, axis)
    return {"mass": float(mass.sum()), "inertia_per_mass": float(mass @ (across**2).sum(axis=1) / mass.sum())}


def delta_pitch_lag(
    span: float,
    chord: float,
    static_margin: float | None = None,
    sample_at: float | None = 0.75,
    samples: int = 4000,
    quarter_chord_moment: bool = False,
) -> dict:
    """Strip theory's pitch-damping lag ``k`` [m] of a rigid flat delta wing (nose to a straight trailing edge,
    ``span`` and keel ``chord`` [m]) with no tail, hands off: the lift it loses per unit ``q / V`` (pitch rate over
    speed, the path's curvature in a steady pull-out), ``C_L = C_L,trim - a k q / V``.

    Each spanwise strip of chord c(y) carries lift in proportion to its area at its quarter chord and takes its angle
    of attack at ``sample_at`` of its chord (0.75: Pistolesi's rule of thin-aerofoil theory, a pitching plate lifts
    like one at the angle of attack of its three-quarter chord; 0.25: where its lift acts). With ``sample_at=None``
    every piece of each chord lifts alone at its own angle of attack, the lift spread evenly along the chord: what a
    sail of flat triangles each under its own air law does. Pitching at q about the centre of gravity adds
    ``q (x_cg - x_s) / V`` to the angle of attack at x_s. The moment about the centre of gravity must vanish, so the
    wing's angle of attack falls ``(q / V) sum w (x_L - x_cg)(x_s - x_cg) / SM`` below trim (weights w the lift's
    shares at x_L, SM [m] the static margin, the centre of gravity ahead of the aerodynamic centre), and the lift
    the pitch rate itself makes, ``a (q / V) sum w (x_cg - x_s)``, gives some back: ``k`` is the difference, about
    ``(r^2 - cov(x_1/4, c) / 2) / SM`` at 0.75, ``r^2 / SM`` at 0.25 and ``(r_1/2^2 + mean c^2 / 12) / SM`` for
    pieces alone (r_1/2 that of the half-chord points). Returns ``k`` and ``alpha_lag`` (the first term alone, [m])
    at ``static_margin`` (if given), the aerodynamic centre ``ac`` [m] forward of the nose and the radius of gyration
    ``radius`` [m] of the strips' lift about their quarter-chord aerodynamic centre.

    ``quarter_chord_moment`` (with ``sample_at=0.75``) adds thin-aerofoil theory's pitch-damping moment about each
    strip's quarter chord, ``C_m = -pi q c / (8 V)`` (= ``-a q c / (16 V)`` at a = 2 pi; the upwash varying linearly
    along the chord, as a parabolic camber, whose Fourier coefficient A1 gives ``C_m,c/4 = pi (A2 - A1) / 4``): the
    angle of attack must fall by ``(q / V) sum w c^2 / 16 / SM`` more, so ``k`` grows by ``mean_w(c^2) / (16 SM)``
    (1.13 m in all at this glider's planform and a 0.29 m static margin, against 0.28 m without it)."""
    semi = 0.5 * span
    y = (np.arange(samples) + 0.5) * semi / samples
    c = chord * (1.0 - y / semi)
    quarter = -chord * y / semi - 0.25 * c  # forward of the nose [m]
    w = c / c.sum()
    ac = float(w @ quarter)
    if sample_at is None:  # pieces alone: 16 evenly loaded pieces along each chord, each at its own angle of attack
        xi = (np.arange(16) + 0.5) / 16.0
        lifting = (-chord * y / semi)[:, None] - xi[None, :] * c[:, None]
        sampled, weights = lifting, np.repeat(w[:, None] / 16.0, 16, axis=1)
        ac = float((weights * lifting).sum())
    else:
        lifting, sampled, weights = quarter, quarter - (sample_at - 0.25) * c, w

    def lags(sm):
        cg = ac + sm
        alpha = float((weights * (lifting - cg) * (sampled - cg)).sum()) / sm
        if quarter_chord_moment:
            alpha += float(w @ (c * c)) / 16.0 / sm
        return alpha + float((weights * (sampled - cg)).sum()), alpha

    out = {"ac": ac, "radius": float(np.sqrt(w @ (quarter - float(w @ quarter)) ** 2))}
    if static_margin is not None:
        out["k"], out["alpha_lag"] = lags(static_margin)
    return out


def pitch_derivatives(scene: str | dict, solver: dict | None = None, settle: float = 15.0) -> dict:
    """The trimmed glider's quasi-static pitch derivatives from its own air law, measured as in a wind tunnel: after
    ``settle`` [s] hands off, the air forces on its particles as they are (sail triangles and drag bodies) are
    computed for rigid velocity fields, the centre of mass's velocity alone, that velocity turned 0.01 rad
    nose-down (angle of attack + 0.01) and a nose-up pitch rate q = 0.01 V [rad/s] about the centre of mass, and
    their lift (across the velocity, in the plane of symmetry) and pitching moment about the centre of mass
    differenced. Returns ``speed`` [m/s], ``cl``, the lift slope ``slope`` [1/rad], the static margin
    ``static_margin`` = -M_alpha / L_alpha [m], ``damping`` = M_qhat / M_alpha [m] (qhat = q / V), ``pitch_lift`` =
    L_qhat / L_alpha [m] and the lag ``k`` = damping - pitch_lift [m] (:func:`delta_pitch_lag`)."""
    import warp as wp

    from warpsim.physics.kernels.aero import body_drag, triangle_air_force

    sim = Simulation(scene_descriptor(scene, solver))
    rec = sim.model.objects[0]
    sim.step(int(round(settle / sim.dt)))
    q = sim.state.particle_q.numpy().astype(np.float64)
    q_prev = sim.state.particle_q_prev.numpy().astype(np.float64)
    inv = sim.model.particle_inv_mass.numpy()
    mass = np.where(inv > 0, 1.0 / np.where(inv > 0, inv, 1.0), 0.0)[rec.particles]
    cg = mass @ q[rec.particles] / mass.sum()
    v_cg = mass @ (q[rec.particles] - q_prev[rec.particles]) / (mass.sum() * sim.dt)
    fwd = q[rec.nose] - q[rec.keel[-1]]
    fwd /= np.linalg.norm(fwd)
    left = q[rec.tips[0]] - q[rec.tips[1]]
    left -= (left @ fwd) * fwd
    left /= np.linalg.norm(left)
    nose_up = -left  # rotating about it lifts the nose
    tris = sim.model.tri_indices.numpy()[: sim.model.tri_count]

    def lift_moment(velocity, omega):
        v = velocity[None, :] + np.cross(omega[None, :], q - cg[None, :])
        sim.state.particle_q_prev.assign(q - v * sim.dt)
        shares = wp.zeros(max(sim.model.tri_count, 1), dtype=wp.vec3, device=sim.model.device)
        drag = wp.zeros(sim.model.particle_count, dtype=wp.vec3, device=sim.model.device)
        triangle_air_force(sim.model, sim.state, sim.control, sim.dt, sim.solver.air, sim.solver.wind, shares)
        body_drag(sim.model, sim.state, sim.control, sim.dt, sim.solver.air, sim.solver.wind, drag)
        force = drag.numpy().astype(np.float64)
        share = shares.numpy()[: sim.model.tri_count].astype(np.float64)  # each vertex's third
        for corner in range(3):
            np.add.at(force, tris[:, corner], share)
        across = np.cross(fwd, left)
        across -= (across @ v_hat) * v_hat
        return force.sum(axis=0) @ across / np.linalg.norm(across), np.cross(q - cg, force).sum(axis=0) @ nose_up

    speed = float(np.linalg.norm(v_cg))
    v_hat = v_cg / speed
    lift, moment = lift_moment(v_cg, np.zeros(3))
    step = 0.01
    lift_a, moment_a = lift_moment(v_cg - step * np.cross(nose_up, v_cg), np.zeros(3))
    lift_q, moment_q = lift_moment(v_cg, step * speed * nose_up)
    sim.state.particle_q_prev.assign(q_prev)
    l_alpha, m_alpha = (lift_a - lift) / step, (moment_a - moment) / step
    l_q, m_q = (lift_q - lift) / step, (moment_q - moment) / step
    dynamic = 0.5 * float(sim.control.air_density.numpy()[0]) * speed**2 * wing_area(scene)
    return {
        "speed": speed,
        "cl": lift / dynamic,
        "slope": l_alpha / dynamic,
        "static_margin": -m_alpha / l_alpha,
        "damping": m_q / m_alpha,
        "pitch_lift": l_q / l_alpha,
        "k": m_q / m_alpha - l_q / l_alpha,
    }


def wing_area(scene: str | dict) -> float:
    """The sail's planform area, span x chord / 2 [m^2]."""
    g = scene_descriptor(scene)["hang_glider"]
    return 0.5 * g["span"] * g["chord"]


def lift_slope_flight(scene: str | dict, solver: dict | None = None, bars=(-0.4, 0.4), settle=25.0, hold=15.0) -> dict:
    """The wing's lift slope [1/rad] and static margin [m] from two steady glides, the bar held at each of ``bars``.

    C_L from the centre of mass's speed and path, ``2 (m/S) g cos gamma / (rho V^2)``, against the keel's angle of
    attack (keel against the sail's mean velocity), averaged over ``hold`` [s] after ``settle`` [s], gives the slope
    a. Moving the pilot forward by dx (measured from the sail's particles) moves the centre of gravity by
    ``(m_pilot / m) dx``, and the wing retrims where the lift's moment about it vanishes again:
    ``SM = C_L (m_pilot / m) dx / (a |dalpha|)``, the static margin with every contribution (sail, pilot's drag,
    pendulum) in it. Returns ``slope``, ``static_margin`` and each ``cl``, ``alpha`` [deg] and ``pilot`` [m]."""
    d = scene_descriptor(scene, solver)
    rho = scene_density(d["air"], d["hang_glider"]["altitude"])  # where it is launched
    load = wing_loading(d)
    g = d["hang_glider"]
    share = g["pilot_mass"] / (g["glider_mass"] + g["pilot_mass"] + g["control_frame_mass"])
    cls, alphas, pilots = [], [], []
    for bar in bars:
        frames = [
            f
            for f in fly_piloted(d, settle + hold, lambda s, b=bar: {"pitch": b}, every=0.1)
            if f["t"] >= settle - 1e-9
        ]
        cg = np.mean([f["cg_velocity"] for f in frames], axis=0)
        gamma = math.atan2(cg[2], math.hypot(cg[0], cg[1]))
        speed = float(np.mean([f["cg_speed"] for f in frames]))
        cls.append(2.0 * load * GRAVITY * math.cos(gamma) / (rho * speed**2))
        alphas.append(float(np.mean([f["pitch_deg"] - math.degrees(_path_angle(f["velocity"])) for f in frames])))
        pilots.append(float(np.mean([f["pilot_forward"] for f in frames])))
    d_alpha = math.radians(alphas[0] - alphas[-1])
    slope = (cls[0] - cls[-1]) / d_alpha
    margin = float(np.mean(cls)) * share * abs(pilots[-1] - pilots[0]) / (slope * abs(d_alpha))
    return {"slope": slope, "static_margin": margin, "cl": cls, "alpha": alphas, "pilot": pilots}


def _path_angle(velocity) -> float:
    """Path angle [rad] of ``velocity`` above the horizontal."""
    return math.atan2(velocity[2], math.hypot(velocity[0], velocity[1]))


def phugoid_flight(
    scene: str | dict, solver: dict | None = None, watch: Callable[[Simulation, dict], None] | None = None
) -> dict:
    """A 2 s pulse of bar in (pitch 0.3) at 20 s from trim, then hands off to 60 s: the airspeed's period [s] from
    its troughs, damping ratio, the trim airspeed [m/s] before the pulse and Lanchester's period
    pi sqrt(2) V / g [s]."""

    def pilot(s):
        if abs(s["t"] - 20.0) < 1e-6:
            return {"pitch": 0.3}
        if abs(s["t"] - 22.0) < 1e-6:
            return {"pitch": 0.0}
        return None

    history = fly_piloted(scene_descriptor(scene, solver), 60.0, pilot, every=0.1, watch=watch)
    trim = float(np.mean([f["airspeed"] for f in history if 10.0 <= f["t"] <= 20.0]))
    pulse = [f for f in history if f["t"] >= 23.0 - 1e-9]
    dv = np.array([f["airspeed"] for f in pulse]) - trim
    troughs = [i for i in range(1, len(dv) - 1) if dv[i] < dv[i - 1] and dv[i] <= dv[i + 1] and dv[i] < -0.2]
    lanchester = math.pi * math.sqrt(2.0) * trim / GRAVITY
    if len(troughs) < 2:
        return {"period": math.nan, "zeta": math.nan, "trim": trim, "lanchester": lanchester}
    period = (pulse[troughs[-1]]["t"] - pulse[troughs[0]]["t"]) / (len(troughs) - 1)
    decrement = math.log(dv[troughs[0]] / dv[troughs[-1]]) / (len(troughs) - 1)
    return {
        "period": period,
        "zeta": decrement / math.hypot(2.0 * math.pi, decrement),
        "trim": trim,
        "lanchester": lanchester,
        "troughs": len(troughs),
        "history": history,
    }


def stall_flight(scene: str | dict, solver: dict | None = None) -> dict:
    """Full bar out (pitch -1) from 15 s, released at 25 s, flown to 40 s: the time [s] to fly at 9 m/s again, the
    largest |pitch| [deg] after the release, the lowest airspeed [m/s] and highest pitch [deg] while held."""

    def pilot(s):
        if abs(s["t"] - 15.0) < 1e-6:
            return {"pitch": -1.0}
        if abs(s["t"] - 25.0) < 1e-6:
            return {"pitch": 0.0}
        return None

    history = fly_piloted(scene_descriptor(scene, solver), 40.0, pilot, every=0.1)
    held = [f for f in history if 15.0 < f["t"] <= 25.05]
    after = [f for f in history if f["t"] > 25.05]
    return {
        "recovery": _crossing(after, 25.0, lambda f: f["airspeed"] >= 9.0) - 25.0,
        "max_pitch": max(abs(f["pitch_deg"]) for f in after),
        "slowest": min(f["airspeed"] for f in held),
        "nose_up": max(f["pitch_deg"] for f in held),
        "history": history,
    }


def glide_flight(scene: str | dict, solver: dict | None = None) -> dict:
    """Hands off for 60 s: glide ratio and mean airspeed [m/s] over 10-60 s, the airspeed's spread and the largest
    |bank| [deg]."""
    history = fly_piloted(scene_descriptor(scene, solver), 60.0, every=0.1)
    frames = [f for f in history if f["t"] >= 10.0 - 1e-9]
    distance = sum(float(np.hypot(*f["velocity"][:2])) * 0.1 for f in frames[1:])
    speeds = np.array([f["airspeed"] for f in frames])
    return {
        "glide": distance / (frames[0]["altitude"] - frames[-1]["altitude"]),
        "speed": float(speeds.mean()),
        "spread": float(np.abs(speeds / speeds.mean() - 1.0).max()),
        "max_bank": max(abs(f["bank_deg"]) for f in frames),
        "history": history,
    }


def wing_loading(scene: str | dict) -> float:
    """Total mass over the sail's planform area (span x chord / 2) [kg/m^2]."""
    g = scene_descriptor(scene)["hang_glider"]
    return (g["glider_mass"] + g["pilot_mass"] + g["control_frame_mass"]) / (0.5 * g["span"] * g["chord"])


def dive_band(
    scene: str | dict,
    trim_speed: float,
    glide_ratio: float,
    max_lift: float = 1.0,
    lift_slope: float | None = None,
    static_margin: float | None = None,
    period_ratio: float | None = None,
) -> dict:
    """The band of the dive recovery height [m] from R.T. Jones (1977) at ``scene``'s wing loading and air density:
    from his closed form at the maximum lift coefficient ``max_lift`` (his 1.0: the wing pulls out at once at its
    highest lift, the least height) to the point mass holding the trim lift coefficient
    ``2 (m/S) g / (rho V^2)`` (``trim_speed`` [m/s]) with the drag of the measured ``glide_ratio`` (a wing held at its
    trim angle of attack through the pull-out). Returns ``wing_loading``, ``density``, ``trim_cl``, ``low``,
    ``jones_trim`` (the closed form at the trim C_L) and ``high``.

    With ``lift_slope`` a [1/rad] and ``static_margin`` [m] it adds what a rigid tailless wing of the scene's planform
    does hands off (:func:`delta_pitch_lag`, :func:`lag_ratio`): ``rigid_lag`` (c, Pistolesi's three-quarter chord) and
    ``thin_lag`` (c, Pistolesi's point with thin-aerofoil theory's quarter-chord pitch-damping moment,
    ``quarter_chord_moment`` of :func:`delta_pitch_lag`), ``panel_lag`` (c, each strip's angle of attack where its lift
    acts) and ``pieces_lag`` (c, every piece of each chord
    lifting alone, as a sail of triangles each under its own air law does), the heights ``rigid``, ``panel`` and
    ``pieces`` [m] of that point mass with those lags, and ``rigid_period`` (and so on), the ratios ``sqrt(1 + c)``
    of their phugoid periods to Lanchester's. With ``period_ratio`` (a measured phugoid period
    over Lanchester's) it adds ``lag`` = ``period_ratio^2 - 1`` and ``predicted`` [m], the point mass with that lag."""
    d = scene_descriptor(scene)
    rho = scene_density(d["air"], d["hang_glider"]["altitude"])  # where it is launched
    load = wing_loading(d)
    cl = 2.0 * load * GRAVITY / (rho * trim_speed**2)
    out = {
        "wing_loading": load,
        "density": rho,
        "trim_cl": cl,
        "low": jones_recovery_height(load, max_lift, rho),
        "jones_trim": jones_recovery_height(load, cl, rho),
        "high": point_mass_recovery(load, cl, glide_ratio, rho),
    }
    if lift_slope is not None and static_margin is not None:
        g = d["hang_glider"]
        for key, at, moment in (
            ("rigid", 0.75, False),
            ("thin", 0.75, True),
            ("panel", 0.25, False),
            ("pieces", None, False),
        ):
            k = delta_pitch_lag(g["span"], g["chord"], static_margin, sample_at=at, quarter_chord_moment=moment)["k"]
            lag = lag_ratio(k, lift_slope, load, rho)
            out[f"{key}_lag"] = lag
            out[key] = point_mass_recovery(load, cl, glide_ratio, rho, lag=lag)
            out[f"{key}_period"] = math.sqrt(1.0 + lag)
    if period_ratio is not None:
        out["lag"] = period_ratio**2 - 1.0
        out["predicted"] = point_mass_recovery(load, cl, glide_ratio, rho, lag=out["lag"])
    return out


def summary(scene: str | dict = "hang-glider", solver: dict | None = None) -> dict:
    """Every handling figure of ``scene`` (one flight each), without the histories."""
    r, hs, t, dv, dvb, p, s, g, a, pd = (
        roll_flight(scene, solver),
        held_shift_flight(scene, solver),
        turn_flight(scene, solver),
        dive_flight(scene, solver),
        dive_flight(scene, solver, bar=-1.0),
        phugoid_flight(scene, solver),
        stall_flight(scene, solver),
        glide_flight(scene, solver),
        lift_slope_flight(scene, solver),
        pitch_derivatives(scene, solver),
    )
    return {
        "time_to_30": r["time_to_30"],
        "reversal": r["reversal"],
        "bank_after_hold": r["bank_after_hold"],
        "hold_range": (r["bank_min"], r["bank_max"]),
        "beta_roll_in": r["beta_roll_in"],
        "beta_reversal": r["beta_reversal"],
        "alpha_max": r["alpha_max"],
        "half_shift": {k: v for k, v in hs.items() if k != "history"},
        "turn20": {k: v for k, v in t[20.0].items()},
        "turn40": {k: v for k, v in t[40.0].items()},
        "dive_height": dv["height"],
        "dive_time": dv["time"],
        "dive_fastest": dv["fastest"],
        "dive_lowest_pitch": dv["lowest_pitch"],
        "dive_bar_out_height": dvb["height"],
        "dive_bar_out_time": dvb["time"],
        "phugoid": {k: v for k, v in p.items() if k != "history"},
        "stall": {k: v for k, v in s.items() if k != "history"},
        "glide": {k: v for k, v in g.items() if k != "history"},
        "lift_slope": a["slope"],
        "static_margin": a["static_margin"],
        "pitch": {k: float(v) for k, v in pd.items()},
    }


def plot_roll_reversal(path, scene: str | dict = "hang-glider") -> dict:
    """Plot bank [deg], the pilot's roll and airspeed [m/s] against time [s] of :func:`roll_flight` (defaults and dt
    0.005/110) to the PNG ``path``; returns the flights."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    flights = {"dt 0.01, 55 iterations": roll_flight(scene), "dt 0.005, 110": roll_flight(scene, FINE)}
    fig, (top, mid, low) = plt.subplots(3, 1, sharex=True, figsize=(8, 7), gridspec_kw={"height_ratios": [3, 1, 2]})
    for (label, r), style in zip(flights.items(), ("-", "--"), strict=True):
        h = [f for f in r["history"] if f["t"] >= 8.0]
        t = [f["t"] for f in h]
        top.plot(t, [f["bank_deg"] for f in h], style, color="C0", label=f"bank, {label}")
        mid.plot(t, [f["roll"] for f in h], style, color="C2", label=label)
        low.plot(t, [f["airspeed"] for f in h], style, color="C1", label=label)
    r = flights["dt 0.01, 55 iterations"]
    for y in (-30.0, 30.0):
        top.axhline(y, color="grey", lw=0.6)
    fine = flights["dt 0.005, 110"]
    top.text(
        0.02,
        0.96,
        f"level to -30°: {r['time_to_30']:.1f} s ({fine['time_to_30']:.1f} s)\n"
        f"reversal -30° to +30°: {r['reversal']:.1f} s ({fine['reversal']:.1f} s)\n"
        f"bar centred at +30°: {r['bank_after_hold']:.0f}° ({fine['bank_after_hold']:.0f}°) 20 s later",
        transform=top.transAxes,
        va="top",
        fontsize=8,
        bbox={"facecolor": "white", "alpha": 0.8, "edgecolor": "none"},
    )
    top.set_ylabel("bank [deg] (+ right)")
    top.legend(fontsize=8, loc="lower right")
    top.set_title("Hang glider: full weight shift from level, reversal from a steady 30° turn, bar centred")
    mid.set_ylabel("roll (bar)")
    mid.set_ylim(-1.15, 1.15)
    low.set_ylabel("airspeed [m/s]")
    low.set_xlabel("time [s]")
    low.legend(fontsize=8, loc="upper right")
    for ax in (top, mid, low):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return flights


FINE = {"dt": 0.005, "iterations": 110}
"""The finer numerics every handling band must also hold at (issue 34)."""


if __name__ == "__main__":  # python -m benchmarks.validation.handling [scene] [dt iterations] [key=value ...]
    import json
    import sys

    args = sys.argv[1:]
    scene = args.pop(0) if args and "=" not in args[0] and not args[0][0].isdigit() else "hang-glider"
    solver = {"dt": float(args.pop(0)), "iterations": int(args.pop(0))} if args and "=" not in args[0] else None
    glider = {k: json.loads(v) for k, v in (a.split("=", 1) for a in args)}
    d = scene_descriptor(scene, None, glider or None)
    print(json.dumps(summary(d, solver), indent=1, default=float))
