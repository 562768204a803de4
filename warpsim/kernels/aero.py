"""Per-triangle air force from the relative wind (paper Section 5.2, slide 14).

For a triangle (A, B, C) with normal ``N = (B - A) x (C - B)``, unit normal ``n``, area ``|N|/2``
and relative wind ``w = wind(z) - (vA + vB + vC)/3`` (``v = (x - x_prev)/dt``), the force is normal
to the triangle and pushed the way the wind blows through it:

* ``paper`` (default): ``F = rho * (n.w)|n.w| * area * n``. This is the paper's formula with the
  sign of ``n.w`` kept (the printed formula squares it and so loses the sign). In coefficient form
  it is a normal-force coefficient ``C_N = 2 sin^2(alpha)`` on ``q = rho |w|^2 / 2``, so it makes
  little force at small angles of attack ``alpha``.
* ``plate``: a flat plate whose normal-force coefficient grows like ``sin(alpha)`` at small angles
  and saturates near 90 degrees, ``C_N = 1 / (0.222 + 0.283 / sin(alpha))`` (Hoerner & Borst,
  *Fluid-Dynamic Lift*, 1985, ch. 21 flat-plate fit; ``C_N(90 deg) = 1.98``, about the paper's 2),
  ``F = 0.5 * rho * |w|^2 * area * C_N * sign(n.w) * n``.

  A uniform load per unit area would put every sail's centre of pressure at its area centroid at every
  angle of attack. A real plate or sail is loaded most near its leading edge: thin-aerofoil theory gives
  a pressure difference ``~ sqrt((1 - xi) / xi)`` at chord fraction ``xi``, with its centre at the quarter
  chord, and as the flow separates the load evens out towards the half chord (Hoerner & Borst, ch. 2 and
  21: the plate's centre of pressure moves from about 0.25 to 0.5 chord between 0 and 90 degrees). A
  builder may give each triangle a static loading factor ``L`` (area-weighted mean 1 over its sail, see
  :func:`warpsim.objects.delta.chordwise_loading`); the plate force is multiplied by
  ``L + (1 - L) * sin(alpha)``, which keeps the sail's total force and moves its centre of pressure from
  near the quarter chord at small angles to the area centroid at 90 degrees. The ``paper`` model ignores it.

Each vertex receives one third of its triangle's force. The wind may grow with height above the
terrain by a power law ``(h / h_ref)^shear_exponent`` (exponent 0 = uniform wind).
"""

from __future__ import annotations

import enum

import warp as wp

from .collision import HeightfieldData, terrain_height

wp.set_module_options({"enable_backward": False})  # forward-only: halves compile time


class AeroModel(enum.IntEnum):
    """Which air-force law acts on each triangle."""

    PAPER = 0
    PLATE = 1


@wp.func
def normal_force(
    n: wp.vec3, area: float, w_rel: wp.vec3, air_density: float, aero_model: int, loading: float
) -> wp.vec3:
    """Air force [N] on a flat triangle of unit normal ``n`` and ``area`` [m^2] in relative wind ``w_rel`` [m/s];
    ``loading`` is its chordwise loading factor (``plate`` only, 1 = uniform)."""
    wn = wp.dot(n, w_rel)
    if aero_model == AeroModel.PAPER:
        return n * (air_density * wn * wp.abs(wn) * area)
    speed = wp.length(w_rel)
    if speed == 0.0:
        return wp.vec3(0.0)
    sin_alpha = wp.abs(wn) / speed
    if sin_alpha < 1.0e-6:
        return wp.vec3(0.0)
    c_n = (1.0 / (0.222 + 0.283 / sin_alpha)) * (loading + (1.0 - loading) * sin_alpha)
    return n * (0.5 * air_density * speed * speed * area * c_n * wp.sign(wn))


@wp.func
def wind_at(wind: wp.vec3, height_above_ground: float, reference_height: float, shear_exponent: float) -> wp.vec3:
    """Wind [m/s] at a height above the terrain [m] under a power-law shear profile."""
    if shear_exponent == 0.0:
        return wind
    h = wp.max(height_above_ground, 0.1)
    return wind * wp.pow(h / reference_height, shear_exponent)


@wp.kernel
def _triangle_air_force(
    tri_indices: wp.array(dtype=wp.vec3i),
    tri_loading: wp.array(dtype=wp.float32),
    particle_world: wp.array(dtype=wp.int32),
    hf: HeightfieldData,
    particle_q: wp.array(dtype=wp.vec3),
    particle_q_prev: wp.array(dtype=wp.vec3),
    wind: wp.array(dtype=wp.vec3),
    dt: float,
    air_density: float,
    aero_model: int,
    aero_scale: float,
    shear_exponent: float,
    shear_reference_height: float,
    tri_force_out: wp.array(dtype=wp.vec3),
):
    t = wp.tid()
    idx = tri_indices[t]
    a = particle_q[idx[0]]
    b = particle_q[idx[1]]
    c = particle_q[idx[2]]
    cross = wp.cross(b - a, c - b)
    cross_len = wp.length(cross)
    if cross_len == 0.0:
        tri_force_out[t] = wp.vec3(0.0)
        return
    velocity = ((a - particle_q_prev[idx[0]]) + (b - particle_q_prev[idx[1]]) + (c - particle_q_prev[idx[2]])) / (
        3.0 * dt
    )
    centre = (a + b + c) / 3.0
    ground = terrain_height(hf, centre[0], centre[1])
    w = wind_at(wind[particle_world[idx[0]]], centre[2] - ground, shear_reference_height, shear_exponent)
    force = normal_force(cross / cross_len, 0.5 * cross_len, w - velocity, air_density, aero_model, tri_loading[t])
    tri_force_out[t] = force * (aero_scale / 3.0)


@wp.func
def gather_air_force(
    i: int,
    particle_tri_start: wp.array(dtype=wp.int32),
    particle_tri_ids: wp.array(dtype=wp.int32),
    tri_force: wp.array(dtype=wp.vec3),
) -> wp.vec3:
    """Sum of the per-vertex air forces [N] of the triangles around particle ``i`` (fixed order)."""
    f = wp.vec3(0.0)
    k = particle_tri_start[i]
    end = particle_tri_start[i + 1]
    while k < end:  # not range(): on the CPU Warp's range checks the step's sign on every pass
        f += tri_force[particle_tri_ids[k]]
        k += 1
    return f


def triangle_air_force(model, state, control, dt: float, air, wind, tri_force_out: wp.array) -> None:
    """Compute each triangle's per-vertex air force [N] into ``tri_force_out`` (shape ``[tri_count]``) for steps
    of ``dt`` [s].

    ``air`` is a :class:`warpsim.config.AirConfig` (law and scale), ``wind`` a :class:`warpsim.config.WindConfig`
    (its shear profile; the wind itself is ``control.wind``).
    """
    if model.tri_count == 0:
        return
    wp.launch(
        _triangle_air_force,
        dim=model.tri_count,
        inputs=[
            model.tri_indices,
            model.tri_loading,
            model.particle_world,
            model.terrain_data,
            state.particle_q,
            state.particle_q_prev,
            control.wind,
            float(dt),
            float(model.air_density),
            int(air.model),
            float(air.scale),
            float(wind.shear_exponent),
            float(wind.reference_height),
        ],
        outputs=[tri_force_out],
        device=model.device,
    )
