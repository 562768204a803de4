"""Heightfield collision: particles never end a step below the terrain.

Two corrections (``CollisionMode``):

* ``clamp`` - the paper's (slide 25): a particle below the ground is lifted vertically onto it.
* ``normal`` - the better correction slide 26 suggests: the particle is pushed out along the
  terrain normal by its penetration depth, and the tangential part of this step's trajectory
  (``x - x_prev``) is reduced by Coulomb-like friction: at most ``friction * depth`` of sliding is
  removed, all of it when the slide is shorter (static friction).

Both end with a vertical clamp so that no particle is left below a curved surface.
"""

from __future__ import annotations

import enum

import numpy as np
import warp as wp

wp.set_module_options({"enable_backward": False})  # forward-only: halves compile time


class CollisionMode(enum.IntEnum):
    """How a particle found below the terrain is corrected."""

    CLAMP = 0
    NORMAL = 1


@wp.struct
class HeightfieldData:
    """Device view of a :class:`~warpsim.physics.terrain.Heightfield`: float32 heights [m] above a float64
    ``base`` [m] (the middle of their range, so that a terrain 3 km up is looked up as finely as one at sea level),
    float64 grid origin [m] and cell size [m] (so that a point 10 km out finds its place in the cell to float64
    precision)."""

    heights: wp.array2d(dtype=wp.float32)
    base: wp.float64
    origin: wp.vec2d
    cell: wp.vec2d


@wp.func
def _cell(hf: HeightfieldData, x: wp.float64, y: wp.float64):
    """The grid cell ``(ix, iy)`` under ``(x, y)`` [m] and the float32 fractions ``(tx, ty)`` in [0, 1] across it,
    found in float64. Points outside the grid take the nearest edge's height: the coordinate is clamped onto the
    grid, and the last cell is used up to and including the far edge (so no sample past the array is ever read)."""
    ny = hf.heights.shape[0]
    nx = hf.heights.shape[1]
    fx = wp.clamp((x - hf.origin[0]) / hf.cell[0], wp.float64(0.0), wp.float64(nx - 1))
    fy = wp.clamp((y - hf.origin[1]) / hf.cell[1], wp.float64(0.0), wp.float64(ny - 1))
    ix = wp.min(int(wp.floor(fx)), nx - 2)
    iy = wp.min(int(wp.floor(fy)), ny - 2)
    return ix, iy, float(fx - wp.float64(ix)), float(fy - wp.float64(iy))


@wp.func
def terrain_height(hf: HeightfieldData, x: wp.float64, y: wp.float64) -> wp.float64:
    """Bilinear terrain height [m] at ``(x, y)`` [m], float64 (the float32 interpolation is of heights above the
    base)."""
    ix, iy, tx, ty = _cell(hf, x, y)
    h00 = hf.heights[iy, ix]
    h10 = hf.heights[iy, ix + 1]
    h01 = hf.heights[iy + 1, ix]
    h11 = hf.heights[iy + 1, ix + 1]
    return hf.base + wp.float64((1.0 - ty) * ((1.0 - tx) * h00 + tx * h10) + ty * ((1.0 - tx) * h01 + tx * h11))


@wp.func
def terrain_normal(hf: HeightfieldData, x: wp.float64, y: wp.float64) -> wp.vec3:
    """Unit upward normal of the bilinear surface at ``(x, y)``."""
    ix, iy, tx, ty = _cell(hf, x, y)
    h00 = hf.heights[iy, ix]
    h10 = hf.heights[iy, ix + 1]
    h01 = hf.heights[iy + 1, ix]
    h11 = hf.heights[iy + 1, ix + 1]
    dhdx = ((1.0 - ty) * (h10 - h00) + ty * (h11 - h01)) / float(hf.cell[0])
    dhdy = ((1.0 - tx) * (h01 - h00) + tx * (h11 - h10)) / float(hf.cell[1])
    return wp.normalize(wp.vec3(-dhdx, -dhdy, 1.0))


