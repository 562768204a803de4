"""Air from the sail's own shape: a vortex-lattice law on a lifting surface's triangles (``air.model = "vortex"``).

The method is the vortex-ring lattice of Katz & Plotkin, *Low-Speed Aerodynamics* (2nd ed., 2001), sections 12.3
and 13.12, on an unstructured mesh:

* every triangle of a lifting surface is a panel carrying a vortex ring of circulation ``G`` along its three edges
  (``a -> b -> c``, right-handed about its normal ``n = (b - a) x (c - b) / |...|``);
* the wake is quasi-steady: from every trailing edge a horseshoe's two semi-infinite legs leave along the surface's
  mean relative wind, carrying the edge's panel's circulation (the Kutta condition);
* no air passes through the sail at each panel's centroid: ``sum_j A_ij G_j = -w_i . n_i`` with ``w_i`` the wind
  minus the sail's own velocity there (so a rolling or yawing sail is damped by its own motion) and ``A_ij`` the
  velocity ring ``j`` (and its wake legs) induces at centroid ``i`` per unit circulation, along ``n_i``;
* the ``N x N`` system of each surface is factorised by Gaussian elimination with partial pivoting (one thread per
  surface, ``N^3 / 3`` multiply-adds) every ``air.vortex_interval`` seconds, the influence matrix rebuilt then (one
  thread per row), and again every step while a factorisation failed (no relative wind, a singular matrix); every
  step the circulations come from those factors and this step's ``w_i . n_i`` by substitution (``N^2``), so the
  sail's own motion, gusts and the controls act at once and only the lattice's geometry and its wake's direction
  lag;
* Kutta-Joukowski on every edge inside the sail or on its leading and side edges: ``F = rho G_e (V x l)`` with
  ``G_e`` the net circulation of the edge (the difference of its two panels'), ``l`` the edge [m] and ``V`` the
  local relative wind at its midpoint (Katz & Plotkin eq. 12.24 with the sail's own motion in ``V``); half of it
  goes to each of the edge's particles. Lift, the lift moments of sweep, dihedral and twist and the damping of
  rotation follow from the shape;
* the induced drag from the far wake (a Trefftz-plane evaluation, Katz & Plotkin 8.3 and 12.3): each trailing edge
  carries its panel's circulation ``G`` into the wake, and the wake legs' downwash ``w`` at its midpoint (half the
  far wake's) loads it with ``rho G (w x l)``; summed over a straight trailing edge this is ``(rho / 2) sum G w_T
  ds``, the far-field induced drag. Its spanwise spread gives the yaw moment of an asymmetric load;
* a section polar for what potential flow leaves out, per panel from the sail law's coefficients
  (:func:`warpsim.physics.kernels.aero.sail_coefficients`): profile drag ``0.5 rho C_D0 |w| w A`` and, past the
  stall angle (of the panel's relative wind to the sail's mean plane), a blend into the flat plate's separated
  normal force (the blend of the ``sail`` law), the lattice's edge forces fading by the mean of their two panels'
  blends.

Induced velocities use a cut-off core (the vortex core of Katz & Plotkin 10.4.5 / 11.5, ``|r1 x r2|^2 + (d |r0|)^2``
in the segment's law) of ``d = 5 %`` of the surface's mean panel size, so a sail that folds or flies edge-on stays
finite. Positions are measured in float32 from one particle of each surface, so the law is the same 10 km out.

Each edge's load goes a quarter of the way towards the far corner of the panel downstream of it (three eighths to
either particle of the edge, a quarter to that corner), where the classical lattice (rings shifted a quarter panel
back) puts its bound vortex; left on the edges, the loads would sit a quarter panel forward.
The free wake of unsteady flow is not modelled here: the wake follows the relative wind of the moment.
"""

from __future__ import annotations

import numpy as np
import warp as wp

from .aero import TurbulenceData, plate_normal_coefficient, stall_blend, turbulence_at, wind_at
from .collision import HeightfieldData, terrain_height
from .influence import TRAILING, factor_lu, matrix_rows, substitute, tick, wake_velocity

