"""Simulation: builds a scene from its descriptor and runs it frame by frame.

A frame is what outputs see (``fps`` per simulated second); between frames the solver takes as many
steps of ``dt`` as one frame lasts. Diagnostics are computed on the host once per frame.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import warp as wp

from .builder import ModelBuilder, check_memory
from .checkpoint import Checkpoint, pack_controls, pack_rng, unpack_controls, unpack_rng
from .controls import ControlError, ControlSchedule, Gusts, check_value
from .descriptor import DescriptorError, world_descriptor
from .kernels.aero import AeroModel
from .kernels.collision import CollisionMode
from .model import Model
from .objects import registry
from .solver import AirSettings, GroundSettings, SolverEuler, SolverVerlet
from .terrain import Heightfield


def make_terrain(cfg: dict, where: str = "scene") -> Heightfield:
    """The terrain described by a descriptor's ``[terrain]`` section."""
    if cfg["kind"] == "flat":
        return Heightfield.flat(size=cfg["size"], height=cfg["height"])
    if cfg["kind"] == "procedural":
        return Heightfield.procedural(
            size=cfg["size"], amplitude=cfg["amplitude"], seed=cfg["seed"], base_height=cfg["height"]
        )
    if not cfg["file"]:
        raise DescriptorError(f"{where}: terrain.kind = 'file' needs terrain.file (a .npy array of heights)")
    try:
        return Heightfield.load(Path(cfg["file"]), size=cfg["size"])
    except (ValueError, OSError) as err:
        raise DescriptorError(f"{where}: terrain.file: {err}") from None


def object_config(kind: str, values: dict):
    """Instantiate an object's config dataclass from its descriptor section."""
    cls = registry.OBJECTS[kind].config
    kwargs = {}
    for f in dataclasses.fields(cls):
        v = values[f.name]
        kwargs[f.name] = tuple(v) if isinstance(v, list) else v
    return cls(**kwargs)


def world_name(name: str, world: int, world_count: int) -> str:
    """An object's name in a batch of ``world_count`` worlds: ``kite`` alone, ``kite_w007`` in world 7."""
    if world_count == 1:
        return name
    return f"{name}_w{world:0{len(str(world_count - 1))}d}"


def build_model(descriptor: dict, device: str | None = "cpu", where: str = "scene") -> Model:
    """Build the model of a validated descriptor on ``device``: ``worlds.count`` copies of its object, each
    with its own ``[worlds]`` values, in one model (they share the terrain and never touch each other)."""
    kind = descriptor["scene"]["object"]
    builder = ModelBuilder(air_density=descriptor["air"]["density"])
    terrain = make_terrain(descriptor["terrain"], where)
    builder.set_terrain(terrain)
    spec = registry.OBJECTS[kind]
    count = descriptor["worlds"]["count"]
    builder.world_count = count
    for world in range(count):
        builder.current_world = world
        values = world_descriptor(descriptor, world)[registry.section(kind)]
        try:
            record = spec.build(builder, object_config(kind, values), terrain)
            if world == 0 and count > 1:  # the first world tells the size of all: refuse what cannot fit
                check_memory(
                    builder.particle_count * count, f"{count:,} worlds of {builder.particle_count:,} particles"
                )
        except ValueError as err:
            at = f" (world {world})" if count > 1 else ""
            raise DescriptorError(f"{where}: [{registry.section(kind)}]{at}: {err}") from None
        record.name = world_name(record.name, world, count)
    try:
        return builder.finalize(device)
    except ValueError as err:
        raise DescriptorError(f"{where}: [{registry.section(kind)}]: {err}") from None


@dataclass
class Frame:
    """Diagnostics of one output frame.

    Attributes:
        index: frame number (0 = initial state). time: simulated time [s].
        positions: host ``[particle_count, 3]`` positions [m].
        worst_stretch: largest ``|l - r|/r`` over all sticks (dimensionless).
        kinetic_energy: total kinetic energy [J] of the free particles.
        velocities: host ``[particle_count, 3]`` velocities ``(x - x_prev)/dt`` [m/s].
        worst_stick: index of the stick with the largest stretch (-1 when there are no sticks).
    """

    index: int
    time: float
    positions: np.ndarray
    worst_stretch: float
    kinetic_energy: float
    velocities: np.ndarray
    worst_stick: int = -1


