"""Heightfield terrain: a regular grid of heights that particles may not go below.

The paper uses a 256x256 heightfield (Section 6.3). Heights are in metres, Z up; the grid covers
``[origin_x, origin_x + size_x] x [origin_y, origin_y + size_y]`` and is sampled bilinearly. Outside
the grid the edge heights are extended. Host queries run the kernels' own lookup
(:mod:`warpsim.physics.kernels.collision`), so a builder, a diagnostic and a kernel see one terrain.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

import numpy as np

DEFAULT_RESOLUTION = 256
MAX_SIDE = 8192  # samples per side of a terrain file (512 MB of float64 heights)
MAX_HEIGHT = 1e5  # [m] largest terrain height a file may hold


class Heightfield:
    """A height grid sampled bilinearly.

    Args:
        heights: shape ``[ny, nx]`` heights in metres; row ``j`` is at ``y = origin_y + j*cell_y``.
        size: ``(size_x, size_y)`` extent of the grid in metres (first to last sample).
        origin: ``(x, y)`` of sample ``[0, 0]`` in metres. Default: grid centred on the origin.
    """

    def __init__(self, heights: np.ndarray, size: tuple[float, float], origin: tuple[float, float] | None = None):
        heights = np.asarray(heights, dtype=np.float64)
        if heights.ndim != 2 or min(heights.shape) < 2:
            raise ValueError(f"heights must be a 2-D array of at least 2x2 samples, got shape {heights.shape}")
        if not np.all(np.isfinite(heights)):
            raise ValueError("heights contain NaN or Inf")
        size_x, size_y = float(size[0]), float(size[1])
        if size_x <= 0.0 or size_y <= 0.0:
            raise ValueError(f"terrain size must be positive, got {size}")
        self.heights = heights
        self.size = (size_x, size_y)
        self.origin = (-0.5 * size_x, -0.5 * size_y) if origin is None else (float(origin[0]), float(origin[1]))
        ny, nx = heights.shape
        self.cell = (size_x / (nx - 1), size_y / (ny - 1))
        self._device_data: dict = {}  # device alias -> HeightfieldData, made on first use
        self._sampler = None  # the host queries' recorded launch, made on first use

    # ------------------------------------------------------------------ constructors
    @classmethod
    def flat(cls, size: float = 1000.0, height: float = 0.0, resolution: int = DEFAULT_RESOLUTION) -> Heightfield:
        """A level terrain at ``height`` metres covering ``size`` x ``size`` metres."""
        return cls(np.full((resolution, resolution), height, dtype=np.float64), (size, size))

    @classmethod
    def procedural(
        cls,
        size: float = 1000.0,
        amplitude: float = 40.0,
        seed: int = 0,
        resolution: int = DEFAULT_RESOLUTION,
        base_height: float = 0.0,
    ) -> Heightfield:
        """Seeded rolling hills: a sum of random-phase waves whose amplitude falls with frequency.

        Args:
            size: side of the square terrain [m].
            amplitude: approximate peak-to-mean height of the hills [m].
            seed: random seed; the same seed always gives the same terrain.
            resolution: samples per side (the paper: 256).
            base_height: mean height [m].
        """
        rng = np.random.default_rng(seed)
        u = np.linspace(0.0, 1.0, resolution)
        gx, gy = np.meshgrid(u, u)
        h = np.zeros_like(gx)
        for octave in range(1, 6):
            for _ in range(3):
                angle = rng.uniform(0.0, 2.0 * np.pi)
                freq = octave * rng.uniform(0.7, 1.3)
                phase = rng.uniform(0.0, 2.0 * np.pi)
                h += np.cos(2.0 * np.pi * freq * (np.cos(angle) * gx + np.sin(angle) * gy) + phase) / octave**1.5
        h *= amplitude / max(np.abs(h).max(), 1e-9)
        return cls(h + base_height, (size, size))

    @classmethod
    def load(cls, path: str | Path, size: float = 1000.0, vertical_scale: float = 1.0) -> Heightfield:
        """Load heights [m] from a ``.npy`` file holding a 2-D array (``vertical_scale`` multiplies them)."""
        path = Path(path)
        if path.suffix.lower() != ".npy":
            raise ValueError(f"{path}: terrain files must be .npy arrays of heights")
        try:
            info = os.stat(path)
        except FileNotFoundError:
            raise ValueError(f"{path}: terrain file not found") from None
        if not stat.S_ISREG(info.st_mode):  # a FIFO would block the reader, a device never end
            raise ValueError(f"{path}: not a regular file")
        with open(path, "rb") as f:
            # the header first: shape and type are checked before any data is read
            try:
                version = np.lib.format.read_magic(f)
                readers = {(1, 0): np.lib.format.read_array_header_1_0, (2, 0): np.lib.format.read_array_header_2_0}
                if version not in readers:
                    raise ValueError(f".npy format version {version} is not supported")
                shape, fortran, dtype = readers[version](f)
            except (ValueError, OSError, SyntaxError, TypeError) as err:
                raise ValueError(f"{path}: not a .npy array ({err})") from None
            if dtype.kind not in "fiu" or dtype.hasobject:
                raise ValueError(f"{path}: heights must be real numbers, the file holds {dtype}")
            if len(shape) != 2 or not all(2 <= n <= MAX_SIDE for n in shape):
                raise ValueError(f"{path}: heights must be a 2-D array of 2 to {MAX_SIDE} samples a side, got {shape}")
            expected = int(np.prod(shape)) * dtype.itemsize
            if info.st_size - f.tell() != expected:
                raise ValueError(
                    f"{path}: the header announces {expected:,} bytes of heights, the file holds "
                    f"{info.st_size - f.tell():,}"
                )
            heights = np.fromfile(f, dtype=dtype, count=int(np.prod(shape))).reshape(
                shape, order="F" if fortran else "C"
            )
        heights = heights.astype(np.float64) * vertical_scale
        if not np.isfinite(heights).all() or np.abs(heights).max() > MAX_HEIGHT:
            raise ValueError(f"{path}: heights must be finite and within +-{MAX_HEIGHT:g} m")
        return cls(heights, (size, size))

    # ------------------------------------------------------------------ queries
    def device_data(self, device=None):
        """The kernels' view of this terrain (:class:`warpsim.physics.kernels.collision.HeightfieldData`) on ``device``
        (default Warp's ``cpu``), made once per device."""
        import warp as wp

        from .kernels.collision import HeightfieldData

        device = wp.get_device(device or "cpu")
        data = self._device_data.get(device.alias)
        if data is None:
            data = HeightfieldData()
            heights = np.asarray(self.heights, dtype=np.float64)
            base = 0.5 * (float(heights.min()) + float(heights.max())) if heights.size else 0.0
            data.heights = wp.array((heights - base).astype(np.float32), dtype=wp.float32, device=device)
            data.base = base
            data.origin = wp.vec2d(*(float(v) for v in self.origin))
            data.cell = wp.vec2d(*(float(v) for v in self.cell))
            self._device_data[device.alias] = data
        return data

    def sample(self, x, y) -> tuple[np.ndarray, np.ndarray]:
        """Heights [m] and unit upward normals (shape ``[..., 3]``) at world ``(x, y)`` [m] (arrays of one shape
        or scalars), computed on the CPU by the same Warp functions the kernels use."""
        from .kernels.collision import TerrainSampler

        if self._sampler is None:
            self._sampler = TerrainSampler(self.device_data("cpu"))
        x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        if x.shape != y.shape:
            x, y = np.broadcast_arrays(x, y)
        heights, normals = self._sampler(x.reshape(-1), y.reshape(-1))
        return heights.reshape(x.shape), normals.reshape(*x.shape, 3)

    def height(self, x, y):
        """Bilinear terrain height [m] at world ``(x, y)`` [m]: a float for scalars, an array for arrays. Outside
        the grid the nearest edge's height."""
        h = self.sample(x, y)[0]
        return float(h) if h.ndim == 0 else h

    def normal(self, x, y) -> np.ndarray:
        """Unit upward normal of the bilinear surface at ``(x, y)`` [m], shape ``[..., 3]``."""
        return self.sample(x, y)[1]

    def __repr__(self) -> str:
        ny, nx = self.heights.shape
        return (
            f"Heightfield({nx}x{ny}, size={self.size[0]:g}x{self.size[1]:g} m, "
            f"heights {self.heights.min():.1f}..{self.heights.max():.1f} m)"
        )
