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

from ..physics.builder import ModelBuilder
from ..physics.config import AIR_DENSITY, NON_NEGATIVE, POSITIVE, STANDARD_AIR, Bounds, Checked, choice, number
from ..physics.model import ObjectRecord
from ..physics.terrain import Heightfield
from .delta import add_rigid_frame, body_axes, chordwise_loading, delta_sail_aero
from .glider_flight import (  # noqa: F401 - the glider's controls and flight figures, re-exported
    apply_controls,
    bank,
    billow_rest_lengths,
    control_rest_lengths,
    flight_state,
)

PAPER_COUNTS = {"particles": 49, "sticks": 198, "triangles": 64}


@dataclass(kw_only=True)
class HangGliderConfig(Checked):
    """Parameters of the hang glider (defaults: a 10 m, ~14 m^2 flex wing of the paper's size that flies).

    Attributes:
        design: ``flying`` (the default: the pilot on a hang strap holding a control bar, a tensioned sail with
            washout struts, a keel pocket, 1.25 degrees of dihedral and a billow shift under weight shift, under the
            ``sail`` air model), ``lattice`` (the same glider under the ``vortex`` air model, the lattice's air from
            the sail's own shape: 1.5 degrees of anhedral, a 1 degree billow shift, the pilot's drag area 0.25 m^2)
            or ``paper`` (Section 6: the pilot on seven control sticks, an untensioned flat sail, the paper's air
            law). In a scene or with ``--set`` it is a preset (:data:`PRESETS`): it sets those keys, ``air.model``,
            ``air.density`` (the paper's constant air, or 0: the standard atmosphere) and ``solver.dt`` (5 ms flying
            and lattice, 10 ms paper), and keys given beside it win. The builder
            itself reads only the individual keys.
        divisions: sail subdivisions per side (paper: 8).
        span: tip-to-tip distance [m].
        chord: nose to trailing-edge distance along the keel [m].
        glider_mass: sail + frame mass [kg] (paper: 20-30), spread over sail and virtual particles.
        pilot_mass: pilot mass [kg] (paper: 55-70).
        hang_depth: pilot below the keel [m].
        pilot_station: pilot's neutral position along the keel, fraction of the chord from the nose.
        frame_height: distance of the upper/lower virtual particles from the sail plane [m].
        pitch_travel: pilot travel forward/back at ``|pitch| = 1`` [m].
        roll_travel: pilot travel sideways at ``|roll| = 1`` [m] (a pilot moves about half a metre each way on the bar).
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
            loading, centre of pressure near the quarter chord; see :mod:`warpsim.physics.kernels.aero`). Off:
            uniform load, centre of pressure at the area centroid, and the glider has almost no pitch
            stiffness.
        suspension: ``sticks`` (the paper: the pilot on seven control sticks to the frame) or ``strap`` (a real
            glider's: a hang strap from a hang point on the keel, and two arms holding a rigid control bar;
            the controls set the arms' lengths and the pilot swings on the strap).
        hang_point: ``strap``: the hang point along the keel, fraction of the chord from the nose (it sets the
            centre of gravity, so the trim speed).
        bar_forward: ``strap``: the control bar ahead of the hang point [m]. bar_width: its width [m].
        control_frame_mass: ``strap``: mass of the hang point and control bar particles [kg] (added to the glider).
        pilot_drag_area: ``sail`` and ``vortex`` air models: the pilot's drag area ``C_D A`` [m^2] (prone in a pod
            harness, about 0.15-0.25; Dees, AIAA 2010-9300 drag build-up; Kilkenny's tunnel tests of five pilots
            advise a range rather than one value). Hung below the wing, it also damps the phugoid.
        frame_drag_area: ``sail`` and ``vortex`` air models, ``strap``: drag area [m^2] of the control frame, wires
            and kingpost.
        dihedral: the wings rise from the keel by this angle [deg]; negative is anhedral. Sweep already rolls a
            wing away from a sideslip, and flex wings are rigged with anhedral to bring that near neutral: too much
            dihedral rolls the wing back to level against the pilot, too little steepens every turn. The flying
            design's 1.25 (``sail`` law) and the lattice design's -1.5 and what other values do: docs/glider.md.
        keel_pocket: hold the cloth on both sides of the keel tube to it (a sail's keel pocket), so the sail
            cannot fold along the keel between keel particles.
        washout_struts: share of each half of the trailing edge, from the tip, held rigid at its washout by
            struts (tip rods, sprogs) tied to the frame (0 = none): a tensioned sail would flatten it otherwise.
        sail_tension: the cloth's sticks are this much shorter than the sail as built (a sail tensioned on its
            frame, as a crossbar or VG does); a taut sail billows less, so its triangles spread less in angle of
            attack. Stretch is reported against the sail as built
            (:meth:`~warpsim.physics.builder.ModelBuilder.pretension`).
        sail_compliance: stretch [m/N] per newton of tension of each of the sail's cloth sticks (0 = rigid, the
            paper's): an elastic sail billows and twists more as the load grows, and under weight shift the loaded
            half of the sail takes a shape of its own (the frame, its ties and the struts stay rigid).
        oswald: ``sail`` air model: span efficiency of the induced drag
            (:func:`~warpsim.physics.kernels.aero.sail_coefficients`).
        profile_drag: ``sail`` air model: the sail's zero-lift drag coefficient.
        stall_angle: ``sail`` air model: angle of attack [deg] where a triangle's flow separates.
        billow_shift: the sail's billow shift under weight shift, as twist: the extra washout [deg] at the tip that
            full weight shift gives the strutted trailing edge of the half the pilot moves towards, and takes from
            the other half (the struts' ties follow; needs ``washout_struts``). On a real flex wing the keel floats
            and swings under the pilot's weight against the leading edges and crossbar, so the half the pilot moves
            towards gets more cloth, billows and twists more, and lifts less: that wing drops (issue 34). It also
            yaws the nose away from the turn (adverse yaw); what it does to the roll, the reversal and the slip:
            docs/glider.md.
    """

    design: str = choice("flying", ("flying", "lattice", "paper"))
    divisions: int = number(8, Bounds(2, 256))
    span: float = number(10.0, POSITIVE)
    chord: float = number(2.8, POSITIVE)
    glider_mass: float = number(25.0, POSITIVE)
    pilot_mass: float = number(65.0, POSITIVE)
    hang_depth: float = number(1.2, POSITIVE)
    pilot_station: float = number(0.55, Bounds(0.0, 1.0))
    frame_height: float = number(1.5, POSITIVE)
    pitch_travel: float = number(0.2, NON_NEGATIVE)
    roll_travel: float = number(0.55, NON_NEGATIVE)
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
    suspension: str = choice("strap", ("sticks", "strap"))
    hang_point: float = number(0.55, Bounds(0.0, 1.0))
    bar_forward: float = number(0.6, NON_NEGATIVE)
    bar_width: float = number(1.4, POSITIVE)
    control_frame_mass: float = number(4.0, POSITIVE)
    pilot_drag_area: float = number(0.2, NON_NEGATIVE)
    frame_drag_area: float = number(0.1, NON_NEGATIVE)
    dihedral: float = number(1.25, Bounds(-30.0, 30.0))
    keel_pocket: bool = True
    washout_struts: float = number(0.5, Bounds(0.0, 1.0))
    sail_tension: float = number(0.03, Bounds(0.0, 0.2))
    sail_compliance: float = number(0.0, NON_NEGATIVE)
    oswald: float = number(0.8, Bounds(0.0, 1.0, low_open=True))
    profile_drag: float = number(0.025, NON_NEGATIVE)
    stall_angle: float = number(18.0, Bounds(0.0, 90.0, low_open=True, high_open=True))
    billow_shift: float = number(16.0, Bounds(-30.0, 30.0))


