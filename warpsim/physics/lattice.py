"""The topology of a vortex lattice on a sail's triangles (host side, NumPy): which edges carry a net circulation,
which panels they separate, which edges shed the wake, and which particles receive each edge's force.

Every triangle of a lifting surface is one panel carrying a vortex ring along its three edges, oriented as the
triangle (``a -> b -> c``, right-handed about its normal ``(b - a) x (c - b)``). An edge shared by two panels carries
the difference of their circulations; an edge on the sail's boundary carries its one panel's, except a trailing
edge, where the wake takes the circulation over (the Kutta condition): there the wake's downwash loads it with the
induced drag instead. See
:mod:`warpsim.physics.kernels.vortex` for the law itself.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

TRAILING = -2
"""``Lattice.edge_panels[:, 1]`` of a trailing edge."""


@dataclass(frozen=True)
class Lattice:
    """The vortex lattice of all lifting surfaces of a model (``V`` panels, ``E`` edges, ``S`` surfaces).

    Attributes:
        panel_tri: ``[V]`` triangle index of each panel; a surface's panels are contiguous.
        panel_surface: ``[V]`` surface of each panel.
        panel_trailing: ``[V]`` bit ``e`` set when the panel's edge ``e`` (from corner ``e`` to corner ``e + 1``)
            is a trailing edge.
        surface_start: ``[S + 1]`` offsets of each surface's panels.
        surface_origin: ``[S]`` a particle of each surface: positions are measured from it in float32.
        matrix_start: ``[S + 1]`` offsets of each surface's ``N_s x N_s`` influence matrix in one flat array.
        edge_panels: ``[E, 2]`` the panel on whose ring the edge runs forward (its circulation counts +) and the
            panel on whose ring it runs backward (-), or -1 on the sail's boundary, or :data:`TRAILING` on a
            trailing edge (loaded by the wake's downwash: the induced drag).
        edge_corner: ``[E]`` the edge's index ``e`` in its first panel (it runs from that panel's corner ``e`` to
            ``e + 1``).
        edge_particles: ``[E, 2]`` the edge's particles, in its first panel's direction.
        edge_opposite: ``[E, 2]`` the corner of each of its two panels off the edge (-1: no second panel).
        particle_edge_start, particle_edge_refs: CSR of ``4 * edge + role`` at each particle (``[P + 1]``, at most
            ``[4 E]``): role 0 and 1 the edge's particles, 2 and 3 its panels' far corners.
    """

    panel_tri: np.ndarray
    panel_surface: np.ndarray
    panel_trailing: np.ndarray
    surface_start: np.ndarray
    surface_origin: np.ndarray
    matrix_start: np.ndarray
    edge_panels: np.ndarray
    edge_corner: np.ndarray
    edge_particles: np.ndarray
    edge_opposite: np.ndarray
    particle_edge_start: np.ndarray
    particle_edge_refs: np.ndarray

    @property
    def panel_count(self) -> int:
        return len(self.panel_tri)

    @property
    def surface_count(self) -> int:
        return len(self.surface_start) - 1

    @property
    def edge_count(self) -> int:
        return len(self.edge_corner)


def surface_edges(tris: np.ndarray) -> dict[tuple[int, int], list[tuple[int, int]]]:
    """Every undirected edge ``(min, max)`` of triangles ``tris`` ``[n, 3]`` -> the ``(triangle row, corner)`` pairs
    that hold it, in triangle order."""
    edges: dict[tuple[int, int], list[tuple[int, int]]] = {}
    for row, tri in enumerate(np.asarray(tris, dtype=np.int64)):
        for e in range(3):
            a, b = int(tri[e]), int(tri[(e + 1) % 3])
            edges.setdefault((min(a, b), max(a, b)), []).append((row, e))
    return edges


def check_surface(tris: np.ndarray, trailing: np.ndarray) -> None:
    """Refuse a lifting surface that cannot carry a lattice, with one line: no panels, no trailing edge, an edge
    held by more than two panels, a trailing edge that is not on the boundary, or two panels of opposite
    orientation across an edge."""
    tris = np.asarray(tris, dtype=np.int64).reshape(-1, 3)
    if len(tris) == 0:
        raise ValueError("a lifting surface needs at least one triangle")
    trailing = np.asarray(trailing, dtype=np.int64).reshape(-1, 2)
    if len(trailing) == 0:
        raise ValueError("a lifting surface needs a trailing edge (where its wake leaves the sail)")
    edges = surface_edges(tris)
    for key, held in edges.items():
        if len(held) > 2:
            raise ValueError(f"edge {key} of a lifting surface is shared by {len(held)} triangles (at most 2)")
        if len(held) == 2:
            (r0, e0), (r1, e1) = held
            if tris[r0][e0] == tris[r1][e1]:  # both run a -> b: the two panels face opposite ways
                raise ValueError(f"the triangles either side of edge {key} of a lifting surface face opposite ways")
    for a, b in trailing:
        held = edges.get((min(a, b), max(a, b)))
        if held is None:
            raise ValueError(f"trailing edge ({a}, {b}) is not an edge of the lifting surface")
        if len(held) != 1:
            raise ValueError(f"trailing edge ({a}, {b}) is inside the lifting surface, not on its boundary")


def build_lattice(
    tri_indices: np.ndarray, surfaces: list[tuple[np.ndarray, np.ndarray]], particle_count: int
) -> Lattice:
    """The :class:`Lattice` of ``surfaces`` (each ``(triangle ids, trailing edges [k, 2] particle pairs)``) on a
    model's triangles ``tri_indices`` ``[T, 3]`` with ``particle_count`` particles."""
    panel_tri, panel_surface, panel_trailing, start, origin, matrix = [], [], [], [0], [], [0]
    edge_panels, edge_corner, edge_particles, edge_opposite = [], [], [], []
    for s, (tri_ids, trailing) in enumerate(surfaces):
        tri_ids = np.asarray(tri_ids, dtype=np.int64)
        tris = tri_indices[tri_ids]
        trailing_set = {(min(int(a), int(b)), max(int(a), int(b))) for a, b in np.asarray(trailing).reshape(-1, 2)}
        first = start[-1]
        for row, t in enumerate(tri_ids):
            bits = 0
            for e in range(3):
                a, b = int(tris[row][e]), int(tris[row][(e + 1) % 3])
                if (min(a, b), max(a, b)) in trailing_set:
                    bits |= 1 << e
            panel_tri.append(int(t))
            panel_surface.append(s)
            panel_trailing.append(bits)
        for key, held in surface_edges(tris).items():
            row, e = held[0]
            other = first + held[1][0] if len(held) == 2 else (TRAILING if key in trailing_set else -1)
            edge_panels.append((first + row, other))
            edge_corner.append(e)
            edge_particles.append((int(tris[row][e]), int(tris[row][(e + 1) % 3])))
            edge_opposite.append(
                (int(tris[row][(e + 2) % 3]), int(tris[held[1][0]][(held[1][1] + 2) % 3]) if len(held) == 2 else -1)
            )
        start.append(first + len(tri_ids))
        origin.append(int(tris[0][0]))
        matrix.append(matrix[-1] + len(tri_ids) ** 2)
    edge_particles = np.array(edge_particles, dtype=np.int32).reshape(-1, 2)
    edge_opposite = np.array(edge_opposite, dtype=np.int32).reshape(-1, 2)
    # each edge's force reaches its two particles (roles 0, 1) and the far corner of either panel (roles 2, 3)
    ends = np.concatenate([edge_particles, edge_opposite], axis=1).reshape(-1)
    refs = np.arange(len(ends), dtype=np.int32)  # 4 * edge + role
    refs, ends = refs[ends >= 0], ends[ends >= 0]
    order = np.argsort(ends, kind="stable")
    counts = np.bincount(ends, minlength=particle_count)
    return Lattice(
        panel_tri=np.array(panel_tri, dtype=np.int32),
        panel_surface=np.array(panel_surface, dtype=np.int32),
        panel_trailing=np.array(panel_trailing, dtype=np.int32),
        surface_start=np.array(start, dtype=np.int32),
        surface_origin=np.array(origin, dtype=np.int32),
        matrix_start=np.array(matrix, dtype=np.int64),
        edge_panels=np.array(edge_panels, dtype=np.int32).reshape(-1, 2),
        edge_corner=np.array(edge_corner, dtype=np.int32),
        edge_particles=edge_particles,
        edge_opposite=edge_opposite,
        particle_edge_start=np.concatenate([[0], np.cumsum(counts)]).astype(np.int32),
        particle_edge_refs=refs[order].astype(np.int32),
    )


