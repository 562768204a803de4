"""Any scene's object written as a mesh file, with a scene beside it that flies it as a design of its own
(``scene.object = "mesh"``): the way to take a built-in object to a CAD tool and back (``warpsim export``).

The mesh holds the object's triangles (its triangle parts as named groups). By default the rest of the model goes
into a structure file beside it (:mod:`warpsim.objects.mesh_structure`): its particles off the cloth, every stick,
mass and per-triangle air, canopies, lifting surfaces, hinges, nails, the line and the pitch/roll controls, numbered
as the written mesh reads back, so that the object flies from the files as it flies built in.

With ``parts`` the model is read off as ``[[mesh.parts]]`` instead (:mod:`warpsim.objects.mesh_parts`), each naming
its vertices by the written file's own numbering (:func:`~warpsim.objects.mesh_file.file_numbering`):

* the nailed cloth particles -> a ``nail``;
* cloth sticks stiffer than the cloth's (weight > 1) -> a ``spar`` (not rigid), and the cloth particles tied to a
  rigid frame's virtual particles -> a rigid ``spar``;
* a line to a nailed anchor (a kite's rope) -> the ``line``, with its length, segments and mass;
* each particle off the cloth heavier than a twentieth of the object (a pilot, a person) -> a ``mass`` hung from the
  cloth particles its sticks reach through lighter particles (lines, straps, a control bar), with its drag area and,
  for a glider, the pilot's travel as its ``shift``.

That form says what it leaves out in the scene file's header (a whole-canopy air law, bending hinges, the masses of
lines and frames folded into the cloth's): a design flown from it is the built-in's shape, not its every setting.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..objects.mesh_file import file_numbering, write_mesh
from ..objects.registry import MESH, section
from ..scene.scene import Scene

HEAVY_SHARE = 0.05
"""A particle off the cloth heavier than this share of its object's mass is exported as a point mass."""


def _aspect_ratio(design: np.ndarray, area: float) -> float:
    """Span^2 / area of a cloth whose span is its widest extent in its own plane (the first principal direction of its
    vertices ``design`` [m]), for the ``sail`` law (an export's axes are the world's, not the design's own)."""
    centred = design - design.mean(axis=0)
    direction = np.linalg.svd(centred, full_matrices=False)[2][0]
    span = float(np.ptp(centred @ direction))
    return float(np.clip(span * span / area, 0.3, 30.0))


def _export_own(own: Scene, record, tris: np.ndarray, out: Path) -> tuple[Path, Path, list[str]]:
    """A mesh design written back as it was read: its vertices in its own coordinates, its groups, and its scene
    with ``mesh.file`` the new file (so that it reads back to the same model)."""
    cloth = np.asarray(record.parts["cloth"], dtype=np.int64)
    local = np.full(int(cloth.max()) + 1, -1, dtype=np.int64)
    local[cloth] = np.arange(len(cloth))
    first = int(record.tri_parts["cloth"][0])
    groups = {n.removeprefix("group:"): np.asarray(ids) - first for n, ids in record.tri_parts.items() if n != "cloth"}
    groups = groups or {"cloth": np.arange(len(tris))}
    write_mesh(out, record.design, local[tris], groups)
    numbering = file_numbering(out.suffix, local[tris], groups, len(record.design))
    mesh = own.table(section(MESH))
    # the file holds the design's own coordinates, units and scale applied, and its groups: a part keeps its groups
    # and boxes, and one that named vertices names them by the new file's own numbering
    parts = []
    for entry, chosen in zip(mesh["parts"], record.selections, strict=True):
        if "vertices" in entry:
            entry = {**entry, "vertices": [int(i) for i in numbering[chosen]]}
        parts.append(entry)
    text = own.as_mesh_design({**mesh, "file": out.name, "units": "m", "scale": 1.0, "parts": parts})
    scene_path = out.with_suffix(".toml")
    header = (
        f"# a design exported by warpsim export to {out.name}, as it was read\n# Run: warpsim run {scene_path.name}\n"
    )
    scene_path.write_text(header + text, encoding="utf-8")
    return out, scene_path, []