# The keys a design sets (README, hang glider): the paper's glider differs from the flying one only in these.
_PAPER_GLIDER = {
    "suspension": "sticks",
    "keel_pocket": False,
    "washout_struts": 0.0,
    "sail_tension": 0.0,
    "dihedral": 0.0,
    "billow_shift": 0.0,
    "roll_travel": 0.4,
    "pilot_drag_area": HangGliderConfig().pilot_drag_area,  # the flying design's: every design sets the same keys
}
_FLYING_GLIDER = {k: getattr(HangGliderConfig(), k) for k in _PAPER_GLIDER}
_LATTICE_GLIDER = {"dihedral": -1.5, "billow_shift": 1.0, "pilot_drag_area": 0.25}
PRESETS = {
    # the flying glider steps 5 ms (two substeps of the paper's 10 ms, the iterations kept): its glide and trim
    # speed within 1.5 % of their converged values, where 10 ms was 3.5-3.8 % off (docs/validation.md)
    "flying": {
        "air": {"model": "sail", "density": STANDARD_AIR},
        "hang_glider": _FLYING_GLIDER,
        "solver": {"dt": 0.005},
    },
    # the flying glider on the vortex lattice (issue 53): anhedral against sweep's dihedral effect, a billow shift
    # the lattice's roll needs 1 degree of, and the pilot's drag at the top of Dees's range (it damps the phugoid)
    "lattice": {
        "air": {"model": "vortex", "density": STANDARD_AIR},
        "hang_glider": {**_FLYING_GLIDER, **_LATTICE_GLIDER},
        "solver": {"dt": 0.005},
    },
    "paper": {
        "air": {"model": "paper", "density": AIR_DENSITY},  # the paper's constant air (slide 14)
        "hang_glider": _PAPER_GLIDER,
        "solver": {"dt": 0.01},
    },
}
"""``hang_glider.design`` presets: ``{design: {section: {key: value}}}`` (see :class:`HangGliderConfig`)."""


