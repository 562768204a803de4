"""A plain, vectorised NumPy version of warpsim's Verlet step: the benchmark's "no Warp" baseline.

Same algorithm, same order and precision as :class:`warpsim.SolverVerlet` (air force per triangle, Verlet,
Jacobi iterations with averaged mass-weighted corrections and Chebyshev weights, elastic sticks as XPBD, the
momentum of free worlds kept, heightfield collision):
positions, previous positions, nail targets and the projection's origins are float64; everything measured
from positions (stick vectors, triangle edges, velocities, heights above the terrain) is a float64 difference
rounded to float32, and the rest is float32. It is written the way a careful NumPy programmer would:
whole-array operations, ``np.bincount`` for the per-particle sums (summed in float64, then rounded: the one
place where its rounding differs from warpsim's float32 sums in stick order), no Python loop over particles
or sticks. The tests check that it agrees with warpsim to float tolerance, so the speed ratio compares equal
work.
"""

from __future__ import annotations

import numpy as np

from warpsim.physics.atmosphere import isa
from warpsim.physics.kernels.aero import STALL_SHARPNESS, AeroModel
from warpsim.physics.kernels.collision import CollisionMode
from warpsim.physics.projection import chebyshev_weights
from warpsim.run.simulation import Simulation

F32 = np.float32
F64 = np.float64


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot product of ``[k, 3]`` arrays, summed in the kernels' order ``(x + y) + z``."""
    return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2]


def _length(a: np.ndarray) -> np.ndarray:
    """Row-wise length of a ``[k, 3]`` array, as ``wp.length``."""
    return np.sqrt(_dot(a, a))


def _f32(a: np.ndarray) -> np.ndarray:
    """A float64 difference of positions rounded to float32, as ``wp.vec3(...)`` in the kernels."""
    return a.astype(F32)


