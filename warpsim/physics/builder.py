"""ModelBuilder: particles, sticks, triangles and nails, plus mesh helpers (:mod:`.shapes`), then
``finalize(device)``."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import warp as wp

from .config import GRAVITY
from .kernels.aero import sail_coefficients
from .kernels.bending import stable_dt
from .kernels.vortex import lattice_arrays
from .lattice import build_lattice, check_surface
from .memory import check_memory  # noqa: F401 - the objects' builders import it from here
from .model import Model, ObjectRecord
from .shapes import MeshShapes
from .terrain import Heightfield


def _csr(keys: np.ndarray, values: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Adjacency lists in CSR form: for each key 0..count-1 the values, in the order they were given."""
    order = np.argsort(keys, kind="stable")
    start = np.zeros(count + 1, dtype=np.int32)
    np.add.at(start, keys + 1, 1)
    return np.cumsum(start).astype(np.int32), values[order].astype(np.int32)


DEFAULT_SAIL = sail_coefficients(2.0)
"""``sail`` coefficients of a triangle whose object sets none (a sail of aspect ratio 2)."""


class ModelBuilder(MeshShapes):
    """Accumulates the pieces of a model on the host; :meth:`finalize` uploads them to a device.

    All positions are in metres, masses in kilograms. Indices returned by ``add_*`` are global.
    """

    def __init__(self, gravity: float = GRAVITY):
        self.gravity = float(gravity)
        self.particle_q: list[Sequence[float]] = []
        self.particle_qd: list[Sequence[float]] = []
        self.particle_mass: list[float] = []
        self.particle_world: list[int] = []
        self.stick_particles: list[tuple[int, int]] = []
        self.stick_rest: list[float] = []
        self.stick_weight: list[float] = []
        self.stick_pretension: list[float] = []
        self.stick_compliance: list[float] = []
        self.tri_indices: list[tuple[int, int, int]] = []
        self.hinge_particles: list[tuple[int, int, int, int]] = []
        self.hinge_weights: list[tuple[float, float, float, float]] = []
        self.hinge_stiffness: list[float] = []
        self.tri_loading: list[float] = []
        self.tri_sail: list[tuple[float, float, float, float]] = []
        self.tri_span: list[tuple[int, int]] = []
        self.drag_area: dict[int, float] = {}
        self.canopies: list[tuple[np.ndarray, np.ndarray, tuple[float, float, float]]] = []
        self.lifting_surfaces: list[tuple[np.ndarray, np.ndarray]] = []
        self._owned_tris: set[int] = set()  # the triangles of the canopies and lifting surfaces: each has one owner
        self.nail_particles: list[int] = []
        self._nailed: set[int] = set()  # the same, for constant-time membership tests
        self.nail_target: list[Sequence[float]] = []
        self.objects: list[ObjectRecord] = []
        self.terrain: Heightfield | None = None
        self.world_count = 1
        self.current_world = 0

    # ------------------------------------------------------------------ sizes
    @property
    def particle_count(self) -> int:
        """Number of particles added so far."""
        return len(self.particle_q)

    @property
    def stick_count(self) -> int:
        """Number of sticks added so far."""
        return len(self.stick_rest)

    @property
    def tri_count(self) -> int:
        """Number of triangles added so far."""
        return len(self.tri_indices)

    def positions(self, ids) -> np.ndarray:
        """Float64 positions [m] of the particles ``ids`` (an index or an array of any shape): ``[..., 3]``, a
        copy. Builders ask for the particles they need, not the whole list (which grows with every world)."""
        ids = np.asarray(ids, dtype=np.int64)
        q = self.particle_q
        return np.array([q[i] for i in ids.ravel()], dtype=np.float64).reshape(*ids.shape, 3)

    def triangle_particles(self, tris) -> np.ndarray:
        """The ``[len(tris), 3]`` int64 particles of the triangles ``tris``."""
        t = self.tri_indices
        return np.array([t[i] for i in np.asarray(tris, dtype=np.int64).ravel()], dtype=np.int64).reshape(-1, 3)

    # ------------------------------------------------------------------ primitives
    def add_particle(self, pos, mass: float, vel=(0.0, 0.0, 0.0)) -> int:
        """Add a particle at ``pos`` [m] of ``mass`` [kg] (> 0) moving at ``vel`` [m/s]; returns its index."""
        mass = float(mass)
        if not np.isfinite(mass) or mass <= 0.0:
            raise ValueError(f"particle mass must be positive and finite, got {mass}")
        self.particle_q.append(tuple(float(v) for v in pos))
        self.particle_qd.append(tuple(float(v) for v in vel))
        self.particle_mass.append(mass)
        self.particle_world.append(self.current_world)
        return self.particle_count - 1

    def add_stick(self, i: int, j: int, rest: float | None = None, weight: float = 1.0) -> int:
        """Add a distance constraint between particles ``i`` and ``j``; ``rest`` [m] defaults to their
        current distance. Returns the stick index.

        ``weight`` (> 0, default 1) is the stick's share in the per-particle average of corrections: a
        stick of weight 2 counts exactly like two identical sticks, the paper's way of stiffening its
        kite rope ("des tiges ont été doublées", Section 7.2) without the cost of a second stick.
        """
        n = self.particle_count
        if not (0 <= i < n and 0 <= j < n) or i == j:
            raise ValueError(f"stick ({i}, {j}) needs two distinct particles among 0..{n - 1}")
        if rest is None:
            rest = float(np.linalg.norm(np.subtract(self.particle_q[j], self.particle_q[i])))
        if not rest > 0.0:
            raise ValueError(f"stick ({i}, {j}) rest length must be positive, got {rest}")
        if not (np.isfinite(weight) and weight > 0.0):
            raise ValueError(f"stick ({i}, {j}) weight must be positive and finite, got {weight}")
        self.stick_particles.append((int(i), int(j)))
        self.stick_rest.append(float(rest))
        self.stick_weight.append(float(weight))
        self.stick_pretension.append(0.0)
        self.stick_compliance.append(0.0)
        return self.stick_count - 1

    def set_compliance(self, sticks, compliance: float) -> None:
        """Make ``sticks`` elastic instead of rigid: each stretches ``compliance`` [m/N] per newton of tension at
        weight 1 (a stiffness of ``1 / compliance`` [N/m]); a stick of weight ``k`` counts as ``k`` such sticks side
        by side, ``k`` times as stiff. 0 makes them rigid again (the paper's sticks). The solver's iterations then
        converge to the elastic sticks' own stretch, the same at every time step (XPBD,
        :mod:`warpsim.physics.kernels.constraints`)."""
        compliance = float(compliance)
        if not (np.isfinite(compliance) and compliance >= 0.0):
            raise ValueError(f"stick compliance must be >= 0 and finite, got {compliance}")
        for st in sticks:
            self.stick_compliance[int(st)] = compliance

    def pretension(self, sticks, share: float) -> None:
        """Make ``sticks`` ``share`` (0 <= share < 1) shorter than they are: a cloth tensioned on its frame pulls
        to this length. Their stretch is still reported against the length as built
        (:attr:`~warpsim.physics.model.Model.stick_pretension`)."""
        if not -1.0 < share < 1.0:
            raise ValueError(f"pretension must be in (-1, 1), got {share}")
        for st in sticks:
            self.stick_rest[st] *= 1.0 - share
            self.stick_pretension[st] = 1.0 - (1.0 - self.stick_pretension[st]) * (1.0 - share)

    def add_triangle(self, i: int, j: int, k: int, loading: float = 1.0) -> int:
        """Add an aerodynamic triangle (i, j, k); returns its index.

        ``loading`` is the triangle's share of its sail's attached-flow load (1 = uniform; see
        :meth:`set_triangle_loading`).
        """
        n = self.particle_count
        if len({i, j, k}) != 3 or not all(0 <= v < n for v in (i, j, k)):
            raise ValueError(f"triangle ({i}, {j}, {k}) needs three distinct particles among 0..{n - 1}")
        self.tri_indices.append((int(i), int(j), int(k)))
        self.tri_loading.append(_check_loading(loading))
        self.tri_sail.append(DEFAULT_SAIL)
        self.tri_span.append((-1, -1))
        return self.tri_count - 1

    def set_triangle_sail(self, tri_ids, coefficients) -> None:
        """Set the ``sail`` air model's coefficients of triangles ``tri_ids``: ``(lift slope [1/rad],
        induced-drag factor, profile drag coefficient, stall angle [rad])``, as made by
        :func:`warpsim.physics.kernels.aero.sail_coefficients` for the sail they belong to (default: those of a sail
        of aspect ratio 2)."""
        coefficients = tuple(float(c) for c in coefficients)
        if len(coefficients) != 4 or not all(np.isfinite(c) and c >= 0.0 for c in coefficients):
            raise ValueError(f"sail coefficients must be 4 finite numbers >= 0, got {coefficients}")
        for t in np.atleast_1d(np.asarray(tri_ids, dtype=np.int64)):
            if not 0 <= t < self.tri_count:
                raise ValueError(f"triangle {t} does not exist")
            self.tri_sail[t] = coefficients

    def set_triangle_span(self, tri_ids, ends) -> None:
        """Give triangles ``tri_ids`` the leading edge they sit behind, as two particles ``ends`` (``[len, 2]`` or one
        pair for all) from root to tip: under the ``sail`` air model their attached flow feels only the wind
        across that edge (simple sweep theory). Without one a triangle feels the whole wind."""
        tri_ids = np.atleast_1d(np.asarray(tri_ids, dtype=np.int64))
        ends = np.broadcast_to(np.asarray(ends, dtype=np.int64), (len(tri_ids), 2))
        for t, (a, b) in zip(tri_ids, ends, strict=True):
            if not 0 <= t < self.tri_count:
                raise ValueError(f"triangle {t} does not exist")
            if not (0 <= a < self.particle_count and 0 <= b < self.particle_count) or a == b:
                raise ValueError(f"a leading edge needs two distinct particles, got ({a}, {b})")
            self.tri_span[t] = (int(a), int(b))

    def set_drag_area(self, particle: int, area: float) -> None:
        """Make ``particle`` a drag body of drag area ``C_D A`` = ``area`` [m^2] (a pilot, a frame's tubes): under
        the ``sail`` air model it feels ``0.5 rho C_D A |w| w`` in the relative wind ``w``."""
        area = float(area)
        if not 0 <= particle < self.particle_count:
            raise ValueError(f"particle {particle} does not exist")
        if not (np.isfinite(area) and area >= 0.0):
            raise ValueError(f"drag area must be finite and >= 0, got {area}")
        self.drag_area[int(particle)] = self.drag_area.get(int(particle), 0.0) + area

    def add_lifting_surface(self, tri_ids, trailing) -> int:
        """Make triangles ``tri_ids`` one lifting surface of the ``vortex`` air law
        (:mod:`warpsim.physics.kernels.vortex`): one vortex ring a triangle, the wake shed from ``trailing``
        (``[k, 2]`` particle pairs, each a boundary edge of those triangles). Under the other laws the triangles keep
        their per-triangle air. Returns the surface's index; refuses a surface without a trailing edge, whose
        triangles do not make one sheet (:func:`warpsim.physics.lattice.check_surface`), or that shares a triangle with
        another surface or a canopy."""
        tri_ids = np.asarray(tri_ids, dtype=np.int64).reshape(-1)
        if len(tri_ids) and (tri_ids.min() < 0 or tri_ids.max() >= self.tri_count):
            raise ValueError("a lifting surface needs existing triangles")
        if self._owned_tris.intersection(int(t) for t in tri_ids):
            raise ValueError("a triangle of the lifting surface already belongs to another surface or a canopy")
        trailing = np.asarray(trailing, dtype=np.int64).reshape(-1, 2)
        check_surface(np.array([self.tri_indices[t] for t in tri_ids], dtype=np.int64).reshape(-1, 3), trailing)
        self.lifting_surfaces.append((tri_ids, trailing))
        self._owned_tris.update(int(t) for t in tri_ids)
        return len(self.lifting_surfaces) - 1

    def add_canopy(self, tri_ids, table, axis, wake_lag: float = 0.0) -> int:
        """Make triangles ``tri_ids`` one parachute canopy whose air force is the whole canopy's
        (:mod:`warpsim.physics.kernels.canopy`) instead of each triangle's own; returns the canopy's index.

        ``table`` is ``[TABLE_ROWS, 2]``: the tangential and normal force coefficients ``(C_T, C_N)`` on the nominal
        area at angles of attack 0, 5, ..., 180 degrees; ``axis`` a direction [m] from the canopy's mouth to its apex
        as built. The nominal area ``S_0`` (the cloth's) and projected area ``S_p0`` are measured here. ``wake_lag``
        (>= 0) is the time its side force takes to follow the angle of attack, in units of ``D_p / |w|`` (the time
        the canopy takes to travel its projected diameter; 0 = at once)."""
        from .kernels.canopy import TABLE_ROWS

        tri_ids = np.atleast_1d(np.asarray(tri_ids, dtype=np.int64))
        table = np.asarray(table, dtype=np.float64)
        if len(tri_ids) == 0 or tri_ids.min() < 0 or tri_ids.max() >= self.tri_count:
            raise ValueError("a canopy needs existing triangles")
        if table.shape != (TABLE_ROWS, 2) or not np.isfinite(table).all():
            raise ValueError(f"a canopy's table must be {TABLE_ROWS} x 2 finite numbers, got shape {table.shape}")
        if self._owned_tris.intersection(int(t) for t in tri_ids):
            raise ValueError("a triangle of the canopy already belongs to another canopy or a lifting surface")
        q = np.asarray(self.particle_q, dtype=np.float64)
        tris = np.asarray(self.tri_indices, dtype=np.int64)[tri_ids]
        a, b, c = q[tris[:, 0]], q[tris[:, 1]], q[tris[:, 2]]
        cross = np.cross(b - a, c - b)
        nominal = 0.5 * float(np.linalg.norm(cross, axis=1).sum())
        area_vec = 0.5 * cross.sum(axis=0)
        projected = float(np.linalg.norm(area_vec))
        if not (nominal > 0.0 and projected > 0.0):
            raise ValueError("a canopy needs a positive projected area")
        orient = 1.0 if float(np.dot(area_vec, np.asarray(axis, dtype=np.float64))) >= 0.0 else -1.0
        self.canopies.append((tri_ids, table, (nominal, projected, orient, float(wake_lag))))
        self._owned_tris.update(int(t) for t in tri_ids)
        return len(self.canopies) - 1

    def set_triangle_loading(self, tri_ids, loading) -> None:
        """Set the chordwise loading factor of triangles ``tri_ids`` (dimensionless, >= 0).

        Used by the ``plate`` air model only: at small angles of attack a triangle's normal force is
        multiplied by its factor, fading to 1 as the flow separates (see :mod:`warpsim.physics.kernels.aero`).
        A sail's factors should average 1 over its area so that its total force is unchanged.
        """
        tri_ids = np.atleast_1d(np.asarray(tri_ids, dtype=np.int64))
        loading = np.broadcast_to(np.asarray(loading, dtype=np.float64), tri_ids.shape)
        for t, value in zip(tri_ids, loading, strict=True):
            if not 0 <= t < self.tri_count:
                raise ValueError(f"triangle {t} does not exist")
            self.tri_loading[t] = _check_loading(value)

    def add_hinge(self, a: int, m: int, b: int, stiffness: float) -> int:
        """Add a bending hinge: particles ``a``, ``m``, ``b`` in a row, resisting their second difference
        ``x_a - 2 x_m + x_b`` with ``stiffness`` [N/m] (``B w / h^3`` for a plate of bending stiffness ``B``
        [N m], spacing ``h`` [m] and strip width ``w`` [m]; :mod:`warpsim.physics.kernels.bending`). Its rest shape
        is straight with ``m`` halfway between ``a`` and ``b``. Returns its index."""
        return self._add_stencil((a, m, b, m), (1.0, -2.0, 1.0, 0.0), stiffness, "hinge")

    def add_twist(self, a: int, b: int, c: int, d: int, stiffness: float) -> int:
        """Add a twist of a grid cell: corners ``a``, ``b`` along one side, ``c``, ``d`` beside them, resisting
        ``x_a - x_b - x_c + x_d`` (the cell's twist times its two sides) with ``stiffness`` [N/m] (``2 B / (h_u h_v)``
        for a plate of bending stiffness ``B`` [N m] and Poisson's ratio 0; :mod:`warpsim.physics.kernels.bending`).
        Its rest shape is a parallelogram. Returns its index (among the hinges)."""
        return self._add_stencil((a, b, c, d), (1.0, -1.0, -1.0, 1.0), stiffness, "twist")

    def _add_stencil(self, ids, weights, stiffness: float, what: str) -> int:
        n = self.particle_count
        ids = tuple(int(i) for i in ids)
        used = {i for i, w in zip(ids, weights, strict=True) if w != 0.0}
        if not all(0 <= i < n for i in ids) or len(used) != sum(w != 0.0 for w in weights):
            raise ValueError(f"{what} {ids} needs distinct particles among 0..{n - 1}")
        stiffness = float(stiffness)
        if not (np.isfinite(stiffness) and stiffness > 0.0):
            raise ValueError(f"{what} {ids} stiffness must be positive and finite, got {stiffness}")
        self.hinge_particles.append(ids)
        self.hinge_weights.append(tuple(float(w) for w in weights))
        self.hinge_stiffness.append(stiffness)
        return len(self.hinge_particles) - 1

    def add_nail(self, i: int, target=None) -> int:
        """Fix particle ``i`` at ``target`` [m] (default: where it is); returns the nail index.

        A nailed particle ignores forces; its target can move through ``Control.nail_target``.
        """
        if not 0 <= i < self.particle_count:
            raise ValueError(f"nail on particle {i}, which does not exist")
        if i in self._nailed:
            raise ValueError(f"particle {i} is already nailed")
        self._nailed.add(int(i))
        self.nail_particles.append(int(i))
        self.nail_target.append(tuple(float(v) for v in (self.particle_q[i] if target is None else target)))
        return len(self.nail_particles) - 1

    # ------------------------------------------------------------------ whole model
    def set_terrain(self, terrain: Heightfield) -> None:
        """Use ``terrain`` as the ground (default: flat at z = 0, 1 km square)."""
        self.terrain = terrain

    def add_object(self, record: ObjectRecord) -> ObjectRecord:
        """Register the record of an object built into this builder (used by outputs and diagnostics)."""
        record.world = self.current_world
        self.objects.append(record)
        return record

    def finalize(self, device: str | None = "cpu") -> Model:
        """Upload everything to ``device`` (default Warp's ``cpu``) and return the :class:`Model`."""
        if self.particle_count == 0:
            raise ValueError("the model has no particles")
        device = wp.get_device(device)
        m = Model()
        m.device = device
        n = self.particle_count
        m.particle_count, m.stick_count, m.tri_count = n, self.stick_count, self.tri_count
        m.nail_count = len(self.nail_particles)
        m.world_count = self.world_count
        self._finalize_particles(m, device)
        self._finalize_sticks(m, device)
        self._finalize_triangles(m, device)
        self._finalize_canopies(m, device)
        self._finalize_hinges(m, device)
        tris = m.tri_indices_np
        start, ids = _csr(tris.reshape(-1), np.repeat(np.arange(len(tris), dtype=np.int32), 3), n)
        m.particle_tri_start = wp.array(start, dtype=wp.int32, device=device)
        m.particle_tri_ids = wp.array(ids, dtype=wp.int32, device=device)
        m.lattice = build_lattice(tris, self.lifting_surfaces, n)
        m.vortex_arrays = lattice_arrays(m.lattice, device)

        m.terrain = self.terrain if self.terrain is not None else Heightfield.flat()
        m.terrain_data = m.terrain.device_data(device)
        m.gravity = wp.vec3(0.0, 0.0, -self.gravity)
        m.objects = list(self.objects)
        return m

    def _finalize_particles(self, m: Model, device) -> None:
        """Set ``m``'s particle arrays: masses [kg] (a nailed particle's ``inf``, its free mass 0, its inverse mass
        0), worlds, nails and their targets [m], and the initial positions [m] and velocities [m/s]. Refuses a
        particle without a positive mass."""
        n = self.particle_count
        mass = np.array(self.particle_mass, dtype=np.float64)
        nails = np.array(self.nail_particles, dtype=np.int32)
        weightless = np.flatnonzero(~(mass > 0.0))
        if len(weightless):
            raise ValueError(
                f"{len(weightless)} particles have no positive mass (first: {weightless[0]}, {mass[weightless[0]]} kg)"
            )
        inv_mass = 1.0 / mass
        inv_mass[nails] = 0.0
        m.particle_mass = mass.copy()
        m.particle_mass[nails] = np.inf
        m.particle_free_mass = mass.copy()
        m.particle_free_mass[nails] = 0.0
        m.particle_inv_mass = wp.array(inv_mass.astype(np.float32), dtype=wp.float32, device=device)
        m.particle_world_np = np.array(self.particle_world, dtype=np.int32)
        m.particle_world = wp.array(m.particle_world_np, dtype=wp.int32, device=device)
        particle_nail = np.full(n, -1, dtype=np.int32)
        particle_nail[nails] = np.arange(len(nails), dtype=np.int32)
        m.particle_nail = wp.array(particle_nail, dtype=wp.int32, device=device)
        m.particle_q0 = np.array(self.particle_q, dtype=np.float64)
        m.particle_qd0 = np.array(self.particle_qd, dtype=np.float64)
        m.nail_particles = nails
        m.nail_target0 = np.array(self.nail_target, dtype=np.float64).reshape(-1, 3)

    def _finalize_sticks(self, m: Model, device) -> None:
        """Set ``m``'s stick arrays: ends, rest lengths [m], weights, pretensions, compliances [m/N] (a stick of
        weight ``k`` counts as ``k`` in parallel), each particle's summed stick weight and its sticks' ends in CSR
        form."""
        n = self.particle_count
        sticks = np.array(self.stick_particles, dtype=np.int32).reshape(-1, 2)
        m.stick_particles_np = sticks
        m.stick_particles = wp.array(sticks, dtype=wp.vec2i, device=device)
        m.stick_rest = wp.array(np.array(self.stick_rest, dtype=np.float32), dtype=wp.float32, device=device)
        weight = np.array(self.stick_weight, dtype=np.float32)
        m.stick_weight = wp.array(weight, dtype=wp.float32, device=device)
        m.stick_pretension = np.array(self.stick_pretension, dtype=np.float64)
        m.stick_compliance = np.array(self.stick_compliance, dtype=np.float64) / weight  # weight k: k in parallel
        weight_sum = np.zeros(n, dtype=np.float64)
        np.add.at(weight_sum, sticks.reshape(-1), np.repeat(weight.astype(np.float64), 2))
        m.particle_stick_weight = weight_sum
        stick_ids = np.arange(len(sticks), dtype=np.int32)
        start, refs = _csr(sticks.reshape(-1), np.stack([2 * stick_ids, 2 * stick_ids + 1], axis=1).reshape(-1), n)
        m.particle_stick_start = wp.array(start, dtype=wp.int32, device=device)
        m.particle_stick_refs = wp.array(refs, dtype=wp.int32, device=device)

    def _finalize_triangles(self, m: Model, device) -> None:
        """Set ``m``'s triangle arrays and their per-triangle air (loading, ``sail`` coefficients, leading edges),
        and its drag bodies (particles and drag areas [m^2], by particle)."""
        tris = np.array(self.tri_indices, dtype=np.int32).reshape(-1, 3)
        m.tri_indices_np = tris
        m.tri_indices = wp.array(tris, dtype=wp.vec3i, device=device)
        m.tri_loading = wp.array(np.array(self.tri_loading, dtype=np.float32), dtype=wp.float32, device=device)
        sail = np.array(self.tri_sail, dtype=np.float32).reshape(-1, 4)
        m.tri_sail = wp.array(sail, dtype=wp.vec4, device=device)
        m.tri_span = wp.array(np.array(self.tri_span, dtype=np.int32).reshape(-1, 2), dtype=wp.vec2i, device=device)
        drag = sorted((p, a) for p, a in self.drag_area.items() if a > 0.0)
        m.drag_count = len(drag)
        m.drag_particles = wp.array(np.array([p for p, _ in drag], dtype=np.int32), dtype=wp.int32, device=device)
        m.drag_area = wp.array(np.array([a for _, a in drag], dtype=np.float32), dtype=wp.float32, device=device)

    def _finalize_canopies(self, m: Model, device) -> None:
        """Set ``m``'s canopy arrays: each canopy's triangles (CSR), its force table and parameters, and its nominal
        area [m^2]; the device arrays hold at least one entry when there is no canopy."""
        m.canopy_count = len(self.canopies)
        if self.canopies:
            sizes = [len(ids) for ids, _, _ in self.canopies]
            canopy_ids = np.concatenate([ids for ids, _, _ in self.canopies]).astype(np.int32)
            owner = np.repeat(np.arange(len(sizes), dtype=np.int32), sizes)
            table = np.concatenate([t for _, t, _ in self.canopies]).astype(np.float32)
            params = np.array([p for _, _, p in self.canopies], dtype=np.float32)
            m.canopy_nominal_area = params[:, 0].astype(np.float64)
        else:
            sizes, canopy_ids, owner = [], np.zeros(1, np.int32), np.zeros(1, np.int32)
            table, params = np.zeros((1, 2), np.float32), np.zeros((1, 4), np.float32)
            m.canopy_nominal_area = np.zeros(0)
        m.canopy_tri_start = wp.array(np.concatenate([[0], np.cumsum(sizes)]).astype(np.int32), device=device)
        m.canopy_tri_ids = wp.array(canopy_ids, dtype=wp.int32, device=device)
        m.canopy_tri_owner = wp.array(owner, dtype=wp.int32, device=device)
        m.canopy_table = wp.array(table, dtype=wp.vec2, device=device)
        m.canopy_params = wp.array(params, dtype=wp.vec4, device=device)

    def _finalize_hinges(self, m: Model, device) -> None:
        """Set ``m``'s hinge arrays (particles, weights, stiffnesses [N/m]; the device arrays hold at least one
        entry), each particle's hinge slots in CSR form, and ``bending_dt`` [s]. Needs ``m.particle_mass``."""
        hinges = np.array(self.hinge_particles, dtype=np.int32).reshape(-1, 4)
        weights = np.array(self.hinge_weights, dtype=np.float32).reshape(-1, 4)
        stiffness = np.array(self.hinge_stiffness, dtype=np.float32)
        m.hinge_count = len(hinges)
        m.hinge_particles_np, m.hinge_weights_np = hinges, weights
        some = len(hinges) > 0  # a device array of at least one, as for the canopies
        m.hinge_particles = wp.array(hinges if some else np.zeros((1, 4), np.int32), dtype=wp.vec4i, device=device)
        m.hinge_weights = wp.array(weights if some else np.zeros((1, 4), np.float32), dtype=wp.vec4, device=device)
        m.hinge_stiffness = wp.array(stiffness if some else np.zeros(1, np.float32), device=device)
        used = weights.reshape(-1) != 0.0  # a hinge's padding slot (weight 0) is nobody's
        slots = np.arange(hinges.size, dtype=np.int32)[used]
        start, refs = _csr(hinges.reshape(-1)[used], slots, self.particle_count)
        m.particle_hinge_start = wp.array(start, dtype=wp.int32, device=device)
        m.particle_hinge_refs = wp.array(refs if len(refs) else np.zeros(1, np.int32), dtype=wp.int32, device=device)
        m.bending_dt = stable_dt(hinges, weights, stiffness, m.particle_mass)


def _check_loading(value: float) -> float:
    value = float(value)
    if not (np.isfinite(value) and value >= 0.0):
        raise ValueError(f"triangle loading must be finite and >= 0, got {value}")
    return value