wp.set_module_options({"enable_backward": False})

CORE_FRACTION = wp.constant(0.05)
"""Vortex core radius as a fraction of the surface's mean panel size (square root of the mean panel area)."""
LOAD_SHIFT = wp.constant(0.25)
"""Share of an edge's load moved to the far corner of its downstream panel: a quarter of the way there."""


@wp.kernel
def _panels(
    panel_tri: wp.array(dtype=wp.int32),
    panel_surface: wp.array(dtype=wp.int32),
    surface_origin: wp.array(dtype=wp.int32),
    tri_indices: wp.array(dtype=wp.vec3i),
    particle_world: wp.array(dtype=wp.int32),
    hf: HeightfieldData,
    particle_q: wp.array(dtype=wp.vec3d),
    particle_q_prev: wp.array(dtype=wp.vec3d),
    wind: wp.array(dtype=wp.vec3),
    turb: TurbulenceData,
    dt: float,
    shear_exponent: float,
    shear_reference_height: float,
    corners_out: wp.array(dtype=wp.vec3),
    point_out: wp.array(dtype=wp.vec3),
    normal_out: wp.array(dtype=wp.vec4),
    wind_out: wp.array(dtype=wp.vec3),
):
    v = wp.tid()
    idx = tri_indices[panel_tri[v]]
    o = particle_q[surface_origin[panel_surface[v]]]
    a = wp.vec3(particle_q[idx[0]] - o)
    b = wp.vec3(particle_q[idx[1]] - o)
    c = wp.vec3(particle_q[idx[2]] - o)
    corners_out[3 * v + 0] = a
    corners_out[3 * v + 1] = b
    corners_out[3 * v + 2] = c
    cross = wp.cross(b - a, c - b)
    length = wp.length(cross)
    n = wp.vec3(0.0)
    if length > 0.0:
        n = cross / length
    normal_out[v] = wp.vec4(n[0], n[1], n[2], 0.5 * length)
    centre = (a + b + c) / 3.0
    point_out[v] = centre
    moved = (particle_q[idx[0]] - particle_q_prev[idx[0]]) + (particle_q[idx[1]] - particle_q_prev[idx[1]])
    moved += particle_q[idx[2]] - particle_q_prev[idx[2]]
    x = o + wp.vec3d(centre)
    height = float(x[2] - terrain_height(hf, x[0], x[1]))
    world = particle_world[idx[0]]
    w = wind_at(wind[world], height, shear_reference_height, shear_exponent) + turbulence_at(turb, world, x)
    wind_out[v] = w - wp.vec3(moved) / (3.0 * dt)


@wp.kernel
def _surfaces(
    surface_start: wp.array(dtype=wp.int32),
    normal: wp.array(dtype=wp.vec4),
    panel_wind: wp.array(dtype=wp.vec3),
    wake_out: wp.array(dtype=wp.vec4),
    plane_out: wp.array(dtype=wp.vec3),
):
    s = wp.tid()
    w = wp.vec3(0.0)
    plane = wp.vec3(0.0)
    area = float(0.0)  # noqa: UP018 -- Warp needs float() for a variable a loop changes
    k = surface_start[s]
    end = surface_start[s + 1]
    while k < end:
        a = normal[k][3]
        w += panel_wind[k] * a
        plane += wp.vec3(normal[k][0], normal[k][1], normal[k][2]) * a
        area += a
        k += 1
    if wp.length(plane) > 0.0:
        plane = wp.normalize(plane)
    plane_out[s] = plane
    d = wp.vec3(0.0)
    core2 = float(0.0)  # noqa: UP018
    if area > 0.0 and wp.length(w) > 0.0:
        d = wp.normalize(w)
        core2 = CORE_FRACTION * CORE_FRACTION * area / float(end - surface_start[s])
    wake_out[s] = wp.vec4(d[0], d[1], d[2], core2)


