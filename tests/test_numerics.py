"""Numbers that come from the physics, not from the numerics: the same flight anywhere on the map, and the
momentum a free body keeps in vacuum (issue 33). Everything is measured from the particles."""

from __future__ import annotations

import numpy as np
import pytest

import warpsim as ws
from warpsim.objects.hang_glider import flight_state
from warpsim.physics.atmosphere import SEA_LEVEL_DENSITY
from warpsim.run.simulation import Simulation
from warpsim.scene import descriptor

VACUUM = {"air": {"scale": 0.0}, "solver": {"damping": 0.0}, "terrain": {"kind": "flat", "height": -1.0e5}}


def _scene(scene: str, *overrides: dict) -> dict:
    d = descriptor.resolve(scene)[0]
    for o in overrides:
        d = descriptor.merge("test", d, o)
    return d


def _glide(overrides: dict, seconds: float = 60.0) -> tuple[float, float, float]:
    """Glide ratio and mean airspeed [m/s] of the hands-off hang glider over 10 s..``seconds``, and its bank [deg]
    at the end, read from the particles every 0.1 s."""
    sim = Simulation(_scene("hang-glider", overrides))
    record = sim.model.objects[0]
    steps = int(round(0.1 / sim.dt))
    states = []
    for _ in range(int(round(seconds / 0.1))):
        sim.step(steps)
        states.append(flight_state(record, sim.state.positions(), sim.state.particle_q_prev.numpy(), sim.dt, (0, 0, 0)))
    flown = states[99:]  # from 10 s on
    distance = sum(float(np.hypot(*s["velocity"][:2])) * 0.1 for s in flown[1:])
    ratio = distance / (flown[0]["altitude"] - flown[-1]["altitude"])
    return ratio, float(np.mean([s["airspeed"] for s in flown])), float(states[-1]["bank_deg"])


@pytest.mark.slow
def test_hands_off_glide_is_the_same_anywhere():
    """float64 positions: the glide 10 km from the origin or 3 km up is the one at the origin (with float32
    world coordinates it was 8.2 here and 10.3-18.5 five km away). In one fixed density: the standard atmosphere's
    would be 26 % thinner 3 km up (tests/test_atmosphere.py flies that)."""
    air = {"density": SEA_LEVEL_DENSITY}
    flat = {"terrain": {"kind": "flat"}, "air": air}
    here = _glide(flat)
    assert here[0] >= 8.0 and 9.0 <= here[1] <= 13.0  # it glides (the validation band)
    for x, y, base in [
        (10000.0, 10000.0, 0.0),
        (-10000.0, -10000.0, 0.0),
        (10000.0, -10000.0, 0.0),
        (0.0, 0.0, 3000.0),
    ]:
        there = _glide(
            {
                "terrain": {"kind": "flat", "height": base},
                "hang_glider": {"position": [x - 300.0, y], "altitude": 300.0},
                "air": air,
            }
        )
        # the issue asks for 1 %; float64 gives the same flight to rounding (2e-8 measured)
        assert there[0] == pytest.approx(here[0], rel=1e-6), (x, y, base)
        assert there[1] == pytest.approx(here[1], rel=1e-6), (x, y, base)
        assert abs(there[2] - here[2]) < 1e-3, (x, y, base)


