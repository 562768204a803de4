"""Rigid wings held in the wind under the vortex law (issue 52): forces and moments measured from the particles'
forces, as coefficients in body axes.

A wing here is a flat lifting surface built with :class:`warpsim.ModelBuilder` (a rectangle of ``span_panels x
chord_panels`` cells, two triangles each, or a delta of ``divisions`` rows), its leading edge at ``x = 0`` and
its trailing edge downstream (``+x``): it flies towards ``-x``, its right wing at ``+y``. The forces are those
the kernels hand to the particles (:func:`warpsim.physics.kernels.vortex.vortex_air_force`), summed.

Body axes are the flight-mechanics ones: ``x`` forward (world ``-x``), ``y`` right (world ``+y``), ``z`` down
(world ``-z``). Sideslip ``beta > 0`` is the wind from the right; roll rate ``p > 0`` drops the right wing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import warp as wp

from warpsim.physics.builder import ModelBuilder
from warpsim.physics.config import AirConfig, WindConfig
from warpsim.physics.kernels.aero import AeroModel
from warpsim.physics.kernels.vortex import VortexScratch, vortex_air_force
from warpsim.physics.lattice import trailing_edges


@dataclass
class Wing:
    """A flat wing's model and its reference figures: area ``S`` [m^2], span ``b`` [m], mean chord ``c`` [m] and
    the moment reference point ``ref`` [m] (world)."""

    model: object
    area: float
    span: float
    chord: float
    ref: np.ndarray


def _finish(builder: ModelBuilder, tris, span: float, area: float, chord: float, ref, device: str) -> Wing:
    points = np.array(builder.particle_q)
    tri_idx = np.array(builder.tri_indices)
    for t in tris:  # every normal up (+z)
        a, b, c = points[tri_idx[t]]
        if np.cross(b - a, c - b)[2] < 0:
            builder.tri_indices[t] = tuple(builder.tri_indices[t][::-1])
    tri_idx = np.array(builder.tri_indices)
    builder.set_triangle_sail(tris, (0.0, 0.0, 0.0, math.radians(60.0)))  # no profile drag, stall far away
    builder.add_lifting_surface(tris, trailing_edges(points, tri_idx[tris], (1.0, 0.0, 0.0)))
    model = builder.finalize(device)
    return Wing(model, area, span, chord, np.asarray(ref, dtype=np.float64))


def rectangle(aspect_ratio: float, span_panels: int, chord_panels: int, offset=(0.0, 0.0, 0.0), device="cpu") -> Wing:
    """A flat rectangular wing of chord 1 m and span ``aspect_ratio`` [m]; moments about its quarter chord."""
    b = ModelBuilder()
    o = np.asarray(offset, dtype=np.float64)
    span = float(aspect_ratio)
    _, _, tris = b.add_grid(
        o + (0.0, -0.5 * span, 0.0),
        (0.0, span / span_panels, 0.0),
        (1.0 / chord_panels, 0.0, 0.0),
        span_panels + 1,
        chord_panels + 1,
        1.0,
    )
    return _finish(b, tris, span, span, 1.0, o + (0.25, 0.0, 0.0), device)


def delta(sweep_deg: float, divisions: int, root_chord: float = 1.0, offset=(0.0, 0.0, 0.0), device="cpu") -> Wing:
    """A flat delta wing whose leading edges are swept ``sweep_deg`` and whose trailing edge is straight; moments
    about its area centroid's chord station (two thirds of the root chord back)."""
    b = ModelBuilder()
    o = np.asarray(offset, dtype=np.float64)
    semi = root_chord / math.tan(math.radians(sweep_deg))
    _, _, tris = b.add_subdivided_triangle(o, o + (root_chord, -semi, 0.0), o + (root_chord, semi, 0.0), divisions, 1.0)
    area = semi * root_chord
    return _finish(b, tris, 2.0 * semi, area, area / (2.0 * semi), o + (2.0 * root_chord / 3.0, 0.0, 0.0), device)


