"""A plain NumPy version of warpsim's vortex-lattice air law (:mod:`warpsim.physics.kernels.vortex`), for the tests.

The same lattice, wake, cut-off core, solve, Kutta-Joukowski edge forces and section polar, written with whole-array
NumPy operations in float64 and ``np.linalg.solve`` (LAPACK's LU with partial pivoting) instead of the kernels'
float32 and their own elimination: the two agree to float32 rounding, which the tests check. It takes from the model
only the surfaces as declared (their triangles and trailing edges) and finds their edges, neighbours and far corners
itself (:func:`edge_table`), so the host topology of :mod:`warpsim.physics.lattice` is checked too. Uniform wind (no
shear profile) only. With a shed wake (:mod:`warpsim.physics.kernels.wake`) it takes the wake's rows of points and
rings' circulations by trailing edge, ``(a, b)`` particles in the ring's order, and finds the trailing edges itself.
"""

from __future__ import annotations

import numpy as np

from warpsim.physics.kernels.aero import STALL_SHARPNESS
from warpsim.physics.kernels.vortex import CORE_FRACTION
from warpsim.physics.lattice import TRAILING

INV_FOUR_PI = 1.0 / (4.0 * np.pi)


def segment_velocity(x: np.ndarray, a: np.ndarray, b: np.ndarray, core2: float) -> np.ndarray:
    """``[M, K, 3]`` velocities at points ``x [M, 3]`` of unit segments ``a -> b`` (``[K, 3]``), cut-off core."""
    r1 = x[:, None, :] - a[None]
    r2 = x[:, None, :] - b[None]
    r0 = (b - a)[None]
    c = np.cross(r1, r2)
    n1 = np.linalg.norm(r1, axis=-1)
    n2 = np.linalg.norm(r2, axis=-1)
    den = (c * c).sum(-1) + core2 * (r0 * r0).sum(-1)
    ok = (n1 > 0) & (n2 > 0) & (den > 0)
    n1, n2, den = np.where(ok, n1, 1.0), np.where(ok, n2, 1.0), np.where(ok, den, 1.0)
    k = (r0 * (r1 / n1[..., None] - r2 / n2[..., None])).sum(-1) * INV_FOUR_PI / den
    return c * np.where(ok, k, 0.0)[..., None]


def ray_velocity(x: np.ndarray, a: np.ndarray, d: np.ndarray, core2: float) -> np.ndarray:
    """``[M, K, 3]`` velocities at ``x`` of unit semi-infinite lines leaving ``a [K, 3]`` along unit ``d [3]``."""
    r1 = x[:, None, :] - a[None]
    n1 = np.linalg.norm(r1, axis=-1)
    c = np.cross(np.broadcast_to(d, r1.shape), r1)
    den = (c * c).sum(-1) + core2
    ok = (n1 > 0) & (den > 0)
    n1, den = np.where(ok, n1, 1.0), np.where(ok, den, 1.0)
    k = (1.0 + (r1 @ d) / n1) * INV_FOUR_PI / den
    return c * np.where(ok, k, 0.0)[..., None]


def ring_velocities(x: np.ndarray, corners: np.ndarray, trailing: np.ndarray, d: np.ndarray, core2: float):
    """``[M, N, 3]`` velocity at ``x [M, 3]`` of each ring ``corners [N, 3, 3]`` of unit circulation with its wake legs
    (``trailing [N]`` edge bits)."""
    v = np.zeros((len(x), len(corners), 3))
    for e in range(3):
        a, b = corners[:, e], corners[:, (e + 1) % 3]
        shed = ((trailing >> e) & 1).astype(bool)[None, :, None]
        v += np.where(
            shed, ray_velocity(x, a, d, core2) - ray_velocity(x, b, d, core2), segment_velocity(x, a, b, core2)
        )
    return v


def _bound_of_trailing(x, corners, trailing, core2):
    """The trailing edges' own bound segments, which :func:`ring_velocities` with no trailing bits counts and the
    wake replaces: added back so that the difference is the wake legs alone."""
    v = np.zeros((len(x), len(corners), 3))
    for e in range(3):
        shed = ((trailing >> e) & 1).astype(bool)[None, :, None]
        v += np.where(shed, segment_velocity(x, corners[:, e], corners[:, (e + 1) % 3], core2), 0.0)
    return v


def edge_table(tris: np.ndarray, panel_tri: np.ndarray, surface_start: np.ndarray, panel_trailing: np.ndarray):
    """The loaded edges of the lifting surfaces, found here from the triangles themselves (not from
    :mod:`warpsim.physics.lattice`, so that its topology is checked too): ``(panels [E, 2], corner [E], particles
    [E, 2], opposite [E, 2])`` with panels ``(first, second)`` (second -1 on the boundary, ``TRAILING`` on a trailing
    edge), the edge's index in its first panel, its particles in that panel's direction and each panel's far corner
    (-1: none)."""
    found: dict = {}
    for s in range(len(surface_start) - 1):
        for v in range(surface_start[s], surface_start[s + 1]):
            tri = tris[panel_tri[v]]
            for e in range(3):
                a, b, c = int(tri[e]), int(tri[(e + 1) % 3]), int(tri[(e + 2) % 3])
                found.setdefault((s, min(a, b), max(a, b)), []).append((v, e, a, b, c))
    panels, corner, particles, opposite = [], [], [], []
    for held in found.values():
        v, e, a, b, c = held[0]
        if len(held) == 2:
            second, far = held[1][0], held[1][4]
        else:
            second, far = (TRAILING if (panel_trailing[v] >> e) & 1 else -1), -1
        panels.append((v, second))
        corner.append(e)
        particles.append((a, b))
        opposite.append((c, far))
    return (
        np.array(panels).reshape(-1, 2),
        np.array(corner),
        np.array(particles).reshape(-1, 2),
        np.array(opposite).reshape(-1, 2),
    )