@wp.kernel
def _keep_basis(
    panel_surface: wp.array(dtype=wp.int32),
    surface_start: wp.array(dtype=wp.int32),
    counter: wp.array(dtype=wp.int32),
    factored: wp.array(dtype=wp.int32),
    corners: wp.array(dtype=wp.vec3),
    point: wp.array(dtype=wp.vec3),
    normal: wp.array(dtype=wp.vec4),
    wake: wp.array(dtype=wp.vec4),
    basis_corners_out: wp.array(dtype=wp.vec3),
    basis_point_out: wp.array(dtype=wp.vec3),
    basis_normal_out: wp.array(dtype=wp.vec4),
    basis_wake_out: wp.array(dtype=wp.vec4),
):
    i = wp.tid()  # what matrix_rows builds panel i's row from, kept when it does: a checkpoint's way to its factors
    s = panel_surface[i]
    if counter[0] != 0 and factored[s] != 0:
        return
    for e in range(3):
        basis_corners_out[3 * i + e] = corners[3 * i + e]
    basis_point_out[i] = point[i]
    basis_normal_out[i] = normal[i]
    if i == surface_start[s]:
        basis_wake_out[s] = wake[s]


@wp.kernel
def _wake_downwash(
    edge_panels: wp.array(dtype=wp.vec2i),
    edge_corner: wp.array(dtype=wp.int32),
    panel_surface: wp.array(dtype=wp.int32),
    panel_trailing: wp.array(dtype=wp.int32),
    surface_start: wp.array(dtype=wp.int32),
    corners: wp.array(dtype=wp.vec3),
    wake: wp.array(dtype=wp.vec4),
    gamma: wp.array(dtype=wp.float32),
    induced_out: wp.array(dtype=wp.vec3),
):
    e = wp.tid()
    p = edge_panels[e][0]
    if edge_panels[e][1] != TRAILING:
        return
    k = edge_corner[e]
    x = 0.5 * (corners[3 * p + k] + corners[3 * p + (k + 1) % 3])
    s = panel_surface[p]
    wk = wake[s]
    induced_out[e] = wake_velocity(
        x, surface_start[s], surface_start[s + 1], panel_trailing, corners, gamma, wp.vec3(wk[0], wk[1], wk[2]), wk[3]
    )


@wp.kernel
def _polar(
    panel_tri: wp.array(dtype=wp.int32),
    panel_surface: wp.array(dtype=wp.int32),
    tri_sail: wp.array(dtype=wp.vec4),
    normal: wp.array(dtype=wp.vec4),
    panel_wind: wp.array(dtype=wp.vec3),
    plane: wp.array(dtype=wp.vec3),
    tri_indices: wp.array(dtype=wp.vec3i),
    particle_world: wp.array(dtype=wp.int32),
    world_density: wp.array(dtype=wp.float32),
    aero_scale: float,
    stall_out: wp.array(dtype=wp.float32),
    tri_force_out: wp.array(dtype=wp.vec3),
):
    v = wp.tid()
    t = panel_tri[v]
    coef = tri_sail[t]
    nv = normal[v]
    n = wp.vec3(nv[0], nv[1], nv[2])
    w = panel_wind[v]
    speed = wp.length(w)
    force = w * (coef[2] * speed)  # profile drag, 0.5 rho A applied below
    sigma = float(0.0)  # noqa: UP018
    if speed > 0.0:
        # the stall: the angle of the local wind to the sail's mean plane, not to this panel's own slope (a
        # cambered sail's aft panels face the wind more steeply than its sections' angle of attack)
        sin_s = wp.min(wp.abs(wp.dot(plane[panel_surface[v]], w)) / speed, 1.0)
        sigma = stall_blend(wp.asin(sin_s), coef[3])
        wn = wp.dot(n, w) / speed
        sin_a = wp.min(wp.abs(wn), 1.0)
        if sin_a > 1.0e-6:
            force += n * (wp.sign(wn) * plate_normal_coefficient(sin_a) * speed * speed * sigma)
    stall_out[v] = sigma
    air_density = world_density[particle_world[tri_indices[t][0]]]
    tri_force_out[t] = force * (0.5 * air_density * nv[3] * aero_scale / 3.0)


