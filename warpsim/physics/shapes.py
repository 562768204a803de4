"""Mesh helpers of :class:`~warpsim.physics.builder.ModelBuilder`: a rectangular cloth, a subdivided triangle (the
paper's Fig. 12) and a rope, each made of the builder's particles, sticks and triangles."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np


def edge_halves(count: int) -> np.ndarray:
    """The share of a line of ``count`` equally spaced points that each stands for: 1 inside, 1/2 at either end (the
    trapezoid rule's weights, in spacings)."""
    share = np.ones(count)
    share[[0, -1]] = 0.5
    return share


class MeshShapes:
    """The shapes a :class:`~warpsim.physics.builder.ModelBuilder` adds in one call (it provides ``add_particle``,
    ``add_stick``, ``add_triangle``, ``stick_count`` and ``tri_count``)."""

    def add_grid(
        self,
        origin,
        axis_u,
        axis_v,
        count_u: int,
        count_v: int,
        mass: float,
        vel=(0.0, 0.0, 0.0),
        shear: bool = True,
        by_area: bool = False,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """A rectangular cloth of ``count_u x count_v`` particles at ``origin + i*axis_u + j*axis_v``.

        ``axis_u``/``axis_v`` are the spacing vectors [m]; ``mass`` [kg] is the total, spread evenly over the
        particles (the paper's: the grid's edges then carry twice the cloth their area holds, its corners four times),
        or with ``by_area`` in proportion to the cloth each particle stands for (a quarter of each cell it touches).
        Sticks on the grid edges and on both diagonals of every cell (``shear``); two triangles per cell.

        Returns ``(particles [count_v, count_u], sticks, triangles)`` index arrays.
        """
        if count_u < 2 or count_v < 2:
            raise ValueError(f"a grid needs at least 2x2 particles, got {count_u}x{count_v}")
        o, du, dv = (np.asarray(a, dtype=np.float64) for a in (origin, axis_u, axis_v))
        share = np.outer(edge_halves(count_v), edge_halves(count_u)) if by_area else np.ones((count_v, count_u))
        m = mass * share / share.sum()
        ids = np.array(
            [[self.add_particle(o + i * du + j * dv, m[j, i], vel) for i in range(count_u)] for j in range(count_v)]
        )
        s0, t0 = self.stick_count, self.tri_count
        for j in range(count_v):
            for i in range(count_u):
                if i + 1 < count_u:
                    self.add_stick(ids[j, i], ids[j, i + 1])
                if j + 1 < count_v:
                    self.add_stick(ids[j, i], ids[j + 1, i])
                if i + 1 < count_u and j + 1 < count_v:
                    self.add_stick(ids[j, i], ids[j + 1, i + 1])
                    if shear:
                        self.add_stick(ids[j, i + 1], ids[j + 1, i])
                    self.add_triangle(ids[j, i], ids[j, i + 1], ids[j + 1, i + 1])
                    self.add_triangle(ids[j, i], ids[j + 1, i + 1], ids[j + 1, i])
        return ids, np.arange(s0, self.stick_count), np.arange(t0, self.tri_count)

    def add_subdivided_triangle(
        self,
        a,
        b,
        c,
        divisions: int,
        mass: float,
        vel=(0.0, 0.0, 0.0),
        shape: Callable | None = None,
        last_row: Sequence[int] | None = None,
    ) -> tuple[list[list[int]], np.ndarray, np.ndarray]:
        """A triangle A, B, C [m] cut into ``divisions**2`` small triangles (paper Fig. 12).

        Row ``r`` (0..divisions) runs from the point on AB to the point on AC at fraction ``r/divisions``
        from A; it holds ``r + 1`` particles. ``mass`` [kg] is spread evenly over the
        ``(divisions+1)(divisions+2)/2`` particles. A stick on every edge of every small triangle.
        ``shape(points [k, 3]) -> points`` may move the flat points (e.g. to twist a sail) before the
        particles and sticks are made, so that the rest lengths are those of the shaped surface.
        ``last_row`` (``divisions + 1`` existing particles, from B to C) joins the triangle to an existing
        mesh along BC: those particles are used instead of new ones (``mass`` then spreads over the new).

        Returns ``(rows, sticks, triangles)``: ``rows[r][k]`` particle indices and index arrays.
        """
        if divisions < 1:
            raise ValueError(f"a subdivided triangle needs at least 1 division, got {divisions}")
        a, b, c = (np.asarray(p, dtype=np.float64) for p in (a, b, c))
        count = (divisions + 1) * (divisions + 2) // 2
        if last_row is not None:
            if len(last_row) != divisions + 1:
                raise ValueError(f"last_row needs {divisions + 1} particles, got {len(last_row)}")
            count -= divisions + 1
        m = mass / count
        rows = []
        for r in range(divisions + 1):
            if r == divisions and last_row is not None:
                rows.append([int(p) for p in last_row])
                break
            left = a + (b - a) * (r / divisions)
            right = a + (c - a) * (r / divisions)
            points = np.array([left + (right - left) * (k / r if r else 0.0) for k in range(r + 1)])
            if shape is not None:
                points = np.asarray(shape(points), dtype=np.float64)
            rows.append([self.add_particle(p, m, vel) for p in points])
        s0, t0 = self.stick_count, self.tri_count
        for r in range(divisions):
            for k in range(r + 1):
                p, q, s = rows[r][k], rows[r + 1][k], rows[r + 1][k + 1]
                self.add_triangle(p, q, s)
                if k < r:
                    self.add_triangle(p, s, rows[r][k + 1])
                self.add_stick(p, q)
                self.add_stick(p, s)
                self.add_stick(q, s)
        return rows, np.arange(s0, self.stick_count), np.arange(t0, self.tri_count)

    def add_rope(
        self,
        start,
        end,
        count: int,
        mass: float,
        vel=(0.0, 0.0, 0.0),
        first: int | None = None,
        weight: float = 1.0,
    ) -> tuple[np.ndarray, np.ndarray]:
        """A rope of ``count`` new particles from ``start`` to ``end`` [m], sticks in a chain.

        ``mass`` [kg] is the rope's total. If ``first`` is given, the chain starts from that existing
        particle (placed at ``start``) and the ``count`` new particles follow it up to ``end``.
        ``weight`` is the sticks' weight in the constraint average (see :meth:`add_stick`).

        Returns ``(particles, sticks)`` (``particles`` includes ``first`` when given).
        """
        if count < 1:
            raise ValueError(f"a rope needs at least 1 particle, got {count}")
        start, end = np.asarray(start, dtype=np.float64), np.asarray(end, dtype=np.float64)
        m = mass / count
        ids = [] if first is None else [int(first)]
        steps = count if first is not None else max(count - 1, 1)
        offset = 1 if first is not None else 0
        for k in range(count):
            ids.append(self.add_particle(start + (end - start) * ((k + offset) / steps), m, vel))
        s0 = self.stick_count
        for p, q in zip(ids[:-1], ids[1:], strict=True):
            self.add_stick(p, q, weight=weight)
        return np.array(ids), np.arange(s0, self.stick_count)