def shed_wake_velocity(x: np.ndarray, rings: dict, origin: np.ndarray, d: np.ndarray, core2: float) -> np.ndarray:
    """``[M, 3]`` velocity at ``x [M, 3]`` (from ``origin``) of a shed wake: ``rings`` maps a trailing edge ``(a, b)``
    to the rows of points behind ``a`` and behind ``b`` (``[R + 1, 3]`` [m] each, row 0 the edge) and its rings'
    circulations ``[R]``; each ring runs
    ``b_k -> a_k -> a_k+1 -> b_k+1 -> b_k``, the oldest ending in two legs along ``d``."""
    v = np.zeros((len(x), 3))
    for pa, pb, g in rings.values():
        pa = (pa - origin).astype(np.float32).astype(np.float64)
        pb = (pb - origin).astype(np.float32).astype(np.float64)
        rows = len(g)
        for k in range(rows):
            if g[k] == 0.0:
                continue
            u = segment_velocity(x, pb[k : k + 1], pa[k : k + 1], core2)
            u += segment_velocity(x, pa[k : k + 1], pa[k + 1 : k + 2], core2)
            u += segment_velocity(x, pb[k + 1 : k + 2], pb[k : k + 1], core2)
            if k == rows - 1:
                u += ray_velocity(x, pa[k + 1 : k + 2], d, core2) - ray_velocity(x, pb[k + 1 : k + 2], d, core2)
            else:
                u += segment_velocity(x, pa[k + 1 : k + 2], pb[k + 1 : k + 2], core2)
            v += u[:, 0] * g[k]
    return v


