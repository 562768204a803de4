"""A wake shed over time for the vortex law (``air.wake = "shed"``): the lift builds up and lags as in unsteady flow.

The quasi-steady wake of :mod:`.vortex` leaves every trailing edge along the relative wind of the moment, so a step
in the angle of attack gives the new lift at once. Here, as in the time-stepping vortex-ring method of Katz & Plotkin
(*Low-Speed Aerodynamics*, 2nd ed., section 13.12), the wake is a sheet of vortex rings the trailing edges leave in
the air:

* behind every trailing edge ``a -> b`` lie ``R = air.wake_rows`` rings between rows of wake points; row 0 is the
  trailing edge itself, and every later row moves with the air it is in (the wind and the turbulence there: a
  prescribed wake, without the sheet's own induction). Every ``air.wake_interval`` the rows move back by one: the
  oldest ring's circulation leaves, and a ring of zero length starts at the edge;
* the ring next to the edge carries its panel's circulation of the step before (so that the edge's net vortex is
  the change of the panel's circulation over one step: the Kutta condition, one step late as in Katz & Plotkin);
  each later ring keeps the circulation it had when it was shed. The oldest ring's far side is replaced by two
  semi-infinite legs along the relative wind, so that a steady flight's wake is the quasi-steady one again;
* the influence matrix then holds the sails' own rings only (a trailing edge's ring keeps its edge), and the wake's
  velocity at each centroid goes to the right-hand side: ``sum_j A_ij G_j = -(w_i + v_wake,i) . n_i``;
* the loads: Kutta-Joukowski on every edge inside the sail and on its leading and side edges as in the quasi-steady
  law (a trailing edge's net vortex, its panel's circulation less its first ring's, is vorticity just shed and is not
  loaded, as in Katz & Plotkin eq. 13.150); the induced drag from the wake's velocity at the trailing edges'
  midpoints; and the unsteady term of the panels' pressure, ``-rho A (dG/dt) n`` (eq. 13.150), which makes the lift
  of a sail whose circulation grows lag behind it.

Cost: every step, each panel reads every ring behind its surface's trailing edges, ``V x E_T x R`` ring evaluations
(``E_T`` trailing edges), and the matrix is rebuilt on the schedule of ``air.vortex_interval`` as before.
"""

from __future__ import annotations

import numpy as np
import warp as wp

from .. import lattice
from .aero import TurbulenceData, turbulence_at, wind_at
from .collision import HeightfieldData, terrain_height
from .influence import TRAILING, ray_velocity, segment_velocity

wp.set_module_options({"enable_backward": False})


@wp.func
def shed_wake_velocity(
    x: wp.vec3,
    o: wp.vec3d,
    first: int,
    end: int,
    edge_vertex: wp.array(dtype=wp.vec2i),
    points: wp.array(dtype=wp.vec3d),
    gamma: wp.array(dtype=wp.float32),
    rows: int,
    d: wp.vec3,
    core2: float,
) -> wp.vec3:
    """Velocity [m/s] at ``x`` [m, from ``o``] of the rings behind trailing edges ``first .. end - 1``."""
    v = wp.vec3(0.0)
    e = first
    while e < end:
        ends = edge_vertex[e]
        k = int(0)  # noqa: UP018 -- Warp needs int() to make a variable a loop may change
        while k < rows:
            g = gamma[e * rows + k]
            if g != 0.0:
                a0 = wp.vec3(points[ends[0] * (rows + 1) + k] - o)
                b0 = wp.vec3(points[ends[1] * (rows + 1) + k] - o)
                a1 = wp.vec3(points[ends[0] * (rows + 1) + k + 1] - o)
                b1 = wp.vec3(points[ends[1] * (rows + 1) + k + 1] - o)
                # the ring b0 -> a0 -> a1 -> b1 -> b0 (the edge's own sense reversed: it cancels the edge's vortex)
                ring = segment_velocity(x, b0, a0, core2) + segment_velocity(x, a0, a1, core2)
                ring += segment_velocity(x, b1, b0, core2)
                if k == rows - 1:  # the oldest ring's far side: two legs to infinity along the relative wind
                    ring += ray_velocity(x, a1, d, core2) - ray_velocity(x, b1, d, core2)
                else:
                    ring += segment_velocity(x, a1, b1, core2)
                v += ring * g
            k += 1
        e += 1
    return v


