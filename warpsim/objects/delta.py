"""What the hang glider and the delta kite share: body axes and the rigid frame of a delta sail.

Both are built on :meth:`warpsim.ModelBuilder.add_subdivided_triangle` (rows from the nose). Their frame
is the two leading edges (first and last particle of every row) and the keel/spine (middle particle of
every even row), held rigid by virtual particles above/below the sail's centre tied to every frame
particle (paper slide 22); the cloth between stays flexible.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..physics.builder import ModelBuilder
from ..physics.kernels.aero import sail_coefficients


def body_axes(heading_deg: float, nose_up_deg: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Forward, left and up unit vectors of a body heading ``heading_deg`` (from +x towards +y) with its
    nose raised ``nose_up_deg`` above horizontal."""
    h, p = np.radians(heading_deg), np.radians(nose_up_deg)
    fwd = np.array([np.cos(h) * np.cos(p), np.sin(h) * np.cos(p), np.sin(p)])
    left = np.array([-np.sin(h), np.cos(h), 0.0])
    up = np.cross(fwd, left)
    return fwd, left, up


@dataclass
class DeltaFrame:
    """Indices of a delta sail's rigid frame.

    Attributes:
        points: frame particles (leading edges and keel), sorted.
        keel: keel particles from the nose back (middle of every even row).
        virtual: the virtual particles, in the order of ``offsets``.
        sticks: frame sticks: sail edges between frame particles, then the virtual particles' ties.
    """

    points: list[int]
    keel: list[int]
    virtual: list[int]
    sticks: list[int]


def add_rigid_frame(
    builder: ModelBuilder,
    rows: list[list[int]],
    sail_sticks,
    centre,
    up,
    offsets: tuple[float, ...],
    virtual_mass: float,
    weight: float,
    vel=(0.0, 0.0, 0.0),
) -> DeltaFrame:
    """Make the leading edges and keel of a subdivided delta sail rigid.

    Adds one virtual particle of ``virtual_mass`` [kg] at ``centre + offset * up`` [m] for each of
    ``offsets``, ties each to every frame particle and chains them; the sail's own sticks between frame
    particles and every new stick get ``weight`` in the constraint average.
    """
    n = len(rows) - 1
    leading = {r[0] for r in rows} | {r[-1] for r in rows}
    keel = [rows[r][r // 2] for r in range(0, n + 1, 2)]
    points = sorted(leading | set(keel))
    inside = set(points)
    ends = builder.stick_particles
    sticks = [int(s) for s in sail_sticks if ends[s][0] in inside and ends[s][1] in inside]
    for s in sticks:
        builder.stick_weight[s] = weight
    centre, up = np.asarray(centre, dtype=np.float64), np.asarray(up, dtype=np.float64)
    virtual = [builder.add_particle(centre + k * up, virtual_mass, vel) for k in offsets]
    q = dict(zip(virtual + points, builder.positions(virtual + points), strict=True))
    # a virtual particle in the sail plane (offset 0) lands on a keel particle when the divisions are a multiple
    # of 3 (the centroid is then a grid point): the two coincide, and a stick between them has no length
    tol = 1e-9 * max(1.0, float(np.linalg.norm(up)))
    sticks += [
        builder.add_stick(v, p, weight=weight) for v in virtual for p in points if np.linalg.norm(q[v] - q[p]) > tol
    ]
    sticks += [builder.add_stick(a, b, weight=weight) for a, b in zip(virtual[:-1], virtual[1:], strict=True)]
    return DeltaFrame(points, keel, virtual, sticks)


def add_spar_braces(builder: ModelBuilder, rows: list[list[int]], weight: float) -> list[int]:
    """Tie every leading-edge particle of a subdivided delta sail to the one two rows further back.

    A chain of short sticks bends at every joint, so under the sail's pull a leading edge bows and its
    sticks stretch while the Jacobi iterations catch up; these sticks (of ``weight`` in the constraint
    average) make each leading edge a straight rod, as a real spar is. Returns the new sticks.
    """
    sticks = []
    for edge in ([r[0] for r in rows], [r[-1] for r in rows]):
        sticks += [builder.add_stick(a, b, weight=weight) for a, b in zip(edge[:-2], edge[2:], strict=True)]
    return sticks


def chordwise_loading(
    builder: ModelBuilder, tris, nose, fwd, left, chord: float, semi_span: float, xi_min: float = 0.02
) -> np.ndarray:
    """Thin-aerofoil chordwise loading factors of a delta sail's triangles (area-weighted mean 1).

    Each triangle's centroid is placed at chord fraction ``xi`` of its chordwise strip (0 at the leading
    edge, 1 at the trailing edge; the nose at ``nose``, the trailing edge ``chord`` [m] behind it along
    ``-fwd``, the tips ``semi_span`` [m] out along ``+-left``) and gets ``sqrt((1 - xi) / xi)``, the
    flat-plate pressure difference of thin-aerofoil theory, whose centre lies at the quarter chord;
    ``xi`` is clipped to ``[xi_min, 1 - xi_min]``. The factors are scaled so that their area-weighted
    mean is 1. Returns the ``[len(tris)]`` factors (also written into the builder).
    """
    tris = np.asarray(tris, dtype=np.int64)
    corners = builder.positions(builder.triangle_particles(tris))
    d = corners.mean(axis=1) - np.asarray(nose, dtype=np.float64)
    behind = -(d @ np.asarray(fwd))
    leading = chord * np.minimum(np.abs(d @ np.asarray(left)) / semi_span, 1.0)
    xi = np.clip((behind - leading) / np.maximum(chord - leading, 1e-9), xi_min, 1.0 - xi_min)
    area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    loading = np.sqrt((1.0 - xi) / xi)
    total = float((area * loading).sum())
    loading = loading * (area.sum() / total) if total > 0.0 else np.ones_like(loading)  # a sail of no area: uniform
    builder.set_triangle_loading(tris, loading)
    return loading


def delta_sail_aero(
    builder: ModelBuilder,
    tris,
    rows: list[list[int]],
    nose,
    left,
    span: float,
    area: float,
    oswald: float,
    profile_drag: float,
    stall_deg: float,
) -> None:
    """Give a subdivided delta sail's triangles their ``sail`` air-model coefficients and leading edges.

    The coefficients are those of a wing of ``span`` [m] and ``area`` [m^2] (:func:`sail_coefficients`, unswept:
    the sweep acts through the leading edges). Each half of the sail sits behind its own leading edge (nose to
    tip); the triangles centred on the keel get the tip-to-tip line.
    """
    tris = np.asarray(tris, dtype=np.int64)
    builder.set_triangle_sail(tris, sail_coefficients(span**2 / area, 0.0, oswald, profile_drag, stall_deg))
    n = len(rows) - 1
    centres = builder.positions(builder.triangle_particles(tris)).mean(axis=1)
    side = (centres - np.asarray(nose)) @ np.asarray(left)
    tol = 1e-6 * span
    ends = np.where(
        (side > tol)[:, None],
        (rows[0][0], rows[n][0]),
        np.where((side < -tol)[:, None], (rows[0][0], rows[n][n]), (rows[n][n], rows[n][0])),
    )
    builder.set_triangle_span(tris, ends)
    # the same sail as one lifting surface of the vortex law, its wake shed from the last row (the trailing edge)
    builder.add_lifting_surface(tris, list(zip(rows[n][:-1], rows[n][1:], strict=True)))