class NumpyVerlet:
    """The step of ``sim`` (a :class:`warpsim.run.simulation.Simulation` with the Verlet solver) in NumPy.

    ``step()`` advances its own float64 host copies ``q``, ``q_prev`` [m] by ``sim.dt`` seconds, reading the
    simulation's controls (rest lengths, nail targets, wind) as they were when it was made.
    """

    def __init__(self, sim: Simulation):
        m, solver = sim.model, sim.solver
        if m.hinge_count:
            # the bending forces (warpsim.physics.kernels.bending) are not written here: refused, not left out
            raise ValueError("the NumPy (and C) reference has no bending stiffness: set flag.design = paper")
        self.dt = F32(sim.dt)
        self.n = m.particle_count
        self.q = sim.state.particle_q.numpy().astype(F64)  # copies
        self.q_prev = sim.state.particle_q_prev.numpy().astype(F64)
        self.inv_mass = m.particle_inv_mass.numpy()
        nail = m.particle_nail.numpy()
        self.nailed = nail >= 0
        self.nail_of = nail[self.nailed]
        self.gravity = np.array(m.gravity, dtype=F32)
        self.air_worlds = solver.world_start.numpy()  # where each world's particles start (its air's density)
        self.tris = m.tri_indices.numpy().reshape(-1, 3)[: m.tri_count]
        self.tri_loading = m.tri_loading.numpy()[: m.tri_count]
        self.tri_world = m.particle_world_np[self.tris[:, 0]] if m.tri_count else np.zeros(0, dtype=np.int32)
        self.tri_sail = m.tri_sail.numpy()[: m.tri_count]
        self.tri_span = m.tri_span.numpy()[: m.tri_count]
        self.particle_world = m.particle_world_np
        self.drag_particles = m.drag_particles.numpy()[: m.drag_count] if m.drag_count else np.zeros(0, np.int32)
        self.drag_area = m.drag_area.numpy()[: m.drag_count] if m.drag_count else np.zeros(0, F32)
        self.air = solver.air
        self.wind_profile = solver.wind
        # whole-canopy air force (warpsim.physics.kernels.canopy): each canopy's triangles, table, parameters,
        # lagged side force
        self.canopies = []
        if m.canopy_count:
            start, ids = m.canopy_tri_start.numpy(), m.canopy_tri_ids.numpy()
            table = m.canopy_table.numpy().reshape(m.canopy_count, -1, 2)
            params = m.canopy_params.numpy()
            for c in range(m.canopy_count):
                self.canopies.append((ids[start[c] : start[c + 1]], table[c], params[c]))
            self.canopy_side = solver.canopy_side.numpy()[: m.canopy_count].copy()
        self.ground = solver.ground
        t = m.terrain
        heights = np.asarray(t.heights, dtype=F64)  # as Heightfield.device_data: float32 above a float64 base
        self.base = 0.5 * (float(heights.min()) + float(heights.max()))
        self.heights = (heights - self.base).astype(F32)
        self.origin = np.asarray(t.origin, dtype=F64)
        self.cell = np.asarray(t.cell, dtype=F64)
        self.ends = m.stick_particles_np
        self.coef = solver.projector.stick_coef.numpy()[: m.stick_count]
        self.scale = solver.projector.particle_scale.numpy()
        cfg = solver.config
        self.relaxation = F32(cfg.relaxation)
        # elastic sticks (XPBD): compliance over dt^2 [1/kg], as the projector computes it (zero for rigid sticks)
        compliance = solver.projector.stick_compliance.numpy()[: m.stick_count]
        self.alpha = compliance * F32(1.0 / (sim.dt * sim.dt))
        self.elastic = self.alpha > 0
        self.damping = F32(cfg.damping)
        self.omegas = [F32(w) for w in chebyshev_weights(cfg.iterations, cfg.chebyshev)]
        self.rest = sim.control.stick_rest.numpy()[: m.stick_count]
        self.nail_target = sim.control.nail_target.numpy().reshape(-1, 3).astype(F64)
        self.wind = sim.control.wind.numpy().reshape(-1, 3)
        # the momentum keeper's worlds, read from it (solver.keep_momentum; none when it is off)
        keeper = getattr(solver, "momentum", None)
        if keeper is not None:
            self.world_start = keeper.body_start.numpy()  # the keeper's free bodies, each one "world" here
            self.world_particles = keeper.body_particles.numpy()
            self.world_free = np.ones(keeper.body_count, dtype=np.int32)
        else:
            self.world_start = np.zeros(1, dtype=np.int32)
            self.world_particles = np.zeros(0, dtype=np.int32)
            self.world_free = np.zeros(0, dtype=np.int32)
        self.density = self.world_density()

    # ------------------------------------------------------------------ pieces
    def _sum_per_particle(self, index: np.ndarray, values: np.ndarray) -> np.ndarray:
        return np.stack([np.bincount(index, values[:, k], minlength=self.n) for k in range(3)], axis=1).astype(F32)

    def _cell(self, x, y):
        ny, nx = self.heights.shape
        x, y = np.asarray(x, dtype=F64), np.asarray(y, dtype=F64)
        fx = np.clip((x - self.origin[0]) / self.cell[0], 0.0, F64(nx - 1))
        fy = np.clip((y - self.origin[1]) / self.cell[1], 0.0, F64(ny - 1))
        # the last cell reaches the far edge inclusive: no sample past the grid is read
        ix = np.minimum(np.floor(fx).astype(np.int64), nx - 2)
        iy = np.minimum(np.floor(fy).astype(np.int64), ny - 2)
        h = self.heights
        return _f32(fx - ix), _f32(fy - iy), h[iy, ix], h[iy, ix + 1], h[iy + 1, ix], h[iy + 1, ix + 1]

    def height(self, x, y):
        """Bilinear terrain height [m], float64 (the float32 interpolation is of heights above the base)."""
        tx, ty, h00, h10, h01, h11 = self._cell(x, y)
        one = F32(1.0)
        return self.base + ((one - ty) * ((one - tx) * h00 + tx * h10) + ty * ((one - tx) * h01 + tx * h11)).astype(F64)

    def normal(self, x, y):
        """Unit upward terrain normal."""
        tx, ty, h00, h10, h01, h11 = self._cell(x, y)
        one = F32(1.0)
        dhdx = ((one - ty) * (h10 - h00) + ty * (h11 - h01)) / F32(self.cell[0])
        dhdy = ((one - tx) * (h01 - h00) + tx * (h11 - h10)) / F32(self.cell[1])
        n = np.stack([-dhdx, -dhdy, np.ones_like(dhdx)], axis=1)
        return n / _length(n)[:, None]

    def air_force(self) -> np.ndarray:
        """Per-particle air force [N] ``[n, 3]``."""
        if len(self.tris) == 0:
            return np.zeros((self.n, 3), dtype=F32)
        q, qp, t = self.q, self.q_prev, self.tris
        a, b, c = q[t[:, 0]], q[t[:, 1]], q[t[:, 2]]  # float64
        cross = np.cross(_f32(b - a), _f32(c - b))
        cross_len = _length(cross)
        ok = cross_len > 0
        safe = np.where(ok, cross_len, F32(1.0))
        n = cross / safe[:, None]
        area = F32(0.5) * cross_len
        moved = (a - qp[t[:, 0]]) + (b - qp[t[:, 1]]) + (c - qp[t[:, 2]])
        velocity = _f32(moved) / (F32(3.0) * self.dt)
        wind = self.wind[self.tri_world]
        shear = self.wind_profile
        if shear.shear_exponent != 0.0:
            centre = (a + b + c) / F64(3.0)
            ground = self.height(centre[:, 0], centre[:, 1])
            h = np.maximum(_f32(centre[:, 2] - ground), F32(0.1))
            wind = wind * ((h / F32(shear.reference_height)) ** F32(shear.shear_exponent))[:, None]
        w = wind - velocity
        wn = _dot(n, w)
        if self.air.model == AeroModel.SAIL:
            force = self._sail(n, area, w, q) * (F32(self.air.scale) / F32(3.0))
            force = np.where(ok[:, None], force, F32(0.0))
            self._canopy_force(force, cross, area, velocity, a, b, c)
            return self._sum_per_particle(t.ravel(), np.repeat(force, 3, axis=0))
        if self.air.model == AeroModel.PAPER:
            mag = self.density[self.tri_world] * wn * np.abs(wn) * area
        else:
            speed = _length(w)
            sin_alpha = np.abs(wn) / np.where(speed > 0, speed, F32(1.0))
            live = (speed > 0) & (sin_alpha >= F32(1e-6))
            sa = np.where(live, sin_alpha, F32(1.0))
            c_n = (F32(1.0) / (F32(0.222) + F32(0.283) / sa)) * (self.tri_loading + (F32(1.0) - self.tri_loading) * sa)
            sign = np.where(wn < 0, F32(-1.0), F32(1.0))  # wp.sign: 1 at zero
            rho = self.density[self.tri_world]
            mag = np.where(live, F32(0.5) * rho * speed * speed * area * c_n * sign, F32(0.0))
        force = np.where(ok[:, None], n * mag[:, None], F32(0.0)) * (F32(self.air.scale) / F32(3.0))
        self._canopy_force(force, cross, area, velocity, a, b, c)
        return self._sum_per_particle(t.ravel(), np.repeat(force, 3, axis=0))

    def _canopy_force(self, force, cross, area, velocity, a, b, c) -> None:
        """Overwrite the canopies' triangles in ``force`` (``[T, 3]``, each vertex's third [N]) with their share of
        the whole canopy's force, as :mod:`warpsim.physics.kernels.canopy` (sums in float64, then rounded)."""
        for k, (ids, table, (nominal, projected0, orient, lag)) in enumerate(self.canopies):
            tri_area = area[ids].astype(F64)
            total = tri_area.sum()
            area_vec = (F64(0.5) * cross[ids].astype(F64)).sum(axis=0)
            projected = np.linalg.norm(area_vec)
            if not (total > 0.0 and projected > 0.0):
                force[ids] = F32(0.0)
                continue
            axis = area_vec * (orient / projected)
            v = (velocity[ids].astype(F64) * tri_area[:, None]).sum(axis=0) / total
            centre = (((a + b + c)[ids] / F64(3.0)) * tri_area[:, None]).sum(axis=0) / total
            wind = self.wind[self.tri_world[ids[0]]].astype(F64)
            shear = self.wind_profile
            if shear.shear_exponent != 0.0:
                h = max(centre[2] - float(self.height(centre[:1], centre[1:2])[0]), 0.1)
                wind = wind * (h / shear.reference_height) ** shear.shear_exponent
            w = wind - v
            speed = np.linalg.norm(w)
            if speed == 0.0:
                force[ids] = F32(0.0)
                continue
            x = np.degrees(np.arccos(np.clip(w @ axis / speed, -1.0, 1.0))) / 5.0
            row = min(int(x), len(table) - 2)
            frac = min(x - row, 1.0)
            coef = table[row] * (1.0 - frac) + table[row + 1] * frac
            q = 0.5 * float(self.density[self.tri_world[ids[0]]]) * speed * speed
            pressure = q * coef[0] * nominal / projected0
            across = w - axis * (w @ axis)
            side = np.zeros(3)
            if np.linalg.norm(across) > 1e-6 * speed:
                side = across * (q * coef[1] * nominal * projected / (projected0 * total * np.linalg.norm(across)))
            if lag > 0.0:
                tau = lag * 2.0 * np.sqrt(projected0 / np.pi) / speed
                side = self.canopy_side[k] + (side - self.canopy_side[k]) * min(float(self.dt) / tau, 1.0)
            self.canopy_side[k] = side
            per = cross[ids].astype(F64) * (0.5 * pressure * orient) + side * tri_area[:, None]
            force[ids] = _f32(per * (float(self.air.scale) / 3.0))

    def _sail(self, n, area, w, q) -> np.ndarray:
        """``sail`` air force [N] per triangle (before the 1/3 share), as
        :func:`warpsim.physics.kernels.aero.sail_force`."""
        one = F32(1.0)
        cl_slope, induced, cd0, stall = (self.tri_sail[:, k] for k in range(4))
        span = np.zeros_like(w)
        has = self.tri_span[:, 0] >= 0
        edge = _f32(q[self.tri_span[has, 1]] - q[self.tri_span[has, 0]])
        span[has] = edge / _length(edge)[:, None]
        speed = _length(w)
        live = speed > 0
        w_hat = w / np.where(live, speed, one)[:, None]
        force = w_hat * (cd0 * speed * speed)[:, None]
        # attached flow on the wind across the leading edge
        w_n = w - span * _dot(w, span)[:, None]
        speed_n = _length(w_n)
        across = speed_n > F32(1e-6) * speed
        wn_hat = w_n / np.where(across, speed_n, one)[:, None]
        d = _dot(n, wn_hat)
        sin_n = np.minimum(np.abs(d), one)
        cos_n = np.sqrt(np.maximum(one - sin_n * sin_n, F32(0.0)))
        cl = cl_slope * np.arcsin(sin_n)
        tilted = cos_n > F32(1e-6)
        sign_d = np.where(d < 0, -one, one)  # wp.sign: 1 at zero
        lift_dir = (n * sign_d[:, None] - wn_hat * sin_n[:, None]) / np.where(tilted, cos_n, one)[:, None]
        lift_dir = np.where(tilted[:, None], lift_dir, F32(0.0))
        attached = (lift_dir * cl[:, None] + wn_hat * (induced * cl * cl)[:, None]) * (speed_n * speed_n)[:, None]
        attached = np.where(across[:, None], attached, F32(0.0))
        # separated flow: the plate's normal force, blended in past the stall
        wn = _dot(n, w_hat)
        sin_a = np.minimum(np.abs(wn), one)
        plate = one / (F32(0.222) + F32(0.283) / np.where(sin_a > F32(1e-6), sin_a, one))
        separated = n * (np.where(wn < 0, -one, one) * plate * speed * speed)[:, None]
        separated = np.where((sin_a > F32(1e-6))[:, None], separated, F32(0.0))
        sigma = one / (one + np.exp(-F32(STALL_SHARPNESS) * (np.arcsin(sin_a) - stall)))
        force = force + (attached * (one - sigma)[:, None] + separated * sigma[:, None])  # the kernel's +=
        rho = self.density[self.tri_world]
        scale = F32(0.5) * rho * area * (self.tri_loading + (one - self.tri_loading) * sin_a)
        return np.where(live[:, None], force * scale[:, None], F32(0.0)).astype(F32)

    def body_drag(self) -> np.ndarray:
        """The drag bodies' drag [N] per particle ``[n, 3]`` (``sail`` air only), as the ``body_drag`` kernel."""
        out = np.zeros((self.n, 3), dtype=F32)
        if self.air.model != AeroModel.SAIL or len(self.drag_particles) == 0:
            return out
        i = self.drag_particles
        x = self.q[i]  # float64
        w = self.wind[self.particle_world[i]]
        shear = self.wind_profile
        if shear.shear_exponent != 0.0:
            ground = self.height(x[:, 0], x[:, 1])
            h = np.maximum(_f32(x[:, 2] - ground), F32(0.1))
            w = w * ((h / F32(shear.reference_height)) ** F32(shear.shear_exponent))[:, None]
        w = w - _f32(x - self.q_prev[i]) / self.dt
        speed = _length(w)
        rho = self.density[self.particle_world[i]]
        out[i] = w * (F32(0.5) * rho * speed * self.drag_area * F32(self.air.scale))[:, None]
        return out

    def verlet(self, force: np.ndarray) -> None:
        """Move every free particle by Verlet (float64 positions, the float32 ``a dt^2`` added); nailed ones to
        their nails."""
        x, xp = self.q, self.q_prev
        acc = self.gravity + force * self.inv_mass[:, None]
        moved = x + (x - xp) * (F64(1.0) - F64(self.damping)) + (acc * (self.dt * self.dt)).astype(F64)
        moved = np.where((self.inv_mass == 0)[:, None], x, moved)
        moved[self.nailed] = self.nail_target[self.nail_of]
        self.q_prev = x
        self.q = moved

    def project(self) -> None:
        """The Jacobi iterations on the sticks."""
        if len(self.ends) == 0:
            return
        a, b = self.ends[:, 0], self.ends[:, 1]
        step = (self.relaxation * self.scale)[:, None]
        free = step[:, 0] != 0  # nailed particles have scale 0 (as in warpsim's fused scheme)
        pinned = self.nailed & ~free
        # the last iterate's float32 increment, and the float32 sum of the increments added to the float64
        # starting positions (the origin)
        last = np.zeros(self.q.shape, dtype=F32)
        offset = np.zeros(self.q.shape, dtype=F32)
        origin = self.q
        # an elastic stick's accumulated lam [kg m] and its last increment (compliant_correction)
        lam = np.zeros(len(self.ends), dtype=F32)
        lam_last = np.zeros(len(self.ends), dtype=F32)
        for omega in self.omegas:
            x = self.q
            d = _f32(x[b] - x[a])
            length = _length(d)
            safe = np.where(length > 0, length, F32(1.0))
            stretch = length - self.rest
            factor = self.coef * stretch / safe
            if self.elastic.any():
                dlam = self.coef * (stretch - self.alpha * lam) / (F32(1.0) + self.alpha * self.coef)
                factor = np.where(self.elastic, dlam / safe, factor)
                step_lam = self.relaxation * dlam
                if omega != 1.0:
                    step_lam = step_lam * omega + lam_last * (omega - F32(1.0))
                moves = self.elastic & (length > 0)
                lam = np.where(moves, lam + step_lam, lam)
                lam_last = np.where(moves, step_lam, lam_last)
            c = d * np.where(length > 0, factor, F32(0.0))[:, None]
            total = self._sum_per_particle(np.concatenate([a, b]), np.concatenate([c, -c]))
            inc = total * step
            if omega != 1.0:
                inc = inc * omega + last * (omega - F32(1.0))
            moved = offset + inc
            q = np.where(free[:, None], origin + moved.astype(F64), x)
            q[pinned] = self.nail_target[self.nail_of[pinned[self.nailed]]]
            offset = np.where(free[:, None], moved, offset)
            last = np.where(free[:, None], inc, last)
            self.q = q

    def keep_momentum(self, predicted: np.ndarray) -> None:
        """Give each free world back the linear and angular momentum the projection moved it by (``predicted``:
        the positions before it), as :mod:`warpsim.physics.kernels.momentum`, in float64."""
        x, xp = self.q, self.q_prev
        for w in np.flatnonzero(self.world_free):
            i = self.world_particles[self.world_start[w] : self.world_start[w + 1]]
            m = F64(1.0) / self.inv_mass[i].astype(F64)
            mass = m.sum()
            centre = (xp[i] * m[:, None]).sum(axis=0) / mass
            r = xp[i] - centre
            delta = x[i] - predicted[i]
            d_p = (delta * m[:, None]).sum(axis=0)
            d_l = (np.cross(r, delta) * m[:, None]).sum(axis=0)
            inertia = np.eye(3) * (_dot(r, r) * m).sum() - (r * m[:, None]).T @ r
            spin = np.zeros(3)
            size = np.trace(inertia)
            if size > 0.0:  # as the kernel: 1e-9 tr(I) on the diagonal (a line of particles has no inertia about it)
                spin = np.linalg.solve(inertia + np.eye(3) * (size * 1.0e-9), d_l)
            x[i] = x[i] - d_p / mass - np.cross(spin, r)

    def collide(self) -> None:
        """Keep free particles at or above the terrain."""
        x = self.q  # float64; the terrain is looked up in float64, the corrections made in float32
        h = self.height(x[:, 0], x[:, 1])
        below = (x[:, 2] < h) & (self.inv_mass != 0)
        if not below.any():
            return
        p = x[below]
        hb = h[below]
        if self.ground.collision == CollisionMode.NORMAL:
            n = self.normal(p[:, 0], p[:, 1])
            depth = _f32(hb - p[:, 2]) * n[:, 2]
            p = p + (n * depth[:, None]).astype(F64)
            move = _f32(p - self.q_prev[below])
            slide = move - n * _dot(move, n)[:, None]
            slide_len = _length(slide)
            safe = np.where(slide_len > 0, slide_len, F32(1.0))
            cut = np.minimum(F32(1.0), F32(self.ground.friction) * depth / safe)
            p = p - (slide * np.where(slide_len > 0, cut, F32(0.0))[:, None]).astype(F64)
            hb = self.height(p[:, 0], p[:, 1])
        p[:, 2] = np.maximum(p[:, 2], hb)
        x[below] = p

    def world_density(self) -> np.ndarray:
        """``[W]`` float32 each world's air density [kg/m^3], as
        :func:`warpsim.physics.kernels.controls.update_air_density` (the scene's fixed density, or the standard
        atmosphere's at the mean height of at most about 64 of the world's particles, summed in order in float64)."""
        air, start = self.air, self.air_worlds
        if air.density > 0.0:
            return np.full(len(start) - 1, air.density, dtype=F32)
        out = np.zeros(len(start) - 1, dtype=F32)
        for w in range(len(start) - 1):
            count = int(start[w + 1] - start[w])
            z = self.q[start[w] : start[w + 1] : max(count // 64, 1), 2]
            mean = np.cumsum(z)[-1] / len(z) if len(z) else 0.0  # in order, as the kernel sums
            out[w] = F32(isa(mean + air.elevation, air.temperature_offset)[2])
        return out

    def step(self) -> None:
        """One step of ``dt``: air force, Verlet, constraints (and the momentum kept), terrain (the paper's order)."""
        self.density = self.world_density()
        self.verlet(self.air_force() + self.body_drag())
        predicted = self.q
        self.project()
        if self.world_free.any():
            self.keep_momentum(predicted)
        self.collide()