def vortex_forces(
    model, q: np.ndarray, q_prev: np.ndarray, dt: float, wind, density, scale: float = 1.0, shed: dict | None = None
):
    """The vortex law's forces on ``model`` at positions ``q`` and ``q_prev`` ``[P, 3]`` [m] for steps of ``dt`` [s],
    in a uniform ``wind`` ``[W, 3]`` [m/s] and air of ``density`` ``[W]`` [kg/m^3] per world: ``(particle_force
    [P, 3], tri_force {triangle: per-vertex force [3]}, gamma [V])``, as the kernels write them into ``particle_air``
    and ``tri_force`` [N] and their circulations [m^2/s].

    ``shed``: a shed wake's state at the solve, ``{"rings": {(a, b): (points of a, points of b, circulations)},
    "gamma_before": [V], "rate": [V] (the smoothed rates of the step before), "smoothing": s}`` (the first ring's
    circulation already its panel's of the step before); ``shed["rate"]`` is then set to this step's."""
    lat = model.lattice
    tris = model.tri_indices_np
    sail = model.tri_sail.numpy().astype(np.float64)
    rho_world = np.broadcast_to(np.asarray(density, dtype=np.float64), (model.world_count,))
    wind = np.asarray(wind, dtype=np.float64).reshape(-1, 3)
    world = model.particle_world_np
    gamma = np.zeros(lat.panel_count)
    stall = np.zeros(lat.panel_count)
    tri_force = {}
    edge_panels, edge_corner, edge_particles, edge_opposite = edge_table(
        tris, lat.panel_tri, lat.surface_start, lat.panel_trailing
    )
    induced = np.zeros((len(edge_corner), 3))
    wake_dir = np.zeros((lat.surface_count, 3))
    rates = np.zeros(lat.panel_count)
    for s in range(lat.surface_count):
        v0, v1 = lat.surface_start[s], lat.surface_start[s + 1]
        idx = tris[lat.panel_tri[v0:v1]]
        origin = q[lat.surface_origin[s]]
        corners = (q[idx] - origin).astype(np.float32).astype(np.float64)
        cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 1])
        length = np.linalg.norm(cross, axis=1)
        n = cross / np.where(length > 0, length, 1.0)[:, None]
        area = 0.5 * length
        point = corners.mean(axis=1)
        moved = (q[idx] - q_prev[idx]).sum(axis=1)
        w = wind[world[idx[:, 0]]] - moved / (3.0 * dt)
        mean = (w * area[:, None]).sum(0)
        trailing = lat.panel_trailing[v0:v1]
        plane = (n * area[:, None]).sum(0)
        plane = plane / np.linalg.norm(plane) if np.linalg.norm(plane) > 0 else plane
        if area.sum() > 0 and np.linalg.norm(mean) > 0:
            d = wake_dir[s] = mean / np.linalg.norm(mean)
            core2 = CORE_FRACTION**2 * area.sum() / (v1 - v0)
            mine = (edge_panels[:, 0] >= v0) & (edge_panels[:, 0] < v1) & (edge_panels[:, 1] == TRAILING)
            p, k = edge_panels[mine, 0] - v0, edge_corner[mine]
            mid = 0.5 * (corners[p, k] + corners[p, (k + 1) % 3])
            if shed is None:
                a = (ring_velocities(point, corners, trailing, d, core2) * n[:, None, :]).sum(-1)
                gamma[v0:v1] = np.linalg.solve(a, -(w * n).sum(1))
                legs = ring_velocities(mid, corners, trailing, d, core2) - ring_velocities(
                    mid, corners, 0 * trailing, d, core2
                )
                legs += _bound_of_trailing(mid, corners, trailing, core2)
                induced[mine] = (legs * gamma[v0:v1][None, :, None]).sum(1)
            else:  # the sail's own rings, edges and all; the wake on the right-hand side
                ring_of = tris[lat.panel_tri[v0 + p]]
                ends = {(int(ring_of[j, k[j]]), int(ring_of[j, (k[j] + 1) % 3])) for j in range(len(p))}
                rings = {key: value for key, value in shed["rings"].items() if key in ends}
                a = (ring_velocities(point, corners, 0 * trailing, d, core2) * n[:, None, :]).sum(-1)
                through = (shed_wake_velocity(point, rings, origin, d, core2) * n).sum(1)
                gamma[v0:v1] = np.linalg.solve(a, -(w * n).sum(1) - through)
                induced[mine] = shed_wake_velocity(mid, rings, origin, d, core2)
        for row, t in enumerate(lat.panel_tri[v0:v1]):
            coef = sail[t]
            speed = np.linalg.norm(w[row])
            force = w[row] * coef[2] * speed
            sigma = 0.0
            if speed > 0:
                sin_s = min(abs(plane @ w[row]) / speed, 1.0)
                sigma = 1.0 / (1.0 + np.exp(-STALL_SHARPNESS * (np.arcsin(sin_s) - coef[3])))
                wn = n[row] @ w[row] / speed
                sin_a = min(abs(wn), 1.0)
                if sin_a > 1e-6:
                    force = force + n[row] * (np.sign(wn) / (0.222 + 0.283 / sin_a) * speed * speed * sigma)
            stall[v0 + row] = sigma
            rho = rho_world[world[tris[int(t)][0]]]
            tri_force[int(t)] = force * (0.5 * rho * area[row] * scale / 3.0)
            if shed is not None:  # the unsteady pressure -rho A dG/dt n, its rate smoothed
                i = v0 + row
                before = shed["rate"][i]
                rate = before + shed["smoothing"] * ((gamma[i] - shed["gamma_before"][i]) / dt - before)
                rates[i] = rate
                tri_force[int(t)] = tri_force[int(t)] + n[row] * (-rho * area[row] * rate * (1.0 - sigma) * scale / 3.0)
    g = gamma[edge_panels[:, 0]].copy()
    sigma = stall[edge_panels[:, 0]].copy()
    inner = edge_panels[:, 1] >= 0
    g[inner] -= gamma[edge_panels[inner, 1]]
    sigma[inner] = 0.5 * (sigma[inner] + stall[edge_panels[inner, 1]])
    a, b = edge_particles[:, 0], edge_particles[:, 1]
    moved = (q[a] - q_prev[a]) + (q[b] - q_prev[b])
    velocity = wind[world[a]] - moved / (2.0 * dt)
    edge = q[b] - q[a]
    trailing_edge = edge_panels[:, 1] == TRAILING
    velocity[trailing_edge], edge[trailing_edge] = induced[trailing_edge], -edge[trailing_edge]  # induced drag
    edge_force = np.cross(velocity, edge) * (rho_world[world[a]] * g * scale * (1.0 - sigma))[:, None]
    # each load a quarter of the way to the far corner of the panel downstream (none on the trailing edges)
    d = wake_dir[lat.panel_surface[edge_panels[:, 0]]]
    mid = 0.5 * (q[a] + q[b])
    far = edge_opposite
    ahead = ((q[far[:, 0]] - mid) * d).sum(1)
    behind = np.where(far[:, 1] >= 0, ((q[np.maximum(far[:, 1], 0)] - mid) * d).sum(1), -np.inf)
    side = np.where(ahead > 0, 1, 0)
    side = np.where((behind > 0) & (behind > ahead), 2, side)
    side[trailing_edge] = 0
    corner = np.where(side == 2, far[:, 1], far[:, 0])
    share = np.where(side > 0, 0.25, 0.0)[:, None]
    particle_force = np.zeros_like(q)
    np.add.at(particle_force, a, 0.5 * (1.0 - share) * edge_force)
    np.add.at(particle_force, b, 0.5 * (1.0 - share) * edge_force)
    np.add.at(particle_force, corner, share * edge_force)
    if shed is not None:
        shed["rate"] = rates
    return particle_force, tri_force, gamma
