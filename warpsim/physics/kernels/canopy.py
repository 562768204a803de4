"""Whole-canopy air force of round parachutes, spread over the canopy's triangles.

A parachute canopy is not a set of independent plates: the air it catches stagnates inside it, so the cloth
feels one pressure difference over its whole inside, and the flow spilling round the rim decides its side
force. Parachute designers therefore describe a canopy by two whole-canopy coefficients measured in wind
tunnels against its angle of attack ``alpha`` (between its axis and the relative wind; Knacke, *Parachute
Recovery Systems Design Manual*, NWC TP 6575, 1991, ch. 5; Ginn, Clark & Braun, AIAA 2014-2390): the
tangential force ``C_T(alpha)`` along the axis and the normal force ``C_N(alpha)`` across it, both on the
nominal (cloth) area ``S_0`` and the dynamic pressure ``q = rho |w|^2 / 2``.

Per canopy and step:

* the canopy's area vector ``S = sum(area_t n_t)`` (oriented from the mouth to the apex: its axis ``a`` and
  projected area ``|S|``), its area-weighted velocity and centre are summed over its triangles;
* ``w`` = wind at the centre minus that velocity; ``cos(alpha) = w.a / |w|``;
* the tangential force is an internal pressure ``dp = q C_T(alpha) S_0 / S_p0`` on every triangle along its
  normal (``S_p0`` the projected area as built), which sums to ``q C_T S_0 |S| / S_p0`` along the axis: the
  built canopy's drag, falling as the canopy closes, and the pressure that keeps the cloth inflated;
* the normal force ``q C_N(alpha) S_0 |S| / S_p0`` points along the part of ``w`` across the axis (positive
  ``C_N`` pushes the canopy downwind of its load: restoring), spread over the triangles by area.

``C_T`` and ``C_N`` are tables over ``alpha`` = 0, 5, ..., 180 degrees (:data:`TABLE_ROWS` rows), given per canopy
by its builder (:func:`warpsim.objects.parachute.canopy_table`). The kernels loop over a canopy's triangles in
a fixed order, so the result is the same on every run and device.
"""

from __future__ import annotations

import warp as wp

from .aero import TurbulenceData, turbulence_at, wind_at
from .collision import HeightfieldData, terrain_height

wp.set_module_options({"enable_backward": False})

TABLE_ROWS = 37
"""Rows of a canopy's coefficient table: ``alpha`` = 0, 5, ..., 180 degrees."""
TABLE_STEP_DEG = 5.0


@wp.kernel
def _canopy_load(
    canopy_tri_start: wp.array(dtype=wp.int32),
    canopy_tri_ids: wp.array(dtype=wp.int32),
    canopy_params: wp.array(dtype=wp.vec4),
    canopy_table: wp.array(dtype=wp.vec2),
    tri_indices: wp.array(dtype=wp.vec3i),
    particle_world: wp.array(dtype=wp.int32),
    hf: HeightfieldData,
    particle_q: wp.array(dtype=wp.vec3d),
    particle_q_prev: wp.array(dtype=wp.vec3d),
    wind: wp.array(dtype=wp.vec3),
    turb: TurbulenceData,
    dt: float,
    world_density: wp.array(dtype=wp.float32),
    shear_exponent: float,
    shear_reference_height: float,
    canopy_side_out: wp.array(dtype=wp.vec3),
    canopy_load_out: wp.array(dtype=wp.vec4),
):
    c = wp.tid()
    params = canopy_params[c]  # S_0 [m^2], S_p0 [m^2], orientation (+-1), wake lag
    area_vec = wp.vec3(0.0)
    area = float(0.0)  # noqa: UP018 -- Warp needs float() to make a variable a loop may change
    velocity = wp.vec3(0.0)
    centre = wp.vec3d(wp.float64(0.0), wp.float64(0.0), wp.float64(0.0))
    k = canopy_tri_start[c]
    end = canopy_tri_start[c + 1]
    first = tri_indices[canopy_tri_ids[k]][0]
    while k < end:
        idx = tri_indices[canopy_tri_ids[k]]
        a = particle_q[idx[0]]
        b = particle_q[idx[1]]
        d = particle_q[idx[2]]
        cross = wp.cross(wp.vec3(b - a), wp.vec3(d - b))
        tri_area = 0.5 * wp.length(cross)
        moved = (a - particle_q_prev[idx[0]]) + (b - particle_q_prev[idx[1]]) + (d - particle_q_prev[idx[2]])
        area_vec += 0.5 * cross
        area += tri_area
        velocity += wp.vec3(moved) * (tri_area / (3.0 * dt))
        centre += (a + b + d) * wp.float64(tri_area / 3.0)
        k += 1
    projected = wp.length(area_vec)
    if area <= 0.0 or projected <= 0.0:
        canopy_load_out[c] = wp.vec4(0.0)
        return
    axis = area_vec * (params[2] / projected)
    velocity = velocity / area
    centre = centre / wp.float64(area)
    height = float(centre[2] - terrain_height(hf, centre[0], centre[1]))
    world = particle_world[first]
    w = wind_at(wind[world], height, shear_reference_height, shear_exponent) + turbulence_at(turb, world, centre)
    w = w - velocity
    speed = wp.length(w)
    if speed == 0.0:
        canopy_load_out[c] = wp.vec4(0.0)
        return
    cos_a = wp.clamp(wp.dot(w, axis) / speed, -1.0, 1.0)
    x = wp.acos(cos_a) * (180.0 / wp.pi) / TABLE_STEP_DEG
    row = wp.min(int(x), TABLE_ROWS - 2)
    frac = wp.min(x - float(row), 1.0)
    coef = canopy_table[c * TABLE_ROWS + row] * (1.0 - frac) + canopy_table[c * TABLE_ROWS + row + 1] * frac
    q = 0.5 * world_density[particle_world[first]] * speed * speed
    pressure = q * coef[0] * params[0] / params[1]  # along axis-oriented normals [Pa]
    across = w - axis * wp.dot(w, axis)
    across_len = wp.length(across)
    side = wp.vec3(0.0)  # normal force per unit cloth area [Pa], as the air would give it steadily
    if across_len > 1.0e-6 * speed:
        side = across * (q * coef[1] * params[0] * projected / (params[1] * area * across_len))
    # the wake lags: the side force follows its steady value with a time constant lag * D_p / |w|
    if params[3] > 0.0:
        tau = params[3] * 2.0 * wp.sqrt(params[1] / wp.pi) / speed
        side = canopy_side_out[c] + (side - canopy_side_out[c]) * wp.min(dt / tau, 1.0)
    canopy_side_out[c] = side  # the lagged side force, read back next step
    canopy_load_out[c] = wp.vec4(pressure * params[2], side[0], side[1], side[2])