def loads(wing: Wing, alpha_deg: float, beta_deg: float = 0.0, p: float = 0.0, r: float = 0.0, speed: float = 1.0):
    """The wing held at ``alpha_deg`` and ``beta_deg`` in a wind of ``speed`` [m/s], rolling at ``p`` and yawing at
    ``r`` [rad/s] (body axes) about its reference point: a dict of the coefficients ``CL``, ``CD`` (wind axes),
    ``CY``, ``Cl``, ``Cm``, ``Cn`` (body axes; ``Cl``/``Cn`` on ``q S b``, ``Cm`` on ``q S c``), ``force`` [N] and
    ``moment`` [N m] (world)."""
    m = wing.model
    a, be = math.radians(alpha_deg), math.radians(beta_deg)
    wind_b = -speed * np.array([math.cos(a) * math.cos(be), math.sin(be), math.sin(a) * math.cos(be)])  # body axes
    to_world = np.diag([-1.0, 1.0, -1.0])
    wind = to_world @ wind_b
    dt = 0.01
    state, control = m.state(dt), m.control()
    q = m.particle_q0
    omega = to_world @ np.array([p, 0.0, r])
    moving = np.cross(omega, q - wing.ref)
    state.particle_q.assign(q)
    state.particle_q_prev.assign(q - moving * dt)
    control.wind.assign(np.array([wind], dtype=np.float32))
    control.air_density.fill_(1.0)
    tri_force = wp.zeros(m.tri_count, dtype=wp.vec3, device=m.device)
    particle = wp.zeros(m.particle_count, dtype=wp.vec3, device=m.device)
    vortex_air_force(
        m,
        state,
        control,
        dt,
        AirConfig(model=AeroModel.VORTEX, density=1.0),
        WindConfig(),
        VortexScratch(m),
        tri_force,
        particle,
    )
    f = particle.numpy().astype(np.float64)
    np.add.at(f, m.tri_indices_np.reshape(-1), np.repeat(tri_force.numpy().astype(np.float64), 3, axis=0))
    force = f.sum(0)
    moment = np.cross(q - wing.ref, f).sum(0)
    qs = 0.5 * speed**2 * wing.area
    u = wind / speed  # where the air goes
    lift_dir = np.array([-u[2], 0.0, u[0]]) / math.hypot(u[0], u[2])
    fb, mb = to_world @ force, to_world @ moment
    return {
        "CL": float(force @ lift_dir / qs),
        "CD": float(force @ u / qs),
        "CY": float(fb[1] / qs),
        "Cl": float(mb[0] / (qs * wing.span)),
        "Cm": float(mb[1] / (qs * wing.chord)),
        "Cn": float(mb[2] / (qs * wing.span)),
        "force": force,
        "moment": moment,
    }


def helmbold(aspect_ratio: float, sweep_half_chord_deg: float = 0.0) -> float:
    """Lift slope [1/rad] of a thin wing by Helmbold's formula with DATCOM's sweep term (2 pi section slope)."""
    t = math.tan(math.radians(sweep_half_chord_deg))
    return 2.0 * math.pi * aspect_ratio / (2.0 + math.sqrt(aspect_ratio**2 * (1.0 + t * t) + 4.0))


def lift_slope(wing: Wing, alpha_deg: float = 5.0) -> float:
    """``dC_L/dalpha`` [1/rad] from the lift at ``+-alpha_deg``."""
    up, down = loads(wing, alpha_deg)["CL"], loads(wing, -alpha_deg)["CL"]
    return (up - down) / (2.0 * math.radians(alpha_deg))


def lifting_line(aspect_ratio: float, terms: int = 60) -> tuple[float, float]:
    """Prandtl's lifting line for a flat rectangular wing of ``aspect_ratio`` (a thin section's ``2 pi``), solved by
    Glauert's series of ``terms`` odd sines collocated at as many stations (Anderson, *Fundamentals of
    Aerodynamics*, 5.3.2): ``(lift slope [1/rad], span efficiency e = 1 / (1 + delta))``."""
    theta = np.arange(1, terms + 1) * (0.5 * math.pi / terms)  # one half-span: the load is symmetric
    n = 2 * np.arange(terms) + 1
    mu = 2.0 * math.pi / (4.0 * aspect_ratio)  # a0 c / (4 b) with c = 1, b = A
    rows = np.sin(np.outer(theta, n)) * (mu * n[None, :] + np.sin(theta)[:, None])
    a = np.linalg.solve(rows, mu * np.sin(theta))  # per radian of angle of attack
    delta = float((n[1:] * (a[1:] / a[0]) ** 2).sum())
    return math.pi * aspect_ratio * float(a[0]), 1.0 / (1.0 + delta)


def tuck(aspect_ratio: float) -> float:
    """Lift slope [1/rad] of a flat rectangular wing from Tuck's accurate solution of the lifting-surface integral
    equation, as its large-aspect-ratio expansion (E. O. Tuck, J. Austral. Math. Soc. B 35, 1993, 127-144):
    ``2 pi - (pi / A)(ln A + 2.5620) + (1.404 / A^2)(ln A + 3.645)``; for aspect ratios of about 4 and more."""
    a = float(aspect_ratio)
    return 2.0 * math.pi - math.pi / a * (math.log(a) + 2.5620) + 1.404 / a**2 * (math.log(a) + 3.645)


def lifting_line_roll(aspect_ratio: float, terms: int = 60) -> float:
    """Roll damping ``C_l_p`` (per unit ``p b / 2V``) of a flat rectangular wing by Prandtl's lifting line: the
    antisymmetric load of a rolling wing in Glauert's series of even sines (Anderson 5.3.2; Phillips, *Mechanics of
    Flight*, 2004, 6.5), ``C_l = -(pi A / 4) A_2``."""
    theta = np.arange(1, terms + 1) * (0.5 * math.pi / (terms + 1))  # one half-span, the root (pi/2) left out
    n = 2 * np.arange(1, terms + 1)
    mu = 2.0 * math.pi / (4.0 * aspect_ratio)
    rows = np.sin(np.outer(theta, n)) * (mu * n[None, :] + np.sin(theta)[:, None])
    a = np.linalg.solve(rows, mu * np.sin(theta) * np.cos(theta))  # local angle of attack (p b / 2V) cos(theta)
    return -0.25 * math.pi * aspect_ratio * abs(float(a[0]))  # the moment opposes the roll: negative
