"""Hang glider (paper Section 6, slides 21-24).

* Sail: triangle nose A, left tip B, right tip C, cut into ``divisions**2`` small triangles
  (paper: 8 divisions -> 45 sail particles, 64 triangles).
* Frame: three virtual particles above, at and below the sail's centre (slide 22), each tied by sticks
  to every particle of the two leading edges and of the keel; the sail between stays flexible.
* Pilot: one heavy particle under the sail on seven control sticks, three to forward frame points and
  four to aft ones (paper Fig. 14). Steering moves the pilot's target position in the glider's frame
  and sets the control sticks' rest lengths to the distances from that target to their frame points:
  ``pitch = +1`` (bar pulled in) moves the pilot forward (forward sticks shorten, aft sticks lengthen:
  nose down, faster); ``roll`` moves the pilot sideways (``+1`` = towards the right tip, +y is left).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..builder import ModelBuilder
from ..config import NON_NEGATIVE, POSITIVE, Bounds, Checked, number
from ..model import ObjectRecord
from ..terrain import Heightfield
from .delta import add_rigid_frame, body_axes, chordwise_loading

PAPER_COUNTS = {"particles": 49, "sticks": 198, "triangles": 64}


@dataclass(kw_only=True)
class HangGliderConfig(Checked):
    """Parameters of the hang glider (defaults: the paper's model, a 10 m, ~14 m^2 glider).

    Attributes:
        divisions: sail subdivisions per side (paper: 8).
        span: tip-to-tip distance [m].
        chord: nose to trailing-edge distance along the keel [m].
        glider_mass: sail + frame mass [kg] (paper: 20-30), spread over sail and virtual particles.
        pilot_mass: pilot mass [kg] (paper: 55-70).
        hang_depth: pilot below the keel [m].
        pilot_station: pilot's neutral position along the keel, fraction of the chord from the nose.
        frame_height: distance of the upper/lower virtual particles from the sail plane [m].
        pitch_travel: pilot travel forward/back at |pitch| = 1 [m].
        roll_travel: pilot travel sideways at |roll| = 1 [m].
        altitude: start height of the nose above the terrain [m].
        position: start (x, y) of the nose [m].
        heading: flight direction, degrees from +x towards +y.
        speed: start speed along the heading [m/s].
        nose_up: start pitch of the keel above horizontal [deg].
        washout: twist of the sail towards the tips [deg]: at the tips the sail behind the leading edge
            is raised by this angle, growing linearly from 0 at the keel (real sails twist this way;
            it is what lets a swept wing trim with its centre of mass ahead of the sail's centre).
        frame_mass_fraction: share of ``glider_mass`` carried by the leading-edge and keel particles
            (the tubes), above 0; the rest minus the virtual particles' share is spread over the sail cloth.
        virtual_mass_fraction: share of ``glider_mass`` carried by the three virtual particles (the kingpost,
            control frame and crossbar they stand for), above 0; ``frame_mass_fraction +
            virtual_mass_fraction`` must stay below 0.95 so the cloth keeps some mass.
        frame_weight: weight of the frame's sticks (leading edges, keel, virtual ties) in the constraint
            average (1 = the paper; 6 counts each as six sticks). Under the pilot's load the frame also needs
            heavy virtual particles (``virtual_mass_fraction``) to stay within 1 % (README, hang glider).
        chord_loading: load the sail most near its leading edge under the ``plate`` air model (thin-aerofoil
            loading, centre of pressure near the quarter chord; see :mod:`warpsim.kernels.aero`). Off:
            uniform load, centre of pressure at the area centroid, and the glider has almost no pitch
            stiffness.
    """

    divisions: int = number(8, Bounds(2, 256))
    span: float = number(10.0, POSITIVE)
    chord: float = number(2.8, POSITIVE)
    glider_mass: float = number(25.0, POSITIVE)
    pilot_mass: float = number(65.0, POSITIVE)
    hang_depth: float = number(1.2, POSITIVE)
    pilot_station: float = number(0.55, Bounds(0.0, 1.0))
    frame_height: float = number(1.5, POSITIVE)
    pitch_travel: float = number(0.2, NON_NEGATIVE)
    roll_travel: float = number(0.4, NON_NEGATIVE)
    altitude: float = number(300.0, POSITIVE)
    position: tuple[float, float] = (-300.0, 0.0)
    heading: float = 0.0
    speed: float = number(12.0, NON_NEGATIVE)
    nose_up: float = 8.0
    washout: float = number(10.0, Bounds(-45.0, 45.0))
    frame_mass_fraction: float = number(0.6, Bounds(0.0, 0.85, low_open=True))
    virtual_mass_fraction: float = number(0.3, Bounds(0.0, 0.85, low_open=True))
    frame_weight: float = number(6.0, POSITIVE)
    chord_loading: bool = True


@dataclass(kw_only=True)
class HangGliderRecord(ObjectRecord):
    """A hang glider's :class:`~warpsim.model.ObjectRecord` with its reference particles and control sticks.

    Attributes:
        nose: the nose particle. keel: keel particles, nose to tail. tips: (left, right) wing-tip particles.
        pilot: the pilot particle. control_sticks: ``[7]`` stick indices, the forward ones first.
        control_forward_count: how many of ``control_sticks`` go to forward frame points.
        pilot_attach_frame: ``[7, 3]`` each control stick's frame point in the glider's build frame
            (forward, left, up) [m] from the nose.
        pilot_neutral_frame: ``[3]`` the pilot's neutral position in that frame [m].
        pitch_travel, roll_travel: pilot travel at full pitch / roll [m].
    """

    nose: int
    keel: np.ndarray
    tips: tuple[int, int]
    pilot: int
    control_sticks: np.ndarray
    control_forward_count: int
    pilot_attach_frame: np.ndarray
    pilot_neutral_frame: np.ndarray
    pitch_travel: float
    roll_travel: float


def build_hang_glider(builder: ModelBuilder, cfg: HangGliderConfig, terrain: Heightfield) -> HangGliderRecord:
    """Add the hang glider of ``cfg`` above ``terrain``; returns its record (parts, stick groups, controls)."""
    n = int(cfg.divisions)
    if n < 2:
        raise ValueError(f"divisions must be at least 2, got {n}")
    fwd, left, up = body_axes(cfg.heading, cfg.nose_up)
    x0, y0 = cfg.position
    nose = np.array([x0, y0, float(terrain.height(x0, y0)) + cfg.altitude])
    tip_l = nose - cfg.chord * fwd + 0.5 * cfg.span * left
    tip_r = nose - cfg.chord * fwd - 0.5 * cfg.span * left
    vel = cfg.speed * np.array([np.cos(np.radians(cfg.heading)), np.sin(np.radians(cfg.heading)), 0.0])

    if cfg.frame_mass_fraction + cfg.virtual_mass_fraction >= 0.95:
        raise ValueError(
            "frame_mass_fraction + virtual_mass_fraction must be below 0.95 (the sail cloth needs mass), got "
            f"{cfg.frame_mass_fraction} + {cfg.virtual_mass_fraction}"
        )
    sail_count = (n + 1) * (n + 2) // 2
    virtual_mass = cfg.virtual_mass_fraction * cfg.glider_mass / 3.0
    semi = 0.5 * cfg.span
    washout_rad = np.radians(cfg.washout)

    def twist(points: np.ndarray) -> np.ndarray:
        d = points - nose
        y = np.abs(d @ left)
        behind_edge = np.maximum(-cfg.chord * y / semi - d @ fwd, 0.0)
        return points + np.outer(behind_edge * np.tan(washout_rad * y / semi), up)

    p0 = builder.particle_count
    rows, sail_sticks, tris = builder.add_subdivided_triangle(
        nose, tip_l, tip_r, n, 1.0, vel, shape=twist
    )  # masses are set per part below
    sail = np.arange(p0, p0 + sail_count)
    if cfg.chord_loading:
        chordwise_loading(builder, tris, nose, fwd, left, cfg.chord, semi)

    centre = (nose + tip_l + tip_r) / 3.0
    frame = add_rigid_frame(
        builder, rows, sail_sticks, centre, cfg.frame_height * up, (1, 0, -1), virtual_mass, cfg.frame_weight, vel
    )
    virtual, keel = frame.virtual, frame.keel
    frame_set = set(frame.points)
    cloth = [p for p in sail if p not in frame_set]
    frame_mass = cfg.frame_mass_fraction * cfg.glider_mass
    for p in frame.points:
        builder.particle_mass[p] = frame_mass / len(frame.points)
    for p in cloth:
        builder.particle_mass[p] = (cfg.glider_mass - frame_mass - 3.0 * virtual_mass) / len(cloth)

    # pilot and control sticks
    neutral = nose - cfg.pilot_station * cfg.chord * fwd - cfg.hang_depth * up
    pilot = builder.add_particle(neutral, cfg.pilot_mass, vel)
    q = n // 3
    forward_points = [rows[0][0], rows[q][0], rows[q][q]]
    b = (2 * n) // 3
    aft_points = [rows[n][n // 2], rows[b][0], rows[b][b], virtual[2]]
    control = [builder.add_stick(pilot, p) for p in forward_points + aft_points]

    positions = np.array(builder.particle_q)
    attach = positions[forward_points + aft_points]
    particles = np.arange(p0, builder.particle_count)
    return builder.add_object(
        HangGliderRecord(
            name="hang_glider",
            kind="hang-glider",
            particles=particles,
            parts={"sail": sail, "virtual": np.array(virtual), "pilot": np.array([pilot])},
            tri_parts={"sail": tris},
            stick_groups={
                "sail": np.setdiff1d(sail_sticks, frame.sticks),
                "frame": np.array(frame.sticks),
                "control": np.array(control),
            },
            paper_counts=PAPER_COUNTS,
            nose=rows[0][0],
            keel=np.array(keel),
            tips=(rows[n][0], rows[n][n]),
            pilot=pilot,
            control_sticks=np.array(control),
            control_forward_count=len(forward_points),
            pilot_attach_frame=_to_frame(attach, nose, fwd, left, up),
            pilot_neutral_frame=_to_frame(neutral[None], nose, fwd, left, up)[0],
            pitch_travel=cfg.pitch_travel,
            roll_travel=cfg.roll_travel,
        )
    )


def _to_frame(points: np.ndarray, origin, fwd, left, up) -> np.ndarray:
    d = points - origin
    return np.stack([d @ fwd, d @ left, d @ up], axis=1)


def control_rest_lengths(record: HangGliderRecord, pitch: float, roll: float) -> np.ndarray:
    """Rest lengths [m] of the control sticks for ``pitch`` and ``roll`` in [-1, 1].

    The pilot's target sits ``pitch * pitch_travel`` forward and ``roll * roll_travel`` to the right of
    the neutral point (glider frame at build time); each control stick's rest length is the distance
    from that target to its frame point.
    """
    for name, value in (("pitch", pitch), ("roll", roll)):
        if not -1.0 <= value <= 1.0:
            raise ValueError(f"{name} must be in [-1, 1], got {value}")
    target = record.pilot_neutral_frame + np.array([pitch * record.pitch_travel, -roll * record.roll_travel, 0.0])
    return np.linalg.norm(record.pilot_attach_frame - target, axis=1)


def apply_controls(record: HangGliderRecord, targets: dict, values: dict) -> None:
    """Write the control sticks' rest lengths for ``values['pitch']``/``values['roll']`` (every control in
    force; one never set is 0) into ``targets['stick_rest']`` (a host copy of ``Control.stick_rest``)."""
    pitch, roll = float(values.get("pitch", 0.0)), float(values.get("roll", 0.0))
    targets["stick_rest"][record.control_sticks] = control_rest_lengths(record, pitch, roll)


def bank(record: HangGliderRecord, q: np.ndarray) -> float:
    """Bank of the sail [deg]: the tip-to-tip line against the horizontal, positive with the right tip lower."""
    span_dir = q[record.tips[0]] - q[record.tips[1]]
    return float(np.degrees(np.arctan2(span_dir[2], np.linalg.norm(span_dir[:2]))))


def flight_state(record: HangGliderRecord, q: np.ndarray, q_prev: np.ndarray, dt: float, wind) -> dict:
    """Diagnostics: nose pitch angle [deg], bank [deg], airspeed [m/s], pilot offset [m] in the sail frame."""
    nose = q[record.nose]
    keel_end = q[record.keel[-1]]
    tip_l, tip_r = q[record.tips[0]], q[record.tips[1]]
    keel_dir = nose - keel_end
    pitch = np.degrees(np.arctan2(keel_dir[2], np.linalg.norm(keel_dir[:2])))
    span_dir = tip_l - tip_r
    sail = record.parts["sail"]
    velocity = (q[sail] - q_prev[sail]).mean(axis=0) / dt
    airspeed = float(np.linalg.norm(velocity - np.asarray(wind)))
    fwd = keel_dir / np.linalg.norm(keel_dir)
    left = span_dir / np.linalg.norm(span_dir)
    up = np.cross(fwd, left)
    up /= np.linalg.norm(up)
    pilot = q[record.pilot] - q[sail].mean(axis=0)
    return {
        "pitch_deg": float(pitch),
        "bank_deg": bank(record, q),
        "airspeed": airspeed,
        "velocity": velocity,
        "pilot_forward": float(pilot @ fwd),
        "pilot_left": float(pilot @ left),
        "pilot_up": float(pilot @ up),
        "altitude": float(q[sail][:, 2].mean()),
    }