@wp.kernel
def _canopy_triangle_force(
    canopy_tri_ids: wp.array(dtype=wp.int32),
    canopy_tri_owner: wp.array(dtype=wp.int32),
    canopy_load: wp.array(dtype=wp.vec4),
    tri_indices: wp.array(dtype=wp.vec3i),
    particle_q: wp.array(dtype=wp.vec3d),
    aero_scale: float,
    tri_force_out: wp.array(dtype=wp.vec3),
):
    k = wp.tid()
    t = canopy_tri_ids[k]
    load = canopy_load[canopy_tri_owner[k]]
    idx = tri_indices[t]
    a = particle_q[idx[0]]
    b = particle_q[idx[1]]
    d = particle_q[idx[2]]
    cross = wp.cross(wp.vec3(b - a), wp.vec3(d - b))
    tri_area = 0.5 * wp.length(cross)
    force = cross * (0.5 * load[0]) + wp.vec3(load[1], load[2], load[3]) * tri_area
    tri_force_out[t] = force * (aero_scale / 3.0)


def canopy_air_force(
    model, state, control, dt: float, air, wind, canopy_side: wp.array, canopy_load: wp.array, tri_force_out: wp.array
):
    """Overwrite the per-vertex air force [N] of every canopy triangle in ``tri_force_out`` with its share of its
    canopy's whole-canopy force (see the module text), for steps of ``dt`` [s]; ``canopy_load`` (``[C]`` vec4) is
    scratch space for each canopy's pressure [Pa] and normal traction [Pa]. ``air`` and ``wind`` as for
    :func:`warpsim.physics.kernels.aero.triangle_air_force`. Models without canopies are left alone."""
    if getattr(model, "canopy_count", 0) == 0:
        return
    wp.launch(
        _canopy_load,
        dim=model.canopy_count,
        inputs=[
            model.canopy_tri_start,
            model.canopy_tri_ids,
            model.canopy_params,
            model.canopy_table,
            model.tri_indices,
            model.particle_world,
            model.terrain_data,
            state.particle_q,
            state.particle_q_prev,
            control.wind,
            control.turbulence.data,
            float(dt),
            control.air_density,
            float(wind.shear_exponent),
            float(wind.reference_height),
        ],
        outputs=[canopy_side, canopy_load],
        device=model.device,
    )
    wp.launch(
        _canopy_triangle_force,
        dim=len(model.canopy_tri_ids),
        inputs=[
            model.canopy_tri_ids,
            model.canopy_tri_owner,
            canopy_load,
            model.tri_indices,
            state.particle_q,
            float(air.scale),
        ],
        outputs=[tri_force_out],
        device=model.device,
    )
