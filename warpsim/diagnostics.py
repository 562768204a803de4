"""What a frame shows: positions, stretch, energy, per-object metrics, blow-ups and terrain contacts.

One module for every reader of a running or recorded scene (the runner's blow-up check, the HDF5 recorder's
diagnostics, the command line's summary), so that a metric is computed one way only. The checks every frame
needs come from the device (:mod:`warpsim.kernels.frame`); the rest is host-side NumPy, on the frames that ask.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .model import Control, Model, State


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
    until the simulation moves on: :class:`~warpsim.runner.Simulation` copies what a frame still held by someone
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
        controls: the controls in force while the frame's last steps ran, by name (what
            :meth:`warpsim.runner.Simulation.set_controls` takes; empty when none was set).

    Read on first use:
        positions: host ``[P, 3]`` positions [m].
        velocities: host ``[P, 3]`` velocities ``(x - x_prev)/dt`` [m/s].
        wind: host ``[W, 3]`` wind of each world at the reference height [m/s].
        stretches: host ``[S]`` ``|l - r|/r`` of every stick (dimensionless, float64 from the host copy; NaN where
            a position is not finite).
        worst_stick: index of the stick of largest stretch (-1 when there are no sticks).
        kinetic_energy: total kinetic energy [J] of the free particles.
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


FIGURES: dict[str, tuple[str, tuple[str, ...] | None, str]] = {
    "altitude": ("m", None, "height of the object's mass centre above the terrain under it"),
    "airspeed": ("m/s", None, "speed of the mass centre relative to its world's wind"),
    "sink": ("m/s", None, "descent speed of the mass centre (positive downwards)"),
    "glide": (
        "-",
        ("hang-glider",),
        "glide ratio: horizontal airspeed / sink of the mass centre (NaN unless it sinks faster than 0.05 m/s)",
    ),
    "bank": ("deg", ("hang-glider",), "bank of the sail, tip to tip against the horizontal, + = right tip lower"),
    "line_angle": ("deg", ("kite",), "elevation of the line above the horizontal, from the anchor to the tow point"),
    "line_pull": ("N", ("kite",), "the line's pull at the anchor, from the rope's sag (objects.kite.anchor_pull)"),
    "radius": ("m", ("parachute",), "mean horizontal distance of the canopy's rim from its centre"),
    "swing": ("deg", ("parachute",), "angle of the line from the person to the canopy's centre from the vertical"),
}
"""The figures :class:`Figures` gives: name -> (unit, the object kinds that have it (None: all), meaning)."""


def figure_names(kind: str) -> tuple[str, ...]:
    """The :data:`FIGURES` an object of ``kind`` has, in table order."""
    return tuple(name for name, (_, kinds, _) in FIGURES.items() if kinds is None or kind in kinds)


class Figures:
    """What a pilot or an observer reads off each object of a frame (:data:`FIGURES`). The heads-up display and
    the sweeps read their figures here, so each is computed one way.

    Call it with a frame (and, for callers that have it, the solver's ``tri_force``: every figure is measured from
    the particles, so none reads it): one dict per object, in model order, of the figures its kind has, as floats
    in their units. A kite's ``line_pull`` is NaN while its rope does not sag
    (:func:`~warpsim.objects.kite.anchor_pull`).
    """

    def __init__(self, model: Model):
        self.model = model

    def __call__(self, frame: Frame, tri_force=None) -> list[dict[str, float]]:
        from .config import GRAVITY
        from .objects.hang_glider import bank
        from .objects.kite import anchor_pull, line_elevation
        from .objects.parachute import projected_radius, swing_angle

        metrics = object_metrics(self.model, frame)
        out = []
        for k, record in enumerate(self.model.objects):
            v = metrics.velocity[k]
            sink = float(-v[2])
            values = {"altitude": float(metrics.altitude[k]), "airspeed": float(metrics.airspeed[k]), "sink": sink}
            if record.kind == "hang-glider":
                horizontal = float(np.linalg.norm((v - frame.wind[record.world])[:2]))
                values["glide"] = horizontal / sink if sink > 0.05 else float("nan")
                values["bank"] = bank(record, frame.positions)
            elif record.kind == "kite":
                values["line_angle"] = line_elevation(record, frame.positions)
                values["line_pull"] = anchor_pull(record, frame.positions, self.model.particle_free_mass, GRAVITY)
            elif record.kind == "parachute":
                values["radius"] = projected_radius(record, frame.positions)
                values["swing"] = swing_angle(record, frame.positions)
            out.append(values)
        return out


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


class FigureWindow:
    """Window means, minima and maxima of each world's figures (:data:`FIGURES`, in their units), the share of
    frames airborne, the first ground contact [s] and the worst stretch, for ``count`` worlds (float64, frame
    order: the same sums for a case whatever chunk it runs in). A sweep's metrics and ``warpsim run``'s closing
    figures are both these."""

    def __init__(self, count: int, figures: Sequence[str]):
        self.figures = list(figures)
        self.sum = np.zeros((len(figures), count))
        self.n = np.zeros((len(figures), count))
        self.low = np.full((len(figures), count), np.inf)
        self.high = np.full((len(figures), count), -np.inf)
        self.frames = np.zeros(count, dtype=np.int64)
        self.airborne = np.zeros(count, dtype=np.int64)
        self.ground_time = np.full(count, np.nan)
        self.worst = np.zeros(count)

    def add(self, values: np.ndarray, live: np.ndarray, in_window: bool, touching: np.ndarray, t: float) -> None:
        """Add one frame: ``values`` ``[F, count]`` figures, for the ``live`` worlds (not read outside the window)."""
        first = live & touching & np.isnan(self.ground_time)
        self.ground_time[first] = t
        if not in_window:
            return
        self.frames[live] += 1
        self.airborne[live & ~touching] += 1
        ok = np.isfinite(values) & live[None, :]
        self.sum += np.where(ok, values, 0.0)
        self.n += ok
        self.low = np.where(ok, np.minimum(self.low, values), self.low)
        self.high = np.where(ok, np.maximum(self.high, values), self.high)

    def row(self, k: int) -> dict:
        """The metrics of world ``k``."""
        out: dict = {}
        for f, name in enumerate(self.figures):
            n = self.n[f, k]
            out[f"{name}_mean"] = self.sum[f, k] / n if n else math.nan
            out[f"{name}_min"] = self.low[f, k] if n else math.nan
            out[f"{name}_max"] = self.high[f, k] if n else math.nan
        frames = int(self.frames[k])
        out["airborne"] = self.airborne[k] / frames if frames else math.nan
        out["ground_time"] = float(self.ground_time[k])
        out["worst_stretch"] = float(self.worst[k])
        out["window_frames"] = frames
        return {key: float(v) if isinstance(v, np.floating) else v for key, v in out.items()}


class FlightFigures:
    """A run's closing figures: each world's :data:`FIGURES` over the window ``[start, stop]`` [s] of simulated
    time, from the frames a run hands out (call it with each :class:`Frame`), every frame as a sweep measures it
    (:class:`FigureWindow`), or at most ``rate`` frames per simulated second.

    Args:
        sim: the :class:`~warpsim.runner.Simulation` (its model, object kind, frame interval and air forces).
        start, stop: the window [s].
        rate: frames measured per simulated second, at most [1/s] (None: every frame, as a sweep).
    """

    def __init__(self, sim, start: float, stop: float, rate: float | None = None):
        self.sim, self.start, self.stop = sim, float(start), float(stop)
        self.kind = sim.descriptor["scene"]["object"]
        self.names = list(figure_names(self.kind))
        interval = sim.steps_per_frame * sim.dt
        self.every = 1 if rate is None else max(1, int(round(1.0 / (rate * interval))))
        self.window = FigureWindow(sim.model.world_count, self.names)
        self.measure = Figures(sim.model)
        self.contacts = GroundContacts(sim.model)
        self.live = np.ones(sim.model.world_count, dtype=bool)
        self._seen = 0

    def __call__(self, frame: Frame) -> None:
        # every frame, as a sweep: each world's worst stretch as the device measured it, and its first ground contact
        self.window.worst = np.maximum(self.window.worst, frame.world_stretch)
        eps = 0.25 * self.sim.dt  # frame times are sums of dt
        if not self.start - eps <= frame.time <= self.stop + eps:
            self.window.add(None, self.live, False, self.contacts.touching(frame), frame.time)
            return
        self._seen += 1
        if (self._seen - 1) % self.every:
            return
        found = self.measure(frame, self.sim.solver.tri_force)
        values = np.array([[f[name] for f in found] for name in self.names], dtype=np.float64)
        self.window.add(values, self.live, True, self.contacts.touching(frame), frame.time)

    def lines(self) -> list[str]:
        """The figures as summary lines: per object with one world; over the worlds (mean, lowest, highest of the
        worlds' window means) with several. Empty when no frame fell in the window."""
        frames = int(self.window.frames.max()) if self.window.frames.size else 0
        if frames == 0:
            return []
        count = self.window.frames.size
        rows = [self.window.row(k) for k in range(count)]

        def shown(name: str, values: list[float]) -> str | None:
            values = [v for v in values if np.isfinite(v)]
            if not values:
                return None
            unit = FIGURES[name][0]
            unit = "" if unit == "-" else f" {unit}"
            text = f"{name.replace('_', ' ')} {_figure(np.mean(values))}{unit}"
            if count > 1:
                text += f" ({_figure(min(values))} to {_figure(max(values))})"
            return text

        parts = [shown(name, [r[f"{name}_mean"] for r in rows]) for name in self.names]
        parts = [p for p in parts if p is not None]
        where = f"means over {self.start:g}-{self.stop:g} s, {frames} frames"
        if count == 1:
            head = f"  {self.sim.model.objects[0].name}"
        else:
            head = f"  {count} worlds (mean, lowest to highest world)"
        return [f"{head}: {', '.join(parts)} ({where})"]


def _figure(value: float) -> str:
    """``value`` to three significant digits, in fixed point with at most two decimals (0.00 for what is smaller)."""
    value = float(value)
    digits = 2 if abs(value) < 1e-2 else min(2, max(0, 2 - math.floor(math.log10(abs(value)))))
    text = f"{value:.{digits}f}"
    return text[1:] if text.startswith("-") and float(text) == 0.0 else text
