"""Mesh files in and out: a design's triangles and named groups read from OBJ, STL, PLY, OFF, glTF/GLB or USD, checked
for what a cloth cannot be made of, and written back.

Formats are read by `trimesh <https://trimesh.org>`_ (STL, PLY, OFF, glTF/GLB), by usd-core (USD: every ``Mesh``
prim, with its transform, the stage's ``metersPerUnit`` and ``upAxis``) and, for OBJ, here: trimesh 5.2 keeps no OBJ
group names (``g`` lines are dropped; ``o`` blocks and ``usemtl`` materials come back as pieces named after the wrong
groups, with the vertices renumbered: measured), and an OBJ file is a plain list of ``v``, ``f``, ``g`` and ``o``
lines. glTF files and y-up USD stages are turned z-up (glTF is y-up by its specification).

Vertices that coincide (within about a millionth of the mesh's size) are welded into one, so that a file whose groups
are separate pieces (glTF nodes, STL triangle soup) makes one connected cloth. A scene names vertices by the file's
own numbering (0-based, in the order it lists them; for glTF, STL and USD, the pieces one after the other), which
:attr:`SurfaceMesh.file_index` maps to the welded mesh.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

FORMATS = (".obj", ".stl", ".ply", ".off", ".gltf", ".glb", ".usd", ".usda", ".usdc", ".usdz")
"""The file extensions a design may be read from."""

MAX_TRIANGLES = 200_000
"""The most triangles a design may have (each is a stick triple, a particle share and an air force per step)."""


class MeshError(ValueError):
    """A mesh file that cannot make a cloth; the message is one line naming the file and what is wrong."""


@dataclass
class SurfaceMesh:
    """A design's surface as read: ``vertices`` ``[V, 3]`` float64 in the file's units (z up), ``triangles``
    ``[T, 3]`` int64 vertex indices, ``groups`` name -> triangle indices, ``meters_per_unit`` when the file says (USD),
    and ``file_index``: the welded index of each vertex the file lists, in its order (-1: on no triangle)."""

    vertices: np.ndarray
    triangles: np.ndarray
    groups: dict[str, np.ndarray] = field(default_factory=dict)
    meters_per_unit: float | None = None
    file_index: np.ndarray | None = None

    def group_vertices(self, name: str) -> np.ndarray:
        """The sorted vertex indices of group ``name``'s triangles."""
        return np.unique(self.triangles[self.groups[name]])