@wp.kernel
def _edge_force(
    edge_panels: wp.array(dtype=wp.vec2i),
    edge_particles: wp.array(dtype=wp.vec2i),
    edge_opposite: wp.array(dtype=wp.vec2i),
    panel_surface: wp.array(dtype=wp.int32),
    wake: wp.array(dtype=wp.vec4),
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
    gamma: wp.array(dtype=wp.float32),
    stall: wp.array(dtype=wp.float32),
    induced: wp.array(dtype=wp.vec3),
    edge_force_out: wp.array(dtype=wp.vec3),
    edge_side_out: wp.array(dtype=wp.int32),
):
    e = wp.tid()
    panels = edge_panels[e]
    g = gamma[panels[0]]
    sigma = stall[panels[0]]
    ends = edge_particles[e]
    a = particle_q[ends[0]]
    b = particle_q[ends[1]]
    edge_side_out[e] = 0
    air_density = world_density[particle_world[ends[0]]]
    if panels[1] == TRAILING:  # the wake's downwash on the circulation it carries away: induced drag (Trefftz)
        edge_force_out[e] = wp.cross(induced[e], wp.vec3(a - b)) * (air_density * g * aero_scale * (1.0 - sigma))
        return
    # the load acts a quarter of the way to the far corner of the panel downstream (the classical lattice's
    # bound vortex lies a quarter panel behind the panel's leading edge): which panel is downstream?
    wk = wake[panel_surface[panels[0]]]
    d = wp.vec3(wk[0], wk[1], wk[2])
    mid = (a + b) * wp.float64(0.5)
    far = edge_opposite[e]
    ahead = wp.dot(wp.vec3(particle_q[far[0]] - mid), d)
    side = int(0)  # noqa: UP018
    if ahead > 0.0:
        side = 1
    if far[1] >= 0:
        behind = wp.dot(wp.vec3(particle_q[far[1]] - mid), d)
        if behind > 0.0 and behind > ahead:
            side = 2
    edge_side_out[e] = side
    if panels[1] >= 0:
        g -= gamma[panels[1]]
        sigma = 0.5 * (sigma + stall[panels[1]])
    moved = (a - particle_q_prev[ends[0]]) + (b - particle_q_prev[ends[1]])
    height = float(mid[2] - terrain_height(hf, mid[0], mid[1]))
    world = particle_world[ends[0]]
    w = wind_at(wind[world], height, shear_reference_height, shear_exponent) + turbulence_at(turb, world, mid)
    velocity = w - wp.vec3(moved) / (2.0 * dt)
    edge_force_out[e] = wp.cross(velocity, wp.vec3(b - a)) * (air_density * g * aero_scale * (1.0 - sigma))


@wp.kernel
def _gather(
    particle_edge_start: wp.array(dtype=wp.int32),
    particle_edge_refs: wp.array(dtype=wp.int32),
    edge_force: wp.array(dtype=wp.vec3),
    edge_side: wp.array(dtype=wp.int32),
    particle_air_out: wp.array(dtype=wp.vec3),
):
    i = wp.tid()
    f = wp.vec3(0.0)
    k = particle_edge_start[i]
    end = particle_edge_start[i + 1]
    while k < end:
        ref = particle_edge_refs[k]
        e = ref / 4
        role = ref - 4 * e
        side = edge_side[e]
        if role < 2:  # one of the edge's particles
            if side == 0:
                f += 0.5 * edge_force[e]
            else:
                f += (0.5 * (1.0 - LOAD_SHIFT)) * edge_force[e]
        elif role - 1 == side:  # the far corner of the panel downstream
            f += LOAD_SHIFT * edge_force[e]
        k += 1
    particle_air_out[i] = f