@wp.kernel
def _move(
    vertex_particle: wp.array(dtype=wp.int32),
    particle_world: wp.array(dtype=wp.int32),
    hf: HeightfieldData,
    particle_q: wp.array(dtype=wp.vec3d),
    wind: wp.array(dtype=wp.vec3),
    turb: TurbulenceData,
    dt: float,
    shear_exponent: float,
    shear_reference_height: float,
    rows: int,
    points_out: wp.array(dtype=wp.vec3d),
):
    v = wp.tid()  # one trailing-edge point: row 0 is the edge now, the rows behind move with the air they are in
    p = vertex_particle[v]
    world = particle_world[p]
    base = v * (rows + 1)
    points_out[base] = particle_q[p]
    k = int(1)  # noqa: UP018
    while k <= rows:
        x = points_out[base + k]
        height = float(x[2] - terrain_height(hf, x[0], x[1]))
        u = wind_at(wind[world], height, shear_reference_height, shear_exponent) + turbulence_at(turb, world, x)
        points_out[base + k] = x + wp.vec3d(u * dt)
        k += 1


@wp.kernel
def _attach(
    edge_panel: wp.array(dtype=wp.int32),
    gamma: wp.array(dtype=wp.float32),
    rows: int,
    ring_out: wp.array(dtype=wp.float32),
):
    e = wp.tid()  # the ring at the edge carries its panel's circulation of the step before
    ring_out[e * rows] = gamma[edge_panel[e]]


@wp.kernel
def _rhs(
    panel_surface: wp.array(dtype=wp.int32),
    surface_origin: wp.array(dtype=wp.int32),
    surface_edges: wp.array(dtype=wp.int32),
    edge_vertex: wp.array(dtype=wp.vec2i),
    particle_q: wp.array(dtype=wp.vec3d),
    point: wp.array(dtype=wp.vec3),
    normal: wp.array(dtype=wp.vec4),
    wake: wp.array(dtype=wp.vec4),
    points: wp.array(dtype=wp.vec3d),
    ring: wp.array(dtype=wp.float32),
    rows: int,
    normal_out: wp.array(dtype=wp.float32),
):
    i = wp.tid()  # the wake's velocity through centroid i, for the right-hand side
    s = panel_surface[i]
    wk = wake[s]
    v = shed_wake_velocity(
        point[i],
        particle_q[surface_origin[s]],
        surface_edges[s],
        surface_edges[s + 1],
        edge_vertex,
        points,
        ring,
        rows,
        wp.vec3(wk[0], wk[1], wk[2]),
        wk[3],
    )
    nv = normal[i]
    normal_out[i] = wp.dot(v, wp.vec3(nv[0], nv[1], nv[2]))


@wp.kernel
def _downwash(
    edge_panels: wp.array(dtype=wp.vec2i),
    edge_corner: wp.array(dtype=wp.int32),
    panel_surface: wp.array(dtype=wp.int32),
    surface_origin: wp.array(dtype=wp.int32),
    surface_edges: wp.array(dtype=wp.int32),
    edge_vertex: wp.array(dtype=wp.vec2i),
    particle_q: wp.array(dtype=wp.vec3d),
    corners: wp.array(dtype=wp.vec3),
    wake: wp.array(dtype=wp.vec4),
    points: wp.array(dtype=wp.vec3d),
    ring: wp.array(dtype=wp.float32),
    rows: int,
    induced_out: wp.array(dtype=wp.vec3),
):
    e = wp.tid()  # the wake's velocity at a trailing edge's midpoint: its induced drag
    p = edge_panels[e][0]
    if edge_panels[e][1] != TRAILING:
        return
    k = edge_corner[e]
    x = 0.5 * (corners[3 * p + k] + corners[3 * p + (k + 1) % 3])
    s = panel_surface[p]
    wk = wake[s]
    induced_out[e] = shed_wake_velocity(
        x,
        particle_q[surface_origin[s]],
        surface_edges[s],
        surface_edges[s + 1],
        edge_vertex,
        points,
        ring,
        rows,
        wp.vec3(wk[0], wk[1], wk[2]),
        wk[3],
    )