def read_mesh(path: str | Path) -> SurfaceMesh:
    """Read the surface of ``path`` (one of :data:`FORMATS`), weld coinciding vertices and check it
    (:func:`check_mesh`); raises :class:`MeshError` with one line otherwise."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in FORMATS:
        raise MeshError(f"{path}: not a mesh file this reads ({', '.join(FORMATS)})")
    if path.is_dir():
        raise MeshError(f"{path}: a folder, not a mesh file")
    if not path.is_file():
        raise MeshError(f"{path}: mesh file not found")
    meters = None
    try:
        if suffix.startswith(".usd"):
            vertices, triangles, groups = _concatenate(_read_usd(path), path)
            meters = _usd_meters(path)
        elif suffix == ".obj":
            vertices, triangles, groups = _read_obj(path)
        else:
            vertices, triangles, groups = _concatenate(_read_trimesh(path), path)
    except MeshError:
        raise
    except Exception as err:  # noqa: BLE001 - a reader's own failure on a broken file, said in one line
        text = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
        raise MeshError(f"{path}: cannot be read as {suffix[1:].upper()}: {text}") from None
    mesh = _weld(vertices, triangles, groups, path)
    mesh.meters_per_unit = meters
    check_mesh(mesh, str(path))
    return mesh


Y_UP_TO_Z_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
"""Turns a y-up file's points into z-up: (x, y, z) -> (x, -z, y), the inverse of Blender's export to glTF."""


def _read_trimesh(path: Path) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """``(node, vertices, triangles)`` pieces of a glTF/GLB, STL, PLY or OFF file read by trimesh, in z-up
    metres-as-written (glTF is y-up by its specification: turned to z-up)."""
    import trimesh

    scene = trimesh.load(path, force="scene", process=False)
    turn = Y_UP_TO_Z_UP if path.suffix.lower() in (".gltf", ".glb") else np.eye(3)
    pieces = []
    # in the order the file lists its meshes (trimesh's graph gives its nodes in another order, which renumbered a
    # written glTF's vertices: a kite's line then hung from the wrong vertex), nodes of one mesh by name
    listed = {name: k for k, name in enumerate(scene.geometry)}
    nodes = sorted(scene.graph.nodes_geometry, key=lambda node: (listed.get(scene.graph[node][1], len(listed)), node))
    for node in nodes:
        transform, name = scene.graph[node]
        geometry = scene.geometry[name]
        if not hasattr(geometry, "faces") or len(geometry.faces) == 0:
            continue  # points or lines: no cloth
        vertices = trimesh.transformations.transform_points(np.asarray(geometry.vertices, dtype=np.float64), transform)
        pieces.append((str(node), vertices @ turn.T, np.asarray(geometry.faces, dtype=np.int64)))
    return pieces


def _read_obj(path: Path) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """An OBJ file's vertices (in the file's order), triangles (polygons as fans) and ``g``/``o`` groups, read
    here: trimesh 5.2 keeps no group names (``g`` lines are dropped; ``o`` blocks and ``usemtl`` materials come back
    as pieces named after the wrong groups, with the vertices renumbered: measured). Faces may be ``v``, ``v/vt``,
    ``v//vn`` or ``v/vt/vn``, with negative (relative) indices; a ``g`` line naming several groups puts its faces in
    the first."""
    vertices: list[tuple[float, float, float]] = []
    triangles: list[tuple[int, int, int]] = []
    owner: list[int] = []
    names: list[str] = []
    current = "default"
    with open(path, encoding="utf-8", errors="replace") as f:
        for number, line in enumerate(f, 1):
            words = line.split()
            if not words or words[0].startswith("#"):
                continue
            head = words[0]
            if head == "v":
                if len(words) < 4:
                    raise MeshError(f"{path}:{number}: a vertex needs three coordinates")
                vertices.append((float(words[1]), float(words[2]), float(words[3])))
            elif head in ("g", "o") and len(words) > 1:
                current = words[1]
            elif head == "f":
                corners = []
                for word in words[1:]:
                    index = int(word.split("/")[0])
                    index = index - 1 if index > 0 else len(vertices) + index
                    if not 0 <= index < len(vertices):
                        name = word.split("/")[0]
                        raise MeshError(f"{path}:{number}: a face names vertex {name}, which does not exist")
                    corners.append(index)
                if len(corners) < 3:
                    raise MeshError(f"{path}:{number}: a face needs at least three vertices")
                if current not in names:
                    names.append(current)
                for k in range(1, len(corners) - 1):
                    triangles.append((corners[0], corners[k], corners[k + 1]))
                    owner.append(names.index(current))
    if not triangles:
        raise MeshError(f"{path}: holds no faces")
    owner_np = np.asarray(owner, dtype=np.int64)
    groups = {name: np.flatnonzero(owner_np == k) for k, name in enumerate(names)}
    return np.asarray(vertices, dtype=np.float64), np.asarray(triangles, dtype=np.int64), groups


def _read_usd(path: Path) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """``(prim path, world-space points, triangles)`` of every ``Mesh`` prim of a USD stage (polygons as fans), z-up
    (a stage whose ``upAxis`` is Y is turned)."""
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.Open(str(path))
    if stage is None:
        raise MeshError(f"{path}: cannot be opened as a USD stage")
    turn = Y_UP_TO_Z_UP if UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y else np.eye(3)
    cache = UsdGeom.XformCache()
    pieces = []
    for prim in stage.Traverse():
        if not prim.IsA(UsdGeom.Mesh):
            continue
        mesh = UsdGeom.Mesh(prim)
        points = np.asarray(mesh.GetPointsAttr().Get() or [], dtype=np.float64).reshape(-1, 3)
        counts = np.asarray(mesh.GetFaceVertexCountsAttr().Get() or [], dtype=np.int64)
        indices = np.asarray(mesh.GetFaceVertexIndicesAttr().Get() or [], dtype=np.int64)
        if len(points) == 0 or len(counts) == 0:
            continue
        if counts.sum() != len(indices) or counts.min() < 3 or indices.min() < 0 or indices.max() >= len(points):
            raise MeshError(f"{path}: mesh {prim.GetPath()} has face counts or indices that do not fit its points")
        matrix = np.asarray(cache.GetLocalToWorldTransform(prim), dtype=np.float64)  # row vectors: p' = p M
        world = (np.c_[points, np.ones(len(points))] @ matrix)[:, :3] @ turn.T
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        tris = [
            (indices[s], indices[s + k], indices[s + k + 1])
            for s, c in zip(starts, counts, strict=True)
            for k in range(1, c - 1)
        ]
        name = prim.GetName()
        if any(n == name for n, _, _ in pieces):
            name = str(prim.GetPath())  # two prims of one name under different parents stay two groups
        pieces.append((name, world, np.asarray(tris, dtype=np.int64)))
    return pieces


def _usd_meters(path: Path) -> float:
    from pxr import Usd, UsdGeom

    return float(UsdGeom.GetStageMetersPerUnit(Usd.Stage.Open(str(path))))


def _concatenate(pieces, path: Path) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """One vertex list, triangle list and group table of named ``pieces``."""
    if not pieces:
        raise MeshError(f"{path}: holds no triangles")
    vertices = np.concatenate([v for _, v, _ in pieces])
    offsets = np.cumsum([0] + [len(v) for _, v, _ in pieces])
    triangles = np.concatenate([t + o for (_, _, t), o in zip(pieces, offsets[:-1], strict=True)])
    groups: dict[str, np.ndarray] = {}
    start = 0
    for name, _, tris in pieces:
        ids = np.arange(start, start + len(tris), dtype=np.int64)
        groups[name] = np.concatenate([groups[name], ids]) if name in groups else ids
        start += len(tris)
    return vertices, triangles, groups


def _weld(vertices: np.ndarray, triangles: np.ndarray, groups: dict, path: Path) -> SurfaceMesh:
    """The mesh of ``triangles`` on ``vertices`` with coinciding vertices welded, numbered in the order the file
    lists them; ``file_index`` maps each of the file's vertices to its welded index (-1: on no triangle)."""
    if not np.isfinite(vertices).all():
        raise MeshError(f"{path}: a vertex is not a finite number")
    if len(triangles) > MAX_TRIANGLES:
        raise MeshError(f"{path}: {len(triangles):,} triangles; a design may have at most {MAX_TRIANGLES:,}")
    used = np.unique(triangles)
    size = float(np.ptp(vertices[used], axis=0).max()) if len(used) else 0.0
    if not size > 0.0:
        raise MeshError(f"{path}: its triangles have no extent (every vertex at one point)")
    grid = np.round(vertices / (1e-6 * size)).astype(np.int64)
    _, first, inverse = np.unique(grid, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    keys = np.unique(inverse[used])
    keys = keys[np.argsort(first[keys], kind="stable")]
    order = np.full(len(first), -1, dtype=np.int64)
    order[keys] = np.arange(len(keys))
    welded = np.zeros((len(keys), 3), dtype=np.float64)
    welded[order[inverse[used]]] = vertices[used]
    # a file's vertex that is on no triangle but coincides with one that is maps to it; one alone maps to -1
    return SurfaceMesh(welded, order[inverse[triangles]], dict(groups), file_index=order[inverse])


def check_mesh(mesh: SurfaceMesh, where: str = "mesh") -> None:
    """Refuse, with one line, a surface a cloth cannot be made of: a degenerate triangle (a repeated vertex or no
    area), the same triangle twice, or an edge held by more than two triangles (non-manifold)."""
    tris, v = mesh.triangles, mesh.vertices
    repeated = (tris[:, 0] == tris[:, 1]) | (tris[:, 1] == tris[:, 2]) | (tris[:, 0] == tris[:, 2])
    size = float(np.ptp(v, axis=0).max())
    area = 0.5 * np.linalg.norm(np.cross(v[tris[:, 1]] - v[tris[:, 0]], v[tris[:, 2]] - v[tris[:, 0]]), axis=1)
    bad = np.flatnonzero(repeated | (area <= 1e-10 * size * size))
    if len(bad):
        t = int(bad[0])
        raise MeshError(
            f"{where}: triangle {t} (vertices {', '.join(str(int(i)) for i in tris[t])}) is degenerate (no area)"
            + (f", and {len(bad) - 1} more" if len(bad) > 1 else "")
        )
    key = np.sort(tris, axis=1)
    _, first, counts = np.unique(key, axis=0, return_index=True, return_counts=True)
    if (counts > 1).any():
        t = int(first[np.flatnonzero(counts > 1)[0]])
        raise MeshError(f"{where}: triangle {t} (vertices {', '.join(str(int(i)) for i in tris[t])}) appears twice")
    edges = np.sort(np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]), axis=1)
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    if (counts > 2).any():
        a, b = unique[np.flatnonzero(counts > 2)[0]]
        raise MeshError(
            f"{where}: edge ({a}, {b}) is held by {counts.max()} triangles (non-manifold: a cloth's edge joins at most "
            "two); split the file's surfaces or remove the extra faces"
        )