def lattice_arrays(lattice, device) -> dict:
    """The device copies of a :class:`~warpsim.physics.lattice.Lattice`'s arrays that the kernels read (a one-element
    placeholder for an empty one)."""

    def up(values, dtype, fill):
        values = values if len(values) else fill
        return wp.array(values, dtype=dtype, device=device)

    zero = np.zeros(1, np.int32)
    return {
        "panel_tri": up(lattice.panel_tri, wp.int32, zero),
        "panel_surface": up(lattice.panel_surface, wp.int32, zero),
        "panel_trailing": up(lattice.panel_trailing, wp.int32, zero),
        "surface_start": up(lattice.surface_start, wp.int32, zero),
        "surface_origin": up(lattice.surface_origin, wp.int32, zero),
        "matrix_start": up(lattice.matrix_start, wp.int64, np.zeros(1, np.int64)),
        "edge_panels": up(lattice.edge_panels, wp.vec2i, np.zeros((1, 2), np.int32)),
        "edge_corner": up(lattice.edge_corner, wp.int32, zero),
        "edge_particles": up(lattice.edge_particles, wp.vec2i, np.zeros((1, 2), np.int32)),
        "particle_edge_start": up(lattice.particle_edge_start, wp.int32, zero),
        "particle_edge_refs": up(lattice.particle_edge_refs, wp.int32, zero),
        "edge_opposite": up(lattice.edge_opposite, wp.vec2i, np.zeros((1, 2), np.int32)),
    }


