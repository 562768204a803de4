"""A design of the user's own from a mesh file (``scene.object = "mesh"``): the file's triangles become the cloth
(a stick on every edge, masses by area, the air on every triangle), and the scene's ``[[mesh.parts]]``
(:mod:`.mesh_parts`) add its frame, nails, a line to the ground and point masses, with the keys to steer them.

The model it makes is the same kind the built-in objects make, so every output, figure, sweep and ``--worlds``
works on it. The file is read by :mod:`.mesh_file`; a relative ``mesh.file`` is taken from the scene file's folder.
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass, field

import numpy as np

from ..physics.builder import ModelBuilder
from ..physics.config import GRAVITY, NON_NEGATIVE, POSITIVE, Bounds, Checked, choice, number
from ..physics.kernels.aero import sail_coefficients
from ..physics.model import ObjectRecord
from ..physics.terrain import Heightfield
from .kite import anchor_pull, line_elevation
from .mesh_file import SurfaceMesh, mesh_edges, read_mesh
from .mesh_parts import LINE_DRAG_COEFFICIENT, Part, parse_parts, parts_schema, select, select_edges
from .mesh_structure import check_faces, read_structure

UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254, "ft": 0.3048, "file": float("nan")}
"""Metres per unit of each ``mesh.units`` (``file``: the file's own, USD's ``metersPerUnit``)."""

SIZE_RANGE = (0.05, 100.0)
"""The sizes [m] a design may span once its units and scale apply (a kite, a wing, a canopy, a flag)."""


def _parts_field():
    return field(default=(), metadata={"entries": parse_parts, "schema": parts_schema()})


@dataclass(kw_only=True)
class MeshConfig(Checked):
    """``[mesh]``: a design read from a mesh file.

    Attributes:
        file: the mesh file (OBJ, STL, PLY, OFF, glTF/GLB, USD; :data:`.mesh_file.FORMATS`), relative to the scene
            file's folder.
        units: the file's length unit (``m``, ``cm``, ``mm``, ``in``, ``ft``, or ``file``: a USD stage's
            ``metersPerUnit``).
        scale: a factor on the design's size after ``units``.
        rotation: turns about the world's x, y and z axes, in that order [deg], from the design's own axes: a design
            is drawn with x forward (its nose, upwind for a kite), y to its left and z up.
        position: where the design's origin goes: (x, y) [m] and its height above the terrain there [m].
        velocity: the design's velocity at the start [m/s] (a glider launched at its trim speed).
        mass_per_area: the cloth's areal density [kg/m^2]: each triangle gives a third of its mass to each corner.
        cloth_compliance: stretch [m/N] per newton of each cloth stick (XPBD; 0 = the paper's rigid sticks, whose
            stretch, and with it the design's shape and figures, follows the time step and iteration count). The
            default 5e-5 is the flying kite's sail (of the order of a ripstop's 20 kN/m in its plane).
        bending_stiffness: the cloth's bending stiffness [N m], on every edge between two triangles that are flat as
            built (the quadratic isometric bending of Bergou et al., 2006); 0 = a cloth that folds freely.
        aspect_ratio: the ``sail`` law's aspect ratio (span^2 / area) of the cloth; 0 = measured from the design's
            planform (its span along y and its area seen from above, in its own axes).
        lattice: make the cloth one lifting surface of the ``vortex`` law, its wake shed from the boundary edges
            that face aft (-x in the design's axes).
        parts: the design's parts (``[[mesh.parts]]``, :mod:`.mesh_parts`).
        structure: a structure file (:mod:`.mesh_structure`, relative to the scene file's folder) holding the whole
            model beyond the mesh's triangles: its particles off the cloth, every stick, mass and per-triangle air
            (what ``warpsim export`` writes for a built-in object). With one, the cloth keys above and ``parts`` do
            not apply and are refused.
    """

    file: str = ""
    units: str = choice("m", tuple(UNITS))
    scale: float = number(1.0, POSITIVE)
    rotation: tuple[float, float, float] = number((0.0, 0.0, 0.0), Bounds(-360.0, 360.0))
    position: tuple[float, float, float] = (0.0, 0.0, 10.0)
    velocity: tuple[float, float, float] = number((0.0, 0.0, 0.0), Bounds(-100.0, 100.0))
    mass_per_area: float = number(0.05, POSITIVE)
    cloth_compliance: float = number(5e-5, NON_NEGATIVE)
    bending_stiffness: float = number(0.0, NON_NEGATIVE)
    aspect_ratio: float = number(0.0, Bounds(0.0, 50.0))
    lattice: bool = False
    parts: tuple = _parts_field()
    structure: str = ""


STRUCTURE_HOLDS = ("velocity", "mass_per_area", "cloth_compliance", "bending_stiffness", "aspect_ratio", "lattice")
"""The ``[mesh]`` keys a structure file holds for itself: refused beside ``mesh.structure``."""


@dataclass(kw_only=True)
class MeshRecord(ObjectRecord):
    """A mesh design's :class:`~warpsim.physics.model.ObjectRecord`.

    Attributes:
        tow: the particle its line hangs from (its bridle's knot), -1 without a line. anchor_particle: the line's
            nailed ground end. anchor_nail: its nail (-1 without a line). sag_chain: the line's particles from the
            anchor up (:func:`~warpsim.objects.kite.anchor_pull`). line_drag: its line has a diameter (a drag).
        payload: the first point mass's particle (-1 without one): its swing is measured.
        shift_sticks: the sticks that hang the point masses with a ``shift``; shift_ends: their far ends' positions
            as built ``[k, 3]`` [m]; shift_mass: each one's mass's position as built ``[k, 3]`` [m]; shift_pitch,
            shift_roll: how far each mass moves at pitch = 1 and roll = 1, ``[k, 3]`` [m].
        design: the cloth's vertices in the design's own coordinates ``[V, 3]`` [m] (units and scale applied), in the
            order of ``parts["cloth"]``: what ``warpsim export`` writes back. selections: each part's chosen vertices
            (indices into ``design``).
        control_sticks, control_grid, control_rest: a structure's controlled sticks, the pitch and roll values
            ``[G]`` they are tabled at and their rest lengths there ``[C, G, G]`` [m] (:mod:`.mesh_structure`).
    """

    tow: int = -1
    anchor_particle: int = -1
    anchor_nail: int = -1
    sag_chain: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    line_drag: bool = False
    payload: int = -1
    shift_sticks: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int32))
    shift_ends: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    shift_mass: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    shift_pitch: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    shift_roll: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    design: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    selections: list = field(default_factory=list)
    control_sticks: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int32))
    control_grid: np.ndarray = field(default_factory=lambda: np.zeros(0))
    control_rest: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 0)))

    def controlled_sticks(self) -> np.ndarray:
        """The point masses' hanging sticks and a structure's control sticks, whose rest lengths ``pitch`` and
        ``roll`` set."""
        return np.concatenate([np.asarray(self.shift_sticks), np.asarray(self.control_sticks)]).astype(np.int32)

    def controlled_nails(self) -> np.ndarray:
        """The line's anchor, which the ``anchor`` control walks."""
        return np.array([self.anchor_nail] if self.anchor_nail >= 0 else [], dtype=np.int32)


def rotation_matrix(degrees) -> np.ndarray:
    """The rotation of turns ``degrees`` = (about x, about y, about z) [deg], applied in that order."""
    ax, ay, az = np.radians(np.asarray(degrees, dtype=np.float64))
    rx = np.array([[1, 0, 0], [0, np.cos(ax), -np.sin(ax)], [0, np.sin(ax), np.cos(ax)]])
    ry = np.array([[np.cos(ay), 0, np.sin(ay)], [0, 1, 0], [-np.sin(ay), 0, np.cos(ay)]])
    rz = np.array([[np.cos(az), -np.sin(az), 0], [np.sin(az), np.cos(az), 0], [0, 0, 1]])
    return rz @ ry @ rx


@functools.lru_cache(maxsize=8)
def _read_cached(path: str, stamp: tuple[int, int]) -> SurfaceMesh:
    return read_mesh(path)


def load_design(cfg: MeshConfig) -> tuple[SurfaceMesh, np.ndarray]:
    """The mesh of ``cfg.file`` and its vertices in the design's own coordinates [m] (units and scale applied); a
    file read once per change however many worlds use it. ``ValueError`` with one line on a bad file or size."""
    if not cfg.file:
        raise ValueError("mesh.file is required: the mesh file of the design (OBJ, STL, glTF/GLB, USD, ...)")
    try:
        stat = os.stat(cfg.file)
        stamp = (stat.st_mtime_ns, stat.st_size)
    except OSError:
        stamp = (0, 0)
    mesh = _read_cached(os.path.abspath(cfg.file), stamp)
    unit = UNITS[cfg.units]
    if cfg.units == "file":
        if mesh.meters_per_unit is None:
            raise ValueError(
                f"{cfg.file}: units = 'file' needs a file that states its unit (USD); say units = 'm', 'mm'"
            )
        unit = mesh.meters_per_unit
    design = mesh.vertices * unit * cfg.scale
    size = float(np.ptp(design, axis=0).max())
    low, high = SIZE_RANGE
    if not low <= size <= high:
        hint = "mm" if size > high else "m"
        fix = (
            "its structure file is in metres: write the mesh in metres (warpsim export writes it so)"
            if cfg.structure
            else f"is its unit {hint!r}? (mesh.units, mesh.scale)"
        )
        raise ValueError(
            f"{cfg.file}: the design spans {size:,.3g} m with units = {cfg.units!r} and scale = {cfg.scale:g}, outside "
            f"{low:g}-{high:g} m; {fix}"
        )
    return mesh, design


def build_mesh(builder: ModelBuilder, cfg: MeshConfig, terrain: Heightfield) -> MeshRecord:
    """Add the design of ``cfg`` (its cloth and parts) standing above ``terrain``; returns its record."""
    if cfg.structure:
        _refuse_beside_structure(cfg)
        mesh, design = load_design(cfg)
        return _build_structured(builder, cfg, terrain, mesh, design)
    mesh, design = load_design(cfg)
    parts = [p if isinstance(p, Part) else None for p in cfg.parts]
    if None in parts:
        parts = parse_parts(list(cfg.parts))
    tris = mesh.triangles
    rot, place, world = _placement(cfg, terrain, design)
    cross, mass = _cloth_masses(cfg, design, tris)
    edges, held = mesh_edges(tris)
    used = np.unique(tris)
    if len(used) != len(design):
        raise ValueError(f"{cfg.file}: {len(design) - len(used)} vertices are on no triangle")
    selections = [select(p, mesh, design) for p in parts]
    spar_edges, spar_mass = _spar_edges_and_masses(parts, mesh, design, edges, mass)

    p0 = builder.particle_count
    velocity = tuple(cfg.velocity)
    ids, cloth_sticks, cloth_tris = _add_cloth(builder, cfg, world, mass, edges, tris, velocity)
    builder.set_triangle_sail(cloth_tris, sail_coefficients(_aspect_ratio(cfg, design, cross)))
    if cfg.lattice:
        builder.add_lifting_surface(cloth_tris, ids[_aft_edges(design, tris, edges, held)])

    rigid = np.zeros(len(design), dtype=bool)
    record = MeshRecord(name="mesh", kind="mesh", design=design, selections=selections)
    parts_of: dict[str, list[int]] = {"cloth": list(ids)}
    groups: dict[str, list[int]] = {"cloth": list(cloth_sticks)}
    curves: dict[str, list[list[int]]] = {}
    shift = {"sticks": [], "ends": [], "mass": [], "pitch": [], "roll": []}
    for part, sel in zip(parts, selections, strict=True):
        if part.kind == "nail":
            for i in sel:
                builder.add_nail(int(ids[i]))
        elif part.kind == "spar":
            sticks = [int(s) for s in cloth_sticks[_edge_rows(edges, spar_edges[part.index])]]
            _add_spar(builder, part, sticks, ids[sel], world[sel], rot, spar_mass[part.index], parts_of, groups)
            if part.values["rigid"]:
                rigid[sel] = True
        elif part.kind == "mass":
            _add_mass(
                builder, record, part, ids[sel], world[sel], place, terrain, parts_of, groups, curves, velocity,
                shift, rot,
            )  # fmt: skip
        elif part.kind == "line":
            _add_line(builder, record, part, ids[sel], world[sel], place, terrain, parts_of, groups, curves, velocity)
    if cfg.bending_stiffness > 0.0:
        _add_bending(builder, ids, design, tris, edges, held, cfg.bending_stiffness, rigid)

    record.particles = np.arange(p0, builder.particle_count)
    record.parts = {name: np.asarray(v, dtype=np.int64) for name, v in parts_of.items()}
    record.tri_parts = {"cloth": cloth_tris, **{f"group:{n}": cloth_tris[t] for n, t in mesh.groups.items()}}
    record.stick_groups = {name: np.asarray(v, dtype=np.int64) for name, v in groups.items()}
    record.curves = curves
    if shift["sticks"]:
        record.shift_sticks = np.asarray(shift["sticks"], dtype=np.int32)
        for key in ("ends", "mass", "pitch", "roll"):
            setattr(record, f"shift_{key}", np.asarray(shift[key], dtype=np.float64).reshape(-1, 3))
    return builder.add_object(record)


def _refuse_beside_structure(cfg: MeshConfig) -> None:
    """``ValueError`` (one line) for ``[mesh]`` keys a structure holds for itself (:data:`STRUCTURE_HOLDS`),
    ``parts``, or units and a scale other than metres (a structure's lengths are metres), set beside
    ``mesh.structure``."""
    defaults = MeshConfig()
    clash = [k for k in STRUCTURE_HOLDS if getattr(cfg, k) != getattr(defaults, k)]
    if cfg.parts:
        clash.insert(0, "parts")
    if clash or cfg.units != "m" or cfg.scale != 1.0:
        what = f"mesh.{clash[0]}" if clash else "mesh.units and mesh.scale (a structure's lengths are metres)"
        raise ValueError(
            f"{what} cannot be set beside mesh.structure, which holds the whole model ({cfg.structure}); remove it, or "
            "remove mesh.structure and describe the design with [[mesh.parts]]"
        )


def _build_structured(builder: ModelBuilder, cfg: MeshConfig, terrain: Heightfield, mesh, design) -> MeshRecord:
    """Add the design of ``cfg`` from its mesh and its structure file (:mod:`.mesh_structure`): the mesh's vertices
    and the structure's points as particles, its sticks, masses, nails, drag bodies, per-triangle air, canopies,
    lifting surfaces and hinges, turned by ``mesh.rotation`` and placed at ``mesh.position`` above ``terrain``."""
    tris = mesh.triangles
    s = read_structure(cfg.structure, len(design), len(tris))
    check_faces(s, tris, cfg.structure)
    rot, place, world = _placement(cfg, terrain, design)
    points = place(s.points).reshape(-1, 3)
    ground = np.asarray(terrain.height(points[:, 0], points[:, 1]), dtype=np.float64).reshape(-1)
    if len(points) and (points[:, 2] < ground - 1e-6).any():
        raise ValueError(
            f"the design's structure is placed {float((ground - points[:, 2]).max()):.3g} m below the terrain at its "
            "lowest (its line's anchor, a payload): mesh.rotation turns it about the design's origin; raise "
            "mesh.position's height or turn it less"
        )
    positions = np.concatenate([world, points])
    p0 = builder.particle_count
    for x, m, v in zip(positions, s.mass, s.velocity @ rot.T, strict=True):
        builder.add_particle(x, m if m > 0.0 else 1.0, v)  # a nailed particle's mass is never used
    ids = np.arange(p0, builder.particle_count)
    s0 = builder.stick_count
    for (a, b), rest, weight, compliance, share in zip(
        s.sticks, s.rest, s.weight, s.compliance, s.pretension, strict=True
    ):
        length = float(np.linalg.norm(positions[b] - positions[a]))
        if not length > 0.0:
            raise ValueError(f"{cfg.structure}: stick ({a}, {b}) joins two particles in one place")
        k = builder.add_stick(int(ids[a]), int(ids[b]), rest=float(rest) * length, weight=float(weight))
        builder.set_compliance([k], float(compliance))
        builder.stick_pretension[k] = float(share)
    t0 = builder.tri_count
    for (a, b, c), loading in zip(tris, s.loading, strict=True):
        builder.add_triangle(int(ids[a]), int(ids[b]), int(ids[c]), loading=float(loading))
    tri_ids = np.arange(t0, builder.tri_count)
    for t, coefficients, edge in zip(tri_ids, s.sail, s.leading_edge, strict=True):
        builder.set_triangle_sail([t], coefficients)
        if edge[0] >= 0:
            builder.set_triangle_span([t], ids[edge])
    for particle, area in zip(s.drag, s.drag_area, strict=True):
        builder.set_drag_area(int(ids[particle]), float(area))
    for chosen, table, axis, lag in s.canopies:
        builder.add_canopy(tri_ids[chosen], table, rot @ axis, lag)
    for chosen, trailing in s.surfaces:
        builder.add_lifting_surface(tri_ids[chosen], ids[trailing])
    for particles, weights, stiffness in zip(s.hinges, s.hinge_weights, s.hinge_stiffness, strict=True):
        builder._add_stencil(tuple(int(i) for i in ids[particles]), weights, float(stiffness), "bending hinge")
    n0 = len(builder.nail_particles)
    for particle, target in zip(s.nails, place(s.nail_targets).reshape(-1, 3), strict=True):
        builder.add_nail(int(ids[particle]), target)

    record = MeshRecord(name="mesh", kind="mesh", design=design)
    if s.tow >= 0 and s.anchor_nail >= 0:
        record.tow, record.anchor_nail = int(ids[s.tow]), n0 + s.anchor_nail
        record.anchor_particle = int(ids[s.nails[s.anchor_nail]])
        record.sag_chain = ids[s.chain].astype(np.int64)
        record.line_drag = s.line_drag
    record.payload = int(ids[s.payload]) if s.payload >= 0 else -1
    record.particles = ids
    record.parts = {**{k: ids[v] for k, v in s.parts.items()}, "cloth": ids[: len(design)]}
    record.tri_parts = {"cloth": tri_ids, **{f"group:{n}": tri_ids[t] for n, t in mesh.groups.items()}}
    record.stick_groups = {k: s0 + v for k, v in s.stick_groups.items()}
    record.curves = {k: [[int(ids[i]) for i in c] for c in chains] for k, chains in s.curves.items()}
    if len(s.control_sticks):
        record.control_sticks = (s0 + s.control_sticks).astype(np.int32)
        ends = s.sticks[s.control_sticks]
        placed = np.linalg.norm(positions[ends[:, 1]] - positions[ends[:, 0]], axis=1)
        record.control_grid = s.control_grid
        record.control_rest = s.control_rest * placed[:, None, None]
    return builder.add_object(record)


def _placement(cfg: MeshConfig, terrain: Heightfield, design: np.ndarray):
    """The design's rotation matrix (:func:`rotation_matrix` of ``mesh.rotation``), ``place`` (points in the
    design's coordinates [m] to the world's [m]: rotated, then moved to ``mesh.position`` above ``terrain``) and the
    design's vertices placed ``[V, 3]`` [m]; ``ValueError`` when a vertex is placed below the terrain."""
    rot = rotation_matrix(cfg.rotation)
    px, py, height = cfg.position
    origin = np.array([px, py, float(terrain.height(px, py)) + height])

    def place(points) -> np.ndarray:
        return np.asarray(points, dtype=np.float64) @ rot.T + origin

    world = place(design)
    ground = np.asarray(terrain.height(world[:, 0], world[:, 1]), dtype=np.float64)
    if (world[:, 2] < ground).any():
        raise ValueError(
            f"the design is placed {float((ground - world[:, 2]).max()):.3g} m below the terrain at its lowest; raise "
            "mesh.position's height (the height of its origin above the terrain)"
        )
    return rot, place, world


def _cloth_masses(cfg: MeshConfig, design: np.ndarray, tris: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The triangles' edge cross products ``[T, 3]`` [m^2] (twice their vector areas, in the design's axes) and the
    vertices' masses ``[V]`` [kg]: each triangle's area times ``mass_per_area``, a third to each corner."""
    cross = np.cross(design[tris[:, 1]] - design[tris[:, 0]], design[tris[:, 2]] - design[tris[:, 0]])
    areas = 0.5 * np.linalg.norm(cross, axis=1)
    mass = np.zeros(len(design))
    np.add.at(mass, tris.reshape(-1), np.repeat(areas * cfg.mass_per_area / 3.0, 3))
    return cross, mass


def _spar_edges_and_masses(parts, mesh, design, edges, mass) -> tuple[dict[int, np.ndarray], dict[int, float]]:
    """Each spar's edges ``[k, 2]`` (rows of ``edges``) and its mass [kg], by part index; adds to the vertices'
    ``mass`` [kg] the share its vertices carry (a rigid spar's virtual particles carry a quarter). ``ValueError``
    for a spar with a mass, or not rigid, that selects no edge."""
    spar_edges: dict[int, np.ndarray] = {}
    spar_mass: dict[int, float] = {}
    for part in parts:
        if part.kind != "spar":
            continue
        inside = select_edges(part, mesh, design, edges)
        spar_edges[part.index] = edges[inside]
        if not inside.any() and (part.values["mass_per_length"] > 0.0 or not part.values["rigid"]):
            raise ValueError(
                f"{part.label()} selects no edge of the mesh (a spar runs along edges between its vertices)"
            )
        length = np.linalg.norm(design[edges[inside, 1]] - design[edges[inside, 0]], axis=1)
        spar_mass[part.index] = float(length.sum()) * part.values["mass_per_length"]
        share = 0.75 if part.values["rigid"] else 1.0  # a rigid spar's virtual particles carry the rest
        np.add.at(mass, edges[inside].reshape(-1), np.repeat(share * length * part.values["mass_per_length"] / 2, 2))
    return spar_edges, spar_mass


def _add_cloth(builder, cfg, world, mass, edges, tris, velocity) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The cloth: a particle at each vertex ``world`` [m] of its ``mass`` [kg] moving at ``velocity`` [m/s], a stick
    on every edge (stretching ``cloth_compliance`` [m/N]) and the triangles. Returns its particles, sticks and
    triangles (the builder's indices)."""
    p0 = builder.particle_count
    for x, m in zip(world, mass, strict=True):
        builder.add_particle(x, m, velocity)
    ids = np.arange(p0, builder.particle_count)
    s0 = builder.stick_count
    for a, b in edges:
        builder.add_stick(int(ids[a]), int(ids[b]))
    cloth_sticks = np.arange(s0, builder.stick_count)
    if cfg.cloth_compliance > 0.0:
        builder.set_compliance(cloth_sticks, cfg.cloth_compliance)
    t0 = builder.tri_count
    for a, b, c in tris:
        builder.add_triangle(int(ids[a]), int(ids[b]), int(ids[c]))
    return ids, cloth_sticks, np.arange(t0, builder.tri_count)


def _add_spar(builder, part, sticks, particles, points, rot, spar_mass, parts_of, groups) -> None:
    """A spar along the cloth's ``sticks``: they weigh the part's ``weight`` and stretch its ``compliance`` [m/N];
    a rigid one also holds its vertices ``particles`` (at ``points`` [m]) in a rigid frame (:func:`_rigid_frame`)
    of the spar's mass ``spar_mass`` [kg], whose virtual particles and ties join ``parts_of`` and the frame."""
    v = part.values
    for s in sticks:
        builder.stick_weight[s] = v["weight"]
    if v["rigid"]:
        virtual, ties = _rigid_frame(builder, particles, points, rot, v, spar_mass)
        parts_of.setdefault("virtual", []).extend(virtual)
        sticks = sticks + ties
    builder.set_compliance(sticks, v["compliance"])
    groups.setdefault("frame", []).extend(sticks)


def _add_mass(builder, record, part, attach, points, place, terrain, parts_of, groups, curves, velocity, shift, rot):
    """A point mass at the part's ``position`` (design coordinates, into the world's by ``place``) moving at
    ``velocity`` [m/s], with its drag area, hung by a stick from each of its vertices ``attach`` (at ``points`` [m]);
    the first mass is the record's ``payload``. A mass with a ``shift`` adds its hanging sticks to ``shift``, with
    how far it moves [m] at pitch = 1 and roll = 1 along the design's axes ``rot``. ``ValueError`` for a mass placed
    below the terrain."""
    v = part.values
    at = place(v["position"])
    if at[2] < float(terrain.height(at[0], at[1])):
        raise ValueError(f"{part.label()} is placed below the terrain; raise it or mesh.position's height")
    payload = builder.add_particle(at, v["mass"], velocity)
    if v["drag_area"] > 0.0:
        builder.set_drag_area(payload, v["drag_area"])
    hang = [builder.add_stick(payload, int(a)) for a in attach]
    groups.setdefault("hang", []).extend(hang)
    curves.setdefault("lines", []).extend([[payload, int(a)] for a in attach])
    parts_of.setdefault("payload", []).append(payload)
    if record.payload < 0:
        record.payload = payload
    if any(v["shift"]):
        fwd, left = rot[:, 0], rot[:, 1]
        shift["sticks"] += hang
        shift["ends"] += list(points)
        shift["mass"] += [at] * len(attach)
        shift["pitch"] += [v["shift"][0] * fwd] * len(attach)
        shift["roll"] += [-v["shift"][1] * left] * len(attach)  # roll = +1: the mass to the right


def _edge_rows(edges: np.ndarray, chosen: np.ndarray) -> np.ndarray:
    """Row indices in ``edges`` (sorted unique pairs) of the pairs ``chosen``."""
    if len(chosen) == 0:
        return np.zeros(0, dtype=np.int64)
    key = edges[:, 0] * (edges.max() + 1) + edges[:, 1]
    want = chosen[:, 0] * (edges.max() + 1) + chosen[:, 1]
    return np.searchsorted(key, want)


def _rigid_frame(builder, particles, points, rot, values, spar_mass) -> tuple[list[int], list[int]]:
    """Hold ``particles`` (at ``points``) as one rigid body: four virtual particles at the corners of a tetrahedron
    around them, tied to each other and to every one of them (a point tied to four corners of a tetrahedron cannot
    move against it, where two or three would leave it a hinge). The virtual particles carry a quarter of the spar's
    mass, or a hundredth of a gram each when it has none. Returns (virtual particles, their sticks)."""
    centre = points.mean(axis=0)
    radius = max(0.5 * float(np.linalg.norm(points - centre, axis=1).max()), 0.05)
    corners = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], dtype=np.float64) / np.sqrt(3.0)
    each = max(spar_mass / 16.0, 1e-5)  # a quarter of the spar's mass over the four (its vertices hold the rest)
    virtual = [
        builder.add_particle(centre + radius * (rot @ c), each, builder.particle_qd[int(particles[0])]) for c in corners
    ]
    ties = [
        builder.add_stick(virtual[i], virtual[j], weight=values["weight"]) for i in range(4) for j in range(i + 1, 4)
    ]
    ties += [builder.add_stick(int(p), q, weight=values["weight"]) for p in particles for q in virtual]
    return virtual, ties


def _add_line(builder, record, part, attach, points, place, terrain, parts_of, groups, curves, velocity) -> None:
    """A line from the part's vertices (through a bridle's knot when there are several) to a nailed anchor."""
    v = part.values
    if len(attach) > 1 and v["bridle"] is None:
        raise ValueError(
            f"{part.label()} hangs from {len(attach)} vertices: give the bridle's knot (bridle = [x, y, z])"
        )
    if v["bridle"] is None:
        tow, start = int(attach[0]), points[0]
    else:
        start = place(v["bridle"])
        legs_length = float(np.linalg.norm(points - start, axis=1).sum())
        knot = max(v["mass_per_length"] * legs_length, 1e-4)  # the bridle's legs' mass, at their knot
        tow = builder.add_particle(start, knot, builder.particle_qd[int(attach[0])])
        legs = [builder.add_stick(tow, int(a), weight=4.0) for a in attach]
        groups["bridle"] = legs
        parts_of["bridle"] = [tow]
    ax, ay = v["anchor"]
    anchor = np.array([ax, ay, float(terrain.height(ax, ay))])
    span = float(np.linalg.norm(start - anchor))
    length = v["length"] or span
    if length < 0.99 * span:
        raise ValueError(
            f"{part.label()}: length {length:g} m is shorter than the {span:.3g} m from its knot to the anchor as "
            "built; move the design (mesh.position) or the anchor, or lengthen the line"
        )
    count = int(v["segments"])
    rope, sticks = builder.add_rope(start, anchor, count, v["mass_per_length"] * length, velocity, first=tow)
    for s in sticks:
        builder.stick_rest[s] = length / count
    if v["stiffness"] > 0.0:
        builder.set_compliance(sticks, length / count / v["stiffness"])
    if v["diameter"] > 0.0:
        record.line_drag = True
        for p in rope[1:-1]:
            builder.set_drag_area(int(p), LINE_DRAG_COEFFICIENT * v["diameter"] * length / count)
    record.tow, record.anchor_particle = tow, int(rope[-1])
    record.anchor_nail = builder.add_nail(int(rope[-1]), anchor)
    record.sag_chain = np.asarray(rope[::-1], dtype=np.int64)
    parts_of["rope"] = [int(p) for p in rope[1:]]
    groups["rope"] = [int(s) for s in sticks]
    curves["rope"] = [[int(p) for p in rope]]


def _aspect_ratio(cfg: MeshConfig, design: np.ndarray, cross: np.ndarray) -> float:
    """``cfg.aspect_ratio``, or the design's span along y squared over its area seen from above (0.3 to 30)."""
    if cfg.aspect_ratio > 0.0:
        return cfg.aspect_ratio
    area = 0.5 * float(np.abs(cross[:, 2]).sum())
    span = float(np.ptp(design[:, 1]))
    return float(np.clip(span * span / area, 0.3, 30.0)) if area > 0.0 else 2.0


def _aft_edges(design, tris, edges, held) -> np.ndarray:
    """The boundary edges ``[k, 2]`` (vertex pairs, each in its triangle's order) whose outward side faces aft
    (-x of the design by more than 45 degrees): where a lifting surface sheds its wake."""
    boundary = {tuple(e) for e in edges[held == 1]}
    out = []
    for tri in tris:
        for k in range(3):
            a, b, c = tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]
            if (min(a, b), max(a, b)) not in boundary:
                continue
            along = design[b] - design[a]
            normal = np.cross(design[b] - design[a], design[c] - design[a])
            outward = np.cross(along, normal)  # in the triangle's plane, across the edge, away from c
            if outward @ (design[c] - design[a]) > 0.0:
                outward = -outward
            if outward[0] < -0.7071 * np.linalg.norm(outward):
                out.append((a, b))
    if not out:
        raise ValueError("mesh.lattice: the cloth has no boundary edge facing aft (-x) to shed a wake from")
    return np.asarray(out, dtype=np.int64)


def _add_bending(builder, ids, design, tris, edges, held, stiffness, rigid) -> None:
    """A quadratic isometric bending hinge (Bergou, Wardetzky, Harmon, Zorin and Grinspun, 2006) on every edge between
    two triangles: the cotangent weights ``K`` of the edge's four vertices and the stiffness ``B / (A_0 + A_1)`` (the
    triangles' areas), whose energy ``k |K x|^2 / 2`` summed over the edges is the plate's ``B/2 kappa^2`` per area
    for a bend of curvature ``kappa`` (checked on a bent strip: tests/test_mesh_design.py). Edges on a rigid
    spar are left out (they do not bend); an edge folded more than 2 degrees as built is refused (the hinge's rest
    shape is flat)."""
    owner: dict[tuple[int, int], list[int]] = {}
    for t, tri in enumerate(tris):
        for k in range(3):
            a, b = int(tri[k]), int(tri[(k + 1) % 3])
            owner.setdefault((min(a, b), max(a, b)), []).append(t)
    for (a, b), two in owner.items():
        if len(two) != 2 or (rigid[a] and rigid[b]):
            continue
        c = int(next(v for v in tris[two[0]] if v not in (a, b)))
        d = int(next(v for v in tris[two[1]] if v not in (a, b)))
        x0, x1, x2, x3 = design[a], design[b], design[c], design[d]
        n0, n1 = np.cross(x1 - x0, x2 - x0), np.cross(x1 - x0, x3 - x0)
        # flat: c and d either side of the edge, n0 and n1 opposite (a cloth folded back on itself is 180 deg)
        fold = np.degrees(np.arccos(np.clip(-(n0 @ n1) / (np.linalg.norm(n0) * np.linalg.norm(n1)), -1.0, 1.0)))
        if fold > 2.0:
            raise ValueError(
                f"mesh.bending_stiffness: the cloth folds {fold:.0f} deg at edge ({a}, {b}) as built; bending needs a "
                "cloth flat where it bends (make that edge a spar, or set bending_stiffness = 0)"
            )

        def cot(u, w):
            return float(u @ w) / float(np.linalg.norm(np.cross(u, w)))

        e0, e1, e2, e3, e4 = x1 - x0, x2 - x0, x3 - x0, x2 - x1, x3 - x1
        c01, c02, c03, c04 = cot(e0, e1), cot(e0, e2), cot(-e0, e3), cot(-e0, e4)
        weights = (c03 + c04, c01 + c02, -c01 - c03, -c02 - c04)
        area = 0.5 * (np.linalg.norm(n0) + np.linalg.norm(n1))
        builder._add_stencil(
            (int(ids[a]), int(ids[b]), int(ids[c]), int(ids[d])), weights, stiffness / area, "bending hinge"
        )


def apply_controls(record: MeshRecord, targets: dict, values: dict) -> None:
    """``pitch`` and ``roll`` (in [-1, 1]) move the point masses that have a ``shift`` forward and to the right
    (their hanging sticks' rest lengths follow); ``anchor`` = (x, y) [m] moves the line's ground end, on the
    terrain. ``targets`` holds host copies of ``stick_rest``, ``nail_target`` and the ``terrain``."""
    if len(record.shift_sticks) and ("pitch" in values or "roll" in values):
        pitch, roll = float(values.get("pitch", 0.0)), float(values.get("roll", 0.0))
        at = record.shift_mass + pitch * record.shift_pitch + roll * record.shift_roll
        targets["stick_rest"][record.shift_sticks] = np.linalg.norm(record.shift_ends - at, axis=1)
    if len(record.control_sticks) and ("pitch" in values or "roll" in values):
        rest = _bilinear(record.control_grid, record.control_rest, values.get("pitch", 0.0), values.get("roll", 0.0))
        targets["stick_rest"][record.control_sticks] = rest
    if "anchor" in values and record.anchor_nail >= 0:
        x, y = values["anchor"]
        targets["nail_target"][record.anchor_nail] = (x, y, float(targets["terrain"].height(x, y)))


def _bilinear(grid: np.ndarray, table: np.ndarray, pitch: float, roll: float) -> np.ndarray:
    """The values ``table`` ``[C, G, G]`` tabled at (pitch, roll) on ``grid`` ``[G]``, read at ``pitch`` and
    ``roll`` (clipped to the grid) by bilinear interpolation: ``[C]``."""

    def cell(x: float) -> tuple[int, float]:
        x = float(np.clip(x, grid[0], grid[-1]))
        k = int(np.clip(np.searchsorted(grid, x) - 1, 0, len(grid) - 2))
        return k, (x - grid[k]) / (grid[k + 1] - grid[k])

    (i, u), (j, v) = cell(pitch), cell(roll)
    return (
        (1 - u) * (1 - v) * table[:, i, j]
        + u * (1 - v) * table[:, i + 1, j]
        + (1 - u) * v * table[:, i, j + 1]
        + u * v * table[:, i + 1, j + 1]
    )


MESH_FIGURES = {
    "line_angle": ("deg", "elevation of the line above the horizontal, anchor to knot (NaN without a line)"),
    "line_pull": (
        "N",
        "the line's pull at the anchor from its sag (objects.kite.anchor_pull; NaN without a line, and for a line with "
        "a diameter, whose drag bends it too: the sag read as weight gave a sixth of the pull)",
    ),
    "glide": (
        "-",
        "horizontal airspeed / sink of the mass centre (NaN unless it sinks faster than 0.05 m/s, and for a design on "
        "a line or nailed)",
    ),
    "swing": (
        "deg",
        "angle from the vertical of the line from the first point mass to the cloth's centre (NaN without one, and "
        "for a design on a line)",
    ),
}


def mesh_figures(model, record: MeshRecord):
    """The mesh design's :data:`MESH_FIGURES` of a frame (a :class:`~.figures.FigureView`)."""
    cloth = record.parts["cloth"]
    # a design on a line or nailed (a flag on its pole) does not glide: its sink is its cloth's motion
    held = record.anchor_nail >= 0 or bool(np.isin(np.asarray(model.nail_particles), record.particles).any())

    def measure(view) -> dict[str, float]:
        nan = float("nan")
        sink = float(-view.velocity[2])
        horizontal = float(np.linalg.norm((view.velocity - view.wind)[:2]))
        glide = horizontal / sink if sink > 0.05 and not held else nan
        out = {"line_angle": nan, "line_pull": nan, "glide": glide, "swing": nan}
        if record.anchor_nail >= 0:
            out["line_angle"] = line_elevation(record, view.positions)
            if not record.line_drag:  # the sag gives the pull of a line that carries only its own weight
                out["line_pull"] = anchor_pull(record, view.positions, model.particle_free_mass, GRAVITY)
        if record.payload >= 0 and record.anchor_nail < 0:  # a kite's tail is no payload
            d = view.positions[cloth].mean(axis=0) - view.positions[record.payload]
            out["swing"] = float(np.degrees(np.arctan2(np.hypot(d[0], d[1]), d[2])))
        return out

    return measure


def mesh_hud(f: dict[str, float]) -> str:
    """The heads-up text of a mesh design: its line's angle and pull when it has a line, else its glide and swing."""
    if np.isfinite(f["line_angle"]):
        pull = f"  pull ~{f['line_pull']:5.1f} N" if np.isfinite(f["line_pull"]) else ""
        return f"line {f['line_angle']:4.1f} deg{pull}"
    glide = f"{f['glide']:4.1f}" if np.isfinite(f["glide"]) else " -- "
    swing = f"  swing {f['swing']:3.0f} deg" if np.isfinite(f["swing"]) else ""
    return f"sink {f['sink']:5.2f} m/s  glide {glide}{swing}"