@dataclass(kw_only=True)
class HangGliderRecord(ObjectRecord):
    """A hang glider's :class:`~warpsim.physics.model.ObjectRecord` with its reference particles and control sticks.

    Attributes:
        nose: the nose particle. keel: keel particles, nose to tail. tips: (left, right) wing-tip particles.
        pilot: the pilot particle. control_sticks: ``[7]`` stick indices, the forward ones first.
        control_forward_count: how many of ``control_sticks`` go to forward frame points.
        pilot_attach_frame: ``[7, 3]`` each control stick's frame point in the glider's build frame
            (forward, left, up) [m] from the nose.
        pilot_neutral_frame: ``[3]`` the pilot's neutral position in that frame [m].
        pitch_travel, roll_travel: pilot travel at full pitch / roll [m].
        hang_point_frame: ``strap``: the hang point in the build frame [m] (None: control sticks).
        billow_shift: as configured [deg]; billow_sticks: the washout struts' ties; billow_particles: the strut
            particle of each tie; billow_points,
            billow_anchors: their strut particles' and anchors' positions in the build frame [m]; billow_side: the
            strut particle's side (+1 left); billow_rise: its rise [m] per radian of extra washout at the tip.
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
    hang_point_frame: np.ndarray | None = None
    billow_shift: float = 0.0
    billow_sticks: np.ndarray | None = None
    billow_particles: np.ndarray | None = None
    billow_points: np.ndarray | None = None
    billow_anchors: np.ndarray | None = None
    billow_side: np.ndarray | None = None
    billow_rise: np.ndarray | None = None

    def controlled_sticks(self) -> np.ndarray:
        """The pilot's arms and the struts' ties the billow shift moves."""
        ties = self.billow_sticks if self.billow_sticks is not None else np.zeros(0, dtype=np.int32)
        return np.concatenate([np.asarray(self.control_sticks), np.asarray(ties)]).astype(np.int32)


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
        raised = behind_edge * np.tan(washout_rad * y / semi) + y * np.tan(np.radians(cfg.dihedral))
        return points + np.outer(raised, up)

    p0 = builder.particle_count
    rows, sail_sticks, tris = builder.add_subdivided_triangle(
        nose, tip_l, tip_r, n, 1.0, vel, shape=twist
    )  # masses are set per part below
    sail = np.arange(p0, p0 + sail_count)
    _sail_air(builder, cfg, tris, rows, nose, fwd, left)

    centre = (nose + tip_l + tip_r) / 3.0
    frame = add_rigid_frame(
        builder, rows, sail_sticks, centre, cfg.frame_height * up, (1, 0, -1), virtual_mass, cfg.frame_weight, vel
    )
    virtual, keel = frame.virtual, frame.keel
    frame_ties, strut_ties = _sail_ties(builder, cfg, rows, sail_sticks, frame)
    billow = _billow_shift_data(builder, cfg, strut_ties, nose, fwd, left, up, semi, washout_rad)
    _sail_masses(builder, cfg, sail, frame, virtual_mass)

    if cfg.suspension == "strap":
        pilot, control, attach, neutral, hang, strap_ties, extra = _hang_strap(
            builder, cfg, rows, frame, nose, fwd, left, up, vel
        )
        frame_ties += strap_ties
        control_forward, strap_groups = len(control), {"strap": np.array([extra.pop("strap")])}
    else:
        pilot, control, attach, neutral = _paper_sticks(builder, cfg, rows, virtual, nose, fwd, up, vel)
        hang, extra, control_forward, strap_groups = None, {}, 3, {}
    builder.set_drag_area(pilot, cfg.pilot_drag_area)
    particles = np.arange(p0, builder.particle_count)
    return builder.add_object(
        HangGliderRecord(
            name="hang_glider",
            kind="hang-glider",
            particles=particles,
            parts={"sail": sail, "virtual": np.array(virtual), "pilot": np.array([pilot]), **extra},
            tri_parts={"sail": tris},
            stick_groups={
                "sail": np.setdiff1d(sail_sticks, frame.sticks),
                "frame": np.unique(frame.sticks + frame_ties),
                "control": np.array(control),
                **strap_groups,
            },
            nose=rows[0][0],
            keel=np.array(keel),
            tips=(rows[n][0], rows[n][n]),
            pilot=pilot,
            control_sticks=np.array(control),
            control_forward_count=control_forward,
            pilot_attach_frame=_to_frame(attach, nose, fwd, left, up),
            pilot_neutral_frame=_to_frame(neutral[None], nose, fwd, left, up)[0],
            hang_point_frame=None if hang is None else _to_frame(hang[None], nose, fwd, left, up)[0],
            pitch_travel=cfg.pitch_travel,
            roll_travel=cfg.roll_travel,
            billow_shift=cfg.billow_shift,
            **billow,
        )
    )


def _sail_air(builder: ModelBuilder, cfg: HangGliderConfig, tris, rows, nose, fwd, left) -> None:
    """The sail's air set-up: its chordwise loading (``chord_loading``) and its delta planform's coefficients for
    the ``sail`` law (:func:`~warpsim.objects.delta.delta_sail_aero`)."""
    semi = 0.5 * cfg.span
    if cfg.chord_loading:
        chordwise_loading(builder, tris, nose, fwd, left, cfg.chord, semi)
    delta_sail_aero(
        builder,
        tris,
        rows,
        nose,
        left,
        cfg.span,
        0.5 * cfg.span * cfg.chord,
        cfg.oswald,
        cfg.profile_drag,
        cfg.stall_angle,
    )


def _sail_ties(builder: ModelBuilder, cfg: HangGliderConfig, rows, sail_sticks, frame) -> tuple[list[int], list]:
    """The sail held on its frame: the washout struts' and the keel pocket's ties (frame sticks), the cloth's
    pretension and its compliance. Returns the frame's ties (stick indices) and the struts' ``(stick, strut particle,
    anchor)``, which the billow shift moves."""
    n = int(cfg.divisions)
    keel = frame.keel
    frame_ties: list[int] = []
    strut_ties: list[tuple[int, int, int]] = []  # (stick, strut particle, anchor): the twist shift moves them
    existing = {frozenset(ends): st for st, ends in enumerate(builder.stick_particles)}

    def tie(p: int, a: int) -> None:
        """Hold particle ``p`` to ``a`` as part of the frame: a new frame stick, or, where a stick already
        joins them (a cloth stick, a frame tie), that stick made a frame stick (frame weight, not tensioned)
        rather than a second stick with another rest length beside it."""
        st = existing.get(frozenset((p, a)))
        if st is None:
            st = existing[frozenset((p, a))] = builder.add_stick(p, a, weight=cfg.frame_weight)
        else:
            builder.stick_weight[st] = max(builder.stick_weight[st], cfg.frame_weight)
        frame_ties.append(st)

    if cfg.washout_struts > 0.0:
        # washout struts (tip rods, "sprogs"): the trailing edge's outer parts held rigid at their twist, so a
        # tensioned sail keeps its washout; each is tied to the virtual particles, its tip and the keel's end
        reach = int(np.floor(cfg.washout_struts * n / 2.0))
        tail = keel[-1]  # the keel's end: on the trailing edge when the divisions are even, a row ahead if odd
        for j in range(1, reach + 1):
            for p, tip in ((rows[n][j], rows[n][0]), (rows[n][n - j], rows[n][n])):
                for a in (*frame.virtual, tip, tail):
                    tie(p, a)
                    strut_ties.append((frame_ties[-1], p, a))
    if cfg.keel_pocket:
        # the sail's pocket along the keel: the cloth particles either side of the keel tube between two keel
        # particles (odd rows) held to it, so the sail cannot fold along the keel
        for i in range(1, n, 2):
            for p in (rows[i][(i - 1) // 2], rows[i][(i + 1) // 2]):
                for a in (*frame.virtual, rows[i - 1][(i - 1) // 2], rows[i + 1][(i + 1) // 2]):
                    tie(p, a)
    if cfg.sail_tension > 0.0:
        builder.pretension(
            np.setdiff1d(sail_sticks, np.concatenate([frame.sticks, frame_ties]).astype(int)), cfg.sail_tension
        )
    if cfg.sail_compliance > 0.0:  # the cloth alone: the frame, its ties and the struts stay rigid
        cloth_sticks = np.setdiff1d(sail_sticks, np.concatenate([frame.sticks, frame_ties]).astype(int))
        builder.set_compliance(cloth_sticks, cfg.sail_compliance)
    return frame_ties, strut_ties


def _sail_masses(builder: ModelBuilder, cfg: HangGliderConfig, sail, frame, virtual_mass: float) -> None:
    """The glider's mass on its particles: ``frame_mass_fraction`` of it on the frame's particles, the rest but the
    virtual particles' on the cloth, evenly [kg]."""
    frame_set = set(frame.points)
    cloth = [p for p in sail if p not in frame_set]
    frame_mass = cfg.frame_mass_fraction * cfg.glider_mass
    for p in frame.points:
        builder.particle_mass[p] = frame_mass / len(frame.points)
    for p in cloth:
        builder.particle_mass[p] = (cfg.glider_mass - frame_mass - 3.0 * virtual_mass) / len(cloth)