class BlowUpError(RuntimeError):
    """The simulation blew up: a position or velocity became NaN/Inf, or a stick stretched past
    ``solver.max_stretch``. Raised by :meth:`Simulation.run` after the state has been put back to the
    last good frame (so a recorder closed afterwards checkpoints that frame).

    Attributes:
        step: the solver step count at the bad frame. time: its simulated time [s].
        object: the name of the object where it happened. reason: what was seen.
        last_good_frame: index of the last good frame; last_good_time: its time [s].
        summary: the :class:`RunSummary` of the run up to the last good frame.
    """

    def __init__(self, step, time, object, reason, last_good_frame, last_good_time, summary):
        self.step, self.time, self.object, self.reason = step, time, object, reason
        self.last_good_frame, self.last_good_time, self.summary = last_good_frame, last_good_time, summary
        kept = (
            f"stopped at the last good frame {last_good_frame} (t = {last_good_time:.4f} s), "
            "which is kept with every frame before it"
            if last_good_frame >= 0
            else "the starting state is already bad, nothing was simulated"
        )
        super().__init__(f"the simulation blew up at step {step} (t = {time:.4f} s) in {object}: {reason}; {kept}")


@dataclass
class RunSummary:
    """What a run did: simulated time [s], steps, wall time [s], rates, worst stick stretch seen, start-up time [s]
    and the objects that touched the terrain."""

    simulated_time: float
    steps: int
    wall_time: float
    worst_stretch: float
    interrupted: bool = False
    blew_up: bool = False
    startup_time: float = 0.0  # [s] model build and kernel load/compilation (not in the rates)
    ground_contacts: tuple = ()  # (object name, time [s]) of each object's first touch of the terrain, by time

    @property
    def steps_per_second(self) -> float:
        """Solver steps per wall-clock second."""
        return self.steps / self.wall_time if self.wall_time > 0 else float("inf")

    @property
    def realtime_factor(self) -> float:
        """Simulated seconds per wall-clock second."""
        return self.simulated_time / self.wall_time if self.wall_time > 0 else float("inf")

    def text(self) -> str:
        """Human-readable summary lines."""
        status = "blew up" if self.blew_up else "interrupted" if self.interrupted else "done"
        text = (
            f"{status}: simulated {self.simulated_time:.3f} s in {self.steps} steps, wall {self.wall_time:.2f} s "
            f"(+ {self.startup_time:.2f} s start-up: model and kernels)\n"
            f"  {self.steps_per_second:,.0f} steps/s, real-time factor {self.realtime_factor:.1f}x, "
            f"worst stick stretch {100 * self.worst_stretch:.3f}%"
            + (" up to the last good frame" if self.blew_up else "")
        )
        contacts = self.ground_contacts
        if 0 < len(contacts) <= 3:
            text += "".join(f"\n  {name} touched the terrain at t = {t:.2f} s" for name, t in contacts)
        elif contacts:
            name, t = contacts[0]
            text += f"\n  {len(contacts)} objects touched the terrain, the first ({name}) at t = {t:.2f} s"
        return text