def export_design(scene: Scene, out: str | Path, parts: bool = False) -> tuple[Path, Path, list[str]]:
    """Write world 0 of ``scene``'s object as the mesh file ``out`` (.obj, .glb, .gltf or .stl) and a scene
    ``out`` with ``.toml`` that flies it; returns (mesh path, scene path, what the export left out).

    A built-in object (or a design flown from a structure) is written with its whole model in a structure file
    ``out`` with ``.structure.toml`` (:mod:`warpsim.objects.mesh_structure`), so that it flies from the files as
    built; with ``parts`` its model is read off as ``[[mesh.parts]]`` instead (nails, spars, a line, point masses:
    a design to edit, which keeps its shape but not its every setting). A design of one's own from parts is written
    back as it was read."""
    out = Path(out)
    single = scene.world(0)  # world 0 with its own [worlds] values
    model = single.build_model("cpu", "export")
    record = model.objects[0]
    tris = np.asarray(model.tri_indices_np, dtype=np.int64)
    if len(tris) == 0:
        raise ValueError(f"the {record.kind} has no triangles to export")
    if _own_design(single):
        return _export_own(single, record, tris, out)
    if not parts:
        return _export_structure(single, model, record, tris, out)
    cloth = np.unique(tris)
    local = {int(p): k for k, p in enumerate(cloth)}
    q0 = np.asarray(model.particle_q0, dtype=np.float64)
    mass = np.asarray(model.particle_free_mass, dtype=np.float64)
    cx, cy = q0[cloth, :2].mean(axis=0)
    ground = float(model.terrain.height(cx, cy))
    origin = np.array([cx, cy, ground])
    design = q0[cloth] - origin
    numbering = _write_cloth(out, record, tris, local, design)

    def vertices_of(ids) -> list[int]:
        return [int(numbering[local[int(i)]]) for i in sorted(ids)]

    sticks = np.asarray(model.stick_particles_np, dtype=np.int64)
    weight = model.stick_weight.numpy().astype(np.float64)
    compliance = np.asarray(model.stick_compliance, dtype=np.float64) * weight
    cloth_sticks = np.isin(sticks, cloth).all(axis=1)
    rope, heavy, virtual, light = _off_cloth(record, cloth, sticks, mass)
    corner = _corner_area(model, tris, q0)
    area = float(corner.sum())
    cloth_mass = float(mass[cloth].sum() + mass[virtual].sum())
    # the design's cloth gets its mass by area and its nails then hold theirs: spread the free mass over the free
    # cloth's area so that the total comes back (a flag, nailed along its hoist, came back 3 % light)
    nailed = np.intersect1d(np.asarray(model.nail_particles, dtype=np.int64), cloth)
    free_area = area - float(corner[nailed].sum())
    left_out: list[str] = []
    parts = _nail_and_spar_parts(model, sticks, weight, cloth_sticks, local, virtual, vertices_of)
    parts += _line_part(model, record, sticks, weight, mass, rope, local, origin, vertices_of, left_out)
    parts += _mass_parts(model, record, sticks, mass, heavy, rope, light, local, origin, vertices_of, left_out)
    left_out += _left_out_of_model(model, corner, cloth, mass, cloth_mass, free_area)

    compliances = compliance[cloth_sticks & (weight <= 1.0)]
    mesh = {
        "file": out.name,
        "position": [float(cx), float(cy), 0.0],
        "velocity": [float(v) for v in np.asarray(model.particle_qd0, dtype=np.float64)[cloth].mean(axis=0)],
        "mass_per_area": cloth_mass / free_area,
        "cloth_compliance": float(np.median(compliances)) if len(compliances) else 0.0,
        "aspect_ratio": _aspect_ratio(design, area),
        "parts": parts,
    }
    scene_path = _write_scene(single, record, out, mesh, left_out)
    found = _left_out_by_flying(model, record, scene_path)  # what the written scene, built, does not have
    if found:
        left_out += found
        scene_path = _write_scene(single, record, out, mesh, left_out)
    return out, scene_path, left_out


