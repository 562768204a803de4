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
import math

import warp as wp

from .collision import HeightfieldData, terrain_height

wp.set_module_options({"enable_backward": False})  # forward-only: halves compile time


class AeroModel(enum.IntEnum):
    """Which air-force law acts on each triangle."""

    PAPER = 0
    PLATE = 1
    SAIL = 2
    VORTEX = 3
    """The ``sail`` law on every triangle, except on the lifting surfaces a builder declares, whose air is the
    vortex lattice's (:mod:`warpsim.physics.kernels.vortex`)."""


STALL_SHARPNESS = wp.constant(40.0)
"""Sharpness ``M`` [1/rad] of the ``sail`` model's blend from attached to separated flow around the stall
angle: half the way at the stall angle, 90 % of it 3.1 degrees later (Beard & McLain's blend uses 50)."""


def sail_coefficients(
    aspect_ratio: float,
    sweep_deg: float = 0.0,
    oswald: float = 0.8,
    profile_drag: float = 0.03,
    stall_deg: float = 18.0,
) -> tuple[float, float, float, float]:
    """The ``sail`` air model's per-triangle coefficients for a sail of ``aspect_ratio`` (span^2 / area) whose
    half-chord line is swept back ``sweep_deg`` degrees: ``(lift slope [1/rad], induced-drag factor,
    profile drag coefficient, stall angle [rad])``.

    * Lift slope: the Helmbold-DATCOM formula for a thin wing of finite span,
      ``a = 2 pi A / (2 + sqrt(A^2 (1 + tan^2 Lambda) + 4))`` (USAF DATCOM 4.1.3.2; Anderson, *Fundamentals of
      Aerodynamics*, 5th ed., eq. 5.81 for the unswept case); it tends to thin-aerofoil theory's ``2 pi`` for a
      long straight wing.
    * Induced drag ``C_L^2 / (pi e A)`` with Oswald's span efficiency ``oswald`` (0.7-0.85 for real wings;
      Raymer, *Aircraft Design*, 6th ed., 12.6).
    * ``profile_drag``: the cloth's skin friction and form drag at zero lift (0.02-0.04 for single-surface
      sails and membrane wings; Hoerner, *Fluid-Dynamic Drag*, 1965, ch. 2 and 14; Cook & Spottiswoode 2006).
    * ``stall_deg``: the angle of attack where the flow separates and the law turns into the ``plate`` one.
    """
    a_r, sweep = float(aspect_ratio), math.radians(float(sweep_deg))
    if not a_r > 0.0 or not 0.0 < oswald <= 1.0 or profile_drag < 0.0 or not 0.0 < stall_deg < 90.0:
        raise ValueError(
            f"sail coefficients need aspect ratio > 0, 0 < oswald <= 1, profile drag >= 0 and 0 < stall < 90 deg, "
            f"got {aspect_ratio}, {oswald}, {profile_drag}, {stall_deg}"
        )
    slope = 2.0 * math.pi * a_r / (2.0 + math.sqrt(a_r * a_r * (1.0 + math.tan(sweep) ** 2) + 4.0))
    return slope, 1.0 / (math.pi * oswald * a_r), float(profile_drag), math.radians(float(stall_deg))


@wp.func
def plate_normal_coefficient(sin_alpha: float) -> float:
    """Hoerner & Borst's flat-plate normal-force coefficient at ``sin(alpha)`` (> 0)."""
    return 1.0 / (0.222 + 0.283 / sin_alpha)


@wp.func
def stall_blend(angle: float, stall_angle: float) -> float:
    """Share (0-1) of a sail's load that the separated flow carries at ``angle`` [rad] of attack against its stall
    angle [rad]: the ``sail`` law's logistic blend of sharpness :data:`STALL_SHARPNESS` (the vortex law's too)."""
    return 1.0 / (1.0 + wp.exp(-STALL_SHARPNESS * (angle - stall_angle)))