class VortexScratch:
    """The vortex law's per-step buffers on the model's device (allocated once, reused by every captured step).

    Attributes: ``corners [3V]``, ``point [V]``, ``normal [V]`` (unit normal and area [m^2]), ``wind [V]`` (relative
    wind at each centroid [m/s]), ``wake [S]`` (wake direction and squared core [m^2]), ``plane [S]`` (each sail's
    area-weighted mean normal), ``matrix`` (each surface's influence matrix, then its LU factors), ``pivot [V]``
    (the factors' row swaps), ``factored [S]`` (1 where the factors hold), ``counter [1]`` (steps since the last
    factorisation, modulo the steps in ``air.vortex_interval``), ``gamma [V]`` (circulations [m^2/s]), ``stall [V]``
    (separated-flow blend, 0-1), ``induced [E]`` (the wake's downwash at each trailing edge's midpoint [m/s]),
    ``edge_force [E]`` [N], ``edge_side [E]`` (0: the load stays on the edge; 1, 2: its first or second panel is
    downstream), ``basis`` (the ``corners``, ``point``, ``normal`` and ``wake`` each surface's latest factors were
    made from: what a checkpoint keeps, :meth:`save` and :meth:`load`).
    """

    def __init__(self, model):
        lat, device = model.lattice, model.device
        v, s, e = max(lat.panel_count, 1), max(lat.surface_count, 1), max(lat.edge_count, 1)
        self.corners = wp.zeros(3 * v, dtype=wp.vec3, device=device)
        self.point = wp.zeros(v, dtype=wp.vec3, device=device)
        self.normal = wp.zeros(v, dtype=wp.vec4, device=device)
        self.wind = wp.zeros(v, dtype=wp.vec3, device=device)
        self.wake = wp.zeros(s, dtype=wp.vec4, device=device)
        self.plane = wp.zeros(s, dtype=wp.vec3, device=device)
        self.matrix = wp.zeros(max(int(lat.matrix_start[-1]), 1), dtype=wp.float32, device=device)
        self.gamma = wp.zeros(v, dtype=wp.float32, device=device)
        self.stall = wp.zeros(v, dtype=wp.float32, device=device)
        self.induced = wp.zeros(e, dtype=wp.vec3, device=device)
        self.edge_force = wp.zeros(e, dtype=wp.vec3, device=device)
        self.edge_side = wp.zeros(e, dtype=wp.int32, device=device)
        self.pivot = wp.zeros(v, dtype=wp.int32, device=device)
        self.factored = wp.zeros(s, dtype=wp.int32, device=device)
        self.counter = wp.zeros(1, dtype=wp.int32, device=device)
        self.no_trailing = wp.zeros(v, dtype=wp.int32, device=device)  # the matrix of a shed wake: no legs
        self.no_wake = wp.zeros(v, dtype=wp.float32, device=device)  # nor a wake's velocity on the right-hand side
        self.shed = None
        """The wake shed over time (:class:`warpsim.physics.kernels.wake.ShedWake`) under ``air.wake = "shed"``."""
        self.basis = (  # the inputs of each surface's latest factorisation (what a checkpoint keeps)
            wp.zeros(3 * v, dtype=wp.vec3, device=device),
            wp.zeros(v, dtype=wp.vec3, device=device),
            wp.zeros(v, dtype=wp.vec4, device=device),
            wp.zeros(s, dtype=wp.vec4, device=device),
        )

    def save(self) -> tuple[int, list[np.ndarray]]:
        """The state the next steps' circulations depend on, besides the particles: the step counter and the
        inputs of each surface's latest factorisation (corners, centroids, normals, wakes), flat float32 arrays."""
        return int(self.counter.numpy()[0]), [a.numpy().reshape(-1).astype(np.float32) for a in self.basis]

    def sizes(self) -> list[int]:
        """The lengths of :meth:`save`'s arrays."""
        return [a.shape[0] * a.dtype._length_ for a in self.basis]

    def load(self, model, counter: int, basis: list[np.ndarray]) -> None:
        """Put a :meth:`save` back and factorise again from its inputs: the same factors, bit for bit, as the
        run that saved it had (the factorisation is deterministic), so a resumed run steps on exactly."""
        for a, values in zip(self.basis, basis, strict=True):
            a.assign(np.asarray(values, dtype=np.float32).reshape(a.shape[0], a.dtype._length_))
        self.counter.zero_()
        self.factored.zero_()
        self.factorise(model, *self.basis)
        self.counter.assign(np.array([counter], dtype=np.int32))

    def factorise(self, model, corners, point, normal, wake) -> None:
        """Build the influence matrix of every surface due a factorisation (the counter at 0, or its last try
        failed) from ``corners``, ``point``, ``normal`` and ``wake`` and factorise it in place; a shed wake's matrix
        keeps the trailing edges' own vortices (no wake legs)."""
        lat, arrays, dev = model.lattice, model.vortex_arrays, model.device
        trailing = arrays["panel_trailing"] if self.shed is None else self.no_trailing
        inputs = [arrays["panel_surface"], trailing, arrays["surface_start"], arrays["matrix_start"]]
        inputs += [self.counter, self.factored, corners, point, normal, wake]
        wp.launch(matrix_rows, dim=lat.panel_count, inputs=inputs, outputs=[self.matrix], device=dev)
        wp.launch(
            factor_lu,
            dim=lat.surface_count,
            inputs=[arrays["surface_start"], arrays["matrix_start"], self.counter, wake],
            outputs=[self.matrix, self.pivot, self.factored],
            device=dev,
        )


