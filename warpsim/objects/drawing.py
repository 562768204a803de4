"""Parts that pictures draw but the physics does not carry as cloth: tubes, balls and points found from the particles.

The viewer and the picture renderer draw a hang glider's keel, leading edges, control frame (A-frame and base bar),
hang strap and the pilot's body; a flag's pole; a kite's spars; a parachutist's body. Each is placed every frame
from particles that exist (the keel's and the control frame's particles, the pilot particle, the flag's nailed
column): drawing only, nothing here changes what is simulated.

Points are numbered as in the positions ``q`` ``[P, 3]``; the points this module adds (the pole's foot, the
pilot's head and feet) follow them, numbered from ``P`` (see :meth:`Shapes.points`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .style import COLOURS

TUBE = (0.30, 0.31, 0.34)  # aluminium tubes, seen against sky and grass
POLE = (0.92, 0.92, 0.88)
STRAP = (0.10, 0.10, 0.12)
HARNESS = (0.20, 0.22, 0.30)  # the pilot's pod harness
SKIN = (0.93, 0.72, 0.58)
HELMET = (0.95, 0.85, 0.10)

BODY = {"shoulders": 0.55, "head": 0.80, "feet": -1.05}
"""Where a prone pilot's shoulders, head and feet are [m] along the keel from the pilot particle (the harness's
hang point, near the pilot's centre of mass); a pilot is about 1.8 m tall."""


def _unit(v: np.ndarray) -> np.ndarray:
    return v / max(float(np.linalg.norm(v)), 1e-9)


@dataclass
class Shapes:
    """Drawn parts found from the particles.

    Attributes:
        tubes: ``(point a, point b, radius [m], rgb)``: a cylinder from a to b.
        balls: ``(point, radius [m], rgb)``.
        hidden_parts: part names whose particles these shapes draw in their place (the pilot's ball).
        particle_count: ``P``, the particles the added points follow.
    """

    particle_count: int
    tubes: list = field(default_factory=list)
    balls: list = field(default_factory=list)
    hidden_parts: set = field(default_factory=set)
    _makers: list = field(default_factory=list)  # (count, function q -> [count, 3])
    _count: int = 0

    def _add(self, count: int, make) -> int:
        """Reserve ``count`` added points made by ``make(q)``; returns the first one's number."""
        first = self.particle_count + self._count
        self._makers.append((count, make))
        self._count += count
        return first

    @property
    def added(self) -> int:
        """How many points this adds to the particles."""
        return self._count

    def points(self, q: np.ndarray) -> np.ndarray:
        """The particles' positions ``q`` ``[P, 3]`` [m] followed by the added points ``[P + added, 3]``."""
        if not self._makers:
            return q
        extra = [np.asarray(make(q), dtype=q.dtype).reshape(count, 3) for count, make in self._makers]
        return np.concatenate([q, *extra])

    def tube_indices(self) -> np.ndarray:
        """``[tubes, 2]`` end points of every tube (for bounds)."""
        return np.array([(a, b) for a, b, _, _ in self.tubes], dtype=np.int64).reshape(-1, 2)


def shapes_for(model) -> Shapes:
    """The drawn parts of every object of ``model`` (see the module notes)."""
    shapes = Shapes(model.particle_count)
    for record in model.objects:
        {"hang-glider": _glider, "flag": _flag, "kite": _kite, "parachute": _parachute}.get(record.kind, _none)(
            shapes, model, record
        )
    return shapes


def _none(shapes, model, record) -> None:
    return None


def _chain(shapes: Shapes, chain, radius: float, rgb) -> None:
    for a, b in zip(chain[:-1], chain[1:], strict=True):
        shapes.tubes.append((int(a), int(b), radius, rgb))


def _glider(shapes: Shapes, model, record) -> None:
    nose, keel, pilot = int(record.nose), [int(k) for k in record.keel], int(record.pilot)
    _chain(shapes, keel, 0.035, TUBE)  # the keel tube, nose to tail
    for tip in record.tips:  # the leading edges: rigid tubes from the nose to each tip
        shapes.tubes.append((nose, int(tip), 0.035, TUBE))
    tail = keel[-1]

    def along(offset: float):
        def make(q):
            return q[pilot] + offset * _unit(q[nose] - q[tail])

        return make

    shoulders = shapes._add(1, along(BODY["shoulders"]))
    head = shapes._add(1, along(BODY["head"]))
    feet = shapes._add(1, along(BODY["feet"]))
    shapes.tubes.append((feet, shoulders, 0.15, HARNESS))  # the pilot prone in a pod harness
    shapes.balls.append((head, 0.13, HELMET))
    frame = record.parts.get("control_frame")
    if frame is not None and len(frame) == 3:  # a hang strap: hang point on the keel, base bar's two ends
        hang, left, right = (int(p) for p in frame)
        shapes.tubes += [(hang, left, 0.025, TUBE), (hang, right, 0.025, TUBE), (left, right, 0.025, TUBE)]
        shapes.tubes.append((hang, pilot, 0.02, STRAP))  # the hang strap
        for end in (left, right):  # arms: shoulders to the bar
            shapes.tubes.append((shoulders, end, 0.045, SKIN))
    else:  # the paper's design: the pilot on control sticks to the frame, drawn as thin lines
        ends = model.stick_particles_np[np.asarray(record.control_sticks, dtype=np.int64)]
        for a, b in ends:
            shapes.tubes.append((int(a), int(b), 0.012, STRAP))
    shapes.hidden_parts.add("pilot")


def _flag(shapes: Shapes, model, record) -> None:
    pole = np.asarray(record.parts["pole"], dtype=np.int64)
    terrain = model.terrain

    def foot(q):
        x, y = q[pole].mean(axis=0)[:2]
        return np.array([x, y, float(terrain.height(x, y))])

    def top(q):
        p = q[pole].mean(axis=0)
        return np.array([p[0], p[1], float(q[pole][:, 2].max()) + 0.12])

    a, b = shapes._add(1, foot), shapes._add(1, top)
    shapes.tubes.append((a, b, 0.04, POLE))
    shapes.balls.append((b, 0.07, (0.85, 0.70, 0.20)))  # the finial


def _kite(shapes: Shapes, model, record) -> None:
    nose = int(record.nose)
    for tip in record.tips:  # the leading-edge spars
        shapes.tubes.append((nose, int(tip), 0.012, TUBE))
    _chain(shapes, [int(s) for s in record.spine], 0.012, TUBE)


def _parachute(shapes: Shapes, model, record) -> None:
    person = int(record.person)
    canopy = np.asarray(record.parts["canopy"], dtype=np.int64)

    def along(offset: float):
        def make(q):  # down the lines: from the canopy's centre through the person
            return q[person] + offset * _unit(q[person] - q[canopy].mean(axis=0))

        return make

    head = shapes._add(1, along(0.25))
    hips = shapes._add(1, along(1.0))
    shoulders = shapes._add(1, along(0.45))
    feet = shapes._add(1, along(1.75))
    shapes.balls.append((head, 0.12, HELMET))
    suit = COLOURS["person"]
    shapes.tubes += [(shoulders, hips, 0.16, suit), (hips, feet, 0.08, suit)]
    shapes.hidden_parts.add("person")
