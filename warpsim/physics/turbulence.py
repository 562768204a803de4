"""Frozen turbulence with a named spectrum: an isotropic von Kármán field in a periodic box, carried by the mean wind.

The field is a divergence-free Gaussian velocity field whose energy spectrum is von Kármán's,
``E(k) ∝ (k L_e)^4 / (1 + (k L_e)^2)^(17/6)`` with ``L_e = L / 0.7468`` for the longitudinal integral length scale
``L`` [m] (the isotropic model of IEC 61400-1 ed. 2, Annex B, which takes ``L = 3.5 Λ1``, ``Λ1 = 0.7 z`` below 60 m).
It is synthesised once per scene by an inverse FFT of spectrally weighted, projected complex Gaussian noise on a
periodic grid of ``GRID`` cells of side ``L / CELLS_PER_LENGTH`` (Mann 1998's method without his shear distortion),
with von Kármán's amplitudes as they are (unit variance per component for the whole spectrum; the eddies shorter than
the grid holds, about 11 % of the variance, are left out rather than given to the larger ones). A world's air adds
``intensity * |wind|`` times the field at ``x - U t + offset`` (Taylor's frozen turbulence: the pattern travels with
the wind ``U`` at the reference height; ``offset`` is drawn from the world's seed, so that worlds with other seeds fly
through other parts of the same field). Between grid points the field is interpolated trilinearly.

Memory: one field per scene, whatever the number of worlds: ``GRID`` = 192 x 96 x 96 cells of three float32
components, 21 MB (and about 0.3 GB for 1.5 s while it is synthesised).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

GRID = (192, 96, 96)
"""Cells of the periodic box along x (the mean wind's usual direction), y and z."""
CELLS_PER_LENGTH = 12
"""Grid cells per integral length scale ``L``: the box is 16 L x 8 L x 8 L (392 m x 196 m x 196 m at L = 24.5 m),
fine enough that the eddies it cannot hold carry about a tenth of the variance, and long enough for the
energy-containing eddies (a world carried 16 L meets the same air again: 39 s at 10 m/s for L = 24.5 m)."""
VON_KARMAN_KE = 0.7468
"""``k_e L`` of von Kármán's spectrum for the longitudinal integral length scale ``L``
(``Γ(1/3) / (Γ(1/2) Γ(5/6))``-based constant; ESDU 85020)."""
LENGTHS = (0.5, 2000.0)
"""[m] the length scales a scene may give (a 32 km box at the top)."""
INTENSITIES = (0.0, 1.0)
"""The turbulence intensities (sigma / mean speed) a scene may give."""


@dataclass(frozen=True)
class Field:
    """A synthesised turbulence field.

    Attributes:
        velocity: ``[nx, ny, nz, 3]`` float32 the field (dimensionless: unit standard deviation per component).
        cell: the grid spacing [m].
        length: the integral length scale ``L`` [m] it was made for.
    """

    velocity: np.ndarray
    cell: float
    length: float

    @property
    def box(self) -> np.ndarray:
        """``[3]`` the periodic box's sides [m]."""
        return np.array(self.velocity.shape[:3], dtype=np.float64) * self.cell

    def sample(self, points: np.ndarray) -> np.ndarray:
        """The field at ``points`` ``[n, 3]`` [m] (trilinear, periodic), ``[n, 3]``: what the kernels compute."""
        p = np.asarray(points, dtype=np.float64) / self.cell
        n = np.array(self.velocity.shape[:3])
        base = np.floor(p).astype(np.int64)
        frac = p - base
        out = np.zeros((len(p), 3))
        for corner in range(8):
            d = np.array([(corner >> 0) & 1, (corner >> 1) & 1, (corner >> 2) & 1])
            weight = np.prod(np.where(d == 1, frac, 1.0 - frac), axis=1)
            i = (base + d) % n
            out += weight[:, None] * self.velocity[i[:, 0], i[:, 1], i[:, 2]]
        return out


def von_karman_energy(k: np.ndarray, length: float) -> np.ndarray:
    """von Kármán's energy spectrum of unit per-component variance, ``E(k)`` [m^3/s^2 per unit sigma^2] at wavenumbers
    ``k`` [rad/m], for the longitudinal integral length scale ``length`` [m] (``∫ E dk = 3/2``)."""
    ke = VON_KARMAN_KE / length
    x = np.asarray(k, dtype=np.float64) / ke
    # normalisation: ∫_0^∞ x^4 / (1 + x^2)^(17/6) dx = Γ(5/2) Γ(1/3) / (2 Γ(17/6))
    norm = math.gamma(2.5) * math.gamma(1.0 / 3.0) / (2.0 * math.gamma(17.0 / 6.0))
    return 1.5 * x**4 / (1.0 + x * x) ** (17.0 / 6.0) / (norm * ke)


def longitudinal_spectrum(k1: np.ndarray, length: float) -> np.ndarray:
    """The one-dimensional spectrum of the longitudinal component of unit variance, ``F_u(k1)`` [m] over
    ``k1`` [rad/m] >= 0 (one-sided, ``∫_0^∞ F_u dk1 = 1``): von Kármán's ``F_u = (2 L / π) (1 + (k1 / k_e)^2)^(-5/6)``,
    ``k_e = 0.7468 / L`` (in frequency, ``4 σ² (L/U) / (1 + 70.8 (f L / U)^2)^(5/6)``)."""
    ke = VON_KARMAN_KE / length
    return (2.0 * length / math.pi) / (1.0 + (np.asarray(k1, dtype=np.float64) / ke) ** 2) ** (5.0 / 6.0)


def synthesise(length: float, seed: int, grid: tuple[int, int, int] = GRID) -> Field:
    """A von Kármán field for the integral length scale ``length`` [m] from ``seed`` (the same seed and length give
    the same field), of unit variance per component for the whole spectrum (less the share the grid cannot hold)."""
    cell = length / CELLS_PER_LENGTH
    rng = np.random.default_rng(seed)
    axes = [2.0 * np.pi * np.fft.fftfreq(n, d=cell) for n in grid]
    kx, ky, kz = np.meshgrid(*axes, indexing="ij")
    k2 = kx * kx + ky * ky + kz * kz
    k = np.sqrt(k2)
    volume = np.prod([2.0 * np.pi / (n * cell) for n in grid])  # the wavenumber cell
    with np.errstate(divide="ignore", invalid="ignore"):
        # the shell of radius k holds E(k) dk over 4 pi k^2 dk of wavenumber space; the real part of the transform
        # keeps half the power of complex noise of unit real and imaginary parts, which the projection halves again
        # for each of the two directions it keeps (hence no further factor: E is the sum over the three components)
        amplitude = np.sqrt(np.where(k > 0, von_karman_energy(k, length) / (4.0 * np.pi * k2), 0.0) * volume)
        unit = [np.where(k > 0, c / k, 0.0) for c in (kx, ky, kz)]
    noise = rng.standard_normal((3, *grid)) + 1j * rng.standard_normal((3, *grid))
    along = unit[0] * noise[0] + unit[1] * noise[1] + unit[2] * noise[2]
    velocity = np.empty((*grid, 3), dtype=np.float32)
    for c in range(3):  # the projection onto the plane normal to k keeps the field divergence-free
        spectral = amplitude * (noise[c] - unit[c] * along)
        velocity[..., c] = np.real(np.fft.ifftn(spectral) * np.prod(grid))
    velocity -= velocity.mean(axis=(0, 1, 2))
    return Field(velocity, cell, float(length))


def world_offset(seed: int, field: Field) -> np.ndarray:
    """Where world ``seed`` enters the field [m] (``[3]``, uniform in the box)."""
    return np.random.default_rng([seed, 7919]).random(3) * field.box


@functools.lru_cache(maxsize=2)
def field(length: float) -> Field:
    """The scene-wide field for the length scale ``length`` [m] (:func:`synthesise` from seed 0; kept for the next
    scene of the same length: worlds and scenes differ by where they enter it, :func:`world_offset`)."""
    return synthesise(length, 0)