@wp.kernel
def _collide_heightfield(
    hf: HeightfieldData,
    particle_inv_mass: wp.array(dtype=wp.float32),
    particle_q_prev: wp.array(dtype=wp.vec3d),
    mode: int,
    friction: float,
    particle_q_out: wp.array(dtype=wp.vec3d),
):
    i = wp.tid()
    if particle_inv_mass[i] == 0.0:
        return
    x = particle_q_out[i]  # float64; the terrain is looked up in float64, corrections made in float32
    h = terrain_height(hf, x[0], x[1])
    if x[2] >= h:
        return
    if mode == CollisionMode.NORMAL:
        n = terrain_normal(hf, x[0], x[1])
        depth = float(h - x[2]) * n[2]
        x = x + wp.vec3d(n * depth)
        # friction on the tangential part of this step's trajectory
        move = wp.vec3(x - particle_q_prev[i])
        slide = move - n * wp.dot(move, n)
        slide_len = wp.length(slide)
        if slide_len > 0.0:
            x = x - wp.vec3d(slide * wp.min(1.0, friction * depth / slide_len))
        h = terrain_height(hf, x[0], x[1])
    particle_q_out[i] = wp.vec3d(x[0], x[1], wp.max(x[2], h))


@wp.kernel
def _sample_terrain(
    hf: HeightfieldData,
    points: wp.array(dtype=wp.vec2d),
    height_out: wp.array(dtype=wp.float64),
    normal_out: wp.array(dtype=wp.vec3),
):
    i = wp.tid()
    p = points[i]
    height_out[i] = terrain_height(hf, p[0], p[1])
    normal_out[i] = terrain_normal(hf, p[0], p[1])


class TerrainSampler:
    """Host queries of a terrain through the kernels' own :func:`terrain_height` and :func:`terrain_normal`, on
    the CPU device. The launch is recorded once over NumPy-backed buffers (re-recorded when more points come), so
    that a query of a few points costs a few microseconds, not a fresh launch's tens (diagnostics ask every frame).
    """

    def __init__(self, hf: HeightfieldData):
        self.hf = hf
        self.capacity = 0
        self._launch = None

    def _record(self, capacity: int) -> None:
        self.points = np.zeros((capacity, 2), dtype=np.float64)
        self.height = np.zeros(capacity, dtype=np.float64)
        self.normal = np.zeros((capacity, 3), dtype=np.float32)
        cpu = "cpu"
        self._launch = wp.launch(
            _sample_terrain,
            capacity,
            [self.hf, wp.array(self.points, dtype=wp.vec2d, device=cpu, copy=False)],
            [
                wp.array(self.height, dtype=wp.float64, device=cpu, copy=False),
                wp.array(self.normal, dtype=wp.vec3, device=cpu, copy=False),
            ],
            device=cpu,
            record_cmd=True,
        )
        self.capacity = capacity

    def __call__(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Heights [m] ``[n]`` and unit normals ``[n, 3]`` at the points ``(x, y)`` [m] (two ``[n]`` arrays): the
        kernel's float64 heights and float32 normals, in new float64 arrays."""
        n = len(x)
        if n == 0:
            return np.zeros(0), np.zeros((0, 3))
        if n > self.capacity:
            self._record(max(n, 64))
        self.points[:n, 0] = x
        self.points[:n, 1] = y
        self._launch.set_dim(n)
        self._launch.launch()
        return self.height[:n].astype(np.float64), self.normal[:n].astype(np.float64)


def collide_heightfield(model, state, mode: CollisionMode, friction: float) -> None:
    """Keep every free particle of ``state`` at or above ``model.terrain`` (in place)."""
    wp.launch(
        _collide_heightfield,
        dim=model.particle_count,
        inputs=[model.terrain_data, model.particle_inv_mass, state.particle_q_prev, int(mode), float(friction)],
        outputs=[state.particle_q],
        device=model.device,
    )
