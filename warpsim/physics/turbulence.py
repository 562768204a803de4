"""Frozen turbulence with a named spectrum: an isotropic von Kármán field in a periodic box, carried by the mean wind.

The field is a divergence-free Gaussian velocity field whose energy spectrum is von Kármán's,
``E(k) ∝ (k L_e)^4 / (1 + (k L_e)^2)^(17/6)`` with ``L_e = L / 0.7468`` for the longitudinal integral length scale
``L`` [m] (the isotropic model of IEC 61400-1 ed. 2, Annex B, which takes ``L = 3.5 Λ1``, ``Λ1 = 0.7 z`` below 60 m).
It is synthesised once per scene by an inverse FFT on a periodic grid of ``GRID`` cells of side
``L / CELLS_PER_LENGTH`` (Mann 1998's method without his shear distortion), every mode with its wavenumber cell's
energy and a random phase (:func:`synthesise`), so that the field has unit variance per component for the whole
spectrum, less the eddies shorter than the grid holds (about 7-8 % of the variance), which are left out rather than
given to the larger ones. A world's air adds
``intensity * |wind|`` times the field at ``x - U t + offset`` (Taylor's frozen turbulence: the pattern travels with
the wind ``U`` at the reference height; ``offset`` is drawn from the world's seed, so that worlds with other seeds fly
through other parts of the same field). Between grid points the field is interpolated trilinearly.

Memory: one field per scene, whatever the number of worlds: ``GRID`` = 320 x 160 x 160 cells of three float32
components, 98 MB (and about 1.1 GB for about 5 s on two cores while it is synthesised).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

GRID = (320, 160, 160)
"""Cells of the periodic box along x (the mean wind's usual direction), y and z."""
CELLS_PER_LENGTH = 20
"""Grid cells per integral length scale ``L``: the box is 16 L x 8 L x 8 L (392 m x 196 m x 196 m at L = 24.5 m),
fine enough that the eddies it cannot hold carry about 7-8 % of the variance, and long enough for the
energy-containing eddies (a world carried 16 L meets the same air again: 39 s at 10 m/s for L = 24.5 m)."""
SAMPLING_FLOOR = 0.125
"""The least :func:`sampling_gain` the synthesis makes up for (a mode near the grid's corner, which trilinear
sampling keeps 1/27 of, is raised at most eightfold in power)."""
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


def sampling_gain(wavenumbers: list[np.ndarray], cell: float) -> np.ndarray:
    """The share of a Fourier mode's variance that trilinear sampling at uniformly spread points keeps,
    ``prod_a (2 + cos(k_a h)) / 3`` over the axes ``a`` (``wavenumbers``: the three broadcastable ``k_a`` [rad/m];
    ``cell``: the grid spacing ``h`` [m]): linear interpolation at a fraction ``s`` of a cell keeps
    ``|1 - s + s e^{i k h}|^2`` of a mode's power, ``1 - (1 - cos k h) / 3`` on average over ``s``."""
    gain = np.ones((), dtype=np.float32)
    for k in wavenumbers:
        gain = gain * ((2.0 + np.cos(k * cell)) / 3.0).astype(np.float32)
    return gain


def synthesise(length: float, seed: int, grid: tuple[int, int, int] = GRID) -> Field:
    """A von Kármán field for the integral length scale ``length`` [m] from ``seed`` (the same seed and length give
    the same field), of unit variance per component for the whole spectrum, less the share of the eddies shorter than
    the grid holds.

    Every Fourier mode gets von Kármán's energy for its wavenumber cell exactly, with random phases (the
    deterministic-amplitude, random-phase synthesis of Shinozuka & Deodatis 1991 that TurbSim also uses): a
    single field then has the model's variance, spectrum and correlations instead of a chi-square draw of them,
    which the few energy-containing modes of a periodic box make wide (±10 % from one seed to the next). Each
    mode's two directions normal to ``k`` (the field stays divergence-free) are ``e1 = x × k / |x × k|``, which has
    no ``u``, and ``e2 = k × e1 / |k|``, so that ``u``'s share of every mode is exact too. The amplitudes are divided
    by the square root of :func:`sampling_gain` (at most by ``1 / sqrt(SAMPLING_FLOOR)``), so that the field as the
    kernels sample it, trilinearly anywhere between the nodes, has von Kármán's spectrum where the grid holds it."""
    cell = length / CELLS_PER_LENGTH
    rng = np.random.default_rng(seed)
    axes = [(2.0 * np.pi * np.fft.fftfreq(n, d=cell)).astype(np.float32) for n in grid]
    kx, ky, kz = np.meshgrid(*axes, indexing="ij", sparse=True)
    k2 = kx * kx + ky * ky + kz * kz
    k = np.sqrt(k2)
    volume = float(np.prod([2.0 * np.pi / (n * cell) for n in grid]))  # the wavenumber cell
    gain = np.maximum(sampling_gain([kx, ky, kz], cell), SAMPLING_FLOOR)
    with np.errstate(divide="ignore", invalid="ignore"):
        # a mode's energy: the shell of radius k holds E(k) dk over 4 pi k^2 dk of wavenumber space, shared by the
        # two directions normal to k
        energy = np.where(k > 0, von_karman_energy(k, length) / (4.0 * np.pi * k2), 0.0) * volume
        amplitude = np.sqrt(energy / gain).astype(np.float32)
        across = np.sqrt(ky * ky + kz * kz)  # [1, ny, nz]
        on_x = across == 0  # k along x (or zero): e1 = y, e2 = z
        e1 = (None, np.where(on_x, 1.0, -kz / across), np.where(on_x, 0.0, ky / across))
        e2 = (
            np.where(on_x, 0.0, across / k),
            np.where(on_x, 0.0, -kx * ky / (across * k)),
            np.where(on_x, 1.0, -kx * kz / (across * k)),
        )
    del k2, k, energy, gain
    for axis, n in enumerate(grid):  # a Nyquist wavenumber is its own mirror: no real divergence-free mode there
        if n % 2 == 0:
            amplitude[(slice(None),) * axis + (n // 2,)] = 0.0
    phase1 = np.exp(2j * np.pi * rng.random(grid, dtype=np.float32)).astype(np.complex64) * amplitude
    phase2 = np.exp(2j * np.pi * rng.random(grid, dtype=np.float32)).astype(np.complex64) * amplitude
    del amplitude
    # a real field: the coefficient of -k is the conjugate of k's (the first of each pair in memory order is kept;
    # k = 0, its own mirror, carries nothing)
    mirror = np.ix_(*[(-np.arange(n)) % n for n in grid])
    order = np.arange(int(np.prod(grid))).reshape(grid)
    kept = order <= order[mirror]
    del order
    velocity = np.empty((*grid, 3), dtype=np.float32)
    for c in range(3):
        coefficient = phase2 * e2[c].astype(np.float32)
        if e1[c] is not None:
            coefficient += phase1 * e1[c].astype(np.float32)
        coefficient = np.where(kept, coefficient, np.conj(coefficient[mirror]))
        velocity[..., c] = np.fft.ifftn(coefficient, norm="forward").real
    return Field(velocity, cell, float(length))


def world_offset(seed: int, field: Field) -> np.ndarray:
    """Where world ``seed`` enters the field [m] (``[3]``, uniform in the box)."""
    return np.random.default_rng([seed, 7919]).random(3) * field.box


@functools.lru_cache(maxsize=2)
def field(length: float) -> Field:
    """The scene-wide field for the length scale ``length`` [m] (:func:`synthesise` from seed 0; kept for the next
    scene of the same length: worlds and scenes differ by where they enter it, :func:`world_offset`)."""
    return synthesise(length, 0)
