"""The hang glider's pitch, in closed forms and measured: R. T. Jones's constant-C_L dive recovery and a point
mass's, the phugoid with a pitch lag (Lanchester's period lengthened), and the glider's pitch inertia, pitch lag,
pitch derivatives and lift slope measured from the particles in flight or in a rigid wind.
"""

from __future__ import annotations

import math

import numpy as np

from warpsim.physics.model import AIR_DENSITY, GRAVITY
from warpsim.run.simulation import Simulation

from .piloting import fly_piloted, path_angle, scene_descriptor, wing_loading


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
        rho = float(np.mean([f["density"] for f in frames]))  # the air it flew these frames in
        cls.append(2.0 * load * GRAVITY * math.cos(gamma) / (rho * speed**2))
        alphas.append(float(np.mean([f["pitch_deg"] - math.degrees(path_angle(f["velocity"])) for f in frames])))
        pilots.append(float(np.mean([f["pilot_forward"] for f in frames])))
    d_alpha = math.radians(alphas[0] - alphas[-1])
    slope = (cls[0] - cls[-1]) / d_alpha
    margin = float(np.mean(cls)) * share * abs(pilots[-1] - pilots[0]) / (slope * abs(d_alpha))
    return {"slope": slope, "static_margin": margin, "cl": cls, "alpha": alphas, "pilot": pilots}