def _momenta(mass: np.ndarray, q: np.ndarray, q_prev: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Verlet's discrete linear momentum ``sum m (x - x_prev) / dt`` [kg m/s] and angular momentum about the mass
    centre ``sum m x_prev x (x - x_prev) / dt`` [kg m^2/s], both exact invariants of internal central forces."""
    v = (q - q_prev) / dt
    centre = (mass[:, None] * q_prev).sum(0) / mass.sum()
    return (mass[:, None] * v).sum(0), (
        mass[:, None] * np.cross(q_prev - centre, v - (mass[:, None] * v).sum(0) / mass.sum())
    ).sum(0)


def _spin(sim, omega) -> np.ndarray:
    """Set the body spinning at ``omega`` [rad/s] about its mass centre; returns the particles' masses [kg]."""
    inv = sim.model.particle_inv_mass.numpy()
    mass = 1.0 / inv
    q = sim.state.positions()
    centre = (mass[:, None] * q).sum(0) / mass.sum()
    sim.state.set_velocity(np.cross(omega, q - centre), sim.dt)
    return mass


@pytest.mark.parametrize("keep, band", [(True, 1e-6), (False, None)])
def test_spinning_hang_glider_keeps_angular_momentum_in_vacuum(keep, band):
    """A hang glider tumbling in free fall, air off, 60 s: uniform gravity exerts no torque, so its angular
    momentum about the mass centre is kept (the issue asks for 1 %; 6e-10 measured); without the momentum
    projection it loses over 10 % (30 % measured at dt 0.01)."""
    sim = Simulation(
        _scene("hang-glider", VACUUM, {"solver": {"keep_momentum": keep}, "hang_glider": {"altitude": 90000.0}})
    )
    mass = _spin(sim, np.array([0.3, 1.0, 0.5]))
    sim.step(1)
    _, l0 = _momenta(mass, sim.state.positions(), sim.state.particle_q_prev.numpy(), sim.dt)
    sim.step(int(round(60.0 / sim.dt)))
    _, l1 = _momenta(mass, sim.state.positions(), sim.state.particle_q_prev.numpy(), sim.dt)
    change = np.linalg.norm(l1 - l0) / np.linalg.norm(l0)
    if band is not None:
        assert change < band
    else:
        assert change > 0.1  # the mechanism matters: the projection alone loses it


def test_tumbling_free_cloth_with_a_heavy_corner_keeps_momentum():
    """A free 9x9 cloth with a 20 kg weight at one corner (a pilot on a sail), thrown tumbling in vacuum with the
    paper's plain average (which alone keeps neither momentum when masses differ): 60 s later its linear
    momentum is what gravity gave it and its angular momentum is kept, within 1 %."""
    b = ws.ModelBuilder()
    b.set_terrain(ws.Heightfield.flat(height=-1.0e6))
    ids, _, _ = b.add_grid((0.0, 0.0, 0.0), (0.25, 0.0, 0.0), (0.0, 0.25, 0.05), 9, 9, mass=2.0)
    heavy = b.add_particle((-0.3, -0.3, -0.5), 20.0)
    b.add_stick(heavy, int(ids[0, 0]))
    b.add_stick(heavy, int(ids[0, 1]))
    b.add_stick(heavy, int(ids[1, 0]))
    m = b.finalize("cpu")
    cfg = ws.SolverConfig(mass_splitting=False, damping=0.0)
    solver = ws.SolverVerlet(m, cfg, air=ws.AirConfig(scale=0.0))
    s, c = m.state(), m.control()
    mass = 1.0 / m.particle_inv_mass.numpy()
    q = s.positions()
    centre = (mass[:, None] * q).sum(0) / mass.sum()
    dt = 0.01
    s.set_velocity(np.cross([1.5, -0.7, 2.0], q - centre) + [1.0, 2.0, 3.0], dt)
    solver.step(s, c, dt)
    p0, l0 = _momenta(mass, s.positions(), s.particle_q_prev.numpy(), dt)
    steps = 6000
    for _ in range(steps):
        solver.step(s, c, dt)
    p1, l1 = _momenta(mass, s.positions(), s.particle_q_prev.numpy(), dt)
    gained = mass.sum() * np.array([0.0, 0.0, -ws.GRAVITY]) * steps * dt
    assert np.linalg.norm(p1 - p0 - gained) < 1e-6 * np.linalg.norm(gained)
    assert np.linalg.norm(l1 - l0) < 0.01 * np.linalg.norm(l0)
    assert np.abs(m.stick_stretch(s.positions())).max() < 0.05  # still a cloth, not a cloud


def test_pilot_moving_alone_keeps_the_gliders_linear_momentum():
    """In vacuum the pilot shifting on the bar (the controls change the arms' rest lengths: internal forces) moves
    no mass centre: the glider's momentum stays what gravity makes it, and its angular momentum stays zero."""
    sim = Simulation(_scene("hang-glider", VACUUM, {"hang_glider": {"altitude": 90000.0}}))
    mass = 1.0 / sim.model.particle_inv_mass.numpy()
    sim.step(1)
    p0, _ = _momenta(mass, sim.state.positions(), sim.state.particle_q_prev.numpy(), sim.dt)
    steps = 0
    for pitch, roll in [(0.5, 1.0), (-1.0, -1.0), (0.0, 0.3)]:
        sim.set_controls(pitch=pitch, roll=roll)
        sim.step(200)
        steps += 200
    p1, l1 = _momenta(mass, sim.state.positions(), sim.state.particle_q_prev.numpy(), sim.dt)
    gained = mass.sum() * np.array([0.0, 0.0, -ws.GRAVITY]) * steps * sim.dt
    assert np.linalg.norm(p1 - p0 - gained) < 1e-6 * np.linalg.norm(p0)
    assert np.linalg.norm(l1) < 1e-6 * np.linalg.norm(p0) * 10.0  # [kg m^2/s] against a 10 m body's scale


def _vacuum_solver(b, **config):
    m = b.finalize("cpu")
    return m, ws.SolverVerlet(m, ws.SolverConfig(damping=0.0, **config), air=ws.AirConfig(scale=0.0))


def test_two_bodies_in_one_world_keep_their_own_momentum():
    """A spinning cloth and a still one in the same world, apart: the projection's momentum is given back to each
    body (the particles its sticks connect), so the still cloth stays still and the spinning one keeps its spin."""
    b = ws.ModelBuilder()
    b.set_terrain(ws.Heightfield.flat(height=-1.0e6))
    spin_ids, _, _ = b.add_grid((0.0, 0.0, 0.0), (0.25, 0.0, 0.0), (0.0, 0.25, 0.0), 7, 7, mass=1.0)
    still_ids, _, _ = b.add_grid((10.0, 0.0, 0.0), (0.25, 0.0, 0.0), (0.0, 0.25, 0.0), 5, 5, mass=1.0)
    m, solver = _vacuum_solver(b)
    s, c = m.state(), m.control()
    dt, mass = 0.01, 1.0 / m.particle_inv_mass.numpy()
    spinning, still = spin_ids.ravel(), still_ids.ravel()
    q = s.positions()
    v = np.zeros_like(q)
    centre = q[spinning].mean(0)
    v[spinning] = np.cross([0.5, 0.3, 2.0], q[spinning] - centre)
    s.set_velocity(v, dt)
    solver.step(s, c, dt)
    _, l0 = _momenta(mass[spinning], s.positions()[spinning], s.particle_q_prev.numpy()[spinning], dt)
    for _ in range(3000):
        solver.step(s, c, dt)
    q, qp = s.positions(), s.particle_q_prev.numpy()
    _, l1 = _momenta(mass[spinning], q[spinning], qp[spinning], dt)
    p_still, l_still = _momenta(mass[still], q[still], qp[still], dt)
    assert np.linalg.norm(l1 - l0) < 1e-6 * np.linalg.norm(l0)
    fall = mass[still].sum() * ws.GRAVITY * 3001 * dt  # momentum gravity gave the still cloth [kg m/s]
    assert np.linalg.norm(p_still[:2]) < 1e-9 * fall and np.linalg.norm(l_still) < 1e-9 * np.linalg.norm(l0)


def test_a_spinning_rope_keeps_its_angular_momentum():
    """Particles on a line have no inertia about it: the projection is solved with that direction left alone, and a
    free 8-link rope spinning end over end keeps its angular momentum (it lost 46 % in 30 s when a line's rotation
    was skipped)."""
    b = ws.ModelBuilder()
    b.set_terrain(ws.Heightfield.flat(height=-1.0e6))
    ids = [b.add_particle((0.25 * k, 0.0, 0.0), 0.1 if k else 2.0) for k in range(9)]
    for i, j in zip(ids, ids[1:], strict=False):
        b.add_stick(i, j)
    m, solver = _vacuum_solver(b, mass_splitting=False)
    s, c = m.state(), m.control()
    dt, mass = 0.01, 1.0 / m.particle_inv_mass.numpy()
    q = s.positions()
    centre = (mass[:, None] * q).sum(0) / mass.sum()
    s.set_velocity(np.cross([0.0, 0.0, 3.0], q - centre), dt)
    solver.step(s, c, dt)
    _, l0 = _momenta(mass, s.positions(), s.particle_q_prev.numpy(), dt)
    for _ in range(3000):
        solver.step(s, c, dt)
    _, l1 = _momenta(mass, s.positions(), s.particle_q_prev.numpy(), dt)
    assert np.linalg.norm(l1 - l0) < 1e-6 * np.linalg.norm(l0)


def _slide(dx: float, dy: float, dz: float) -> np.ndarray:
    """How far [m] a 2-particle body slides in 5 s down a 0.3 slope with friction, its terrain and itself moved by
    ``(dx, dy, dz)`` [m]."""
    n, cell = 64, 1.0
    xs = np.arange(n) * cell
    heights = np.tile(-0.3 * xs, (n, 1)) + dz
    b = ws.ModelBuilder()
    b.set_terrain(ws.Heightfield(heights, (cell * (n - 1), cell * (n - 1)), origin=(dx, dy)))
    z = -0.3 * 20.0 + dz
    a = b.add_particle((dx + 20.0, dy + 30.0, z + 0.05), 1.0)
    c = b.add_particle((dx + 20.0, dy + 30.5, z + 0.05), 1.0)
    b.add_stick(a, c)
    m = b.finalize("cpu")
    ground = ws.GroundConfig(friction=0.1)
    solver = ws.SolverVerlet(m, ws.SolverConfig(damping=0.0), air=ws.AirConfig(scale=0.0), ground=ground)
    s, ctrl = m.state(), m.control()
    start = s.positions()
    for _ in range(500):
        solver.step(s, ctrl, 0.01)
    return s.positions() - start


def test_ground_contact_is_the_same_anywhere():
    """A body sliding down a slope slides as far 10 km from the origin and 3 km up as at the origin: the terrain is
    looked up in float64 (float32 world coordinates and heights made it slide 4 % and 6.5 % less there)."""
    here = _slide(0.0, 0.0, 0.0)
    assert here[0, 0] > 5.0  # it slides
    for shift in [(10000.0, 10000.0, 0.0), (-10000.0, 10000.0, 0.0), (0.0, 0.0, 3000.0)]:
        np.testing.assert_allclose(_slide(*shift), here, atol=1e-6, err_msg=str(shift))