@wp.func
def sail_force(
    n: wp.vec3, area: float, w_rel: wp.vec3, span: wp.vec3, air_density: float, loading: float, coef: wp.vec4
) -> wp.vec3:
    """``sail`` air force [N] on a flat triangle (unit normal ``n``, ``area`` [m^2]) in relative wind ``w_rel``
    [m/s]: lift perpendicular to the wind and drag along it, with the coefficients ``coef`` of
    :func:`sail_coefficients` and the chordwise ``loading`` factor. ``span`` is the unit direction of the
    sail's leading edge at the triangle (zero: none); the attached flow feels only the wind across it
    (simple sweep theory), which is what rolls a swept wing away from a sideslip."""
    speed = wp.length(w_rel)
    if speed == 0.0:
        return wp.vec3(0.0)
    w_hat = w_rel / speed
    # attached flow: the wind across the leading edge, its angle of attack, lift slope and drag
    w_n = w_rel - span * wp.dot(w_rel, span)
    speed_n = wp.length(w_n)
    force = w_hat * (coef[2] * speed * speed)  # profile drag
    sin_n = 0.0
    if speed_n > 1.0e-6 * speed:
        wn_hat = w_n / speed_n
        d = wp.dot(n, wn_hat)
        sin_n = wp.min(wp.abs(d), 1.0)
        cos_n = wp.sqrt(wp.max(1.0 - sin_n * sin_n, 0.0))
        cl_att = coef[0] * wp.asin(sin_n)
        lift_dir = wp.vec3(0.0)
        if cos_n > 1.0e-6:
            lift_dir = (n * wp.sign(d) - wn_hat * sin_n) / cos_n
        attached = (lift_dir * cl_att + wn_hat * (coef[1] * cl_att * cl_att)) * (speed_n * speed_n)
    else:
        attached = wp.vec3(0.0)
    # separated flow: the plate's normal force on the whole wind
    wn = wp.dot(n, w_hat)
    sin_a = wp.min(wp.abs(wn), 1.0)
    separated = wp.vec3(0.0)
    if sin_a > 1.0e-6:
        separated = n * (wp.sign(wn) * plate_normal_coefficient(sin_a) * speed * speed)
    sigma = stall_blend(wp.asin(sin_a), coef[3])
    force += attached * (1.0 - sigma) + separated * sigma
    return force * (0.5 * air_density * area * (loading + (1.0 - loading) * sin_a))


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


@wp.struct
class TurbulenceData:
    """A frozen turbulence field on the device (:mod:`warpsim.physics.turbulence`) and where each world is in it.

    Attributes:
        velocity: ``[nx, ny, nz]`` vec3 the periodic field (unit standard deviation per component).
        inv_cell: 1 / the grid spacing [1/m] (float64: a float32 one is off by 1e-4 cells 3 km out).
        shift: ``[W]`` vec3d what each world adds to a position to find it in the field [m] (its entry point, less
            the distance the mean wind has carried the field).
        scale: ``[W]`` float32 each world's turbulence standard deviation [m/s] (0: none).
    """

    velocity: wp.array3d(dtype=wp.vec3)
    inv_cell: wp.float64
    shift: wp.array(dtype=wp.vec3d)
    scale: wp.array(dtype=wp.float32)


@wp.func
def _wrap(i: int, n: int) -> int:
    return ((i % n) + n) % n


@wp.func
def turbulence_at(turb: TurbulenceData, world: int, x: wp.vec3d) -> wp.vec3:
    """The turbulence [m/s] world ``world`` has at ``x`` [m] now (trilinear in the periodic field; zero without)."""
    s = turb.scale[world]
    if s == 0.0:
        return wp.vec3(0.0)
    p = (x + turb.shift[world]) * turb.inv_cell
    fx = wp.floor(p[0])
    fy = wp.floor(p[1])
    fz = wp.floor(p[2])
    tx = float(p[0] - fx)
    ty = float(p[1] - fy)
    tz = float(p[2] - fz)
    nx = turb.velocity.shape[0]
    ny = turb.velocity.shape[1]
    nz = turb.velocity.shape[2]
    i0 = _wrap(int(fx), nx)
    j0 = _wrap(int(fy), ny)
    k0 = _wrap(int(fz), nz)
    i1 = (i0 + 1) % nx
    j1 = (j0 + 1) % ny
    k1 = (k0 + 1) % nz
    v = turb.velocity
    low = (v[i0, j0, k0] * (1.0 - tx) + v[i1, j0, k0] * tx) * (1.0 - ty) + (
        v[i0, j1, k0] * (1.0 - tx) + v[i1, j1, k0] * tx
    ) * ty
    high = (v[i0, j0, k1] * (1.0 - tx) + v[i1, j0, k1] * tx) * (1.0 - ty) + (
        v[i0, j1, k1] * (1.0 - tx) + v[i1, j1, k1] * tx
    ) * ty
    return (low * (1.0 - tz) + high * tz) * s


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
    tri_sail: wp.array(dtype=wp.vec4),
    tri_span: wp.array(dtype=wp.vec2i),
    particle_world: wp.array(dtype=wp.int32),
    hf: HeightfieldData,
    particle_q: wp.array(dtype=wp.vec3d),
    particle_q_prev: wp.array(dtype=wp.vec3d),
    wind: wp.array(dtype=wp.vec3),
    turb: TurbulenceData,
    dt: float,
    world_density: wp.array(dtype=wp.float32),
    aero_model: int,
    aero_scale: float,
    shear_exponent: float,
    shear_reference_height: float,
    tri_force_out: wp.array(dtype=wp.vec3),
):
    t = wp.tid()
    idx = tri_indices[t]
    # float64 positions; edges, velocity and centre are measured in float64, then rounded to float32
    a = particle_q[idx[0]]
    b = particle_q[idx[1]]
    c = particle_q[idx[2]]
    cross = wp.cross(wp.vec3(b - a), wp.vec3(c - b))
    cross_len = wp.length(cross)
    if cross_len == 0.0:
        tri_force_out[t] = wp.vec3(0.0)
        return
    moved = (a - particle_q_prev[idx[0]]) + (b - particle_q_prev[idx[1]]) + (c - particle_q_prev[idx[2]])
    velocity = wp.vec3(moved) / (3.0 * dt)
    centre = (a + b + c) / wp.float64(3.0)
    height = float(centre[2] - terrain_height(hf, centre[0], centre[1]))
    world = particle_world[idx[0]]
    w = wind_at(wind[world], height, shear_reference_height, shear_exponent) + turbulence_at(turb, world, centre)
    air_density = world_density[world]
    n = cross / cross_len
    if aero_model == AeroModel.SAIL or aero_model == AeroModel.VORTEX:
        ends = tri_span[t]
        span = wp.vec3(0.0)
        if ends[0] >= 0:
            span = wp.normalize(wp.vec3(particle_q[ends[1]] - particle_q[ends[0]]))
        force = sail_force(n, 0.5 * cross_len, w - velocity, span, air_density, tri_loading[t], tri_sail[t])
    else:
        force = normal_force(n, 0.5 * cross_len, w - velocity, air_density, aero_model, tri_loading[t])
    tri_force_out[t] = force * (aero_scale / 3.0)


