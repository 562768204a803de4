"""The viewer's geometry in NumPy, apart from OpenGL: a unit sphere, vertex normals, tube meshes between
particles, and the camera's projection and view matrices (column vectors, OpenGL's clip space)."""

from __future__ import annotations

import numpy as np

from .backend import View


def sphere(rings: int = 6, segments: int = 10) -> tuple[np.ndarray, np.ndarray]:
    """A unit sphere: vertices ``[v, 3]`` (also its normals) and triangles ``[t, 3]``."""
    theta = np.linspace(0.0, np.pi, rings + 1)
    phi = np.linspace(0.0, 2 * np.pi, segments, endpoint=False)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    v = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], -1).reshape(-1, 3)
    tris = []
    for i in range(rings):
        for j in range(segments):
            a, b = i * segments + j, i * segments + (j + 1) % segments
            tris += [(a, a + segments, b + segments), (a, b + segments, b)]
    return v.astype(np.float32), np.array(tris, dtype=np.int32)


def vertex_normals(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Area-weighted vertex normals of a triangle mesh (unnormalised; the shader normalises)."""
    p = points[triangles]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    out = np.zeros_like(points)
    for k in range(3):
        np.add.at(out, triangles[:, k], n)
    return out


def perspective(fov: float, aspect: float, near: float, far: float) -> np.ndarray:
    f = 1.0 / np.tan(np.radians(fov) / 2)
    return np.array(
        [
            [f / aspect, 0, 0, 0],
            [0, f, 0, 0],
            [0, 0, (far + near) / (near - far), 2 * far * near / (near - far)],
            [0, 0, -1, 0],
        ]
    )


def view_matrix(view: View, width: int, height: int, below: float = 0.0) -> np.ndarray:
    """The 4x4 matrix from world coordinates [m] to clip space of ``view`` in a ``width`` x ``height`` picture;
    ``below``: the fraction of the height a panel covers at the top (the heads-up text): what the field of view
    holds is drawn in the rest, below the panel, shrunk by ``1 - below`` about the bottom middle (the panel's
    strip and the sides show what lies beyond it)."""
    eye, target = np.asarray(view.eye, float), np.asarray(view.target, float)
    near = max(0.05, float(np.linalg.norm(target - eye)) / 500)  # depth precision where the object is
    projection = perspective(view.fov, width / max(height, 1), near, 20000.0)
    # normalised x and y scaled by 1 - below, then y moved down by below: [-1, 1] -> [-1, 1 - 2 below]
    projection[:2] *= 1.0 - below
    projection[1] -= below * projection[3]
    return projection @ look_at(eye, target)


def tube_mesh(count: int, sides: int = 8) -> np.ndarray:
    """Triangles ``[t, 3]`` of ``count`` capped tubes whose vertices are, per tube, ``sides`` around one end,
    ``sides`` around the other, then the two ends' centres."""
    k = np.arange(sides)
    k1 = (k + 1) % sides
    per = 2 * sides + 2
    one = np.concatenate(
        [
            np.stack([k, k1, sides + k1], 1),
            np.stack([k, sides + k1, sides + k], 1),
            np.stack([np.full(sides, 2 * sides), k1, k], 1),
            np.stack([np.full(sides, 2 * sides + 1), sides + k, sides + k1], 1),
        ]
    )
    return (one[None] + per * np.arange(count)[:, None, None]).reshape(-1, 3).astype(np.int32)


def tube_points(a: np.ndarray, b: np.ndarray, radius: np.ndarray, sides: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and normals ``[count * (2 * sides + 2), 3]`` of tubes from ``a`` to ``b`` ``[count, 3]`` [m] of
    ``radius`` ``[count]`` [m], in the order :func:`tube_mesh` numbers them."""
    axis = b - a
    n = axis / np.maximum(np.linalg.norm(axis, axis=1, keepdims=True), 1e-9)
    u = np.cross(n, [0.0, 0.0, 1.0])
    flat = np.linalg.norm(u, axis=1) < 1e-3
    u[flat] = np.cross(n[flat], [1.0, 0.0, 0.0])
    u /= np.maximum(np.linalg.norm(u, axis=1, keepdims=True), 1e-9)
    v = np.cross(n, u)
    angle = 2 * np.pi * np.arange(sides) / sides
    ring = np.cos(angle)[None, :, None] * u[:, None] + np.sin(angle)[None, :, None] * v[:, None]  # [count, sides, 3]
    r = np.asarray(radius)[:, None, None]
    points = np.concatenate([a[:, None] + r * ring, b[:, None] + r * ring, a[:, None], b[:, None]], axis=1)
    normals = np.concatenate([ring, ring, -n[:, None], n[:, None]], axis=1)
    return points.reshape(-1, 3), normals.reshape(-1, 3)


def look_at(eye: np.ndarray, target: np.ndarray) -> np.ndarray:
    forward = target - eye
    forward = forward / max(np.linalg.norm(forward), 1e-9)
    up = np.array([0.0, 0.0, 1.0])
    if abs(forward @ up) > 0.999:
        up = np.array([0.0, 1.0, 0.0])
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    true_up = np.cross(right, forward)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = right, true_up, -forward
    m[:3, 3] = -m[:3, :3] @ eye
    return m