STRUCTURE_SUFFIX = ".structure.toml"
"""What the structure file beside an exported mesh ``kite.obj`` is called: ``kite.structure.toml``."""


def structure_path(out: Path) -> Path:
    """The structure file an export to the mesh file ``out`` writes beside it."""
    return out.with_name(out.stem + STRUCTURE_SUFFIX)


def writes_structure(scene: Scene, parts: bool = False) -> bool:
    """Whether :func:`export_design` of ``scene`` (with ``parts``) writes a structure file: it does for a built-in
    object and for a design flown from a structure, unless ``parts``; a design of one's own from ``[[mesh.parts]]``
    is written back as it was read, without one."""
    return not parts and not _own_design(scene)


def _own_design(scene: Scene) -> bool:
    """Whether ``scene`` flies a design of one's own from ``[[mesh.parts]]`` (a mesh without a structure file), which
    an export writes back as it was read."""
    return scene.kind == MESH and not scene.table(section(MESH)).get("structure")


def _export_structure(single: Scene, model, record, tris: np.ndarray, out: Path) -> tuple[Path, Path, list[str]]:
    """Write the object's cloth as the mesh file ``out`` (its triangle parts as groups), its whole model beyond the
    triangles as the structure file beside it (:func:`structure_path`) in the numbering the mesh reads back with, and
    the scene that flies the two; returns (mesh path, scene path, what is left out: the controls a structure does not
    carry)."""
    from ..objects import registry
    from ..objects.mesh_file import read_mesh
    from ..objects.mesh_structure import Structure, structure_text

    cloth = np.unique(tris)
    q0 = np.asarray(model.particle_q0, dtype=np.float64)
    origin = q0[cloth].mean(axis=0)  # the design's origin at its cloth's centre, placed that high above the ground
    height = float(origin[2] - model.terrain.height(origin[0], origin[1]))
    local = {int(p): k for k, p in enumerate(cloth)}
    _write_cloth(out, record, tris, local, q0[cloth] - origin)
    back = read_mesh(out)
    if len(back.vertices) != len(cloth) or len(back.triangles) != len(tris):
        raise ValueError(f"{out}: read back with {len(back.vertices)} vertices for the cloth's {len(cloth)}")
    # every particle's index in the design: the cloth's as the mesh reads back, then the rest in their order
    new = np.full(model.particle_count, -1, dtype=np.int64)
    new[cloth] = _nearest(back.vertices, q0[cloth] - origin)
    off = np.setdiff1d(np.asarray(record.particles, dtype=np.int64), cloth)
    new[off] = len(cloth) + np.arange(len(off))
    order = np.argsort(new[np.concatenate([cloth, off])])
    every = np.concatenate([cloth, off])[order]  # the object's particles in the design's order
    tri_new = _triangle_order(back.triangles, new[tris])

    def per_triangle(values: np.ndarray) -> np.ndarray:
        out_values = np.empty_like(values)
        out_values[tri_new] = values
        return out_values

    weight = model.stick_weight.numpy().astype(np.float64)
    sticks = np.asarray(model.stick_particles_np, dtype=np.int64)
    span = model.tri_span.numpy().astype(np.int64)
    span = np.where(span >= 0, new[np.maximum(span, 0)], -1)
    mass = np.asarray(model.particle_free_mass, dtype=np.float64)
    drag = model.drag_particles.numpy().astype(np.int64)
    nails = np.asarray(model.nail_particles, dtype=np.int64)
    heavy = [int(p) for p in off if mass[p] > HEAVY_SHARE * mass[record.particles].sum()]
    anchor = int(getattr(record, "anchor_nail", -1))
    structure = Structure(
        vertices=len(cloth),
        triangles=len(tris),
        corners=np.asarray(back.triangles, dtype=np.int64),
        points=q0[off] - origin,
        velocity=np.asarray(model.particle_qd0, dtype=np.float64)[every],
        mass=mass[every],
        nails=new[nails],
        nail_targets=np.asarray(model.nail_target0, dtype=np.float64) - origin,
        drag=new[drag],
        drag_area=model.drag_area.numpy().astype(np.float64),
        sticks=new[sticks],
        rest=model.stick_rest.numpy().astype(np.float64) / _lengths(q0, sticks),
        weight=weight,
        compliance=np.asarray(model.stick_compliance, dtype=np.float64) * weight,  # per stick of weight 1
        pretension=np.asarray(model.stick_pretension, dtype=np.float64),
        sail=per_triangle(model.tri_sail.numpy().astype(np.float64)),
        leading_edge=per_triangle(span),
        loading=per_triangle(model.tri_loading.numpy().astype(np.float64)),
        canopies=_canopies(model, q0, tri_new),
        surfaces=[(tri_new[t], new[e]) for t, e in _lifting_surfaces(model)],
        hinges=new[np.asarray(model.hinge_particles_np, dtype=np.int64)],
        hinge_weights=np.asarray(model.hinge_weights_np, dtype=np.float64),
        hinge_stiffness=model.hinge_stiffness.numpy()[: model.hinge_count].astype(np.float64),
        tow=int(new[record.tow]) if anchor >= 0 else -1,
        anchor_nail=anchor,
        chain=new[np.asarray(getattr(record, "sag_chain", []), dtype=np.int64)] if anchor >= 0 else np.zeros(0),
        line_drag=bool(getattr(record, "line_drag", False)),
        payload=int(new[max(heavy, key=lambda p: mass[p])]) if heavy else -1,
        parts={k: new[np.asarray(v, dtype=np.int64)] for k, v in record.parts.items()},
        stick_groups={k: np.asarray(v, dtype=np.int64) for k, v in record.stick_groups.items()},
        curves={k: [[int(new[i]) for i in c] for c in v] for k, v in record.curves.items()},
    )
    structure.control_sticks, structure.control_grid, structure.control_rest = _control_table(model, record, q0)
    where = structure_path(out)
    header = (
        f"# The whole model of the {record.kind} beyond its mesh's triangles, written by warpsim export beside "
        f"{out.name}.\n# Particles 0..{len(cloth) - 1} are the mesh's vertices as warpsim reads it, the rest the "
        "points below; per-triangle lists follow the mesh's triangles.\n"
    )
    where.write_text(structure_text(structure, header), encoding="utf-8")
    # a control that moves no stick or nail of the object steers nothing to lose (a glider's anchor, a kite's pitch)
    steers = {
        "pitch": len(record.controlled_sticks()) > 0,
        "roll": len(record.controlled_sticks()) > 0,
        "anchor": len(record.controlled_nails()) > 0,
    }
    kept = ({"anchor"} if anchor >= 0 else set()) | ({"pitch", "roll"} if len(structure.control_sticks) else set())
    lost = [c for c in registry.OBJECTS[record.kind].controls if c not in kept and steers.get(c, True)]
    left_out = [f"its controls {', '.join(lost)} (a structure carries pitch, roll and a line's anchor)"] if lost else []
    mesh = {"file": out.name, "structure": where.name, "position": [float(origin[0]), float(origin[1]), height]}
    scene_path = _write_scene(single, record, out, mesh, left_out)
    return out, scene_path, left_out