class Simulation:
    """A scene ready to run: model, state, control and solver built from a validated descriptor.

    Args:
        descriptor: validated descriptor (see :mod:`warpsim.descriptor`).
        device: Warp device (``cpu`` default, ``cuda`` when present).
        use_graph: replay the step as a captured graph (default True).
        where: origin of the descriptor for error messages.
    """

    def __init__(self, descriptor: dict, device: str | None = "cpu", use_graph: bool = True, where: str = "scene"):
        started = time.perf_counter()
        self.descriptor = descriptor
        self.model = build_model(descriptor, device, where)
        solver_cfg = descriptor["solver"]
        self.dt = float(solver_cfg["dt"])
        air = AirSettings(
            model=AeroModel[descriptor["air"]["model"].upper()],
            scale=descriptor["air"]["scale"],
            shear_exponent=descriptor["wind"]["shear_exponent"],
            shear_reference_height=descriptor["wind"]["reference_height"],
        )
        ground = GroundSettings(
            mode=CollisionMode[descriptor["ground"]["collision"].upper()], friction=descriptor["ground"]["friction"]
        )
        if solver_cfg["method"] == "verlet":
            self.solver = SolverVerlet(
                self.model,
                iterations=solver_cfg["iterations"],
                relaxation=solver_cfg["relaxation"],
                chebyshev=solver_cfg["chebyshev"],
                mass_splitting=solver_cfg["mass_splitting"],
                damping=solver_cfg["damping"],
                air=air,
                ground=ground,
                use_graph=use_graph,
            )
        else:
            self.solver = SolverEuler(
                self.model,
                stiffness=solver_cfg["spring_stiffness"],
                damping=solver_cfg["spring_damping"],
                air=air,
                ground=ground,
                use_graph=use_graph,
            )
        self.state = self.model.state()
        self.state.set_velocity(self.model.particle_qd0, self.dt)
        self.control = self.model.control()
        problem = self.blowup(self.frame(0))
        if problem:
            raise DescriptorError(
                f"{where}: the built {problem[0]} is not sound: {problem[1]}; check its sizes, masses, speed and dt"
            )
        self.steps_taken = 0
        self.world_count = descriptor["worlds"]["count"]
        winds = [world_descriptor(descriptor, k)["wind"] for k in range(self.world_count)]
        # per world: the gusts blowing there (None = steady wind)
        self.gusts: list[Gusts | None] = [
            Gusts(w["velocity"], w["gust_intensity"], w["gust_period"], w["gust_seed"])
            if w["gust_intensity"] > 0.0
            else None
            for w in winds
        ]
        self.control.set_wind(np.array([w["velocity"] for w in winds]))
        try:
            self.schedule = ControlSchedule(descriptor.get("controls", []), self.control_names(), where)
        except ControlError as err:
            raise DescriptorError(str(err)) from None
        self.controls: dict = {}  # every control set so far, by name (what is in force now)
        self._scheduled: dict = {}  # the schedule's last values, so that held values are not set again
        fps = float(descriptor["scene"]["fps"])
        self.steps_per_frame = max(1, int(round(1.0 / (fps * self.dt))))
        self._contact_setup()
        self.solver.load_kernels()  # compile now, not in the first frame's time (the graph is captured there)
        wp.synchronize_device(self.model.device)
        self.startup_time = time.perf_counter() - started  # [s] model build, kernel load/compilation

    def set_controls(self, **values) -> None:
        """Set controls between steps, e.g. ``set_controls(pitch=0.5, roll=-0.2)`` (each in [-1, 1]) for the
        hang glider, ``set_controls(anchor=(10.0, 0.0))`` [m] for the kite, ``set_controls(wind=(6, 0, 0))``
        [m/s] for any scene. A control not given keeps its value.

        Raises ``ValueError`` for a control the scene's object does not have or an invalid value.
        """
        allowed = self.control_names()
        for name, value in values.items():
            if name not in allowed:
                raise ValueError(f"this scene has no control {name!r}; its controls are: {', '.join(allowed)}")
            values[name] = check_value(name, value)
        if "wind" in values:
            self.control.set_wind(values["wind"])
            for gusts in self.gusts:
                if gusts is not None:
                    gusts.mean = np.asarray(values["wind"], dtype=np.float64)
        self.controls.update(values)
        if set(values) <= {"wind"}:
            return
        object_values = {k: v for k, v in self.controls.items() if k != "wind"}
        targets = {
            "stick_rest": self.control.stick_rest.numpy().copy(),
            "nail_target": self.control.nail_target.numpy().copy(),
            "terrain": self.model.terrain,
        }
        for record in self.model.objects:
            spec = registry.OBJECTS[record.kind]
            if spec.apply_controls is not None:
                spec.apply_controls(record, targets, object_values)
        self.control.stick_rest.assign(targets["stick_rest"])
        self.control.nail_target.assign(targets["nail_target"])

    def control_names(self) -> tuple[str, ...]:
        """Names of the controls this scene accepts (its object's and ``wind``)."""
        names = []
        for record in self.model.objects:
            names += [c for c in registry.OBJECTS[record.kind].controls if c not in names]
        return (*names, "wind")

    def apply_schedule(self) -> None:
        """Apply the descriptor's ``[[controls]]`` schedule at the current time, and advance the gusts.

        With gusts, a scheduled ``wind`` sets the mean the gusts blow around. Scheduled controls act on
        every world.
        """
        values = self.schedule.at(self.state.time + 1e-9) if self.schedule else {}
        if any(g is not None for g in self.gusts):
            if "wind" in values:
                mean = tuple(float(v) for v in values.pop("wind"))
                if self._scheduled.get("wind") != mean:
                    self.set_controls(wind=mean)
                    self._scheduled["wind"] = mean
            interval = self.steps_per_frame * self.dt
            winds = self.control.wind.numpy().copy()
            for k, gusts in enumerate(self.gusts):
                if gusts is not None:
                    winds[k] = gusts.advance(interval)
            self.control.set_wind(winds)
        changed = {k: v for k, v in values.items() if self._scheduled.get(k) != v}
        if changed:
            self.set_controls(**changed)
            self._scheduled.update(changed)

    def step(self, count: int = 1) -> None:
        """Take ``count`` solver steps of ``dt``."""
        for _ in range(count):
            self.solver.step(self.state, self.control, self.dt)
        self.steps_taken += count

    def frame(self, index: int) -> Frame:
        """Diagnostics of the current state as frame ``index``."""
        q = self.state.positions()
        with np.errstate(invalid="ignore", over="ignore"):  # a blown-up state is reported by blowup()
            stretches = np.abs(self.model.stick_stretch(q, self.control.stick_rest.numpy()))
            worst_stick = int(np.argmax(stretches)) if len(stretches) else -1  # argmax finds a NaN first
            stretch = float(stretches[worst_stick]) if len(stretches) else 0.0
            v = self.state.velocities(self.dt)
            energy = float(0.5 * np.sum(self.model.particle_free_mass * np.einsum("ij,ij->i", v, v)))
        return Frame(index, self.state.time, q, stretch, energy, v, worst_stick)

    def blowup(self, frame: Frame) -> tuple[str, str] | None:
        """``(object name, what is wrong)`` when ``frame`` shows a blow-up, else None: a non-finite position
        or velocity, or a worst stick stretch above ``solver.max_stretch`` (when that is > 0)."""
        model = self.model
        bad = ~(np.isfinite(frame.positions).all(axis=1) & np.isfinite(frame.velocities).all(axis=1))
        if bad.any():
            p = int(np.flatnonzero(bad)[0])
            return self._object_of(p), f"particle {p} has a non-finite position or velocity ({bad.sum()} particles)"
        limit = float(self.descriptor["solver"]["max_stretch"])
        if limit > 0.0 and not frame.worst_stretch <= limit:  # NaN stretch counts as too much
            k = frame.worst_stick
            a, b = (int(i) for i in model.stick_particles_np[k])
            return (
                self._object_of(a),
                f"stick {k} (particles {a}-{b}) is stretched {100 * frame.worst_stretch:.1f}% "
                f"(limit solver.max_stretch = {100 * limit:g}%)",
            )
        return None

    # parts that lie on the ground or hold an object to it by design; their contact is not news
    GROUNDED_PARTS = ("rope", "pole", "lines", "virtual")
    CONTACT_DISTANCE = 0.02  # [m] a particle this close to the terrain surface touches it

    def _contact_setup(self) -> None:
        model = self.model
        free = np.isfinite(model.particle_mass)
        ids, owner = [np.zeros(0, dtype=np.int64)], [np.zeros(0, dtype=np.int64)]
        for k, record in enumerate(model.objects):
            particles = np.asarray(record.particles, dtype=np.int64)
            grounded = [np.asarray(record.parts[p], dtype=np.int64) for p in self.GROUNDED_PARTS if p in record.parts]
            keep = free[particles] & ~np.isin(particles, np.concatenate([np.zeros(0, np.int64), *grounded]))
            ids.append(particles[keep])
            owner.append(np.full(int(keep.sum()), k, dtype=np.int64))
        self._contact_ids = np.concatenate(ids)
        self._contact_owner = np.concatenate(owner)
        self._terrain_top = float(model.terrain.heights.max()) + self.CONTACT_DISTANCE
        self.ground_contacts: dict[str, float] = {}  # object name -> first time [s] it touched the terrain

    def _note_contacts(self, frame: Frame) -> None:
        """Record the objects that touch the terrain in ``frame`` for the first time."""
        if len(self.ground_contacts) == len(self.model.objects) or not len(self._contact_ids):
            return
        z = frame.positions[self._contact_ids, 2]
        low = np.flatnonzero(z < self._terrain_top)  # only those can touch: a cheap test first
        if not len(low):
            return
        p = frame.positions[self._contact_ids[low]]
        touching = low[p[:, 2] - self.model.terrain.height(p[:, 0], p[:, 1]) < self.CONTACT_DISTANCE]
        for k in np.unique(self._contact_owner[touching]):
            name = self.model.objects[int(k)].name
            self.ground_contacts.setdefault(name, float(frame.time))

    def _contacts(self) -> tuple:
        return tuple(sorted(self.ground_contacts.items(), key=lambda item: item[1]))

    def _object_of(self, particle: int) -> str:
        for record in self.model.objects:
            if particle in record.particles:
                return record.name
        return "no object"

    def checkpoint(self) -> Checkpoint:
        """Everything needed to continue this run exactly (host copies, see :class:`warpsim.checkpoint.Checkpoint`):
        state, control arrays, every world's gusts, the controls in force and the step count."""
        names = self.control_names()
        worlds = len(self.gusts)
        gust_active = np.zeros(worlds, dtype=np.uint8)
        gust_g = np.zeros((worlds, 3), dtype=np.float64)
        gust_mean = np.zeros((worlds, 3), dtype=np.float64)
        gust_rng = np.zeros((worlds, 6), dtype=np.uint64)
        for k, gusts in enumerate(self.gusts):
            if gusts is not None:
                gust_active[k] = 1
                gust_g[k], gust_mean[k] = gusts.g, gusts.mean
                gust_rng[k] = pack_rng(gusts.rng.bit_generator.state)
        control_set, control_value = pack_controls(names, self.controls)
        scheduled_set, scheduled_value = pack_controls(names, self._scheduled)
        return Checkpoint(
            q=self.state.positions().astype(np.float32, copy=True),
            q_prev=self.state.particle_q_prev.numpy().copy(),
            time=np.array([self.state.time], dtype=np.float64),
            steps=np.array([self.steps_taken], dtype=np.int64),
            stick_rest=self.control.stick_rest.numpy().copy(),
            nail_target=self.control.nail_target.numpy().copy(),
            wind=self.control.wind.numpy().copy(),
            gust_active=gust_active,
            gust_g=gust_g,
            gust_mean=gust_mean,
            gust_rng=gust_rng,
            control_set=control_set,
            control_value=control_value,
            scheduled_set=scheduled_set,
            scheduled_value=scheduled_value,
            control_names=names,
        )

    def restore(self, checkpoint: Checkpoint) -> None:
        """Continue from a :meth:`checkpoint` of a simulation of the same descriptor (bit for bit).

        Raises ``ValueError`` when its fields do not fit this scene (other shapes, types or controls).
        """
        checkpoint.check_like(self.checkpoint())
        self.state.particle_q.assign(checkpoint.q)
        self.state.particle_q_prev.assign(checkpoint.q_prev)
        self.state.time = float(checkpoint.time[0])
        self.steps_taken = int(checkpoint.steps[0])
        self.control.stick_rest.assign(checkpoint.stick_rest)
        self.control.nail_target.assign(checkpoint.nail_target)
        self.control.wind.assign(checkpoint.wind)
        for k, gusts in enumerate(self.gusts):
            if gusts is not None and checkpoint.gust_active[k]:
                gusts.g = checkpoint.gust_g[k].copy()
                gusts.mean = checkpoint.gust_mean[k].copy()
                gusts.rng.bit_generator.state = unpack_rng(checkpoint.gust_rng[k])
        names = checkpoint.control_names
        self.controls = unpack_controls(names, checkpoint.control_set, checkpoint.control_value)
        self._scheduled = unpack_controls(names, checkpoint.scheduled_set, checkpoint.scheduled_value)

    def run(
        self,
        seconds: float,
        on_frame: Callable[[Frame], None] | None = None,
        on_progress: Callable[[float, float, int, float], None] | None = None,
        realtime: bool = False,
        stop: Callable[[], bool] | None = None,
    ) -> RunSummary:
        """Run for ``seconds`` of simulated time, calling ``on_frame`` on the initial and every later frame.

        Frames lie on a fixed grid: frame ``k`` ends after ``k * steps_per_frame`` steps counted from the
        start of the scene; controls and gusts change at frame starts. A run that ends between two grid
        points emits a last, shorter frame with the next index; a run continued from there (after
        :meth:`restore`) first completes that frame and emits it again under the same index, so a run
        cut in two and continued gives the same frames, bit for bit, as one run. When continuing, the
        current state is not passed to ``on_frame`` again.

        ``on_progress(t, seconds, steps, wall)`` is called at most about 5 times per wall second.
        ``stop()`` is asked before every frame (the CLI's answers True after SIGINT/SIGTERM); True, or a
        ``KeyboardInterrupt``, ends the run there and the summary says ``interrupted``.

        Every frame is checked (:meth:`blowup`) before ``on_frame`` sees it. A bad frame is not passed on:
        the state goes back to the last good frame and :class:`BlowUpError` is raised.
        """
        total_steps = int(round(seconds / self.dt))
        spf = self.steps_per_frame
        worst = 0.0
        steps = 0
        start = time.perf_counter()
        last_report = start
        interrupted = False
        try:
            index = -(-self.steps_taken // spf)  # ceil: the frame the current state belongs to
            first = self.frame(index)
            problem = self.blowup(first)
            if problem:
                raise BlowUpError(
                    self.steps_taken, first.time, *problem, -1, first.time, RunSummary(0.0, 0, 0.0, 0.0, blew_up=True)
                )
            worst = first.worst_stretch
            good, good_frame = self.checkpoint(), first  # taken before on_frame can touch the state
            if on_frame and self.steps_taken == 0:
                on_frame(first)
            while steps < total_steps:
                if stop is not None and stop():
                    interrupted = True
                    break
                into = self.steps_taken % spf
                if into == 0:  # a frame starts: controls and gusts move
                    self.apply_schedule()
                n = min(spf - into, total_steps - steps)
                self.step(n)
                steps += n
                index = -(-self.steps_taken // spf)
                frame = self.frame(index)
                problem = self.blowup(frame)
                if problem:
                    bad_step = self.steps_taken
                    self.restore(good)
                    steps -= bad_step - self.steps_taken
                    wp.synchronize_device(self.model.device)
                    summary = RunSummary(
                        steps * self.dt,
                        steps,
                        time.perf_counter() - start,
                        worst,
                        blew_up=True,
                        startup_time=self.startup_time,
                        ground_contacts=self._contacts(),
                    )
                    raise BlowUpError(bad_step, frame.time, *problem, good_frame.index, good_frame.time, summary)
                worst = max(worst, frame.worst_stretch)
                self._note_contacts(frame)
                good, good_frame = self.checkpoint(), frame
                if on_frame:
                    on_frame(frame)
                now = time.perf_counter()
                if realtime:
                    ahead = steps * self.dt - (now - start)
                    if ahead > 0:
                        time.sleep(ahead)
                if on_progress and now - last_report > 0.2:
                    on_progress(self.state.time, seconds, steps, now - start)
                    last_report = now
        except KeyboardInterrupt:
            interrupted = True
        wp.synchronize_device(self.model.device)
        wall = time.perf_counter() - start
        return RunSummary(steps * self.dt, steps, wall, worst, interrupted, False, self.startup_time, self._contacts())