def trailing_edges(points: np.ndarray, tris: np.ndarray, downstream, cos_limit: float = 0.5) -> np.ndarray:
    """The boundary edges of a sail (``points [P, 3]`` [m], triangles ``tris [n, 3]``) that the air leaves by when
    it flows along ``downstream`` (a direction in the sail's build frame): those whose outward normal in the sail's
    plane is within ``acos(cos_limit)`` of it (60 degrees by default: a rectangle's back edge, not its tips).
    Returns ``[k, 2]`` particle pairs."""
    points = np.asarray(points, dtype=np.float64)
    tris = np.asarray(tris, dtype=np.int64).reshape(-1, 3)
    d = np.asarray(downstream, dtype=np.float64)
    d = d / np.linalg.norm(d)
    chosen = []
    for held in surface_edges(tris).values():
        if len(held) != 1:
            continue
        row, e = held[0]
        a, b, c = points[tris[row]]
        n = np.cross(b - a, c - b)
        n /= np.linalg.norm(n)
        p, q = int(tris[row][e]), int(tris[row][(e + 1) % 3])
        outward = np.cross(points[q] - points[p], n)  # the triangle runs p -> q anticlockwise about n
        outward /= np.linalg.norm(outward)
        d_plane = d - n * (d @ n)
        norm = np.linalg.norm(d_plane)
        if norm > 0.0 and outward @ d_plane / norm >= cos_limit:
            chosen.append((p, q))
    return np.array(chosen, dtype=np.int32).reshape(-1, 2)