def _billow_shift_data(builder: ModelBuilder, cfg: HangGliderConfig, strut_ties, nose, fwd, left, up, semi, washout):
    """The washout struts' ties for the billow shift: their sticks, the strut particle's and the anchor's positions
    in the build frame [m], the strut particle's side (+1 left) and how far [m] it rises per radian of extra
    washout at the tip (the derivative of the sail's twist, ``behind_edge * sec^2(washout y / semi) y / semi``)."""
    if not strut_ties:
        return {}
    sticks, ps, anchors = (np.array(c, dtype=int) for c in zip(*strut_ties, strict=True))
    p_frame = _to_frame(builder.positions(ps), nose, fwd, left, up)
    a_frame = _to_frame(builder.positions(anchors), nose, fwd, left, up)
    y = np.abs(p_frame[:, 1])
    behind_edge = np.maximum(-cfg.chord * y / semi - p_frame[:, 0], 0.0)
    rise = behind_edge * (y / semi) / np.cos(washout * y / semi) ** 2
    return {
        "billow_sticks": sticks,
        "billow_particles": ps,
        "billow_points": p_frame,
        "billow_anchors": a_frame,
        "billow_side": np.sign(p_frame[:, 1]),
        "billow_rise": rise,
    }


def _paper_sticks(builder: ModelBuilder, cfg: HangGliderConfig, rows, virtual, nose, fwd, up, vel):
    """The paper's pilot (Fig. 14): one particle on seven control sticks, three to forward frame points and four
    to aft ones. Returns the pilot, the control sticks, their frame points [m] and the pilot's neutral point."""
    n = len(rows) - 1
    neutral = nose - cfg.pilot_station * cfg.chord * fwd - cfg.hang_depth * up
    pilot = builder.add_particle(neutral, cfg.pilot_mass, vel)
    q, b = n // 3, (2 * n) // 3
    points = [rows[0][0], rows[q][0], rows[q][q], rows[n][n // 2], rows[b][0], rows[b][b], virtual[2]]
    control = [builder.add_stick(pilot, p) for p in points]
    return pilot, control, builder.positions(points), neutral


def _hang_strap(builder: ModelBuilder, cfg: HangGliderConfig, rows, frame, nose, fwd, left, up, vel):
    """A real glider's suspension: a hang point on the keel, a control frame (A-frame) under it, and the pilot
    hanging from the hang point on a strap, holding the base bar with two arms.

    The hang point and the two ends of the base bar are frame particles, each tied by sticks of the frame's
    weight to the virtual particles, the keel and the leading edges (the down tubes and flying wires), so the
    control frame is rigid with the sail. The strap keeps the pilot ``hang_depth`` below the hang point; the
    arms' rest lengths are the controls (:func:`control_rest_lengths`): pushing or pulling the bar swings the
    pilot forward, back or sideways on the strap. Returns the pilot, the two arm sticks, the base bar's ends
    [m], the pilot's neutral point [m], the hang point [m], the new frame sticks and the new parts (with the
    strap's stick under ``"strap"``).
    """
    n = len(rows) - 1
    w = cfg.frame_weight
    keel = frame.keel
    keel_pos = builder.positions(keel)
    station = cfg.hang_point * cfg.chord
    hang = nose - station * fwd
    # the keel particles either side of the hang point, and the leading-edge particles of the nearest row
    along = (nose - keel_pos) @ fwd
    behind = int(np.clip(np.searchsorted(along, station), 1, len(keel) - 1))
    row = int(np.clip(round(cfg.hang_point * n), 1, n))
    anchors = [*frame.virtual, keel[behind - 1], keel[behind], rows[row][0], rows[row][-1]]
    part_mass = 0.5 * cfg.control_frame_mass
    h = builder.add_particle(hang, part_mass, vel)
    # a tie to a keel particle the hang point (nearly) sits on would be a stick of (almost) no length, whose
    # relative stretch means nothing: skip ties shorter than a quarter of a row (the others hold it)
    near = 0.25 * cfg.chord / n
    ties = [builder.add_stick(h, a, weight=w) for a in anchors if np.linalg.norm(builder.positions(a) - hang) > near]
    bar_centre = hang + cfg.bar_forward * fwd - cfg.hang_depth * up
    bar = [builder.add_particle(bar_centre + s * 0.5 * cfg.bar_width * left, 0.5 * part_mass, vel) for s in (1.0, -1.0)]
    for end, side in zip(bar, (rows[row][0], rows[row][-1]), strict=True):
        ties += [builder.add_stick(end, a, weight=w) for a in (h, *frame.virtual, keel[0], keel[-1], side)]
    ties.append(builder.add_stick(bar[0], bar[1], weight=w))
    for p in (h, *bar):
        builder.set_drag_area(p, cfg.frame_drag_area / 3.0)
    neutral = hang - cfg.hang_depth * up
    pilot = builder.add_particle(neutral, cfg.pilot_mass, vel)
    strap = builder.add_stick(h, pilot)
    arms = [builder.add_stick(pilot, end) for end in bar]
    extra = {"control_frame": np.array([h, *bar]), "strap": strap}
    return pilot, arms, builder.positions(bar), neutral, hang, ties, extra


def _to_frame(points: np.ndarray, origin, fwd, left, up) -> np.ndarray:
    d = points - origin
    return np.stack([d @ fwd, d @ left, d @ up], axis=1)