def mesh_edges(triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The unique edges ``[E, 2]`` (sorted pairs) of ``triangles`` and how many triangles hold each ``[E]``."""
    edges = np.sort(np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]]), axis=1)
    return np.unique(edges, axis=0, return_counts=True)


def file_numbering(suffix: str, triangles: np.ndarray, groups: dict[str, np.ndarray], count: int) -> np.ndarray:
    """For each of ``count`` vertices, the index it has in the file :func:`write_mesh` writes with that suffix (the
    first, when the format lists it more than once): OBJ its own; glTF, group after group, each group's vertices in
    order; STL, triangle after triangle. A scene's ``vertices`` selection names these."""
    suffix = suffix.lower()
    if suffix == ".obj":
        return np.arange(count, dtype=np.int64)
    out = np.full(count, -1, dtype=np.int64)
    if suffix == ".stl":
        corners = triangles.reshape(-1)
        first = np.unique(corners, return_index=True)
        out[first[0]] = first[1]
        return out
    offset = 0
    for ids in groups.values():
        used = np.unique(triangles[ids])
        fresh = out[used] < 0
        out[used[fresh]] = offset + np.flatnonzero(fresh)
        offset += len(used)
    return out


def write_mesh(path: str | Path, vertices: np.ndarray, triangles: np.ndarray, groups: dict[str, np.ndarray]) -> None:
    """Write ``triangles`` ``[T, 3]`` on ``vertices`` ``[V, 3]`` [m] to ``path`` with each group (name -> triangle
    indices, covering every triangle once) named: OBJ (``o`` lines, written here: trimesh writes no groups), glTF/GLB
    (one named node per group, y-up as glTF is, by trimesh) or STL (no groups: one surface). An OBJ file read back
    by :func:`read_mesh` numbers its vertices as ``vertices``; glTF lists each group's vertices apart and STL each
    triangle's, so they come back in that order, welded."""
    path = Path(path)
    suffix = path.suffix.lower()
    vertices, triangles = np.asarray(vertices, dtype=np.float64), np.asarray(triangles, dtype=np.int64)
    if suffix == ".obj":
        lines = ["# written by warpsim export: metres, z up"]
        lines += [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in vertices]
        for name, ids in groups.items():
            lines.append(f"o {name}")
            lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in triangles[ids]]
        path.write_text("\n".join(lines) + "\n", encoding="utf-8")
        return
    import trimesh

    if suffix == ".stl":
        trimesh.Trimesh(vertices, triangles, process=False).export(path)
        return
    if suffix in (".glb", ".gltf"):
        scene = trimesh.Scene()
        up = vertices @ Y_UP_TO_Z_UP  # z-up to glTF's y-up (the inverse turn)
        for name, ids in groups.items():
            used = np.unique(triangles[ids])
            local = np.searchsorted(used, triangles[ids])
            scene.add_geometry(trimesh.Trimesh(up[used], local, process=False), geom_name=name, node_name=name)
        if suffix == ".gltf":  # its buffers inside the file: trimesh's side files (gltf_buffer_0.bin, ...) have
            # names of their own, and a second export to the same folder replaced the first's
            from trimesh.exchange.gltf import export_gltf

            path.write_bytes(export_gltf(scene, embed_buffers=True)["model.gltf"])
        else:
            scene.export(path)
        return
    raise MeshError(f"{path}: writes OBJ, STL, glTF or GLB (.obj, .stl, .gltf, .glb)")
