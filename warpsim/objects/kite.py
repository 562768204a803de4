"""Delta kite on its rope (paper Section 7, Figs. 17-18).

* Sail: the main delta triangle cut like the hang glider's (paper: 14 particles per side, 13 divisions).
* Keel: a triangle at half the resolution standing perpendicular under the spine, set back from the
  nose (paper: 6 particles per side). Its top edge is made of the spine's own particles (every second
  row of the sail, from row 2 on), its apex is the tow point.
* Spars: two virtual particles above and below the sail's centre tied to every particle of the leading
  edges and the spine keep them rigid; sticks between every second leading-edge particle keep the leading
  edges straight (``straight_spars``); the cloth between stays flexible.
* Rope: a chain of particles much lighter than the sail from the tow point to the ground (paper: 14);
  the sticks nearest the keel count double (``rope_doubled``, the paper's doubled sticks). The ground
  end is a nail whose target is the ``anchor`` control: (x, y) [m], z on the terrain.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..physics.builder import ModelBuilder
from ..physics.config import (
    AIR_DENSITY,
    GRAVITY,
    NON_NEGATIVE,
    POSITIVE,
    STANDARD_AIR,
    Bounds,
    Checked,
    choice,
    number,
)
from ..physics.kernels.aero import sail_coefficients
from ..physics.model import Model, ObjectRecord
from ..physics.terrain import Heightfield
from .delta import add_rigid_frame, add_spar_braces, body_axes, chordwise_loading, delta_sail_aero
from .figures import FigureView, Measure

PAPER_COUNTS = {"particles": 152, "sticks": 458, "triangles": 221}


@dataclass(kw_only=True)
class KiteConfig(Checked):
    """Parameters of the delta kite (defaults: the paper's resolution, a 1.8 m, 0.8 m^2, 120 g kite with a tail).

    Attributes:
        design: ``flying`` (the default: towed from 47 % of the keel, the keel's edges reinforced, a flat sail
            whose centre of pressure moves with its angle of attack, 25 deg dihedral and a tail, under the ``sail``
            air model with a 2.5 ms step and 45 over-relaxed, accelerated iterations, it flies as a real delta
            does) or ``paper`` (Section 7: a 200 g kite towed from 35 %, 20 deg dihedral, no tail, the paper's air
            law, 10 ms step and plain 55 iterations). In a scene or with ``--set`` it is a preset
            (:data:`PRESETS`): it sets those keys, ``air.model``, ``air.density`` (the paper's constant air, or 0: the
            standard atmosphere) and the solver's ``dt``, ``iterations``, ``relaxation`` and ``chebyshev``, and keys
            given beside it win. The builder itself reads only the
            individual keys.
        divisions: main-sail subdivisions per side (paper: 14 particles per side -> 13).
        keel_divisions: keel subdivisions per side (paper: 6 particles per side -> 5); the keel's top
            edge spans ``2 * keel_divisions`` sail rows from row 2, so it must fit in ``divisions``.
        span: wing-tip distance [m].
        spine: nose to trailing edge along the spine [m].
        keel_depth: tow point below the spine [m].
        tow_point: position of the tow point along the keel's top edge (0 = front, 1 = back).
        mass: kite mass [kg] (sail, spars and keel).
        frame_height: distance of the virtual particles from the sail [m].
        spar_mass_fraction: share of ``mass`` carried by the two virtual particles (the spars they stand for);
            the rest is spread evenly over the sail and keel particles.
        frame_mass_fraction: share of ``mass`` carried by the spine's and the leading edges' own particles, spread
            evenly over them (0 by default: the cloth carries it). Real spars weigh most of a delta's mass and put its
            centre of mass near half the root chord; 0.6 does, but does not fly at the default step (docs/objects.md,
            the kite's limits).
        frame_weight: weight of the spar and keel sticks in the constraint average (1 = the paper).
        sail_compliance: stretch [m/N] per newton of tension of each of the sail's cloth sticks (weight 1; a sleeve
            stick of weight 4 is 4 times as stiff), so that the iterations converge to cloth of that stiffness at
            every step (:meth:`~warpsim.physics.builder.ModelBuilder.set_compliance`); 0 makes them rigid (the
            paper's, and the ``paper`` design's). The default, 5e-5 m/N (20 kN/m per stick), is nylon ripstop's secant
            to break (the fabric's sources and what the kite's figures do with it: docs/objects.md).
        frame_compliance: stretch [m/N] per newton of tension of each of the frame's sticks (the spars' ties to the
            virtual particles, the braces and the sail's edges between frame particles) and the keel's (its cloth and
            reinforced edges), at weight 1 (they weigh ``frame_weight``, the spine's ties ``spine_weight``, so they
            are 4 to 8 times as stiff); 0 makes them rigid (the paper's, and the ``paper`` design's). Rigid ties are
            the limit the iterations approach as the steps are refined, so a ladder of steps would fly ever stiffer
            kites; no real frame is rigid, and no single measured value applies to ties that stand for a rod's
            stretch and its bending (the default 1e-4 and the range that flies: docs/objects.md).
        straight_spars: tie every leading-edge particle to the one two rows back, so the leading edges stay
            straight rods (not in the paper; without them they bow and stretch ~1.7 % in steady flight).
        rope_length: tow point to anchor [m].
        rope_particles: particles of the rope, the nailed ground end included (paper: 14).
        rope_mass: rope mass [kg] (much lighter than the kite).
        rope_doubled: rope sticks nearest the keel that count double (the paper's doubled sticks).
        anchor: ground end of the rope, (x, y) [m].
        heading: direction from the anchor to the kite [deg from +x towards +y] (downwind).
        elevation: start angle of the rope above horizontal [deg].
        attack: start angle of the sail to the horizontal [deg].
        dihedral: the wings rise from the spine by this angle [deg] towards the sail's back (downwind)
            side, as a delta kite's sail sets in the wind; it gives the kite its roll and yaw stability.
        keel_edges: tie the tow point straight to the keel's two ends on the spine and to the virtual particles
            (the keel's reinforced edges; not in the paper): without them the line's pull stretches the keel's
            cloth sticks near the tow point by ~9 % in steady flight under the ``sail`` air model.
        keel_tension: the keel's cloth sticks (all but its top edge, the spine's own particles) are this much
            shorter than the keel as built, so it sets taut between the spine and the tow point, as a keel is cut
            to (not in the paper): a slack keel of sticks without bending stiffness buckles sideways under the spine's
            compression and holds the kite to one side like a rudder (docs/objects.md).
        spine_sleeve: weight in the constraint average of the sail's cloth sticks that meet the spine (the sail
            is sewn to the spine through a reinforced sleeve; 1 = plain cloth, the paper): the keel hangs the line's
            pull on the spine's particles, and plain cloth round them stretches and swings the kite out of the
            window (docs/objects.md).
        spine_weight: weight of the spine's ties to the virtual particles (the spine spar, which carries the
            line's pull from the keel), set apart from ``frame_weight``: changing ``frame_weight`` leaves these
            ties at ``spine_weight`` (the paper design's 4 is its frame weight).
        profile_drag: ``sail`` air model: the sail's zero-lift drag coefficient
            (:func:`~warpsim.physics.kernels.aero.sail_coefficients`).
        stall_angle: ``sail`` air model: angle of attack [deg] where a triangle's flow separates.
        billow: the sail's cloth sticks are this much longer than the sail as built (a delta's sail is cut
            with billow, so it sets cambered between its spars; not in the paper). 0 by default: with
            ``chord_loading`` a billowed sail lets the kite settle to one side of the wind window.
        chord_loading: load the sail's triangles chordwise as thin-aerofoil theory loads each chordwise strip
            (:func:`~warpsim.objects.delta.chordwise_loading`), so its centre of pressure lies near half the root
            chord from the nose at small angles of attack and moves back to the area centroid (2/3) as the flow
            separates: the kite trims its sail at a real angle of attack (about 11 deg in 6 m/s) instead of the
            ~5 deg a load spread evenly leaves it (the centroid at every angle).
        tail_drag: drag area ``C_D A`` [m^2] of a tail (a tube or ribbon tail) hung from the spine's back end
            (``sail`` air model only): its drag behind the tow point keeps the kite's nose into the wind, which
            holds it in the middle of the wind window (0: no tail).
        delta_lift: ``sail`` air model: give the sail the lift slope of its delta planform, the Helmbold-DATCOM
            slope at its half-chord sweep (:func:`~warpsim.physics.kernels.aero.sail_coefficients`), divided per
            triangle by the cosine of the leading edge's sweep, which the attached flow's sweep theory takes off
            again; without it the sail lifts about 0.7 of its planform's slope.
    """

    design: str = choice("flying", ("flying", "paper"))
    divisions: int = number(13, Bounds(3, 256))
    keel_divisions: int = number(5, Bounds(1, 128))
    span: float = number(1.8, POSITIVE)
    spine: float = number(0.9, POSITIVE)
    keel_depth: float = number(0.3, POSITIVE)
    tow_point: float = number(0.47, Bounds(0.0, 1.0))
    mass: float = number(0.12, POSITIVE)
    frame_height: float = number(0.4, POSITIVE)
    spar_mass_fraction: float = number(0.1, Bounds(0.0, 1.0, low_open=True, high_open=True))
    frame_mass_fraction: float = number(0.0, Bounds(0.0, 1.0, high_open=True))
    frame_weight: float = number(4.0, POSITIVE)
    sail_compliance: float = number(5e-5, NON_NEGATIVE)
    frame_compliance: float = number(1e-4, NON_NEGATIVE)
    straight_spars: bool = True
    rope_length: float = number(30.0, POSITIVE)
    rope_particles: int = number(14, Bounds(2, 4096))
    rope_mass: float = number(0.03, POSITIVE)
    rope_doubled: int = number(4, Bounds(0, 4096))
    anchor: tuple[float, float] = (0.0, 0.0)
    heading: float = 0.0
    elevation: float = number(10.0, Bounds(0.0, 90.0))
    attack: float = number(40.0, Bounds(0.0, 90.0))
    dihedral: float = number(25.0, Bounds(-45.0, 45.0))
    keel_edges: bool = True
    keel_tension: float = number(0.02, Bounds(0.0, 0.2))
    spine_sleeve: float = number(4.0, POSITIVE)
    spine_weight: float = number(8.0, POSITIVE)
    profile_drag: float = number(0.03, NON_NEGATIVE)
    stall_angle: float = number(18.0, Bounds(0.0, 90.0, low_open=True, high_open=True))
    billow: float = number(0.0, Bounds(0.0, 0.2))
    chord_loading: bool = True
    tail_drag: float = number(0.15, NON_NEGATIVE)
    delta_lift: bool = True


PRESETS = {
    # the sail law pulls the kite about 10 times its weight, and its figures converge with its sticks: a step of
    # 2.5 ms with 45 iterations over-relaxed by 1.5 and accelerated by Chebyshev at rho 0.995 puts its line angle
    # within 3 % of its converged value (its pull 3.5 %) at 1.6 times the work of the former 5 ms, 55 iterations and
    # rho 0.99 (4.8-7.3 % off), and flies it steadily in winds where that slid aside or crashed (docs/objects.md,
    # "How the kite flies")
    "flying": {
        "air": {"model": "sail", "density": STANDARD_AIR},
        "solver": {"dt": 0.0025, "iterations": 45, "relaxation": 1.5, "chebyshev": 0.995},
        "kite": {
            k: getattr(KiteConfig(), k)
            for k in (
                "tow_point",
                "keel_edges",
                "keel_tension",
                "spine_sleeve",
                "spine_weight",
                "billow",
                "chord_loading",
                "delta_lift",
                "tail_drag",
                "dihedral",
                "mass",
                "sail_compliance",
                "frame_compliance",
            )
        },
    },
    "paper": {
        "air": {"model": "paper", "density": AIR_DENSITY},  # the paper's constant air (slide 14)
        "solver": {"dt": 0.01, "iterations": 55, "relaxation": 1.0, "chebyshev": 0.95},  # the solver's defaults
        "kite": {
            "tow_point": 0.35,
            "keel_edges": False,
            "keel_tension": 0.0,
            "spine_sleeve": 1.0,
            "spine_weight": 4.0,
            "billow": 0.0,
            "chord_loading": False,
            "delta_lift": False,
            "tail_drag": 0.0,
            "dihedral": 20.0,
            "mass": 0.2,
            "sail_compliance": 0.0,  # the paper's rigid sticks
            "frame_compliance": 0.0,
        },
    },
}
"""``kite.design`` presets: ``{design: {section: {key: value}}}`` (see :class:`KiteConfig`)."""


@dataclass(kw_only=True)
class KiteRecord(ObjectRecord):
    """A kite's :class:`~warpsim.physics.model.ObjectRecord` with its reference particles and its anchor.

    Attributes:
        nose: the nose particle. tow: the tow point (keel apex, the rope's top).
        anchor_particle: the rope's nailed ground end. anchor_nail: its nail (index into ``Control.nail_target``).
        spine: spine particles, nose to tail. tips: (left, right) wing-tip particles.
        sag_chain: the rope's particles from the anchor up to the first doubled stick (the rope's plain sticks),
            whose sag gives the line's pull (:func:`anchor_pull`).
    """

    nose: int
    tow: int
    anchor_particle: int
    anchor_nail: int
    spine: np.ndarray
    tips: tuple[int, int]
    sag_chain: np.ndarray

    def controlled_nails(self) -> np.ndarray:
        """The rope's anchor, which the ``anchor`` control walks."""
        return np.array([self.anchor_nail], dtype=np.int32)


def build_kite(builder: ModelBuilder, cfg: KiteConfig, terrain: Heightfield) -> KiteRecord:
    """Add the kite of ``cfg`` and its rope; returns its record (parts, stick groups, anchor nail)."""
    n = int(cfg.divisions)
    _kite_check(cfg)
    sail_count, keel_count, per_particle = _kite_masses(cfg)
    (fwd, left, up), anchor, tow, (nose, tip_l, tip_r) = _kite_geometry(cfg, terrain)
    p0 = builder.particle_count
    rows, sail_sticks, sail_tris = _kite_sail(builder, cfg, (nose, tip_l, tip_r), left, up, per_particle * sail_count)
    _kite_sail_air(builder, cfg, sail_tris, rows, nose, fwd, left)
    keel_top, keel_rows, keel_sticks, keel_tris, keel = _kite_keel(builder, cfg, rows, tow, per_particle, keel_count)
    tow_particle = keel_rows[0][0]
    spars = _kite_frame(builder, cfg, rows, sail_sticks, (nose + tip_l + tip_r) / 3.0, up)
    if cfg.keel_edges:
        keel_sticks = np.concatenate([keel_sticks, _kite_keel_edges(builder, cfg, tow_particle, keel_top, spars)])
    cloth = _kite_cloth(builder, cfg, sail_sticks, spars, keel_sticks)
    if cfg.tail_drag > 0.0:
        builder.set_drag_area(spars.keel[-1], cfg.tail_drag)
    rope, rope_sticks, nail = _kite_rope(builder, cfg, tow, anchor, tow_particle)

    return builder.add_object(
        KiteRecord(
            name="kite",
            kind="kite",
            particles=np.arange(p0, builder.particle_count),
            parts={
                "sail": np.arange(p0, p0 + sail_count),
                "keel": keel,
                "virtual": np.array(spars.virtual),
                "rope": np.array(rope[1:]),
            },
            tri_parts={"sail": sail_tris, "keel": keel_tris},
            stick_groups={
                "sail": cloth,
                "frame": np.array(spars.sticks),
                "keel": keel_sticks,
                "rope": rope_sticks,
            },
            curves={"rope": [[int(i) for i in rope]]},
            nose=rows[0][0],
            tow=tow_particle,
            anchor_particle=int(rope[-1]),
            anchor_nail=nail,
            spine=np.array(spars.keel),
            tips=(rows[n][0], rows[n][n]),
            sag_chain=np.array(rope[::-1][: len(rope) - max(int(cfg.rope_doubled), 0)], dtype=np.int64),
        )
    )


def _kite_check(cfg: KiteConfig) -> None:
    """Refuse divisions below 3, a keel below 1 division or too large for the sail's rows, and a rope of fewer than
    2 particles (``ValueError``)."""
    n, kd = int(cfg.divisions), int(cfg.keel_divisions)
    if n < 3 or kd < 1:
        raise ValueError(f"divisions must be >= 3 and keel_divisions >= 1, got {n} and {kd}")
    if 2 + 2 * kd > n:
        raise ValueError(f"keel_divisions = {kd} needs divisions >= {2 + 2 * kd} (the keel spans 2 sail rows each)")
    if cfg.rope_particles < 2:
        raise ValueError(f"rope_particles must be at least 2, got {cfg.rope_particles}")


def _kite_masses(cfg: KiteConfig) -> tuple[int, int, float]:
    """The sail's and the keel's own particle counts and the cloth's mass per particle [kg] (what the spars and the
    frame do not carry, spread evenly over both); ``ValueError`` when the spars and the frame leave the cloth none."""
    n, kd = int(cfg.divisions), int(cfg.keel_divisions)
    cloth_share = 1.0 - cfg.spar_mass_fraction - cfg.frame_mass_fraction
    if cloth_share <= 0.0:
        raise ValueError(
            f"spar_mass_fraction + frame_mass_fraction must be below 1 (the cloth needs a mass), got "
            f"{cfg.spar_mass_fraction:g} + {cfg.frame_mass_fraction:g}"
        )
    sail_count = (n + 1) * (n + 2) // 2
    keel_count = (kd + 1) * (kd + 2) // 2 - (kd + 1)
    return sail_count, keel_count, cfg.mass * cloth_share / (sail_count + keel_count)


def _kite_geometry(cfg: KiteConfig, terrain: Heightfield):
    """Where the kite starts: its body axes ``(fwd, left, up)`` (nose into the wind), the anchor on ``terrain``, the
    tow point at the rope's length and elevation from it, and the sail's corners ``(nose, left tip, right tip)``, all
    [m]."""
    n, kd = int(cfg.divisions), int(cfg.keel_divisions)
    fwd, left, up = body_axes(cfg.heading + 180.0, cfg.attack)  # nose into the wind
    ax, ay = cfg.anchor
    anchor = np.array([ax, ay, float(terrain.height(ax, ay))])
    h, e = np.radians(cfg.heading), np.radians(cfg.elevation)
    tow = anchor + cfg.rope_length * np.array([np.cos(h) * np.cos(e), np.sin(h) * np.cos(e), np.sin(e)])
    # spine row r lies r/n of the spine behind the nose; the tow point sits under rows 2 .. 2 + 2 kd
    front, back = 2 / n, (2 + 2 * kd) / n
    along = front + cfg.tow_point * (back - front)
    nose = tow + along * cfg.spine * fwd + cfg.keel_depth * up
    tip_l = nose - cfg.spine * fwd + 0.5 * cfg.span * left
    tip_r = nose - cfg.spine * fwd - 0.5 * cfg.span * left
    return (fwd, left, up), anchor, tow, (nose, tip_l, tip_r)


def _kite_sail(builder: ModelBuilder, cfg: KiteConfig, corners, left, up, mass: float):
    """The sail: the triangle ``corners`` (nose, left tip, right tip) [m] cut ``divisions`` times, ``mass`` [kg]
    spread evenly over its particles, its wings raised by the ``dihedral`` towards the tips. Returns its rows,
    sticks and triangles (:meth:`~warpsim.physics.shapes.MeshShapes.add_subdivided_triangle`)."""
    nose, tip_l, tip_r = corners
    tan_dihedral = np.tan(np.radians(cfg.dihedral))

    def dihedral(points: np.ndarray) -> np.ndarray:
        return points + np.outer(np.abs((points - nose) @ left) * tan_dihedral, up)

    return builder.add_subdivided_triangle(nose, tip_l, tip_r, int(cfg.divisions), mass, shape=dihedral)


def _kite_frame(builder: ModelBuilder, cfg: KiteConfig, rows, sail_sticks, centre, up):
    """The spars: two virtual particles ``frame_height`` [m] above and below the sail's ``centre`` [m], carrying
    ``spar_mass_fraction`` of the mass and tied to the spine and the leading edges, with the ``straight_spars``
    braces and the frame's weights (:func:`_kite_frame_weights`). Returns the frame
    (:func:`~warpsim.objects.delta.add_rigid_frame`), its sticks the braces too."""
    spars = add_rigid_frame(
        builder,
        rows,
        sail_sticks,
        centre,
        cfg.frame_height * up,
        (1, -1),
        cfg.mass * cfg.spar_mass_fraction / 2.0,
        cfg.frame_weight,
    )
    if cfg.straight_spars:
        spars.sticks.extend(add_spar_braces(builder, rows, cfg.frame_weight))
    _kite_frame_weights(builder, cfg, rows, sail_sticks, spars)
    return spars


def _kite_keel_edges(builder: ModelBuilder, cfg: KiteConfig, tow_particle: int, keel_top, spars) -> list[int]:
    """The keel's reinforced edges (``keel_edges``): the tow point tied straight to the keel's ends on the spine and
    to the spars' virtual particles, so the line's pull reaches the frame in one stick, not down a chain of keel
    cloth sticks that stretch under it. Returns the new sticks, of ``frame_weight``."""
    return [
        builder.add_stick(tow_particle, a, weight=cfg.frame_weight) for a in (keel_top[0], keel_top[-1], *spars.virtual)
    ]


def _kite_cloth(builder: ModelBuilder, cfg: KiteConfig, sail_sticks, spars, keel_sticks) -> np.ndarray:
    """The sail's own cloth sticks (its sticks but the frame's), made to stretch ``sail_compliance`` [m/N] and cut
    ``billow`` long, and the frame's and the keel's sticks made to stretch ``frame_compliance`` [m/N]. Returns the
    cloth sticks."""
    cloth = np.setdiff1d(sail_sticks, spars.sticks)
    if cfg.sail_compliance > 0.0:
        builder.set_compliance(cloth, cfg.sail_compliance)
    if cfg.frame_compliance > 0.0:
        # the spars and the keel elastic: with rigid ties every finer step would fly a stiffer kite
        builder.set_compliance([*spars.sticks, *keel_sticks], cfg.frame_compliance)
    if cfg.billow > 0.0:
        builder.pretension(cloth, -cfg.billow)
    return cloth


def _kite_rope(builder: ModelBuilder, cfg: KiteConfig, tow, anchor, tow_particle: int):
    """The rope: ``rope_particles`` particles of ``rope_mass`` [kg] in all, from the tow point ``tow`` [m] down to
    ``anchor`` [m], its first ``rope_doubled`` sticks counting double, its ground end nailed there. Returns its
    particles (the tow point first), its sticks and the nail."""
    count = int(cfg.rope_particles)
    rope, rope_sticks = builder.add_rope(tow, anchor, count, cfg.rope_mass, first=tow_particle)
    for s in rope_sticks[: cfg.rope_doubled]:
        builder.stick_weight[s] = 2.0
    return rope, rope_sticks, builder.add_nail(rope[-1], anchor)


def _kite_sail_air(builder: ModelBuilder, cfg: KiteConfig, sail_tris, rows, nose, fwd, left) -> None:
    """The sail's air set-up: its chordwise loading (``chord_loading``), its delta planform's coefficients for the
    ``sail`` law, and with ``delta_lift`` the planform's own lift slope."""
    if cfg.chord_loading:
        chordwise_loading(builder, sail_tris, nose, fwd, left, cfg.spine, 0.5 * cfg.span)
    delta_sail_aero(
        builder,
        sail_tris,
        rows,
        nose,
        left,
        cfg.span,
        0.5 * cfg.span * cfg.spine,
        0.8,
        cfg.profile_drag,
        cfg.stall_angle,
    )
    if cfg.delta_lift:
        # the planform's lift slope (Helmbold-DATCOM with its half-chord sweep), per triangle divided by the cosine
        # of the leading edge's sweep, which the attached flow's sweep theory takes off again (sail_force)
        half_chord_sweep = np.degrees(np.arctan(cfg.spine / cfg.span))
        edge_cos = 0.5 * cfg.span / np.hypot(0.5 * cfg.span, cfg.spine)
        slope, induced, drag0, stall = sail_coefficients(
            2.0 * cfg.span / cfg.spine, half_chord_sweep, 0.8, cfg.profile_drag, cfg.stall_angle
        )
        builder.set_triangle_sail(sail_tris, (slope / edge_cos, induced, drag0, stall))


def _kite_keel(builder: ModelBuilder, cfg: KiteConfig, rows, tow, per_particle: float, keel_count: int):
    """The keel: a triangle of cloth from the tow point up to the spine's particles (its top edge), its sticks of
    frame weight and, with ``keel_tension``, cut taut. Returns its top edge's particles, rows, sticks, triangles and
    particles."""
    kd = int(cfg.keel_divisions)
    keel_top = [rows[r][r // 2] for r in range(2, 3 + 2 * kd, 2)]
    top_front, top_back = builder.positions([keel_top[0], keel_top[-1]])
    k0 = builder.particle_count
    keel_rows, keel_sticks, keel_tris = builder.add_subdivided_triangle(
        tow, top_front, top_back, kd, per_particle * keel_count, last_row=keel_top
    )
    for s in keel_sticks:
        builder.stick_weight[s] = cfg.frame_weight  # the keel is the kite's reinforced part
    if cfg.keel_tension > 0.0:
        # the keel cut taut: every keel stick but its top edge (the spine's particles, which the frame holds)
        on_top, ends = set(keel_top), builder.stick_particles
        cloth = [int(s) for s in keel_sticks if not (ends[s][0] in on_top and ends[s][1] in on_top)]
        builder.pretension(cloth, cfg.keel_tension)
    keel = np.arange(k0, builder.particle_count)

    return keel_top, keel_rows, keel_sticks, keel_tris, keel


def _kite_frame_weights(builder: ModelBuilder, cfg: KiteConfig, rows, sail_sticks, spars) -> None:
    """The spars' own mass on the spine and leading edges (``frame_mass_fraction``), the spine's ties at
    ``spine_weight`` and the sail's sleeve round the spine at ``spine_sleeve``."""
    n = int(cfg.divisions)
    if cfg.frame_mass_fraction > 0.0:
        # the spars' own mass, spread evenly over the spine's and the leading edges' particles
        frame = sorted({*spars.keel, *(rows[r][0] for r in range(n + 1)), *(rows[r][r] for r in range(n + 1))})
        for i in frame:
            builder.particle_mass[i] += cfg.mass * cfg.frame_mass_fraction / len(frame)
    spine, virtual, ends = set(spars.keel), set(spars.virtual), builder.stick_particles
    for s in spars.sticks:  # the spine spar's ties to the virtual particles
        a, b = ends[s]
        if (a in spine and b in virtual) or (b in spine and a in virtual):
            builder.stick_weight[s] = cfg.spine_weight
    if cfg.spine_sleeve != 1.0:
        # the sail sewn to the spine through a reinforced sleeve: its cloth sticks from the spine count more
        for s in sail_sticks:
            if (ends[s][0] in spine) != (ends[s][1] in spine):
                builder.stick_weight[s] = cfg.spine_sleeve


def apply_controls(record: KiteRecord, targets: dict, values: dict) -> None:
    """Move the rope's ground end to ``values['anchor']`` = (x, y) [m], on the terrain.

    ``targets`` holds host copies of ``stick_rest``, ``nail_target`` and the ``terrain``.
    """
    if "anchor" in values:
        x, y = values["anchor"]
        targets["nail_target"][record.anchor_nail] = (x, y, float(targets["terrain"].height(x, y)))


def line_elevation(record: KiteRecord, q: np.ndarray) -> float:
    """Elevation of the line above the horizontal [deg], from the anchor to the tow point."""
    d = q[record.tow] - q[record.anchor_particle]
    return float(np.degrees(np.arctan2(d[2], np.linalg.norm(d[:2]))))


def anchor_elevation(record: KiteRecord, q: np.ndarray) -> float:
    """Elevation of the line above the horizontal [deg] where it leaves the anchor (its last stick)."""
    rope = record.parts["rope"]
    above = rope[-2] if len(rope) >= 2 else record.tow
    d = q[above] - q[record.anchor_particle]
    return float(np.degrees(np.arctan2(d[2], np.linalg.norm(d[:2]))))


FLAT_ROPE_SLOPE = math.tan(math.radians(1.0))
"""A rope whose every segment lies within this slope of the horizontal lies on the ground (:func:`anchor_pull`)."""


def anchor_pull(record: KiteRecord, q: np.ndarray, mass: np.ndarray, gravity: float = 9.80665) -> float:
    """The line's pull at the anchor [N], from the rope's sag alone (no air force enters it).

    A rope of sticks that carries only its own weight ``m_j g`` at each particle ``j`` holds the same horizontal
    tension ``H`` in every segment, and its slope steps up by ``m_j g / H`` at each particle: over the rope's plain
    sticks from the anchor up (:attr:`KiteRecord.sag_chain`), ``H = g * sum(m_j) / (tan(theta_top) -
    tan(theta_anchor))`` with ``theta`` the segments' elevations, and the pull along the anchor's segment is
    ``H / cos(theta_anchor)`` (the catenary's statics, e.g. Irvine, *Cable Structures*, 1981, ch. 1). ``q``: ``[P,
    3]`` positions [m]; ``mass``: ``[P]`` particle masses [kg]. NaN when the chain has fewer than three particles,
    does not sag (slack or whipping rope: its slope does not grow upwards) or lies flat, within a degree of the
    horizontal all along (on the ground, where the ground and not its tension holds it up: the statics would give
    a pull of 1e10 N).
    """
    chain = record.sag_chain
    if len(chain) < 3:
        return float("nan")
    d = np.diff(q[chain], axis=0)
    slope = d[:, 2] / np.linalg.norm(d[:, :2], axis=1)
    rise = slope[-1] - slope[0]
    if not rise > 0.0 or np.abs(slope).max() < FLAT_ROPE_SLOPE:
        return float("nan")
    horizontal = gravity * float(mass[chain[1:-1]].sum()) / rise
    return horizontal * float(np.hypot(1.0, slope[0]))


def line_state(record: KiteRecord, q: np.ndarray) -> dict:
    """Diagnostics: line elevation angle [deg] (anchor to tow point), kite height [m], tow-anchor distance [m]."""
    d = q[record.tow] - q[record.anchor_particle]
    return {
        "elevation_deg": line_elevation(record, q),
        "height": float(q[record.parts["sail"]][:, 2].mean()),
        "distance": float(np.linalg.norm(d)),
        "tow": q[record.tow].copy(),
    }


# ---------------------------------------------------------------------------------------------- figures
KITE_FIGURES = {
    "line_angle": ("deg", "elevation of the line above the horizontal, from the anchor to the tow point"),
    "line_pull": ("N", "the line's pull at the anchor, from the rope's sag (objects.kite.anchor_pull)"),
}


def kite_figures(model: Model, record: ObjectRecord) -> Measure:
    """The kite's :data:`KITE_FIGURES` of a frame, measured from the particles (the pull from the rope's sag:
    NaN while the rope does not sag, :func:`~warpsim.objects.kite.anchor_pull`)."""

    def measure(view: FigureView) -> dict[str, float]:
        return {
            "line_angle": line_elevation(record, view.positions),
            "line_pull": anchor_pull(record, view.positions, model.particle_free_mass, GRAVITY),
        }

    return measure


def kite_hud(f: dict[str, float]) -> str:
    """The kite's heads-up text: the line's elevation and its pull at the anchor."""
    return f"line {f['line_angle']:4.1f} deg  pull ~{f['line_pull']:5.1f} N"