@wp.kernel
def _body_drag(
    drag_particles: wp.array(dtype=wp.int32),
    drag_area: wp.array(dtype=wp.float32),
    particle_world: wp.array(dtype=wp.int32),
    hf: HeightfieldData,
    particle_q: wp.array(dtype=wp.vec3d),
    particle_q_prev: wp.array(dtype=wp.vec3d),
    wind: wp.array(dtype=wp.vec3),
    turb: TurbulenceData,
    dt: float,
    world_density: wp.array(dtype=wp.float32),
    aero_scale: float,
    shear_exponent: float,
    shear_reference_height: float,
    accumulate: int,
    particle_air_out: wp.array(dtype=wp.vec3),
):
    k = wp.tid()
    i = drag_particles[k]
    x = particle_q[i]
    world = particle_world[i]
    w = wind_at(wind[world], float(x[2] - terrain_height(hf, x[0], x[1])), shear_reference_height, shear_exponent)
    w += turbulence_at(turb, world, x)
    w = w - wp.vec3(x - particle_q_prev[i]) / dt
    drag = w * (0.5 * world_density[particle_world[i]] * wp.length(w) * drag_area[k] * aero_scale)
    if accumulate != 0:
        drag += particle_air_out[i]
    particle_air_out[i] = drag


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

    ``air`` is a :class:`warpsim.physics.config.AirConfig` (law and scale), ``wind`` a
    :class:`warpsim.physics.config.WindConfig`
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
            model.tri_sail,
            model.tri_span,
            model.particle_world,
            model.terrain_data,
            state.particle_q,
            state.particle_q_prev,
            control.wind,
            control.turbulence.data,
            float(dt),
            control.air_density,
            int(air.model),
            float(air.scale),
            float(wind.shear_exponent),
            float(wind.reference_height),
        ],
        outputs=[tri_force_out],
        device=model.device,
    )


def body_drag(model, state, control, dt: float, air, wind, particle_air_out: wp.array) -> None:
    """Parasitic drag [N] of the model's drag bodies (a pilot, a frame: particles given a drag area ``C_D A``
    [m^2]), ``0.5 rho C_D A |w| w`` in the relative wind ``w``, written into ``particle_air_out`` (``[P]``) at
    their particles (added to what is there when the model has lifting surfaces under the ``vortex`` law, whose
    forces are written there first). Only the ``sail`` and ``vortex`` air models have drag bodies; the others leave
    the array at zero."""
    if model.drag_count == 0 or int(air.model) not in (AeroModel.SAIL, AeroModel.VORTEX):
        return
    accumulate = int(int(air.model) == AeroModel.VORTEX and model.lattice.panel_count > 0)
    wp.launch(
        _body_drag,
        dim=model.drag_count,
        inputs=[
            model.drag_particles,
            model.drag_area,
            model.particle_world,
            model.terrain_data,
            state.particle_q,
            state.particle_q_prev,
            control.wind,
            control.turbulence.data,
            float(dt),
            control.air_density,
            float(air.scale),
            float(wind.shear_exponent),
            float(wind.reference_height),
            accumulate,
        ],
        outputs=[particle_air_out],
        device=model.device,
    )
