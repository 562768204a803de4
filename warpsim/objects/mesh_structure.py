"""A mesh design's whole model beyond its triangles (``mesh.structure``): what ``warpsim export`` writes beside a
built-in object's mesh so that the object flies from the files as it flies built in.

A mesh file holds triangles and their groups. A built-in object is more than its cloth: particles off it (a pilot, a
control bar, a rope, suspension lines, a rigid frame's virtual particles), sticks of their own weights, compliances,
pretensions and rest lengths, each particle's own mass, each triangle's ``sail`` coefficients, leading edge and
loading, drag bodies, a canopy's whole-canopy air, lifting surfaces, bending hinges and nails. The structure file is
a TOML file that lists all of them, by particle:

* particles ``0 .. V-1`` are the mesh's vertices as warpsim reads it (the numbering ``[[mesh.parts]]`` ``vertices``
  use), and ``V ..`` the structure's own ``points``, in the design's own coordinates [m];
* per-triangle lists follow the mesh's triangles as warpsim reads them;
* a stick's rest length is given over its length as placed, so that a mesh whose vertices were moved in a CAD tool
  (the same vertices and triangles, reshaped) is at rest in its new shape; each particle keeps its mass as written.

With a structure, the design's cloth gets no stick, mass or air of its own from ``[mesh]``: the structure holds each.
It is checked against the mesh when the scene is built: a mesh whose vertex or triangle count changed since the
export (edited in a CAD tool) is refused in one line, since the structure's lists would no longer fit it.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import tomllib

FORMAT = 2
"""The structure file's format version (``format`` in it; 2 added ``[faces]``, the mesh's triangles as written)."""


class StructureError(ValueError):
    """A structure file that does not fit its mesh or holds a bad value; the message is one line naming the file."""


@dataclass
class Structure:
    """A design's model beyond its triangles, as read from a structure file (``P`` particles: the mesh's ``V``
    vertices, then ``points``; ``S`` sticks; ``T`` triangles).

    Attributes:
        vertices, triangles: the mesh's vertex and triangle counts it was written for.
        corners: ``[T, 3]`` each triangle's vertices as the mesh was written and reads back, so that a mesh whose
            triangles were reordered or renumbered since (a CAD tool may) is refused rather than given other
            triangles' air.
        points: ``[P - V, 3]`` the particles off the mesh, in the design's coordinates [m].
        velocity: ``[P, 3]`` every particle's velocity at the start [m/s], in the design's axes.
        mass: ``[P]`` every particle's mass [kg] (0 for a nailed particle: it does not move).
        nails: ``[N]`` the nailed particles; nail_targets: ``[N, 3]`` where each is held (design coordinates) [m].
        drag: ``[D]`` the drag bodies' particles; drag_area: ``[D]`` their ``C_D A`` [m^2].
        sticks: ``[S, 2]`` particle pairs; rest (each stick's rest length over its length as placed: 1 for a stick
            at rest as built, less for a pretensioned one, so that a mesh reshaped in a CAD tool is at rest in its new
            shape), weight, compliance [m/N at weight 1], pretension (the share the stick was shortened by as built,
            as it is reported): ``[S]`` each.
        sail: ``[T, 4]`` the ``sail`` law's coefficients (lift slope [1/rad], induced-drag factor, profile drag, stall
            angle [rad]); leading_edge: ``[T, 2]`` the particles of the leading edge each triangle sits behind (-1:
            none); loading: ``[T]`` the chordwise loading factors.
        canopies: each ``(triangles, table [37, 2], axis [3], wake_lag)``: a whole-canopy air law.
        surfaces: each ``(triangles, trailing [k, 2] particle pairs)``: a lifting surface of the ``vortex`` law.
        hinges: ``[H, 4]`` particles, hinge_weights ``[H, 4]``, hinge_stiffness ``[H]`` [N/m]: bending stencils.
        tow: the particle the line hangs from (-1: no line); anchor_nail: its ground end's nail (-1); chain: the
            line's particles from the anchor up; line_drag: the line has drag. payload: the swing's point mass (-1).
        parts, stick_groups, curves: the object's named particle, stick and line sets, for outputs and ``info``.
        control_sticks: ``[C]`` the sticks the ``pitch`` and ``roll`` controls set (a pilot's arms); control_grid:
            ``[G]`` the control values both are sampled at (from -1 to 1); control_rest: ``[C, G, G]`` each stick's
            rest length over its length as placed at (pitch, roll) on the grid, read between by bilinear
            interpolation.
    """

    vertices: int
    triangles: int
    corners: np.ndarray
    points: np.ndarray
    velocity: np.ndarray
    mass: np.ndarray
    nails: np.ndarray
    nail_targets: np.ndarray
    drag: np.ndarray
    drag_area: np.ndarray
    sticks: np.ndarray
    rest: np.ndarray
    weight: np.ndarray
    compliance: np.ndarray
    pretension: np.ndarray
    sail: np.ndarray
    leading_edge: np.ndarray
    loading: np.ndarray
    canopies: list = field(default_factory=list)
    surfaces: list = field(default_factory=list)
    hinges: np.ndarray = field(default_factory=lambda: np.zeros((0, 4), dtype=np.int64))
    hinge_weights: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))
    hinge_stiffness: np.ndarray = field(default_factory=lambda: np.zeros(0))
    tow: int = -1
    anchor_nail: int = -1
    chain: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    line_drag: bool = False
    payload: int = -1
    parts: dict = field(default_factory=dict)
    stick_groups: dict = field(default_factory=dict)
    curves: dict = field(default_factory=dict)
    control_sticks: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    control_grid: np.ndarray = field(default_factory=lambda: np.zeros(0))
    control_rest: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 0)))

    @property
    def particle_count(self) -> int:
        return self.vertices + len(self.points)

    def as_toml(self) -> dict:
        """The structure as the plain tables of its file (:func:`read_structure` reads them back)."""

        def plain(a):
            return np.asarray(a).tolist()

        out = {
            "format": FORMAT,
            "vertices": self.vertices,
            "triangles": self.triangles,
            "faces": {"corners": plain(self.corners)},
            "points": {"position": plain(self.points)},
            "particles": {"mass": plain(self.mass), "velocity": plain(self.velocity)},
            "nails": {"particles": plain(self.nails), "targets": plain(self.nail_targets)},
            "drag": {"particles": plain(self.drag), "areas": plain(self.drag_area)},
            "sticks": {
                "ends": plain(self.sticks),
                "rest": plain(self.rest),
                "weight": plain(self.weight),
                "compliance": plain(self.compliance),
                "pretension": plain(self.pretension),
            },
            "air": {"sail": plain(self.sail), "leading_edge": plain(self.leading_edge), "loading": plain(self.loading)},
            "canopies": [
                {"triangles": plain(t), "table": plain(tab), "axis": plain(ax), "wake_lag": float(lag)}
                for t, tab, ax, lag in self.canopies
            ],
            "lifting_surfaces": [{"triangles": plain(t), "trailing": plain(tr)} for t, tr in self.surfaces],
            "hinges": {
                "particles": plain(self.hinges),
                "weights": plain(self.hinge_weights),
                "stiffness": plain(self.hinge_stiffness),
            },
            "line": {
                "tow": int(self.tow),
                "anchor_nail": int(self.anchor_nail),
                "chain": plain(self.chain),
                "drag": bool(self.line_drag),
            },
            "payload": int(self.payload),
            "parts": {k: plain(v) for k, v in self.parts.items()},
            "stick_groups": {k: plain(v) for k, v in self.stick_groups.items()},
            "curves": {k: [plain(c) for c in v] for k, v in self.curves.items()},
        }
        g = len(self.control_grid)
        out["controls"] = {  # written empty for an object without pitch and roll, so that a lost table is refused
            "sticks": plain(self.control_sticks),
            "grid": plain(self.control_grid),
            "rest": plain(np.asarray(self.control_rest).reshape(-1, g)) if g else [],  # a row per pitch, per stick
        }
        return out


_COMMENTS = {
    "faces": "each triangle's three vertices, as the mesh was written (checked against the mesh when it is read)",
    "points": "the particles off the mesh, numbered after its vertices: positions in the design's coordinates [m]",
    "particles": "every particle (the mesh's vertices, then the points): mass [kg] (0: nailed), velocity [m/s]",
    "nails": "the nailed particles and where each is held [m]",
    "drag": "the drag bodies: particle and C_D A [m^2]",
    "sticks": "particle pairs; rest: rest length over the length as placed; weight; compliance [m/N] at weight 1; "
    "pretension: the share shortened as built",
    "air": "per triangle: sail law (lift slope [1/rad], induced-drag factor, profile drag, stall [rad]), leading "
    "edge (particles, -1: none), chordwise loading",
    "canopies": "whole-canopy air laws: triangles, table (C_T, C_N on the nominal area at 0, 5, ... 180 deg), axis "
    "(any length: the direction from the canopy's mouth to its apex, in the design's axes), wake lag (the side "
    "force's lag, in canopy diameters travelled)",
    "lifting_surfaces": "the vortex law's surfaces: triangles and trailing edges (particle pairs)",
    "hinges": "bending stencils: four particles, their weights and a stiffness [N/m]",
    "line": "the line: the particle it hangs from, its anchor's nail, its particles from the anchor up, its drag",
    "parts": "named particle sets (for outputs and warpsim info)",
    "stick_groups": "named stick sets",
    "curves": "chains of particles drawn as lines",
    "controls": "the sticks pitch and roll set: their rest over their length as placed, a row of roll values per "
    "pitch value of the grid, stick after stick",
}


def _value(v) -> str:
    """One TOML value: a number, a bool, a string or a list of them (one line)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        return f"{float(v):.12g}"  # 12 digits: a picometre in a kilometre, a rest ratio to 1e-12
    if isinstance(v, str):
        import tomli_w

        return tomli_w.dumps({"x": v})[4:].strip()
    return "[" + ", ".join(_value(x) for x in v) + "]"


_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def _key(name: str) -> str:
    """``name`` as a TOML key: bare when it can be, quoted otherwise (a part called ``left tip`` or ``a.b``)."""
    return name if _BARE_KEY.fullmatch(name) else _value(str(name))


def _key_lines(key: str, v) -> list[str]:
    """``key = v``, a list of lists one row per line, a long flat list wrapped."""
    key = _key(key)
    if isinstance(v, list) and v and isinstance(v[0], list):
        return [f"{key} = ["] + [f"    {_value(row)}," for row in v] + ["]"]
    text = f"{key} = {_value(v)}"
    if len(text) <= 118 or not isinstance(v, list):
        return [text]
    lines, line = [f"{key} = ["], "   "
    for x in v:
        word = f" {_value(x)},"
        if len(line) + len(word) > 118:
            lines.append(line)
            line = "   "
        line += word
    return [*lines, line, "]"]


def structure_text(structure: Structure, header: str = "") -> str:
    """The structure file's text (TOML, read back by :func:`read_structure`): its tables with a comment each, lists
    of rows one row per line; ``header`` (comment lines) first."""
    tables = structure.as_toml()
    lines = [header.rstrip("\n")] if header else []
    lines += [
        "# vertices, triangles: the mesh this was written for; payload: the particle whose swing is measured (-1: none)"
    ]
    # plain keys and empty lists of tables first: a key written after a [table] header would belong to that table
    lines += [f"{k} = {_value(v)}" for k, v in tables.items() if not isinstance(v, (dict, list)) or v == []]
    for name, table in tables.items():
        if isinstance(table, dict):
            lines += ["", f"# {_COMMENTS[name]}", f"[{name}]"]
            for key, v in table.items():
                lines += _key_lines(key, v)
        elif isinstance(table, list):
            if not table:
                continue
            lines += ["", f"# {_COMMENTS[name]}"]
            for entry in table:
                lines.append(f"[[{name}]]")
                for key, v in entry.items():
                    lines += _key_lines(key, v)
    return "\n".join(lines) + "\n"


_TABLES = {
    "faces": ("corners",),
    "points": ("position",),
    "particles": ("mass", "velocity"),
    "nails": ("particles", "targets"),
    "drag": ("particles", "areas"),
    "sticks": ("ends", "rest", "weight", "compliance", "pretension"),
    "air": ("sail", "leading_edge", "loading"),
    "hinges": ("particles", "weights", "stiffness"),
    "line": ("tow", "anchor_nail", "chain", "drag"),
    "controls": ("sticks", "grid", "rest"),
    "parts": None,  # names of the file's choosing
    "stick_groups": None,
    "curves": None,
}
"""Each table of a structure file and its keys (None: keys named by the file)."""

_LISTS = {"canopies": ("triangles", "table", "axis", "wake_lag"), "lifting_surfaces": ("triangles", "trailing")}
"""Each list of tables (``[[canopies]]``) and its entries' keys."""

_TOP = ("format", "vertices", "triangles", "payload")
"""The file's plain top-level keys."""


def read_structure(path: str | Path, vertices: int | None = None, triangles: int | None = None) -> Structure:
    """Read and check the structure file ``path``, written for a mesh of ``vertices`` and ``triangles`` (when given:
    :func:`fits`); :class:`StructureError` with one line naming the file and key on a missing file, bad TOML, a
    missing or unknown table or key, a value of the wrong type, a list of the wrong length or an index out of
    range."""
    path = Path(path)
    if path.is_dir():
        raise StructureError(f"{path}: is a folder, not a structure file (mesh.structure)")
    if not path.is_file():
        raise StructureError(f"{path}: structure file not found (mesh.structure)")
    try:
        with open(path, "rb") as f:
            data = tomllib.load(f)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
        raise StructureError(f"{path}: not a structure file: {str(err).splitlines()[0]}") from None
    except OSError as err:
        raise StructureError(f"{path}: cannot be read: {err.strerror or err}") from None
    except RecursionError:
        raise StructureError(f"{path}: not a structure file: its lists are nested too deep") from None
    if "format" not in data:
        raise StructureError(f"{path}: no format = {FORMAT} line; is it a structure file written by warpsim export?")
    if type(data["format"]) is not int or data["format"] != FORMAT:
        raise StructureError(
            f"{path}: format = {data['format']!r}; this warpsim reads structure format {FORMAT} (the integer): "
            "re-export the design with warpsim export"
        )
    try:
        _check_layout(data)
        if vertices is not None and triangles is not None:
            written = (_integer(data["vertices"], "vertices", 3), _integer(data["triangles"], "triangles", 1))
            fits(written, vertices, triangles, str(path))
        return _structure_of(data)
    except StructureError:
        raise
    except (TypeError, ValueError) as err:
        raise StructureError(f"{path}: {str(err).strip()}") from None
    except RecursionError:
        raise StructureError(f"{path}: its lists are nested too deep") from None


def _check_layout(data: dict) -> None:
    """Refuse (``ValueError``, one line) a missing or unknown table or key, with the closest name."""
    import difflib

    known = set(_TABLES) | set(_LISTS) | set(_TOP)
    for key in data:
        if key not in known:
            close = difflib.get_close_matches(key, sorted(known), n=1)
            raise ValueError(f"unknown table or key {key!r}" + (f" (did you mean {close[0]!r}?)" if close else ""))
    for key in (*_TOP, *_TABLES, *_LISTS):
        if key not in data:
            raise ValueError(f"it has no {key!r} (the export writes every table; re-export the design)")
    for name, keys in _TABLES.items():
        if name not in data:
            continue
        if not isinstance(data[name], dict):
            raise ValueError(f"{name} must be a table ([{name}])")
        if keys is not None:
            _check_keys(name, data[name], keys)
    for name, keys in _LISTS.items():
        if not isinstance(data[name], list) or not all(isinstance(e, dict) for e in data[name]):
            raise ValueError(f"{name} must be a list of tables ([[{name}]])")
        for k, entry in enumerate(data[name]):
            _check_keys(f"{name} ({k + 1})", entry, keys)


def _check_keys(name: str, table: dict, keys: tuple) -> None:
    import difflib

    for key in table:
        if key not in keys:
            close = difflib.get_close_matches(key, keys, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise ValueError(f"{name}: unknown key {key!r}{hint}; its keys are {', '.join(keys)}")
    for key in keys:
        if key not in table:
            raise ValueError(f"{name} has no {key!r}")


def _integer(value, name: str, low: int = -1) -> int:
    """``value`` as an int of at least ``low``; ``ValueError`` naming ``name`` otherwise."""
    if type(value) is not int or value < low:
        raise ValueError(f"{name} must be a whole number of at least {low}, got {value!r}")
    return value


def _holds_bool(values) -> bool:
    """Whether the (nested) list ``values`` holds a ``true`` or ``false`` anywhere."""
    if isinstance(values, bool):
        return True
    return isinstance(values, list) and any(_holds_bool(v) for v in values)


def _array(table: dict, key: str, dtype, shape: tuple, name: str) -> np.ndarray:
    """``table[key]`` (the file's ``name.key``) as an array of ``dtype`` (whole numbers for an integer one) with
    ``shape`` (``-1``: any length); an empty list fits any."""
    values = table[key]
    integer = np.issubdtype(dtype, np.integer)
    want = "a list of shape (" + ", ".join("any" if n == -1 else str(n) for n in shape) + ")"
    kind = "whole numbers" if integer else "numbers"
    try:
        raw = np.asarray(values)
    except ValueError:
        raise ValueError(f"{name}.{key} must be {want} of {kind}") from None
    if raw.size and (raw.dtype.kind not in ("iu" if integer else "iuf") or _holds_bool(values)):
        raise ValueError(f"{name}.{key} must be {want} of {kind}")  # NumPy would read true/false as 1/0
    a = raw.astype(dtype)
    if a.size == 0 and a.shape[:1] == (0,):  # an empty list: no rows, which a list of a set length must allow
        if shape[0] not in (-1, 0):
            raise ValueError(f"{name}.{key} must be {want}, got an empty list")
        return np.zeros((0, *shape[1:]), dtype=dtype)
    if a.ndim != len(shape) or any(s not in (-1, n) for s, n in zip(shape, a.shape, strict=True)):
        raise ValueError(f"{name}.{key} must be {want}, got {a.shape}")
    if not np.isfinite(a).all():
        raise ValueError(f"{name}.{key} holds a value that is not finite")
    return a


def _structure_of(data: dict) -> Structure:
    """The :class:`Structure` of a structure file's tables ``data`` (their layout checked by :func:`_check_layout`),
    its types, lengths and indices checked."""
    v, t = _integer(data["vertices"], "vertices", 3), _integer(data["triangles"], "triangles", 1)
    points = _array(data["points"], "position", np.float64, (-1, 3), "points")
    p = v + len(points)
    particles, sticks, air = data["particles"], data["sticks"], data["air"]
    s = Structure(
        vertices=v,
        triangles=t,
        corners=_array(data["faces"], "corners", np.int64, (t, 3), "faces"),
        points=points,
        velocity=_array(particles, "velocity", np.float64, (p, 3), "particles"),
        mass=_array(particles, "mass", np.float64, (p,), "particles"),
        nails=_array(data["nails"], "particles", np.int64, (-1,), "nails"),
        nail_targets=_array(data["nails"], "targets", np.float64, (-1, 3), "nails"),
        drag=_array(data["drag"], "particles", np.int64, (-1,), "drag"),
        drag_area=_array(data["drag"], "areas", np.float64, (-1,), "drag"),
        sticks=_array(sticks, "ends", np.int64, (-1, 2), "sticks"),
        rest=_array(sticks, "rest", np.float64, (-1,), "sticks"),
        weight=_array(sticks, "weight", np.float64, (-1,), "sticks"),
        compliance=_array(sticks, "compliance", np.float64, (-1,), "sticks"),
        pretension=_array(sticks, "pretension", np.float64, (-1,), "sticks"),
        sail=_array(air, "sail", np.float64, (t, 4), "air"),
        leading_edge=_array(air, "leading_edge", np.int64, (t, 2), "air"),
        loading=_array(air, "loading", np.float64, (t,), "air"),
    )
    if len(s.mass) != p or len(s.velocity) != p:
        raise ValueError(f"particles.mass and particles.velocity need one entry for each of the {p} particles")
    if len(s.sail) != t or len(s.leading_edge) != t or len(s.loading) != t:
        raise ValueError(f"air.sail, air.leading_edge and air.loading need one entry for each of the {t} triangles")
    from ..physics.kernels.canopy import TABLE_ROWS

    for k, c in enumerate(data["canopies"]):
        axis = _array(c, "axis", np.float64, (3,), f"canopies ({k + 1})")
        lag = c["wake_lag"]
        if type(lag) not in (int, float) or not 0.0 <= lag < 100.0:
            raise ValueError(f"canopies ({k + 1}).wake_lag must be a number from 0 to 100, got {lag!r}")
        if not np.linalg.norm(axis) > 0.0:
            raise ValueError(f"canopies ({k + 1}).axis must point from the canopy's mouth to its apex, not be 0")
        table = _array(c, "table", np.float64, (TABLE_ROWS, 2), f"canopies ({k + 1})")
        s.canopies.append((_array(c, "triangles", np.int64, (-1,), f"canopies ({k + 1})"), table, axis, float(lag)))
    for k, surface in enumerate(data["lifting_surfaces"]):
        s.surfaces.append(
            (
                _array(surface, "triangles", np.int64, (-1,), f"lifting_surfaces ({k + 1})"),
                _array(surface, "trailing", np.int64, (-1, 2), f"lifting_surfaces ({k + 1})"),
            )
        )
    hinges = data["hinges"]
    s.hinges = _array(hinges, "particles", np.int64, (-1, 4), "hinges")
    s.hinge_weights = _array(hinges, "weights", np.float64, (len(s.hinges), 4), "hinges")
    s.hinge_stiffness = _array(hinges, "stiffness", np.float64, (len(s.hinges),), "hinges")
    line = data["line"]
    s.tow, s.anchor_nail = _integer(line["tow"], "line.tow"), _integer(line["anchor_nail"], "line.anchor_nail")
    s.chain = _array(line, "chain", np.int64, (-1,), "line")
    if type(line["drag"]) is not bool:
        raise ValueError(f"line.drag must be true or false, got {line['drag']!r}")
    s.line_drag = line["drag"]
    if (s.tow >= 0) != (s.anchor_nail >= 0) or (s.tow >= 0 and len(s.chain) < 2):
        raise ValueError(
            "a line needs its tow, its anchor_nail and a chain of two particles or more (all -1/empty: none)"
        )
    s.payload = _integer(data["payload"], "payload")
    s.parts = {str(k): _array(data["parts"], k, np.int64, (-1,), "parts") for k in data["parts"]}
    s.stick_groups = {
        str(k): _array(data["stick_groups"], k, np.int64, (-1,), "stick_groups") for k in data["stick_groups"]
    }
    s.curves = {}
    for k, chains in data["curves"].items():
        if not isinstance(chains, list):
            raise ValueError(f"curves.{k} must be a list of particle lists")
        s.curves[str(k)] = [_array({k: c}, k, np.int64, (-1,), "curves").tolist() for c in chains]
    controls = data["controls"]
    s.control_sticks = _array(controls, "sticks", np.int64, (-1,), "controls")
    s.control_grid = _array(controls, "grid", np.float64, (-1,), "controls")
    g = len(s.control_grid)
    if not g and controls["rest"] != []:
        raise ValueError("controls.rest must be empty when controls.grid is (no controls)")
    s.control_rest = (
        _array(controls, "rest", np.float64, (len(s.control_sticks) * g, g), "controls").reshape(-1, g, g)
        if g
        else s.control_rest
    )
    if len(s.control_rest) != len(s.control_sticks):
        raise ValueError("controls.rest needs a grid of rows for each of controls.sticks")
    if len(s.control_sticks) and (g < 2 or s.control_grid[0] != -1.0 or s.control_grid[-1] != 1.0):
        raise ValueError("controls.grid must run from -1 to 1 in two values or more")
    if len(s.control_sticks) and (np.diff(s.control_grid) <= 0).any():
        raise ValueError("controls.grid must increase")
    if len(s.control_sticks) and (s.control_sticks.min() < 0 or s.control_sticks.max() >= len(s.sticks)):
        raise ValueError(f"controls.sticks must name sticks among 0..{len(s.sticks) - 1}")
    if (s.control_rest <= 0).any():
        raise ValueError("controls.rest must be positive")
    _check(s)
    return s


def _check(s: Structure) -> None:
    """Refuse lists of unequal lengths and particle or triangle indices out of range (``ValueError``, one line)."""
    n_sticks = len(s.sticks)
    for key in ("rest", "weight", "compliance", "pretension"):
        if len(getattr(s, key)) != n_sticks:
            raise ValueError(f"sticks.{key} has {len(getattr(s, key))} values for {n_sticks} sticks")
    if len(s.nail_targets) != len(s.nails) or len(s.drag_area) != len(s.drag):
        raise ValueError("nails.targets and drag.areas must have one entry per nailed particle and drag body")
    p = s.particle_count
    particle_lists = {
        "sticks.ends": s.sticks,
        "nails.particles": s.nails,
        "drag.particles": s.drag,
        "hinges.particles": s.hinges,
        "line.chain": s.chain,
        "air.leading_edge": s.leading_edge[s.leading_edge[:, 0] >= 0] if len(s.leading_edge) else s.leading_edge,
        **{f"parts.{k}": v for k, v in s.parts.items()},
        **{f"curves.{k}": np.asarray([i for c in v for i in c], dtype=np.int64) for k, v in s.curves.items()},
        **{f"lifting_surfaces.trailing ({k + 1})": tr for k, (_, tr) in enumerate(s.surfaces)},
    }
    for key, ids in particle_lists.items():
        if len(ids) and (ids.min() < 0 or ids.max() >= p):
            raise ValueError(
                f"{key} names particle {int(ids.max() if ids.max() >= p else ids.min())}, not among 0..{p - 1}"
            )
    for key, ids in {
        **{f"canopies ({k + 1}).triangles": c[0] for k, c in enumerate(s.canopies)},
        **{f"lifting_surfaces ({k + 1}).triangles": f[0] for k, f in enumerate(s.surfaces)},
    }.items():
        if len(ids) == 0 or ids.min() < 0 or ids.max() >= s.triangles:
            raise ValueError(f"{key} must name triangles among 0..{s.triangles - 1}")
    if len(s.corners) and (s.corners.min() < 0 or s.corners.max() >= s.vertices):
        raise ValueError(f"faces.corners must name vertices among 0..{s.vertices - 1}")
    if len(s.leading_edge) and ((s.leading_edge[:, 0] < 0) != (s.leading_edge[:, 1] < 0)).any():
        raise ValueError("air.leading_edge: each row names two particles, or is [-1, -1] (no leading edge)")
    for key, value in (("line.tow", s.tow), ("payload", s.payload)):
        if not -1 <= value < p:
            raise ValueError(f"{key} = {value} is not a particle among 0..{p - 1} (or -1: none)")
    if not -1 <= s.anchor_nail < len(s.nails):
        raise ValueError(f"line.anchor_nail = {s.anchor_nail} is not one of the {len(s.nails)} nails (or -1: none)")
    if (s.mass < 0).any() or (np.delete(s.mass, s.nails) <= 0).any():
        raise ValueError("particles.mass must be positive for every particle that is not nailed")
    if (s.rest <= 0).any() or (s.weight <= 0).any() or (s.compliance < 0).any():
        raise ValueError("sticks need positive rest ratios and weights, and compliances >= 0")
    if (np.abs(s.pretension) >= 1.0).any():
        raise ValueError("sticks.pretension must lie between -1 and 1 (the share a stick was shortened by)")
    for k, ids in s.stick_groups.items():
        if len(ids) and (ids.min() < 0 or ids.max() >= len(s.sticks)):
            raise ValueError(f"stick_groups.{k} names a stick outside 0..{len(s.sticks) - 1}")


def fits(written: tuple[int, int], vertices: int, triangles: int, where: str) -> None:
    """Refuse (``StructureError``, one line) a structure ``written`` for a mesh of (vertices, triangles) other than
    ``vertices`` and ``triangles``."""
    if tuple(written) != (vertices, triangles):
        raise StructureError(
            f"{where}: written for a mesh of {written[0]} vertices and {written[1]} triangles, but "
            f"the mesh has {vertices} and {triangles} (edited since its export?); re-export it, or remove "
            "mesh.structure and describe the design with [[mesh.parts]]"
        )


def cyclic_corners(t: np.ndarray) -> np.ndarray:
    """Each triangle of ``t`` ``[T, 3]`` from its smallest corner, in its own cyclic order (a triangle read with its
    corners rotated, as a format conversion may, is the same triangle)."""
    start = np.argmin(t, axis=1)
    return np.stack([t[np.arange(len(t)), (start + k) % 3] for k in range(3)], axis=1)


def check_faces(structure: Structure, triangles: np.ndarray, where: str) -> None:
    """Refuse (``StructureError``, one line) a mesh whose triangles ``[T, 3]`` are not the structure's ``corners``
    (each up to a rotation of its corners): reordered since the export, turned over, or on renumbered vertices (a
    CAD tool may do any of these), since the structure's per-triangle and per-particle lists would then describe
    other triangles and vertices."""
    mesh, written = cyclic_corners(np.asarray(triangles, dtype=np.int64)), cyclic_corners(structure.corners)
    differ = np.flatnonzero((mesh != written).any(axis=1))
    if not len(differ):
        return
    k = int(differ[0])
    first = f"triangle {k} is {mesh[k].tolist()}, the structure's {written[k].tolist()}"
    if sorted(map(tuple, mesh.tolist())) == sorted(map(tuple, written.tolist())):
        why = "its triangles were reordered since the export (the same triangles in another order)"
    elif sorted(map(tuple, np.sort(mesh, axis=1).tolist())) == sorted(map(tuple, np.sort(written, axis=1).tolist())):
        why = "some of its triangles were turned over since the export (their corners in the other order)"
    else:
        why = "its vertices were renumbered or its triangles edited since the export"
    raise StructureError(
        f"{where}: {why}: {len(differ)} of {len(mesh)} triangles differ ({first}); re-export the design, or keep the "
        "file's vertex and face order"
    )