@wp.kernel
def _unsteady(
    panel_tri: wp.array(dtype=wp.int32),
    tri_indices: wp.array(dtype=wp.vec3i),
    particle_world: wp.array(dtype=wp.int32),
    world_density: wp.array(dtype=wp.float32),
    normal: wp.array(dtype=wp.vec4),
    gamma: wp.array(dtype=wp.float32),
    gamma_before: wp.array(dtype=wp.float32),
    stall: wp.array(dtype=wp.float32),
    dt: float,
    smoothing: float,
    aero_scale: float,
    rate_out: wp.array(dtype=wp.float32),
    tri_force_out: wp.array(dtype=wp.vec3),
):
    v = wp.tid()  # the unsteady part of the panel's pressure, -rho A (dG/dt) n, a third to each corner
    t = panel_tri[v]
    nv = normal[v]
    rho = world_density[particle_world[tri_indices[t][0]]]
    # dG/dt smoothed over the shedding interval: the term is the air's added mass on the sail's normal motion, and
    # taken a step late from a light sail's own jitter it would feed that jitter (an added mass above the sail's)
    rate = rate_out[v] + smoothing * ((gamma[v] - gamma_before[v]) / dt - rate_out[v])
    rate_out[v] = rate
    scale = -rho * nv[3] * rate * (1.0 - stall[v]) * aero_scale / 3.0
    tri_force_out[t] = tri_force_out[t] + wp.vec3(nv[0], nv[1], nv[2]) * scale


@wp.kernel
def _shed_points(counter: wp.array(dtype=wp.int32), rows: int, points_out: wp.array(dtype=wp.vec3d)):
    v = wp.tid()  # a new row: every row moves back one, and a ring of zero length starts at the edge
    if counter[0] != 0:
        return
    base = v * (rows + 1)
    k = rows
    while k >= 1:
        points_out[base + k] = points_out[base + k - 1]
        k -= 1


@wp.kernel
def _shed_rings(counter: wp.array(dtype=wp.int32), rows: int, ring_out: wp.array(dtype=wp.float32)):
    e = wp.tid()
    if counter[0] != 0:
        return
    k = rows - 1
    while k >= 1:
        ring_out[e * rows + k] = ring_out[e * rows + k - 1]
        k -= 1


@wp.kernel
def _tick(interval: int, counter_out: wp.array(dtype=wp.int32)):
    counter_out[0] = (counter_out[0] + 1) % interval


def trailing_edge_tables(model) -> dict[str, np.ndarray]:
    """The lattice's trailing edges as the shed wake numbers them: ``vertex_particle [T]`` (the trailing edges'
    particles), ``edge_vertex [E_T, 2]`` (each edge's ends ``a, b`` in its panel's ring order, as indices into
    those), ``edge_panel [E_T]`` and ``surface_edges
    [S + 1]`` (where each surface's trailing edges start)."""
    lat = model.lattice
    tris = model.tri_indices_np
    edge_panels = np.asarray(lat.edge_panels).reshape(-1, 2)
    trailing = np.flatnonzero(edge_panels[:, 1] == lattice.TRAILING)
    panel = edge_panels[trailing, 0]
    corner = np.asarray(lat.edge_corner)[trailing]
    ring = tris[np.asarray(lat.panel_tri)[panel]]
    a, b = ring[np.arange(len(panel)), corner], ring[np.arange(len(panel)), (corner + 1) % 3]
    order = np.lexsort((trailing, np.asarray(lat.panel_surface)[panel]))  # by surface, then as the lattice has them
    trailing, panel, a, b = trailing[order], panel[order], a[order], b[order]
    vertex_particle, index = np.unique(np.concatenate([a, b]), return_inverse=True)
    surface = np.asarray(lat.panel_surface)[panel]
    return {
        "vertex_particle": vertex_particle.astype(np.int32),
        "edge_vertex": index.reshape(2, -1).T.astype(np.int32),
        "edge_panel": panel.astype(np.int32),
        "surface_edges": np.searchsorted(surface, np.arange(lat.surface_count + 1)).astype(np.int32),
    }