def vortex_air_force(
    model, state, control, dt: float, air, wind, scratch: VortexScratch, tri_force_out, particle_air_out
):
    """The vortex law on the model's lifting surfaces for steps of ``dt`` [s]: the section polar's forces [N, per
    vertex] into ``tri_force_out`` at the surfaces' triangles (after the per-triangle law has written every
    triangle), and the lattice's Kutta-Joukowski forces [N] into ``particle_air_out`` (``[P]``: every particle is
    written, zero off the surfaces). ``air`` and ``wind`` as for
    :func:`~warpsim.physics.kernels.aero.triangle_air_force`. Does nothing without lifting surfaces."""
    lat = model.lattice
    if lat.panel_count == 0:
        return
    arrays, dev, rho, scale = model.vortex_arrays, model.device, control.air_density, float(air.scale)
    shed = scratch.shed  # a wake shed over time (air.wake = "shed", :mod:`.wake`), or None: the quasi-steady wake
    if shed is not None:
        shed.before_solve(model, state, control, dt, wind, scratch.gamma)
    interval = max(1, int(round(float(air.vortex_interval) / float(dt))))  # steps between factorisations
    shear = (float(wind.shear_exponent), float(wind.reference_height))
    sc = scratch
    wp.launch(
        _panels,
        dim=lat.panel_count,
        inputs=[
            arrays["panel_tri"],
            arrays["panel_surface"],
            arrays["surface_origin"],
            model.tri_indices,
            model.particle_world,
            model.terrain_data,
            state.particle_q,
            state.particle_q_prev,
            control.wind,
            control.turbulence.data,
            float(dt),
            *shear,
        ],
        outputs=[sc.corners, sc.point, sc.normal, sc.wind],
        device=dev,
    )
    wp.launch(
        _surfaces,
        dim=lat.surface_count,
        inputs=[arrays["surface_start"], sc.normal, sc.wind],
        outputs=[sc.wake, sc.plane],
        device=dev,
    )
    wp.launch(
        _keep_basis,
        dim=lat.panel_count,
        inputs=[
            arrays["panel_surface"],
            arrays["surface_start"],
            sc.counter,
            sc.factored,
            sc.corners,
            sc.point,
            sc.normal,
            sc.wake,
        ],
        outputs=list(sc.basis),
        device=dev,
    )
    sc.factorise(model, sc.corners, sc.point, sc.normal, sc.wake)
    if shed is not None:
        shed.right_hand_side(model, state, sc)
    wp.launch(
        substitute,
        dim=lat.surface_count,
        inputs=[
            arrays["surface_start"],
            arrays["matrix_start"],
            sc.normal,
            sc.wind,
            sc.matrix,
            sc.pivot,
            sc.factored,
            sc.no_wake if shed is None else shed.normal,
        ],
        outputs=[sc.gamma],
        device=dev,
    )
    if shed is not None:
        shed.downwash(model, state, sc)
    if shed is None:
        wp.launch(
            _wake_downwash,
            dim=lat.edge_count,
            inputs=[
                arrays["edge_panels"],
                arrays["edge_corner"],
                arrays["panel_surface"],
                arrays["panel_trailing"],
                arrays["surface_start"],
                sc.corners,
                sc.wake,
                sc.gamma,
            ],
            outputs=[sc.induced],
            device=dev,
        )
    wp.launch(
        _polar,
        dim=lat.panel_count,
        inputs=[
            arrays["panel_tri"],
            arrays["panel_surface"],
            model.tri_sail,
            sc.normal,
            sc.wind,
            sc.plane,
            model.tri_indices,
            model.particle_world,
            rho,
            scale,
        ],
        outputs=[sc.stall, tri_force_out],
        device=dev,
    )
    if shed is not None:
        shed.unsteady(model, control, dt, scale, sc, tri_force_out)
    wp.launch(
        _edge_force,
        dim=lat.edge_count,
        inputs=[
            arrays["edge_panels"],
            arrays["edge_particles"],
            arrays["edge_opposite"],
            arrays["panel_surface"],
            sc.wake,
            model.particle_world,
            model.terrain_data,
            state.particle_q,
            state.particle_q_prev,
            control.wind,
            control.turbulence.data,
            float(dt),
            rho,
            scale,
            *shear,
            sc.gamma,
            sc.stall,
            sc.induced,
        ],
        outputs=[sc.edge_force, sc.edge_side],
        device=dev,
    )
    wp.launch(
        _gather,
        dim=model.particle_count,
        inputs=[arrays["particle_edge_start"], arrays["particle_edge_refs"], sc.edge_force, sc.edge_side],
        outputs=[particle_air_out],
        device=dev,
    )
    wp.launch(tick, dim=1, inputs=[interval], outputs=[sc.counter], device=dev)
    if shed is not None:
        shed.after_step(model, dt)
