"""The parts of a design read from a mesh file (``[[mesh.parts]]`` in a scene): nails, spars, a line and point masses,
each choosing its vertices by the file's groups, by vertex indices or by a box, checked when the scene is read.

A part is one TOML table with a ``kind`` and its keys (units in brackets)::

    [[mesh.parts]]            # the spine and the spreader: one rigid frame of 0.02 kg/m
    kind = "spar"
    group = ["spine", "spreader"]
    mass_per_length = 0.02

    [[mesh.parts]]            # a bridle from two vertices to a knot, then a line to the ground
    kind = "line"
    vertices = [3, 17]
    bridle = [0.1, 0.0, -0.4] # the knot, in the design's own coordinates [m]
    anchor = [0.0, 0.0]       # (x, y) on the ground [m]

Keys: ``spar``: ``mass_per_length`` [kg/m], ``rigid`` (one rigid body, default true; false: stiff sticks on its
edges only), ``weight`` (its sticks' share in the solver's average, default 4), ``compliance`` [m/N] (each stick's
stretch per newton, 0 = rigid). ``line``: ``anchor`` (x, y) [m] on the ground (required), ``bridle`` (x, y, z) [m]
its knot when it hangs from several vertices, ``length`` [m] (0 = from the knot to the anchor as built),
``segments``, ``mass_per_length`` [kg/m] (0.5 g/m: a braided kite line), ``diameter`` [m] (its drag), ``stiffness``
``EA`` [N] (5000: a braided line's; 0 = rigid sticks). ``mass``: ``mass`` [kg] and ``position`` (x, y, z) [m]
(required), ``drag_area`` ``C_D A`` [m^2], ``shift`` (forward, right) [m] it moves at pitch = 1 and roll = 1 (a
pilot's weight shift). ``nail``: its vertices fixed where they are built.

Selections (exactly one per part): ``group`` (a name or a list of the file's groups: OBJ ``g``/``o``, glTF nodes, USD
Mesh prims), ``vertices`` (indices of the welded mesh, :mod:`.mesh_file`) or ``box`` (``[x0, y0, z0, x1, y1, z1]``
in the design's own coordinates [m], after ``units`` and ``scale``, before ``rotation`` and ``position``, or a list
of such boxes: the vertices inside any of them).
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass

import numpy as np

from .mesh_file import MAX_TRIANGLES

SELECTORS = ("group", "vertices", "box")

MAX_SEGMENTS = 1000
"""The most segments a line may have (each a particle and a stick)."""

MAX_LINE = 10_000.0
"""The longest line [m]."""

_KEYS: dict[str, dict[str, tuple[str, object]]] = {
    # kind -> key -> (type, default); "required" marks a key without a default
    "nail": {},
    "spar": {
        "mass_per_length": ("number>=0", 0.0),
        "rigid": ("bool", True),
        "weight": ("number>0", 4.0),
        "compliance": ("number>=0", 0.0),
    },
    "line": {
        "anchor": ("xy", "required"),
        "bridle": ("xyz", None),
        "length": ("number>=0", 0.0),
        "segments": ("count", 30),
        "mass_per_length": ("number>0", 0.0005),
        "diameter": ("number>=0", 0.001),
        "stiffness": ("number>=0", 5000.0),
    },
    "mass": {
        "mass": ("number>0", "required"),
        "position": ("xyz", "required"),
        "drag_area": ("number>=0", 0.0),
        "shift": ("xy", [0.0, 0.0]),
    },
}
"""Each part kind's own keys: ``(type, default)``."""

LINE_DRAG_COEFFICIENT = 1.2
"""Drag coefficient of a line's particles on its diameter times its segment length (a cylinder across the flow,
Hoerner, *Fluid-Dynamic Drag*, 1965, ch. 3; applied to the whole relative wind, along the line too)."""


@dataclass(frozen=True)
class Part:
    """One checked part: its ``kind``, its selection (``selector``, ``selection``) and its own keys (``values``)."""

    index: int
    kind: str
    selector: str
    selection: object
    values: dict

    def label(self) -> str:
        """How messages name it: ``part 2 (spar)``."""
        return f"part {self.index + 1} ({self.kind})"


