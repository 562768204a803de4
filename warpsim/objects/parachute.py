"""Round parachute (paper Section 8): canopy of concentric rings of triangles, lines, a heavy person.

The canopy is a spherical cap: a centre particle and ``rings`` rings, ring ``i`` holding ``6 i``
particles (paper Fig. 19: six rings). Suspension lines run from evenly spaced rim particles to the
person, built like the kite rope at a lower resolution.

The canopy's air force (``canopy``):

* ``flat`` (default) and ``ringslot``: the whole canopy's force from tangential and normal force coefficients
  against its angle of attack (:data:`CANOPIES`, :mod:`warpsim.physics.kernels.canopy`): an internal pressure that
  inflates the cloth and gives the drag, and a side force spread over the triangles. The flat canopy's side
  force is unstable about its axis, with a stable angle of attack at 25 degrees, and follows the angle of attack
  a canopy's travel of its own diameter late (its wake re-forming): it swings as flat circular canopies do. The
  ringslot's slots let the air through evenly: it restores the canopy at once and it hardly swings.
* ``paper``: each triangle feels the scene's ``[air]`` law on its own, as in the paper. Without air pressure
  in the canopy the person's weight pulls the rim shut (Section 8.2); ``hoop = true`` adds the paper's fix
  (Section 8.3): a virtual particle at the rim's centre tied to every rim particle, plus sticks skipping one rim
  particle, which together make the rim a rigid hoop.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..physics.builder import ModelBuilder
from ..physics.config import NON_NEGATIVE, POSITIVE, Bounds, Checked, choice, number
from ..physics.kernels.canopy import TABLE_ROWS, TABLE_STEP_DEG
from ..physics.model import Model, ObjectRecord
from ..physics.terrain import Heightfield
from .figures import FigureView, Measure


@dataclass(kw_only=True)
class ParachuteConfig(Checked):
    """Parameters of the round parachute.

    Attributes:
        rings: canopy rings (paper: 6).
        radius: horizontal radius of the built canopy rim [m].
        dome_angle: polar angle of the rim on the canopy's sphere [deg] (90 = hemisphere).
        canopy_mass: canopy fabric mass [kg].
        person_mass: person (and harness) mass [kg].
        line_count: suspension lines.
        line_particles: particles per line between rim and person (lower resolution than the kite rope).
        line_length: rim-to-person distance [m].
        line_mass: mass of all lines together [kg].
        hoop: add the rim hoop of Section 8.3.
        hub_mass_fraction: mass of the hoop's virtual centre particle, as a share of ``canopy_mass`` (it adds to
            the canopy's mass).
        hoop_weight: weight of the hoop's sticks in the constraint average (1 = the paper; the paper's
            own way to stiffen a part is to double its sticks, weight 2).
        line_weight: weight of the line sticks (the paper doubles the kite rope's sticks for the same
            reason: light line particles under a heavy load stretch).
        altitude: start height of the canopy apex above the terrain [m].
        position: start (x, y) [m].
        speed: start descent speed [m/s].
        canopy: the canopy's air force: ``flat`` (a flat circular canopy) or ``ringslot`` (a slotted one) from
            whole-canopy coefficients (:data:`CANOPIES`, :mod:`warpsim.physics.kernels.canopy`), or ``paper``: each
            triangle on its own under the scene's ``[air]`` model (the paper's Section 8, where only the hoop keeps
            the canopy open).
    """

    rings: int = number(6, Bounds(1, 64))
    radius: float = number(3.5, POSITIVE)
    dome_angle: float = number(60.0, Bounds(0.0, 90.0, low_open=True))
    canopy_mass: float = number(8.0, POSITIVE)
    person_mass: float = number(80.0, POSITIVE)
    line_count: int = number(12, Bounds(3, 1024))
    line_particles: int = number(3, Bounds(0, 64))
    line_length: float = number(7.0, POSITIVE)
    line_mass: float = number(1.0, POSITIVE)
    hoop: bool = True
    hub_mass_fraction: float = number(0.05, POSITIVE)
    hoop_weight: float = number(6.0, POSITIVE)
    line_weight: float = number(1.0, POSITIVE)
    altitude: float = number(400.0, POSITIVE)
    position: tuple[float, float] = (0.0, 0.0)
    speed: float = number(5.0, NON_NEGATIVE)
    canopy: str = choice("flat", ("flat", "ringslot", "paper"))


@dataclass(frozen=True)
class CanopyType:
    """Whole-canopy force coefficients of a kind of round canopy, on its nominal area (see :func:`canopy_table`).

    Attributes:
        tangential: ``C_T`` at zero angle of attack, the steady-descent drag coefficient ``C_D0``.
        normal_side: ``C_N`` with the wind across the axis (90 degrees).
        normal_slope: ``dC_N/dalpha`` at zero angle of attack [1/rad]; negative = statically unstable about the
            axis (the canopy slides off to one side and swings).
        wake_lag: the time the side force takes to follow the angle of attack, in times to travel the projected
            diameter (see :mod:`warpsim.physics.kernels.canopy`).
    """

    tangential: float
    normal_side: float
    normal_slope: float
    wake_lag: float = 1.0


CANOPIES = {
    # Knacke, NWC TP 6575 (1991), Table 5-1: flat circular C_D0 0.75-0.80, oscillation +-10-40 deg. The normal
    # force is unstable about the axis and crosses zero at a stable angle of attack of 25 deg (the middle of the
    # table's swing), as flat and conical canopies do (Knacke ch. 5, static stability; Ginn et al., AIAA
    # 2014-2390): slope -0.24 / rad with C_N(90 deg) = 0.5. Knacke's C_D0 is a rate of descent measured on swinging
    # canopies; swinging makes the canopy's air speed exceed its rate of descent, so C_T(0) = 0.695 is set for the
    # swinging canopy's measured rate to give C_D0 0.76-0.79 (scenes/parachute.toml, dt 0.01/55 to 0.0025/220).
    "flat": CanopyType(tangential=0.695, normal_side=0.5, normal_slope=0.5 - 0.5 / np.cos(np.radians(25.0)) ** 4),
    # Knacke Table 5-1: ringslot C_D0 0.56-0.65, oscillation 0 to +-5 deg; the slots let the air through evenly, so
    # the normal force restores the canopy from zero angle of attack on (positive slope, assumed +0.3 / rad).
    "ringslot": CanopyType(tangential=0.60, normal_side=0.5, normal_slope=0.3, wake_lag=0.0),
}
"""The canopies a parachute may have (``ParachuteConfig.canopy``), with their sources."""


def canopy_table(kind: CanopyType) -> np.ndarray:
    """``[TABLE_ROWS, 2]`` tangential and normal force coefficients ``(C_T, C_N)`` of canopy ``kind`` at angles of
    attack 0, 5, ..., 180 degrees (between the axis, mouth to apex, and the relative wind).

    ``C_T = C_D0 cos(alpha)`` while the mouth faces the wind and half that from behind (a dome's convex side drags
    about half its concave side); ``C_N = sin(alpha) (C_N90 - c cos^4(alpha))`` with ``c = C_N90 - slope``, which has
    the slope at zero and the side force at 90 degrees of :class:`CanopyType` and, for a negative slope, a stable
    angle of attack where ``cos^4(alpha) = C_N90 / c``."""
    alpha = np.radians(TABLE_STEP_DEG * np.arange(TABLE_ROWS))
    cos_a = np.cos(alpha)
    c_t = kind.tangential * cos_a * np.where(cos_a >= 0.0, 1.0, 0.5)
    c_n = np.sin(alpha) * (kind.normal_side - (kind.normal_side - kind.normal_slope) * cos_a**4)
    return np.stack([c_t, c_n], axis=1)


def _zip_rings(inner: list[int], inner_angles: np.ndarray, outer: list[int], outer_angles: np.ndarray):
    """Triangles joining two closed rings (both starting at angle 0), walking both in angle order."""
    ni, no = len(inner), len(outer)
    if ni == 1:
        return [(inner[0], outer[j], outer[(j + 1) % no]) for j in range(no)]

    def angle(angles, k, count):
        return angles[k % count] + 2 * np.pi * (k // count)

    tris, i, j = [], 0, 0
    while i < ni or j < no:
        advance_outer = i >= ni or (j < no and angle(outer_angles, j + 1, no) <= angle(inner_angles, i + 1, ni))
        if advance_outer:
            tris.append((inner[i % ni], outer[j % no], outer[(j + 1) % no]))
            j += 1
        else:
            tris.append((inner[i % ni], outer[j % no], inner[(i + 1) % ni]))
            i += 1
    return tris


@dataclass(kw_only=True)
class ParachuteRecord(ObjectRecord):
    """A parachute's :class:`~warpsim.physics.model.ObjectRecord` with its rim and person.

    Attributes:
        rim: the canopy's rim particles, in order around it. person: the person particle.
    """

    rim: np.ndarray
    person: int


def build_parachute(builder: ModelBuilder, cfg: ParachuteConfig, terrain: Heightfield) -> ObjectRecord:
    """Add the parachute of ``cfg`` above ``terrain``; returns its record."""
    if cfg.rings < 1:
        raise ValueError(f"rings must be at least 1, got {cfg.rings}")
    if cfg.line_count < 3 or cfg.line_particles < 0:
        raise ValueError("a parachute needs at least 3 lines and line_particles >= 0")
    x0, y0 = cfg.position
    apex = np.array([x0, y0, float(terrain.height(x0, y0)) + cfg.altitude])
    theta_max = np.radians(cfg.dome_angle)
    sphere = cfg.radius / np.sin(theta_max)
    centre = apex - np.array([0.0, 0.0, sphere])
    vel = (0.0, 0.0, -cfg.speed)
    particle_count = 1 + 3 * cfg.rings * (cfg.rings + 1)
    m = cfg.canopy_mass / particle_count
    p0, t0, s0 = builder.particle_count, builder.tri_count, builder.stick_count

    rings = [[builder.add_particle(apex, m, vel)]]
    angles = [np.zeros(1)]
    for i in range(1, cfg.rings + 1):
        theta = theta_max * i / cfg.rings
        phi = 2 * np.pi * np.arange(6 * i) / (6 * i)
        pts = centre + sphere * np.stack(
            [np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.full_like(phi, np.cos(theta))], axis=1
        )
        rings.append([builder.add_particle(p, m, vel) for p in pts])
        angles.append(phi)
    edges = set()
    for i in range(1, cfg.rings + 1):
        for tri in _zip_rings(rings[i - 1], angles[i - 1], rings[i], angles[i]):
            builder.add_triangle(*tri)
            for a, b in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])):
                edges.add((min(a, b), max(a, b)))
    for a, b in sorted(edges):
        builder.add_stick(a, b)
    canopy_sticks = np.arange(s0, builder.stick_count)
    rim = rings[-1]

    rim_centre = centre + np.array([0.0, 0.0, sphere * np.cos(theta_max)])
    person_pos = rim_centre - np.array([0.0, 0.0, cfg.line_length])
    person = builder.add_particle(person_pos, cfg.person_mass, vel)
    line_particles, line_sticks, chains = [], [], []
    per_line_mass = cfg.line_mass / (cfg.line_count * max(cfg.line_particles, 1))
    for k in range(cfg.line_count):
        top = rim[int(round(k * len(rim) / cfg.line_count)) % len(rim)]
        start = builder.positions(top)
        if cfg.line_particles:
            end = start + (person_pos - start) * (cfg.line_particles / (cfg.line_particles + 1))
            ids, sticks = builder.add_rope(
                start, end, cfg.line_particles, per_line_mass * cfg.line_particles, vel, top, weight=cfg.line_weight
            )
            line_particles += list(ids[1:])
            line_sticks += list(sticks)
            last = ids[-1]
            chains.append([int(i) for i in ids] + [person])
        else:
            last = top
            chains.append([int(top), person])
        line_sticks.append(builder.add_stick(last, person, weight=cfg.line_weight))

    canopy_tris = np.arange(t0, builder.tri_count)
    if cfg.canopy != "paper":
        kind = CANOPIES[cfg.canopy]
        builder.add_canopy(canopy_tris, canopy_table(kind), apex - rim_centre, kind.wake_lag)

    virtual, hoop_sticks = [], []
    if cfg.hoop:
        hub = builder.add_particle(rim_centre, cfg.hub_mass_fraction * cfg.canopy_mass, vel)
        virtual.append(hub)
        n = len(rim)
        hoop_sticks = [builder.add_stick(hub, r, weight=cfg.hoop_weight) for r in rim]
        hoop_sticks += [builder.add_stick(rim[k], rim[(k + 2) % n], weight=cfg.hoop_weight) for k in range(n)]

    return builder.add_object(
        ParachuteRecord(
            name="parachute",
            kind="parachute",
            particles=np.arange(p0, builder.particle_count),
            parts={
                "canopy": np.arange(p0, p0 + particle_count),
                "lines": np.array(line_particles, dtype=int),
                "person": np.array([person]),
                "virtual": np.array(virtual, dtype=int),
            },
            tri_parts={"canopy": canopy_tris},
            stick_groups={
                "canopy": canopy_sticks,
                "lines": np.array(line_sticks),
                "hoop": np.array(hoop_sticks, dtype=int),
            },
            curves={"lines": chains},
            rim=np.array(rim),
            person=person,
        )
    )


def projected_radius(record: ParachuteRecord, q: np.ndarray) -> float:
    """Mean horizontal distance [m] of the rim particles from their centroid."""
    rim = q[record.rim]
    d = rim[:, :2] - rim[:, :2].mean(axis=0)
    return float(np.linalg.norm(d, axis=1).mean())


def swing_angle(record: ParachuteRecord, q: np.ndarray) -> float:
    """Angle [deg] from the vertical of the line from the person to the canopy's centre (its particles' mean)."""
    v = q[record.parts["canopy"]].mean(axis=0) - q[record.person]
    return float(np.degrees(np.arctan2(np.hypot(v[0], v[1]), v[2])))


def descent_and_swing(sim, seconds: float, settle: float = 10.0) -> tuple[float, float, float]:
    """Run the parachute of ``sim`` (a :class:`warpsim.run.simulation.Simulation`, first object) for ``seconds``
    [s], frame by frame (so the scene's gusts and controls act), and measure from its particles: the person's mean
    rate of descent [m/s] and the largest and root-mean-square swing angles [deg] (:func:`swing_angle`), all over the
    frames after the first ``settle`` seconds."""
    record = sim.model.objects[0]
    times, heights, swings = [], [], []

    def on_frame(frame) -> None:
        if frame.time >= settle - 0.5 * sim.dt:
            times.append(frame.time)
            heights.append(frame.positions[record.person, 2])
            swings.append(swing_angle(record, frame.positions))

    sim.run(seconds - sim.state.time, on_frame=on_frame)
    if len(times) < 2:
        raise ValueError(f"run longer than settle ({settle} s) + two frames, got {seconds} s")
    swings = np.array(swings)
    descent = (heights[0] - heights[-1]) / (times[-1] - times[0])
    return float(descent), float(swings.max()), float(np.sqrt((swings**2).mean()))


# ---------------------------------------------------------------------------------------------- figures
PARACHUTE_FIGURES = {
    "radius": ("m", "mean horizontal distance of the canopy's rim from its centre"),
    "swing": ("deg", "angle of the line from the person to the canopy's centre from the vertical"),
}


def parachute_figures(model: Model, record: ObjectRecord) -> Measure:
    """The parachute's :data:`PARACHUTE_FIGURES` of a frame."""

    def measure(view: FigureView) -> dict[str, float]:
        return {"radius": projected_radius(record, view.positions), "swing": swing_angle(record, view.positions)}

    return measure


def parachute_hud(f: dict[str, float]) -> str:
    """The parachute's heads-up text: rate of descent, canopy radius and swing."""
    return f"descent {f['sink']:5.2f} m/s  radius {f['radius']:4.2f} m  swing {f['swing']:3.0f} deg"
