"""What a frame shows: positions, stretch, energy, per-object metrics, blow-ups and terrain contacts.

One module for every reader of a running or recorded scene (the runner's blow-up check, the HDF5 recorder's
diagnostics, the command line's summary), so that a metric is computed one way only. The checks every frame
needs come from the device (:mod:`warpsim.physics.kernels.frame`); the rest is host-side NumPy, on the frames that ask.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from ..physics.model import Control, Model, State


class FrameSource:
    """Where the frames of one simulation read the state: its model, state and control, and its step ``dt`` [s].
    :meth:`copy` takes the host copies a frame keeps (on the CPU device through views made once, so that a copy
    costs what NumPy's copy does)."""

    def __init__(self, model: Model, state: State, control: Control, dt: float):
        self.model, self.state, self.control, self.dt = model, state, control, dt
        arrays = (state.particle_q, state.particle_q_prev, control.stick_rest, control.wind)
        self._views = tuple(a.numpy() for a in arrays) if model.device.is_cpu else None

    def copy(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Host copies of ``(positions [P, 3], previous positions [P, 3], rest lengths [S], wind [W, 3])``."""
        if self._views is not None:
            return tuple(v.copy() for v in self._views)
        s, c = self.state, self.control
        return s.particle_q.numpy(), s.particle_q_prev.numpy(), c.stick_rest.numpy(), c.wind.numpy()


class Frame:
    """One output frame of a run.

    What the device reported after the frame's steps is here at once; what needs the state on the host is read on
    first use (a run that only checks its frames copies no positions). A frame reads the simulation's arrays
    until the simulation moves on: :class:`~warpsim.run.simulation.Simulation` copies what a frame still held by someone
    needs (:meth:`fetch`) before it steps, restores or sets controls again.

    Attributes:
        index: frame number (0 = the initial state). time: simulated time [s].
        steps: solver steps taken since the scene started.
        worst_stretch: largest ``|l - r|/r`` over all sticks (dimensionless, float32 from the device; NaN when
            some position or velocity is not finite).
        finite: every position and velocity is finite.
        world_stretch: host ``[W]`` worst stick stretch of each world (finite sticks only).
        world_nonfinite: host ``[W]`` number of particles of each world with a non-finite position or velocity.
        clearance: host ``[K]`` lowest height [m] above the terrain of each object's particles that can touch it
            (:class:`GroundContacts`), ``1e30`` for an object with none.
        blowups: what is wrong in each world that is bad in this frame, by world index, where the worlds are
            checked one by one (:meth:`warpsim.run.simulation.Simulation.frames` with ``each_world``); empty
            otherwise (a frame checked whole is handed out only when it is good).
        controls: the controls in force when the frame's stepping began (after the keys or a replay set theirs
            at its start; a schedule may change them at its own steps within the frame), by name (what
            :meth:`warpsim.run.simulation.Simulation.set_controls` takes; empty when none was set).

    Read on first use:

    - ``positions``: host ``[P, 3]`` positions [m].
    - ``velocities``: host ``[P, 3]`` velocities ``(x - x_prev)/dt`` [m/s].
    - ``wind``: host ``[W, 3]`` wind of each world at the reference height [m/s].
    - ``stretches``: host ``[S]`` ``|l - r|/r`` of every stick (dimensionless, float64 from the host copy; NaN
      where a position is not finite).
    - ``worst_stick``: index of the stick of largest stretch (-1 when there are no sticks).
    - ``kinetic_energy``: total kinetic energy [J] of the free particles.
    """

    def __init__(
        self,
        index: int,
        time: float,
        steps: int,
        report: tuple[np.ndarray, np.ndarray, np.ndarray],
        source: FrameSource,
        controls: dict | None = None,
    ):
        self.index, self.time, self.steps = index, time, steps
        self.world_stretch, self.world_nonfinite, self.clearance = report
        self.blowups: dict[int, str] = {}
        self.finite = not self.world_nonfinite.any()
        self.worst_stretch = float(self.world_stretch.max()) if self.finite else float("nan")
        self.controls = {} if controls is None else controls
        self._source = source
        self._host = None

    def fetch(self) -> None:
        """Copy the state this frame shows to the host now (once; later reads use the copy)."""
        if self._host is None:
            self._host = self._source.copy()

    def _arrays(self):
        self.fetch()
        return self._host

    @functools.cached_property
    def positions(self) -> np.ndarray:
        return self._arrays()[0]

    @functools.cached_property
    def velocities(self) -> np.ndarray:
        q, q_prev = self._arrays()[:2]
        return (q - q_prev) / self._source.dt

    @functools.cached_property
    def wind(self) -> np.ndarray:
        return self._arrays()[3]

    @functools.cached_property
    def stretches(self) -> np.ndarray:
        q, _, rest, _ = self._arrays()
        with np.errstate(invalid="ignore", over="ignore"):
            return np.abs(self._source.model.stick_stretch(q, rest))

    @functools.cached_property
    def worst_stick(self) -> int:
        return int(np.argmax(self.stretches)) if len(self.stretches) else -1  # argmax finds a NaN first

    @functools.cached_property
    def kinetic_energy(self) -> float:
        v = self.velocities
        with np.errstate(invalid="ignore", over="ignore"):
            return float(0.5 * np.sum(self._source.model.particle_free_mass * np.einsum("ij,ij->i", v, v)))


def object_of(model: Model, particle: int) -> str:
    """The name of the object particle ``particle`` belongs to (``"no object"`` for none)."""
    for record in model.objects:
        if particle in record.particles:
            return record.name
    return "no object"


def find_blowup(model: Model, frame: Frame, max_stretch: float) -> tuple[str, str] | None:
    """``(object name, what is wrong)`` when ``frame`` shows a blow-up, else None: a non-finite position or
    velocity, or a worst stick stretch above ``max_stretch`` (dimensionless; 0 = no limit)."""
    if _reported_sound(frame, max_stretch):
        return None
    bad = ~(np.isfinite(frame.positions).all(axis=1) & np.isfinite(frame.velocities).all(axis=1))
    if bad.any():
        p = int(np.flatnonzero(bad)[0])
        return object_of(model, p), f"particle {p} has a non-finite position or velocity ({bad.sum()} particles)"
    if max_stretch > 0.0 and not frame.worst_stretch <= max_stretch:  # NaN stretch counts as too much
        return object_of(model, int(model.stick_particles_np[frame.worst_stick][0])), _stretch_reason(
            model, frame.worst_stick, frame.worst_stretch, max_stretch
        )
    return None


def _reported_sound(frame: Frame, max_stretch: float) -> bool:
    """The device's report says all is well (no host copy needed): every value finite, no stick past
    ``max_stretch`` (0 = no limit)."""
    return frame.finite and (max_stretch <= 0.0 or frame.worst_stretch <= max_stretch)


def _stretch_reason(model: Model, stick: int, stretch: float, max_stretch: float) -> str:
    a, b = (int(i) for i in model.stick_particles_np[stick])
    return (
        f"stick {stick} (particles {a}-{b}) is stretched {100 * stretch:.1f}% "
        f"(limit solver.max_stretch = {100 * max_stretch:g}%)"
    )


def world_blowups(model: Model, frame: Frame, max_stretch: float) -> dict[int, str]:
    """What is wrong in each world of ``frame`` that shows a blow-up, by world index (the worlds of a batch
    never touch each other, so one world's blow-up leaves the others sound): a non-finite position or
    velocity, or a stick of that world stretched past ``max_stretch`` (dimensionless; 0 = no limit). Particles
    and sticks are numbered within their world, so a world says the same whatever batch it runs in."""
    if _reported_sound(frame, max_stretch):
        return {}
    world = model.particle_world_np
    first_particle = np.searchsorted(world, np.arange(model.world_count))  # worlds are built one after another
    bad = ~(np.isfinite(frame.positions).all(axis=1) & np.isfinite(frame.velocities).all(axis=1))
    problems: dict[int, str] = {}
    for w in np.unique(world[bad]):
        mine = np.flatnonzero(bad & (world == w))
        problems[int(w)] = (
            f"particle {mine[0] - first_particle[w]} has a non-finite position or velocity ({len(mine)} particles)"
        )
    if max_stretch > 0.0 and len(frame.stretches):
        over = ~(frame.stretches <= max_stretch)  # NaN counts as too much
        if over.any():
            stick_world = world[model.stick_particles_np[:, 0]]
            first_stick = np.searchsorted(stick_world, np.arange(model.world_count))
            sticks = np.flatnonzero(over)
            for w in np.unique(stick_world[sticks]):
                if int(w) in problems:
                    continue
                mine = sticks[stick_world[sticks] == w]
                k = int(mine[np.argmax(np.nan_to_num(frame.stretches[mine], nan=np.inf))])
                a, b = (int(i) - first_particle[w] for i in model.stick_particles_np[k])
                problems[int(w)] = (
                    f"stick {k - first_stick[w]} (particles {a}-{b}) is stretched {100 * frame.stretches[k]:.1f}% "
                    f"(limit solver.max_stretch = {100 * max_stretch:g}%)"
                )
    return problems


@dataclass
class ObjectMetrics:
    """Per-object metrics of one frame, one row per object of the model (``K`` objects).

    Attributes:
        centre: ``[K, 3]`` mass centre of the free particles [m].
        altitude: ``[K]`` height of the mass centre above the terrain under it [m].
        velocity: ``[K, 3]`` velocity of the mass centre [m/s].
        airspeed: ``[K]`` speed of the mass centre relative to its world's wind [m/s].
    """

    centre: np.ndarray
    altitude: np.ndarray
    velocity: np.ndarray
    airspeed: np.ndarray


def object_metrics(model: Model, frame: Frame) -> ObjectMetrics:
    """The :class:`ObjectMetrics` of ``frame``."""
    mass = model.particle_free_mass
    count = len(model.objects)
    centre, velocity = np.zeros((count, 3)), np.zeros((count, 3))
    for k, record in enumerate(model.objects):
        m = mass[record.particles]
        total = m.sum() if m.sum() > 0 else 1.0
        centre[k] = (m[:, None] * frame.positions[record.particles]).sum(axis=0) / total
        velocity[k] = (m[:, None] * frame.velocities[record.particles]).sum(axis=0) / total
    worlds = np.array([record.world for record in model.objects], dtype=np.int64)
    altitude = centre[:, 2] - model.terrain.height(centre[:, 0], centre[:, 1])
    airspeed = np.linalg.norm(velocity - frame.wind[worlds], axis=1)
    return ObjectMetrics(centre, altitude, velocity, airspeed)


class GroundContacts:
    """The first time each object touches the terrain, for the run summary.

    Parts that lie on the ground or hold an object to it by design (``GROUNDED_PARTS``) and nailed particles
    are left out: their contact is not news. A particle within ``CONTACT_DISTANCE`` of the surface touches it.
    The device measures each object's lowest clearance every frame (:attr:`Frame.clearance`, from the particles
    :meth:`owners` names).
    """

    GROUNDED_PARTS = ("rope", "pole", "lines", "virtual")
    CONTACT_DISTANCE = 0.02  # [m]

    def __init__(self, model: Model):
        self.model = model
        self.first: dict[str, float] = {}  # object name -> first time [s] it touched the terrain

    def owners(self) -> np.ndarray:
        """Host ``[P]`` int32: the object whose contact each particle tells, -1 where its contact is not news."""
        model = self.model
        owner = np.full(model.particle_count, -1, dtype=np.int32)
        free = np.isfinite(model.particle_mass)
        for k, record in enumerate(model.objects):
            particles = np.asarray(record.particles, dtype=np.int64)
            grounded = [np.asarray(record.parts[p], dtype=np.int64) for p in self.GROUNDED_PARTS if p in record.parts]
            keep = free[particles] & ~np.isin(particles, np.concatenate([np.zeros(0, np.int64), *grounded]))
            owner[particles[keep]] = k
        return owner

    def touching(self, frame: Frame) -> np.ndarray:
        """``[K]`` bool: which objects touch the terrain in ``frame`` (their grounded parts and nails aside)."""
        return frame.clearance < self.CONTACT_DISTANCE

    def note(self, frame: Frame) -> None:
        """Record the objects that touch the terrain in ``frame`` for the first time."""
        if len(self.first) == len(self.model.objects):
            return
        for k in np.flatnonzero(self.touching(frame)):
            self.first.setdefault(self.model.objects[int(k)].name, float(frame.time))

    def by_time(self) -> tuple[tuple[str, float], ...]:
        """``(object name, time [s])`` of each first contact, earliest first."""
        return tuple(sorted(self.first.items(), key=lambda item: item[1]))