def parse_parts(entries) -> list[Part]:
    """Check ``[[mesh.parts]]`` entries (a list of tables) and return them as :class:`Part`; raises ``ValueError``
    with one line naming the part and the key."""
    if not isinstance(entries, (list, tuple)):
        raise ValueError(f"mesh.parts must be [[mesh.parts]] tables, got {entries!r}")
    parts = []
    lines = 0
    for index, entry in enumerate(entries):
        where = f"part {index + 1}"
        if not isinstance(entry, dict):
            raise ValueError(f"{where} must be a table with a kind, got {entry!r}")
        kind = entry.get("kind")
        if kind is None:
            raise ValueError(f'{where} needs a kind: one of {", ".join(_KEYS)} (kind = "{next(iter(_KEYS))}")')
        if not isinstance(kind, str) or kind not in _KEYS:
            close = difflib.get_close_matches(str(kind), list(_KEYS), n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise ValueError(f"{where}: kind = {kind!r} is not one of {', '.join(_KEYS)}{hint}")
        where = f"{where} ({kind})"
        allowed = {"kind", *SELECTORS, *_KEYS[kind]}
        unknown = sorted(set(entry) - allowed)
        if unknown:
            close = difflib.get_close_matches(str(unknown[0]), sorted(allowed), n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise ValueError(f"{where}: unknown key {unknown[0]!r}{hint}; its keys are {', '.join(sorted(allowed))}")
        chosen = [s for s in SELECTORS if s in entry]
        if len(chosen) != 1:
            raise ValueError(f"{where} must choose its vertices with exactly one of group, vertices or box")
        selector = chosen[0]
        selection = _check_selection(where, selector, entry[selector])
        values = {}
        for key, (kind_of, default) in _KEYS[kind].items():
            if key not in entry:
                if default == "required":
                    raise ValueError(f"{where} needs {key}")
                values[key] = default
                continue
            values[key] = _check_key(where, key, kind_of, entry[key])
        if kind == "line":
            if values["length"] > MAX_LINE:
                raise ValueError(f"{where}: length must be at most {MAX_LINE:g} m, got {values['length']:g}")
            lines += 1
            if lines > 1:
                raise ValueError(f"{where}: a design has at most one line (the anchor control walks it)")
        parts.append(Part(index, kind, selector, selection, values))
    return parts


def _check_selection(where: str, selector: str, value):
    if selector == "group":
        names = [value] if isinstance(value, str) else value
        if not isinstance(names, list) or not names or not all(isinstance(n, str) and n for n in names):
            raise ValueError(f"{where}: group must be a group's name or a list of names, got {value!r}")
        return tuple(names)
    if selector == "vertices":
        if (
            not isinstance(value, list)
            or not value
            or not all(isinstance(i, int) and not isinstance(i, bool) and 0 <= i < MAX_TRIANGLES * 3 for i in value)
        ):
            raise ValueError(f"{where}: vertices must be a list of vertex indices (whole numbers >= 0), got {value!r}")
        return tuple(value)
    boxes = value if isinstance(value, list) and value and all(isinstance(b, list) for b in value) else [value]
    out = []
    for box in boxes:
        box = _check_key(where, "box", "box", box)
        if not all(box[k] <= box[k + 3] for k in range(3)):
            raise ValueError(f"{where}: box must be [x0, y0, z0, x1, y1, z1] with x0 <= x1, y0 <= y1, z0 <= z1")
        out.append(tuple(box))
    return tuple(out)


def _check_key(where: str, key: str, kind_of: str, value):
    numeric = isinstance(value, (int, float)) and not isinstance(value, bool)
    if kind_of == "bool":
        if not isinstance(value, bool):
            raise ValueError(f"{where}: {key} must be true or false, got {value!r}")
        return value
    if kind_of == "count":
        if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_SEGMENTS:
            raise ValueError(f"{where}: {key} must be a whole number from 1 to {MAX_SEGMENTS}, got {value!r}")
        return value
    if kind_of.startswith("number"):
        if not numeric or not np.isfinite(value) or abs(value) > 1e9:
            raise ValueError(f"{where}: {key} must be a finite number, got {value!r}")
        if kind_of == "number>0" and not value > 0:
            raise ValueError(f"{where}: {key} must be > 0, got {value!r}")
        if kind_of == "number>=0" and not value >= 0:
            raise ValueError(f"{where}: {key} must be >= 0, got {value!r}")
        return float(value)
    size = {"xy": 2, "xyz": 3, "box": 6}[kind_of]
    if (
        not isinstance(value, list)
        or len(value) != size
        or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
        or not all(np.isfinite(v) and abs(v) <= 1e7 for v in value)
    ):
        raise ValueError(f"{where}: {key} must be a list of {size} finite numbers, got {value!r}")
    return [float(v) for v in value]


def select(part: Part, mesh, design: np.ndarray) -> np.ndarray:
    """The sorted vertex indices ``part`` chooses on ``mesh`` (a :class:`~.mesh_file.SurfaceMesh` whose vertices lie
    at ``design`` ``[V, 3]``, the design's own coordinates [m]); ``ValueError`` when it chooses none or names what the
    mesh has not."""
    return np.flatnonzero(_labels(part, mesh, design) >= 0)


def select_edges(part: Part, mesh, design: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Which of ``edges`` (``[E, 2]`` vertex pairs) belong to ``part``: both ends in one of its groups' triangles'
    edges, in one of its boxes, or among its vertices (an edge that merely joins two of its boxes is not the spar's:
    a diamond kite's cloth diagonals from the spine to the spreader)."""
    if part.selector == "group":
        inside = np.zeros(len(edges), dtype=bool)
        key = edges[:, 0] * len(design) + edges[:, 1]
        for name in part.selection:
            tris = mesh.triangles[mesh.groups[name]]
            own = np.sort(np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]), axis=1)
            inside |= np.isin(key, own[:, 0] * len(design) + own[:, 1])
        return inside
    labels = _labels(part, mesh, design)
    return (labels[edges[:, 0]] >= 0) & (labels[edges[:, 0]] == labels[edges[:, 1]])


def _labels(part: Part, mesh, design: np.ndarray) -> np.ndarray:
    """For each vertex, which of the part's boxes holds it (the first), 0 for any vertex of its groups or vertices,
    -1 for one it does not choose."""
    labels = np.full(len(design), -1, dtype=np.int64)
    if part.selector == "group":
        missing = [n for n in part.selection if n not in mesh.groups]
        if missing:
            have = ", ".join(mesh.groups) or "none (STL has no groups)"
            raise ValueError(f"{part.label()}: the mesh has no group {missing[0]!r} (its groups: {have})")
        labels[np.unique(np.concatenate([mesh.triangles[mesh.groups[n]].reshape(-1) for n in part.selection]))] = 0
    elif part.selector == "vertices":
        listed = np.asarray(part.selection, dtype=np.int64)
        index = mesh.file_index if mesh.file_index is not None else np.arange(len(design))
        if listed.max() >= len(index):
            raise ValueError(f"{part.label()}: vertex {int(listed.max())} does not exist (the file lists {len(index)})")
        welded = index[listed]
        if (welded < 0).any():
            raise ValueError(f"{part.label()}: vertex {int(listed[welded < 0][0])} is on no triangle of the mesh")
        labels[welded] = 0
    else:
        for k, box in reversed(list(enumerate(part.selection))):
            inside = ((design >= np.asarray(box[:3])) & (design <= np.asarray(box[3:]))).all(axis=1)
            if not inside.any() and len(part.selection) > 1:  # one box of several that holds nothing: a typo
                raise ValueError(f"{part.label()}: its box {k + 1} of {len(part.selection)} selects no vertex")
            labels[inside] = k
    if (labels < 0).all():
        low, high = design.min(axis=0), design.max(axis=0)
        bounds = ", ".join(f"{a:.3g}..{b:.3g}" for a, b in zip(low, high, strict=True))
        raise ValueError(
            f"{part.label()} selects no vertex of the mesh (its vertices span x, y, z = {bounds} m in the design's "
            "own coordinates)"
        )
    return labels


def parts_schema() -> dict:
    """The JSON Schema of ``[[mesh.parts]]`` (for ``warpsim schema``): an array of tables, each a ``kind`` and its
    keys."""
    types = {
        "number>=0": {"type": "number", "minimum": 0},
        "number>0": {"type": "number", "exclusiveMinimum": 0},
        "bool": {"type": "boolean"},
        "count": {"type": "integer", "minimum": 1, "maximum": MAX_SEGMENTS},
        "xy": {"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2},
        "xyz": {"type": "array", "items": {"type": "number"}, "minItems": 3, "maxItems": 3},
    }
    properties: dict = {
        "kind": {"enum": list(_KEYS)},
        "group": {"anyOf": [{"type": "string"}, {"type": "array", "items": {"type": "string"}, "minItems": 1}]},
        "vertices": {"type": "array", "items": {"type": "integer", "minimum": 0}, "minItems": 1},
        "box": {
            "anyOf": [
                {"type": "array", "items": {"type": "number"}, "minItems": 6, "maxItems": 6},
                {
                    "type": "array",
                    "minItems": 1,
                    "items": {"type": "array", "items": {"type": "number"}, "minItems": 6, "maxItems": 6},
                },
            ]
        },
    }
    required = [
        {
            "if": {"properties": {"kind": {"const": kind}}},
            "then": {"required": [k for k, (_, d) in keys.items() if d == "required"]},
        }
        for kind, keys in _KEYS.items()
        if any(d == "required" for _, d in keys.values())
    ]
    for keys in _KEYS.values():
        for key, (kind_of, _) in keys.items():
            properties.setdefault(key, types[kind_of])
    return {
        "type": "array",
        "items": {
            "type": "object",
            "required": ["kind"],
            "properties": properties,
            "additionalProperties": False,
            "allOf": required,
        },
    }