CONTROL_GRID = np.linspace(-1.0, 1.0, 17)
"""The pitch and roll values an export tables its object's controlled sticks at (read between bilinearly)."""


def _control_table(model, record, q0: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The sticks the object's ``pitch`` and ``roll`` controls set, :data:`CONTROL_GRID` and their rest lengths over
    their lengths as built ``[C, G, G]`` at each (pitch, roll) of it, from the object's own controls (empty for an
    object without those controls)."""
    from ..objects import registry

    spec = registry.OBJECTS[record.kind]
    if spec.apply_controls is None or not {"pitch", "roll"} <= set(spec.controls):
        return np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros((0, 0, 0))
    sticks = np.asarray(record.controlled_sticks(), dtype=np.int64)
    base = {
        "stick_rest": model.stick_rest.numpy().astype(np.float64),
        "nail_target": np.asarray(model.nail_target0, dtype=np.float64).copy(),
        "terrain": model.terrain,
    }
    g = len(CONTROL_GRID)
    table = np.zeros((len(sticks), g, g))
    for i, pitch in enumerate(CONTROL_GRID):
        for j, roll in enumerate(CONTROL_GRID):
            targets = {k: v.copy() if isinstance(v, np.ndarray) else v for k, v in base.items()}
            spec.apply_controls(record, targets, {"pitch": float(pitch), "roll": float(roll)})
            table[:, i, j] = targets["stick_rest"][sticks]
    ends = np.asarray(model.stick_particles_np, dtype=np.int64)[sticks]
    return sticks, CONTROL_GRID.copy(), table / _lengths(q0, ends)[:, None, None]


def _lengths(q: np.ndarray, sticks: np.ndarray) -> np.ndarray:
    """The lengths [m] of ``sticks`` ``[S, 2]`` between the points ``q`` [m]; ``ValueError`` when one is 0 (a rest
    length is written over it)."""
    length = np.linalg.norm(q[sticks[:, 1]] - q[sticks[:, 0]], axis=1)
    if not (length > 0.0).all():
        raise ValueError(f"stick {int(np.argmin(length))} joins two particles in one place: its rest has no ratio")
    return length


def _nearest(found: np.ndarray, wanted: np.ndarray) -> np.ndarray:
    """For each point of ``wanted`` ``[n, 3]`` [m], the index of the nearest point of ``found`` ``[n, 3]`` (a mesh
    read back: OBJ's nine digits, glTF's float32); ``ValueError`` when the matching is not one to one."""
    index = np.empty(len(wanted), dtype=np.int64)
    for start in range(0, len(wanted), 512):
        block = wanted[start : start + 512]
        index[start : start + len(block)] = np.argmin(
            ((block[:, None, :] - found[None, :, :]) ** 2).sum(axis=2), axis=1
        )
    if len(np.unique(index)) != len(wanted):
        raise ValueError("the mesh read back does not hold the cloth's vertices one to one")
    return index


def _triangle_order(found: np.ndarray, wanted: np.ndarray) -> np.ndarray:
    """For each triangle of ``wanted`` ``[T, 3]`` (vertex indices), the index of the same triangle, corners in the
    same cyclic order, in ``found``; ``ValueError`` when one is missing or turned over."""
    from ..objects.mesh_structure import cyclic_corners

    found_keys = {tuple(k): i for i, k in enumerate(cyclic_corners(found).tolist())}
    try:
        return np.array([found_keys[tuple(k)] for k in cyclic_corners(wanted).tolist()], dtype=np.int64)
    except KeyError:
        raise ValueError("the mesh read back lost or turned over one of the cloth's triangles") from None


def _canopies(model, q0: np.ndarray, tri_new: np.ndarray) -> list:
    """Each canopy of ``model`` as ``(triangles in the design's order, table [rows, 2], axis [3], wake lag)``; the axis
    is its area vector, signed as the canopy's mouth-to-apex orientation."""
    if not model.canopy_count:
        return []
    start = model.canopy_tri_start.numpy()
    ids = model.canopy_tri_ids.numpy()
    table = model.canopy_table.numpy().astype(np.float64)
    params = model.canopy_params.numpy().astype(np.float64)
    rows = len(table) // model.canopy_count
    tris = np.asarray(model.tri_indices_np, dtype=np.int64)
    out = []
    for c in range(model.canopy_count):
        chosen = ids[start[c] : start[c + 1]]
        a, b, d = q0[tris[chosen, 0]], q0[tris[chosen, 1]], q0[tris[chosen, 2]]
        area = 0.5 * np.cross(b - a, d - b).sum(axis=0)
        out.append((tri_new[chosen], table[c * rows : (c + 1) * rows], params[c, 2] * area, float(params[c, 3])))
    return out


def _lifting_surfaces(model) -> list:
    """Each lifting surface of ``model`` as ``(triangles, trailing edges [k, 2] particle pairs)``."""
    lattice = model.lattice
    tris = np.asarray(model.tri_indices_np, dtype=np.int64)
    out = []
    for s in range(lattice.surface_count):
        panels = range(int(lattice.surface_start[s]), int(lattice.surface_start[s + 1]))
        chosen = np.array([int(lattice.panel_tri[k]) for k in panels], dtype=np.int64)
        trailing = [
            (int(tris[t][e]), int(tris[t][(e + 1) % 3]))
            for k, t in zip(panels, chosen, strict=True)
            for e in range(3)
            if int(lattice.panel_trailing[k]) >> e & 1
        ]
        out.append((chosen, np.asarray(trailing, dtype=np.int64).reshape(-1, 2)))
    return out


def _left_out_by_flying(model, record, scene_path: Path) -> list[str]:
    """What the model of the written scene lacks against ``model`` (the object exported): per-triangle air
    coefficients, sweep, chordwise loading, lifting surfaces, drag bodies, sticks' own compliances, controls; each
    said once. A written scene that does not build is said too."""
    from ..objects import registry
    from ..scene.descriptor import DescriptorError

    try:
        again = Scene.load(str(scene_path)).build_model("cpu", "export check")
    except (DescriptorError, ValueError) as err:
        return [f"(the written scene does not build as it is: {str(err).splitlines()[0]})"]
    out = []

    def rows(array) -> np.ndarray:
        values = np.asarray(array.numpy() if hasattr(array, "numpy") else array, dtype=np.float64)
        return np.unique(np.round(values.reshape(len(values), -1), 6), axis=0)

    if rows(model.tri_sail).shape != rows(again.tri_sail).shape or not np.allclose(
        rows(model.tri_sail), rows(again.tri_sail)
    ):
        out.append("its per-triangle air coefficients (the design's come from mesh.aspect_ratio and the air law)")
    if (model.tri_span.numpy()[:, 0] >= 0).any() and not (again.tri_span.numpy()[:, 0] >= 0).any():
        out.append("its leading edges' sweep")
    if not np.allclose(np.sort(model.tri_loading.numpy()), np.sort(again.tri_loading.numpy())):
        out.append("its chordwise loading")
    if model.lattice.panel_count > again.lattice.panel_count:
        out.append("its lifting surfaces (the vortex law's lattice)")
    if model.drag_count > again.drag_count:
        out.append(f"{model.drag_count - again.drag_count} of its drag bodies (a pilot's, a frame's, a tail's)")
    if len(np.unique(np.round(model.stick_compliance, 12))) > len(np.unique(np.round(again.stick_compliance, 12))):
        out.append("its sticks' own compliances (the design's cloth has one, its spars another)")
    kept = set(registry.OBJECTS[registry.MESH].controls)
    lost = [c for c in registry.OBJECTS[record.kind].controls if c not in kept]
    if lost:
        out.append(f"its controls {', '.join(lost)} (a design has {', '.join(sorted(kept))})")
    if len(record.controlled_sticks()) and not len(again.objects[0].controlled_sticks()):
        out.append("its pitch and roll (no mass of the written parts shifts: give one a shift)")
    return out


def _write_cloth(out: Path, record, tris: np.ndarray, local: dict[int, int], design: np.ndarray) -> np.ndarray:
    """Write the cloth's triangles ``tris`` (particles, renumbered by ``local``) on the vertices ``design`` [m] as the
    mesh file ``out``, grouped by the record's named triangle parts (a triangle in the first that names it, the rest
    in ``cloth``); returns the file's own numbering of the vertices (:func:`file_numbering`)."""
    groups: dict[str, list[int]] = {}
    taken = np.zeros(len(tris), dtype=bool)
    named = [(n, ids) for n, ids in record.tri_parts.items() if n != "cloth"] + [("cloth", np.arange(len(tris)))]
    for name, ids in named:
        free = [int(t) for t in ids if not taken[t]]
        if free:
            groups[name.removeprefix("group:")] = free
            taken[free] = True
    mesh_tris = np.vectorize(local.get)(tris)
    groups_np = {n: np.asarray(v) for n, v in groups.items()}
    write_mesh(out, design, mesh_tris, groups_np)
    return file_numbering(out.suffix, mesh_tris, groups_np, len(design))


def _off_cloth(record, cloth: np.ndarray, sticks: np.ndarray, mass: np.ndarray):
    """The object's particles off the cloth, by what they are: its rope's (a set), the heavy ones (each over
    :data:`HEAVY_SHARE` of the object's mass ``mass`` [kg]: point masses), a rigid frame's virtual particles (tied
    by ``sticks`` to three cloth particles or more) and the light rest (lines, straps, bars; a set)."""
    rope = set(int(p) for p in record.parts.get("rope", []))
    heavy = [
        int(p) for p in np.setdiff1d(record.particles, cloth) if mass[p] > HEAVY_SHARE * mass[record.particles].sum()
    ]
    virtual = [
        int(p)
        for p in np.setdiff1d(record.particles, cloth)
        if int(p) not in rope
        and int(p) not in heavy
        and int(np.isin(sticks[(sticks == p).any(axis=1)], cloth).sum()) >= 3
    ]
    light = set(int(p) for p in np.setdiff1d(record.particles, cloth)) - rope - set(heavy) - set(virtual)
    return rope, heavy, virtual, light


def _nail_and_spar_parts(model, sticks, weight, cloth_sticks, local, virtual, vertices_of) -> list[dict]:
    """The ``nail`` of the nailed cloth particles, the rigid ``spar`` of the cloth particles tied to the ``virtual``
    particles, and the flexible ``spar`` of the cloth's sticks of weight over 1 (each part only where it has
    vertices)."""
    parts: list[dict] = []
    nailed = [int(p) for p in model.nail_particles if int(p) in local]
    if nailed:
        parts.append({"kind": "nail", "vertices": vertices_of(nailed)})
    if virtual:
        tied = {int(o) for s in sticks[np.isin(sticks, virtual).any(axis=1)] for o in s if int(o) in local}
        parts.append({"kind": "spar", "vertices": vertices_of(tied), "rigid": True, "weight": float(weight.max())})
    stiff = cloth_sticks & (weight > 1.0)
    if stiff.any():
        ends = {int(p) for p in sticks[stiff].reshape(-1)}
        parts.append(
            {"kind": "spar", "vertices": vertices_of(ends), "rigid": False, "weight": float(np.median(weight[stiff]))}
        )
    return parts


def _line_part(model, record, sticks, weight, mass, rope, local, origin, vertices_of, left_out) -> list[dict]:
    """The ``line`` of a rope to a nailed anchor, as a list of one (empty without one): its anchor (x, y) [m], length
    [m], segments and mass per length [kg/m], hung from the cloth particle it ties to or through a bridle's knot (its
    position relative to ``origin`` [m]). Adds to ``left_out`` a rope's doubled sticks."""
    anchor_nail = getattr(record, "anchor_nail", -1)
    if not (anchor_nail >= 0 and rope):
        return []
    q0 = np.asarray(model.particle_q0, dtype=np.float64)
    tow = int(record.tow)
    rope_sticks = np.asarray(record.stick_groups.get("rope", []), dtype=np.int64)
    length = float(model.stick_rest.numpy()[rope_sticks].sum())
    target = model.nail_target0[anchor_nail]
    line = {
        "kind": "line",
        "anchor": [float(target[0]), float(target[1])],
        "length": length,
        "segments": len(rope_sticks),
        "mass_per_length": float(mass[sorted(rope)].sum()) / length,
        "diameter": 0.0,
    }
    if tow in local:
        line["vertices"] = vertices_of([tow])
    else:
        legs = {int(o) for s in sticks[(sticks == tow).any(axis=1)] for o in s if int(o) in local}
        line["vertices"] = vertices_of(legs)
        line["bridle"] = [float(v) for v in q0[tow] - origin]
    if (weight[rope_sticks] > 1.0).any():
        left_out.append("the rope's doubled sticks (the line's sticks all count once)")
    return [line]


def _mass_parts(model, record, sticks, mass, heavy, rope, light, local, origin, vertices_of, left_out) -> list[dict]:
    """A ``mass`` for each ``heavy`` particle, hung from the cloth particles its sticks reach through light ones (not
    heavy, not the rope's): its mass [kg] with its lines' and straps', position relative to ``origin`` [m], drag area
    [m^2] and, for a glider, its ``shift``. Adds to ``left_out`` a heavy particle that no stick ties to the cloth."""
    q0 = np.asarray(model.particle_q0, dtype=np.float64)
    drag = dict(zip(model.drag_particles.numpy().tolist(), model.drag_area.numpy().tolist(), strict=True))
    parts: list[dict] = []
    for p in heavy:
        reach, hang, seen = [p], set(), {p}
        while reach:  # through lines, straps and bars to the cloth
            here = reach.pop()
            for a, b in sticks[(sticks == here).any(axis=1)]:
                other = int(b if a == here else a)
                if other in seen:
                    continue
                seen.add(other)
                if other in local:
                    hang.add(other)
                elif other not in heavy and other not in rope:
                    reach.append(other)
        if not hang:
            left_out.append(f"a point mass of {mass[p]:.3g} kg that no stick ties to the cloth")
            continue
        extra = float(mass[sorted(seen & light)].sum())  # its lines' and straps' mass (a frame's is the cloth's)
        entry = {
            "kind": "mass",
            "vertices": vertices_of(hang),
            "mass": float(mass[p]) + extra,
            "position": [float(v) for v in q0[p] - origin],
            "drag_area": float(drag.get(p, 0.0)),
        }
        travel = [float(getattr(record, "pitch_travel", 0.0)), float(getattr(record, "roll_travel", 0.0))]
        if any(travel):
            entry["shift"] = travel
        parts.append(entry)
    return parts


def _corner_area(model, tris, q0) -> np.ndarray:
    """Each particle's share of the triangles ``tris``' area [m^2]: a third of each triangle it is a corner of."""
    out = np.zeros(model.particle_count)
    a = 0.5 * np.linalg.norm(np.cross(q0[tris[:, 1]] - q0[tris[:, 0]], q0[tris[:, 2]] - q0[tris[:, 0]]), axis=1)
    np.add.at(out, tris.reshape(-1), np.repeat(a / 3.0, 3))
    return out


def _left_out_of_model(model, corner: np.ndarray, cloth, mass, cloth_mass: float, area: float) -> list[str]:
    """What of the model the export cannot carry: its bending hinges, a whole-canopy air law, and free particle
    masses [kg] off by more than 1 % of the heaviest from the cloth's ``cloth_mass`` [kg] spread by ``area`` [m^2]
    (the free cloth's) over each particle's share ``corner`` [m^2] (:func:`_corner_area`)."""
    left_out = []
    if model.hinge_count:
        left_out.append("its bending hinges (mesh.bending_stiffness is 0)")
    if model.canopy_count:
        left_out.append("its whole-canopy air law (each triangle takes the scene's air.model)")
    free = mass[cloth] > 0.0  # a nailed particle holds no free mass
    by_area = corner[cloth] * cloth_mass / area
    if np.abs(by_area - mass[cloth])[free].max(initial=0.0) > 0.01 * mass[cloth].max():
        left_out.append("its particles' own masses (the export's cloth has them by area, its frame's folded in)")
    return left_out


def _write_scene(single: Scene, record, out: Path, mesh: dict, left_out: list[str]) -> Path:
    """Write the scene of ``single`` flying the ``[mesh]`` table ``mesh`` beside the mesh file ``out`` (``out`` with
    ``.toml``), its header naming the object and what was ``left_out``; returns its path."""
    text = single.as_mesh_design(mesh)
    scene_path = out.with_suffix(".toml")
    holds = (
        f"its cloth, and its whole model beyond the cloth's triangles in {mesh['structure']}"
        if mesh.get("structure")
        else "its cloth and its parts as a design of its own"
    )
    header = [
        f"# {record.kind} exported by warpsim export to {out.name}: {holds}.",
        "# Run: warpsim run " + scene_path.name,
    ]
    if left_out:
        header.append("# Left out: " + "; ".join(left_out) + ".")
    scene_path.write_text("\n".join(header) + "\n" + text, encoding="utf-8")
    return scene_path