class ShedWake:
    """The shed wake's tables and state on the model's device (``air.wake = "shed"``).

    Attributes: the tables of :func:`trailing_edge_tables` as device arrays; ``points [T * (R + 1)]`` vec3d the
    wake's rows of points [m] behind each trailing-edge particle (row 0 the particle); ``ring [E_T * R]`` the rings'
    circulations [m^2/s]; ``normal [V]`` the wake's velocity through each centroid [m/s]; ``gamma_before [V]`` the
    circulations of the step before; ``rate [V]`` their smoothed rates of change [m^2/s^2]; ``counter [1]`` steps
    since the last row was shed, modulo ``interval`` steps.
    """

    def __init__(self, model, rows: int, interval: float):
        self.rows = int(rows)
        self.interval = float(interval)
        tables = trailing_edge_tables(model)
        device = model.device
        self.vertex_count = max(len(tables["vertex_particle"]), 1)
        self.edge_count = max(len(tables["edge_panel"]), 1)
        self.tables = {
            name: wp.array(values if len(values) else np.zeros((1, *values.shape[1:]), np.int32), device=device)
            for name, values in tables.items()
        }
        self.tables["edge_vertex"] = wp.array(
            tables["edge_vertex"] if len(tables["edge_vertex"]) else np.zeros((1, 2), np.int32),
            dtype=wp.vec2i,
            device=device,
        )
        self.trailing_vertices = len(tables["vertex_particle"])
        self.trailing_edges = len(tables["edge_panel"])
        start = np.zeros((1, 3))
        if self.trailing_vertices:
            start = np.asarray(model.particle_q0, dtype=np.float64)[tables["vertex_particle"]]
        self.points = wp.array(np.repeat(start, self.rows + 1, axis=0), dtype=wp.vec3d, device=device)
        self.ring = wp.zeros(self.edge_count * self.rows, dtype=wp.float32, device=device)
        self.normal = wp.zeros(max(model.lattice.panel_count, 1), dtype=wp.float32, device=device)
        self.gamma_before = wp.zeros(max(model.lattice.panel_count, 1), dtype=wp.float32, device=device)
        self.rate = wp.zeros(max(model.lattice.panel_count, 1), dtype=wp.float32, device=device)
        self.counter = wp.zeros(1, dtype=wp.int32, device=device)

    def steps_between(self, dt: float) -> int:
        """Steps of ``dt`` [s] between two rows shed (at least one)."""
        return max(1, int(round(self.interval / float(dt))))

    def before_solve(self, model, state, control, dt: float, wind, gamma) -> None:
        """Move the wake's rows with the air, attach the first ring to its panel's circulation of the step before
        (still in ``gamma``), and keep those circulations for the unsteady term."""
        wp.copy(self.gamma_before, gamma)
        if self.trailing_edges == 0:
            return
        shear = (float(wind.shear_exponent), float(wind.reference_height))
        wp.launch(
            _move,
            dim=self.trailing_vertices,
            inputs=[
                self.tables["vertex_particle"],
                model.particle_world,
                model.terrain_data,
                state.particle_q,
                control.wind,
                control.turbulence.data,
                float(dt),
                *shear,
                self.rows,
            ],
            outputs=[self.points],
            device=model.device,
        )
        wp.launch(
            _attach,
            dim=self.trailing_edges,
            inputs=[self.tables["edge_panel"], gamma, self.rows],
            outputs=[self.ring],
            device=model.device,
        )

    def right_hand_side(self, model, state, scratch) -> None:
        """The wake's velocity through every centroid, along its normal, into ``normal``."""
        if self.trailing_edges == 0:
            return
        arrays = model.vortex_arrays
        wp.launch(
            _rhs,
            dim=model.lattice.panel_count,
            inputs=[
                arrays["panel_surface"],
                arrays["surface_origin"],
                self.tables["surface_edges"],
                self.tables["edge_vertex"],
                state.particle_q,
                scratch.point,
                scratch.normal,
                scratch.wake,
                self.points,
                self.ring,
                self.rows,
            ],
            outputs=[self.normal],
            device=model.device,
        )

    def downwash(self, model, state, scratch) -> None:
        """The wake's velocity at every trailing edge's midpoint into ``scratch.induced``."""
        if self.trailing_edges == 0:
            return
        arrays = model.vortex_arrays
        wp.launch(
            _downwash,
            dim=model.lattice.edge_count,
            inputs=[
                arrays["edge_panels"],
                arrays["edge_corner"],
                arrays["panel_surface"],
                arrays["surface_origin"],
                self.tables["surface_edges"],
                self.tables["edge_vertex"],
                state.particle_q,
                scratch.corners,
                scratch.wake,
                self.points,
                self.ring,
                self.rows,
            ],
            outputs=[scratch.induced],
            device=model.device,
        )

    def unsteady(self, model, control, dt: float, scale: float, scratch, tri_force_out) -> None:
        """Add the panels' unsteady pressure, ``-rho A (dG/dt) n``, to their triangles' forces."""
        wp.launch(
            _unsteady,
            dim=model.lattice.panel_count,
            inputs=[
                model.vortex_arrays["panel_tri"],
                model.tri_indices,
                model.particle_world,
                control.air_density,
                scratch.normal,
                scratch.gamma,
                self.gamma_before,
                scratch.stall,
                float(dt),
                min(1.0, float(dt) / self.interval),
                float(scale),
            ],
            outputs=[self.rate, tri_force_out],
            device=model.device,
        )

    def after_step(self, model, dt: float) -> None:
        """Shed a row when it is due."""
        if self.trailing_edges:
            wp.launch(
                _shed_points,
                dim=self.trailing_vertices,
                inputs=[self.counter, self.rows],
                outputs=[self.points],
                device=model.device,
            )
            wp.launch(
                _shed_rings,
                dim=self.trailing_edges,
                inputs=[self.counter, self.rows],
                outputs=[self.ring],
                device=model.device,
            )
        wp.launch(_tick, dim=1, inputs=[self.steps_between(dt)], outputs=[self.counter], device=model.device)

    def save(self, gamma) -> tuple[int, list[np.ndarray]]:
        """The wake's state: the counter, then the rows' points [m], the rings' circulations, the smoothed rates and
        the panels' circulations ``gamma`` [m^2/s] (which the next step's first rings take), flat float64 arrays
        without the padding of a surface without trailing edges (so that the layout is the same however the worlds
        are split into groups)."""
        points = self.points.numpy()[: self.trailing_vertices * (self.rows + 1)]
        ring = self.ring.numpy()[: self.trailing_edges * self.rows]
        arrays = (points.reshape(-1), ring, self.rate.numpy(), gamma.numpy())
        return int(self.counter.numpy()[0]), [np.asarray(a, dtype=np.float64).reshape(-1) for a in arrays]

    def sizes(self, gamma) -> list[int]:
        """The lengths of :meth:`save`'s arrays."""
        rows = self.rows
        return [3 * self.trailing_vertices * (rows + 1), self.trailing_edges * rows, self.rate.shape[0], gamma.shape[0]]

    def load(self, counter: int, state: list[np.ndarray], gamma) -> None:
        """Put a :meth:`save` back."""
        self.counter.assign(np.array([counter], dtype=np.int32))
        if self.trailing_edges:
            points = self.points.numpy()
            points[: self.trailing_vertices * (self.rows + 1)] = np.asarray(state[0]).reshape(-1, 3)
            self.points.assign(points)
            ring = self.ring.numpy()
            ring[: self.trailing_edges * self.rows] = state[1]
            self.ring.assign(ring)
        self.rate.assign(np.asarray(state[2], dtype=np.float32))
        gamma.assign(np.asarray(state[3], dtype=np.float32))

    def reset(self, model, state, gamma) -> None:
        """Start the wake afresh from the trailing edges where they are now (no rings, no rates, no circulations):
        after a blow-up, the state goes back to the last good frame, whose wake is not kept."""
        particles = self.tables["vertex_particle"].numpy()
        points = np.zeros((self.points.shape[0], 3))
        if self.trailing_vertices:
            where = state.particle_q.numpy()[particles[: self.trailing_vertices]]
            points[: self.trailing_vertices * (self.rows + 1)] = np.repeat(where, self.rows + 1, axis=0)
        self.points.assign(points)
        for a in (self.ring, self.rate, self.gamma_before, gamma, self.counter):
            a.zero_()
