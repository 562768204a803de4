"""Simulation: a scene built from its descriptor, run frame by frame.

A frame is what outputs see (``fps`` per simulated second); between frames the solver takes as many
steps of ``dt`` as one frame lasts. The pieces live beside it: :mod:`warpsim.scene` builds the model,
:func:`warpsim.physics.solver.make_solver` the solver, :mod:`warpsim.run.inputs` turns controls, schedule and gusts into
control arrays, :mod:`warpsim.run.diagnostics` says what a frame shows. After each frame the device reports a few
numbers (worst stretch, non-finite particles, terrain clearance: :mod:`warpsim.physics.kernels.frame`), captured in one
graph with the frame's steps; positions reach the host only when an output, the viewer or a check asks.

With ``threads > 1`` on the CPU the worlds of a batch are cut into one group per thread
(:mod:`warpsim.run.groups`), each replayed by its own thread. The threads meet at every frame end, where outputs,
controls and checks see one whole frame; the frames are bit for bit those of one thread.
"""

from __future__ import annotations

import time
import weakref
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np
import warp as wp

from ..physics import atmosphere
from ..physics.kernels import frame as frame_kernels
from ..physics.solver import SOLVERS, load_modules, make_solver
from ..scene.controls import ControlError, ControlSchedule
from ..scene.descriptor import DescriptorError
from ..scene.scene import Scene
from .checkpoint import (
    Checkpoint,
    canopy_sides,
    restore_checkpoint,
    take_checkpoint,
    vortex_states,
    wake_states,
)
from .diagnostics import Frame, FrameSource, GroundContacts, find_blowup, world_blowups
from .figures import Flight, FlightFigures
from .groups import GroupThreads, WorldGroup, split_worlds
from .inputs import Inputs, control_names
from .summary import BlowUpError, RunSummary, _Pace, available_cores

__all__ = ["BlowUpError", "Flight", "Frame", "RunSummary", "Simulation", "available_cores"]


FRAME_GRAPH_BYTES_PER_STEP = 16 * 1024
"""Memory [bytes] one solver step takes in a captured frame graph (measured: a kite frame of 1,000 steps adds
about 15 MB per graph on the CPU, whatever ``solver.iterations``); capturing it takes about 0.6 ms per step."""

MAX_FRAME_GRAPH_STEPS = (4 << 20) // FRAME_GRAPH_BYTES_PER_STEP
"""Most steps a frame may have and still be captured as one graph (256: 4 MB and about 0.15 s per graph). A
longer frame (``fps`` below about 0.4 at ``dt`` = 0.01 s) replays the solver's one-step graph once per step,
which computes the same bits; without this bound ``--fps 0.001`` captured 100,000 steps twice, gigabytes."""


@dataclass(frozen=True)
class GoodFrame:
    """The last frame that passed its checks, where the state goes back to after a blow-up.

    Attributes:
        index: the frame's index. time: its simulated time [s]. steps: solver steps taken up to it.
        slot: the probe slot (0 or 1) that keeps its positions; a new frame is measured into the other one.
    """

    index: int
    time: float
    steps: int
    slot: int

    @property
    def free_slot(self) -> int:
        """The probe slot a new frame is measured into: never this frame's own."""
        return 1 - self.slot


class Simulation:
    """A scene ready to run: model, state, control, solver and inputs built from a validated descriptor.

    Args:
        scene: the :class:`~warpsim.scene.scene.Scene`, a validated descriptor (see :mod:`warpsim.scene.descriptor`),
            or a built-in object, scene name or ``.toml`` path (:meth:`warpsim.scene.scene.Scene.load`).
        device: Warp device (``cpu`` default, ``cuda`` when present).
        use_graph: replay each step (and each frame) as a captured graph (default True).
        where: origin of the descriptor for error messages.
        terrain: heights to use instead of the descriptor's ``[terrain]`` (a recording's stored terrain).
        threads: how many threads step the worlds, each a group of consecutive worlds (default 1; at most one
            per world; on the CPU only, a GPU steps every world in one launch). The frames are bit for bit the
            same for any number: only the wall time changes.
    """

    def __init__(
        self,
        scene: Scene | dict | str,
        device: str | None = "cpu",
        use_graph: bool = True,
        where: str = "scene",
        terrain=None,
        threads: int = 1,
    ):
        started = time.perf_counter()
        self.scene = Scene.of(scene, where)
        self.settings = cfg = self.scene.settings
        # every kernel module the run launches, compiled together on a cold cache before anything else uses one
        load_modules((*SOLVERS[cfg.solver.method].modules, frame_kernels), device)
        self.model = self.scene.build_model(device, where, terrain)
        self.dt = cfg.solver.dt
        try:
            self.solver = make_solver(
                self.model, cfg.solver, air=cfg.air, wind=cfg.wind, ground=cfg.ground, use_graph=use_graph
            )
            self.solver.check_dt(self.dt)
        except ValueError as err:  # a solver setting the model cannot take (elastic sticks without mass splitting)
            raise DescriptorError(f"{where}: [solver]: {err}") from None
        self.state = self.model.state(self.dt)
        self.control = self.model.control()
        if cfg.air.density == 0.0 and cfg.air.scale > 0.0:  # the standard atmosphere: every object must start in it
            _check_altitudes(self.model, cfg.air.elevation, where)
        self.solver.update_air(self.state, self.control)
        self.steps_taken = 0
        self.world_count = self.model.world_count
        winds = [self.scene.wind_of(k) for k in range(self.world_count)]
        try:
            schedule = ControlSchedule(self.scene.controls, control_names(self.model), where)
        except ControlError as err:
            raise DescriptorError(str(err)) from None
        try:
            self.inputs = Inputs(self.model, self.control, winds, schedule, self.dt)
        except ValueError as err:  # worlds that cannot share a turbulence field
            raise DescriptorError(f"{where}: [wind]: {err}") from None
        self.contacts = GroundContacts(self.model)
        self._groups = split_worlds(self, threads, where)
        self.threads = len(self._groups)
        self._threads = GroupThreads(self._groups, self)
        self._source = FrameSource(self.model, self.state, self.control, self.dt)
        self._out = _nothing  # the last frame handed out (a weak reference), copied before the state moves on
        # (frame index, the controls in force when that frame's stepping began): what a frame records and a replay
        # sets again at the frame's start (the schedule may change them within the frame, at its own steps)
        self._start_controls: tuple[int, dict] = (-1, {})
        self._good = GoodFrame(0, 0.0, 0, 0)  # the last frame that passed its checks
        self._saved_version, self._saved = -1, None  # inputs and control arrays of the last good frame
        first = self.frame(0)
        problem = self.blowup(first)
        if problem:
            raise DescriptorError(
                f"{where}: the built {problem[0]} is not sound: {problem[1]}; check its sizes, masses, speed and dt"
            )
        self._keep_good(first)
        del first
        self.steps_per_frame = cfg.scene.steps_per_frame(self.dt)
        # per group and probe slot, the whole frame (probe, steps, probe) as one graph; a frame of more steps than
        # MAX_FRAME_GRAPH_STEPS (a low --fps) is stepped through the solver's one-step graph instead, so that the
        # graphs' memory and capture time stay bounded whatever the frame rate
        if self.solver.use_graph and self.steps_per_frame <= MAX_FRAME_GRAPH_STEPS:
            for group in self._groups:
                group.graphs = (self._capture_frame(group, 0), self._capture_frame(group, 1))
        wp.synchronize_device(self.model.device)
        self.startup_time = time.perf_counter() - started  # [s] model build, kernel load/compilation

    @property
    def descriptor(self) -> dict:
        """A copy of the scene's plain descriptor (:meth:`warpsim.scene.scene.Scene.descriptor`): what is written
        (TOML, a recording) or merged; read the scene's settings from :attr:`scene`."""
        return self.scene.descriptor()

    @property
    def groups(self) -> tuple[WorldGroup, ...]:
        """The groups of worlds the threads step (:mod:`warpsim.run.groups`; one without threads)."""
        return tuple(self._groups)

    @property
    def controls(self) -> dict:
        """Every control set so far, by name (what is in force now)."""
        return self.inputs.in_force

    def set_controls(self, **values) -> None:
        """Set controls between steps, e.g. ``set_controls(pitch=0.5, roll=-0.2)`` (each in [-1, 1]) for the
        hang glider, ``set_controls(anchor=(10.0, 0.0))`` [m] for the kite, ``set_controls(wind=(6, 0, 0))``
        [m/s] for any scene. A control not given keeps its value.

        Raises ``ValueError`` for a control the scene's object does not have or an invalid value.
        """
        self._release()
        self.inputs.set(**values)

    def control_names(self) -> tuple[str, ...]:
        """Names of the controls this scene accepts (its object's and ``wind``)."""
        return self.inputs.names

    def apply_schedule(self) -> None:
        """Apply the descriptor's ``[[controls]]`` schedule when it changes something at the current step (:meth:`step`
        does this itself at every such step)."""
        self._release()
        self.inputs.apply_schedule(self.steps_taken)

    def step(self, count: int = 1) -> None:
        """Take ``count`` solver steps of ``dt`` (each group on its own thread), applying the schedule at the steps
        where it changes something; the gusts advance with every step."""
        self._release()
        end = self.steps_taken + count
        while self.steps_taken < end:
            self.inputs.apply_schedule(self.steps_taken)
            self._note_frame_start()
            change = self.inputs.next_change(self.steps_taken)
            self._solver_steps(end - self.steps_taken if change is None else min(end, change) - self.steps_taken)

    def _note_frame_start(self) -> None:
        """At a frame's first step, keep the controls in force (after the schedule and ``before`` have acted)."""
        spf = getattr(self, "steps_per_frame", 0)
        if spf and self.steps_taken % spf == 0:
            self._start_controls = (self.steps_taken // spf + 1, dict(self.inputs.in_force))

    def _solver_steps(self, count: int) -> None:
        """Take ``count`` solver steps, the inputs as they are."""
        if len(self._groups) == 1:
            for _ in range(count):
                self.solver.step(self.state, self.control, self.dt)
        else:
            for group in self._groups:  # each group's step graph captured here, never by two threads at once
                if not group.prepared:
                    group.solver.prepare(group.state, group.control, self.dt)
                    group.prepared = True

            def steps(group: WorldGroup) -> None:
                for _ in range(count):
                    group.solver.step(group.state, group.control, self.dt)

            self._threads.each(steps)
            for _ in range(count):  # the groups' states kept their own time
                self.state.time += self.dt
        self.steps_taken += count

    def frame(self, index: int) -> Frame:
        """The current state measured as frame ``index`` (see :class:`warpsim.run.diagnostics.Frame`), with the
        controls in force."""
        self._measure(self._good.free_slot)  # never over the last good frame's slot
        return self._hand_out(index)

    def _measure(self, slot: int) -> None:
        """Have every group's probe report the state as it is and keep its positions in ``slot``."""
        for group in self._groups:
            group.probe.begin()
            group.probe.measure(group.state, group.control, slot)

    def _report(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The probes' report of the whole simulation (see :meth:`warpsim.physics.kernels.frame.FrameProbe.read`): the
        groups' reports joined, in world and object order."""
        parts = [group.probe.read() for group in self._groups]
        return parts[0] if len(parts) == 1 else tuple(np.concatenate(part) for part in zip(*parts, strict=True))

    def _hand_out(self, index: int) -> Frame:
        """Frame ``index`` of the probe's report, remembered so that :meth:`_release` can copy what it needs."""
        self._release()
        started, at_start = self._start_controls
        controls = dict(at_start) if started == index else dict(self.inputs.in_force)
        frame = Frame(index, self.state.time, self.steps_taken, self._report(), self._source, controls)
        self._out = weakref.ref(frame)
        return frame

    def _release(self) -> None:
        """Before the state or the controls change: the last frame handed out, if someone still holds it, copies
        the state it shows to the host (a frame nobody holds costs nothing)."""
        frame = self._out()
        if frame is not None:
            frame.fetch()
            self._out = _nothing

    def _capture_frame(self, group: WorldGroup, slot: int):
        """The graph of one whole frame of ``group`` kept in probe ``slot``: the probe's start, ``steps_per_frame``
        solver steps, the probe's report (for the group's state and control, whose kernels are loaded; the same
        kernels as stepping one by one)."""
        with wp.ScopedCapture(device=self.model.device) as capture:
            group.probe.begin()
            for _ in range(self.steps_per_frame):
                group.solver.launch(group.state, group.control, self.dt)
            group.probe.measure(group.state, group.control, slot)
        return capture.graph

    def _replay(self, slot: int) -> None:
        """Replay every group's frame graph for probe ``slot``, each group on its own thread."""
        self._threads.each(lambda group: wp.capture_launch(group.graphs[slot]))

    def _step_frame(self, count: int) -> None:
        """Take ``count`` steps (one frame or what is left of it) and have the probe report and keep the state in
        the slot that is not the last good frame's."""
        self._release()
        slot = self._good.free_slot
        self.inputs.apply_schedule(self.steps_taken)
        self._note_frame_start()
        change = self.inputs.next_change(self.steps_taken)
        steady = change is None or change >= self.steps_taken + count  # no scheduled change inside the frame
        if count == self.steps_per_frame and self._groups[0].graphs is not None and steady:
            self._replay(slot)
            for _ in range(count):  # the same sum of dt as the solver keeps step by step
                self.state.time += self.dt
            self.steps_taken += count
        else:
            for group in self._groups:
                group.probe.begin()
            self.step(count)
            for group in self._groups:
                group.probe.measure(group.state, group.control, slot)

    def _keep_good(self, frame: Frame) -> None:
        """Make ``frame``, the last one measured and just checked, the last good frame, with the controls in force
        now."""
        self._good = GoodFrame(frame.index, frame.time, frame.steps, self._good.free_slot)
        # the controls changed since the last good frame (the gusts and the turbulence move with every step)
        moving = self.control.gusts is not None or self.control.turbulence.field is not None
        if self._saved_version != self.inputs.version or moving:
            self._saved_version = self.inputs.version
            c = self.control
            saved = (c.stick_rest_target, c.nail_target_goal, c.wind)
            self._saved = (self.inputs.save(), *(a.numpy().copy() for a in saved))

    def blowup(self, frame: Frame) -> tuple[str, str] | None:
        """``(object name, what is wrong)`` when ``frame`` shows a blow-up (non-finite values, or a stick past
        ``solver.max_stretch``), else None."""
        return find_blowup(self.model, frame, self.settings.solver.max_stretch)

    def checkpoint(self) -> Checkpoint:
        """Everything needed to continue this run exactly (host copies, see :class:`warpsim.run.checkpoint.Checkpoint`):
        state, control arrays, every world's gusts, the controls in force and the step count."""
        return take_checkpoint(self)

    def restore(self, checkpoint: Checkpoint) -> None:
        """Continue from a :meth:`checkpoint` of a simulation of the same descriptor (bit for bit).

        Raises ``ValueError`` when its fields do not fit this scene (other shapes, types or controls) or its time
        is not its step count's.
        """
        checkpoint.check_like(self.checkpoint())
        checkpoint.check_time(self.dt)
        self._release()
        restore_checkpoint(self, checkpoint)

    def start_frames(self) -> Frame:
        """Check the current state and make it the last good frame that :meth:`advance` goes back to on a
        blow-up; returns it (its index is the frame the current step count belongs to).

        Raises :class:`BlowUpError` (with an empty summary) when the current state is already bad.
        """
        first = self.frame(-(-self.steps_taken // self.steps_per_frame))  # ceil: the frame the state belongs to
        problem = self.blowup(first)
        if problem:
            raise BlowUpError(
                self.steps_taken, first.time, *problem, -1, first.time, RunSummary(0.0, 0, 0.0, 0.0, blew_up=True)
            )
        self._keep_good(first)
        return first

    def advance(self, limit: int | None = None, before: Callable[[int], None] | None = None) -> Frame:
        """Step to the end of the current frame (at most ``limit`` steps) and return that frame, checked.

        The schedule acts at its own steps and the gusts at every step (:meth:`step`), whatever the frames; at a
        frame start ``before(index)`` is called with the index of the frame about to be stepped (a keyboard or a
        recorded flight sets its controls there, through :meth:`set_controls`). A bad frame is not returned: the
        state goes back to the last good frame (see :meth:`start_frames`, which must have been called once) and
        :class:`BlowUpError` is raised, its ``summary`` None.
        """
        frame = self._to_frame_end(limit, before)
        problem = self.blowup(frame)
        if problem:
            bad_step = self.steps_taken
            self._go_back()
            raise BlowUpError(bad_step, frame.time, *problem, self._good.index, self._good.time, None)
        self.contacts.note(frame)
        self._keep_good(frame)
        return frame

    def _to_frame_end(self, limit: int | None, before: Callable[[int], None] | None) -> Frame:
        """Step to the end of the current frame (at most ``limit`` steps; ``before`` at a frame start, as in
        :meth:`advance`) and hand out that frame, unchecked."""
        spf = self.steps_per_frame
        into = self.steps_taken % spf
        if into == 0 and before is not None:  # a frame starts: a keyboard or a recorded flight sets its controls
            self.apply_schedule()
            before(self.steps_taken // spf + 1)
        n = spf - into if limit is None else min(spf - into, limit)
        self._step_frame(n)
        return self._hand_out(-(-self.steps_taken // spf))

    def frames(
        self,
        seconds: float | None = None,
        before: Callable[[int], None] | None = None,
        *,
        each_world: bool = False,
    ) -> Iterator[Frame]:
        """The run's frames, checked, one per ``next``: the current state first, then every frame stepped for
        ``seconds`` of simulated time from now (None: for as long as the consumer asks). What :meth:`run`, the
        viewer and a sweep's chunk step by.

        The frames lie on :meth:`run`'s grid and ``before`` acts at frame starts as in :meth:`advance`. The
        iterator steps only when the next frame is asked for, so a consumer that stops asking (Ctrl-C, the
        window closed, every case of a sweep blown up) leaves the state at the last frame it was given.

        Checked: a bad frame is not yielded; the state goes back to the last good frame and :class:`BlowUpError`
        ends the iterator, as :meth:`advance` does (its ``summary`` None; a state already bad when the iterator
        starts raises it from :meth:`start_frames`, with an empty summary). With ``each_world`` the worlds are
        checked one by one instead (a sweep's cases, which go on when one of them blows up): every frame is
        yielded, its :attr:`~warpsim.run.diagnostics.Frame.blowups` naming the worlds that are bad in it (a world
        once bad steps on unchecked; nothing goes back).
        """
        end = None if seconds is None else self.steps_taken + int(round(seconds / self.dt))

        def worlds_checked(frame: Frame) -> Frame:
            frame.blowups = world_blowups(self.model, frame, self.settings.solver.max_stretch)
            return frame

        if each_world:
            frame = worlds_checked(self.frame(-(-self.steps_taken // self.steps_per_frame)))
        else:
            frame = self.start_frames()
        yield frame
        del frame  # a frame nobody holds is not copied when the state moves on
        while end is None or self.steps_taken < end:
            limit = None if end is None else end - self.steps_taken
            if each_world:
                frame = worlds_checked(self._to_frame_end(limit, before))
            else:
                frame = self.advance(limit, before)
            yield frame
            del frame

    def _go_back(self) -> None:
        """Put the state, the control arrays and the inputs back to the last good frame (:meth:`advance` and
        :meth:`start_frames` check every frame they return, and the probe keeps its positions)."""
        self._release()
        inputs, stick_rest_target, nail_target_goal, wind = self._saved
        time, steps, slot = self._good.time, self._good.steps, self._good.slot
        # the rest lengths and nail targets ramp every step: each group's probe keeps them with the positions
        kept = [group.probe.kept(slot) for group in self._groups]
        q, q_prev, stick_rest = (np.concatenate(arrays) for arrays in list(zip(*kept, strict=True))[:3])
        if self.model.nail_count:  # a group without nails keeps one unused target
            nail_target = np.concatenate([k[3][: g.model.nail_count] for k, g in zip(kept, self._groups, strict=True)])
        else:
            nail_target = self.control.nail_target.numpy().copy()
        self.restore(
            Checkpoint(
                q=q,
                q_prev=q_prev,
                time=np.array([time], dtype=np.float64),
                steps=np.array([steps], dtype=np.int64),
                stick_rest=stick_rest,
                stick_rest_target=stick_rest_target,
                nail_target=nail_target,
                nail_target_goal=nail_target_goal,
                canopy_side=canopy_sides(self),  # as now: the frame probes keep positions, not these
                # the lattice's as now (a blow-up's NaN put to 0), then factorised again and its wake reset (below)
                vortex_state=np.nan_to_num(vortex_states(self), nan=0.0, posinf=0.0, neginf=0.0),
                vortex_wake=np.nan_to_num(wake_states(self), nan=0.0, posinf=0.0, neginf=0.0),
                wind=wind,
                **inputs,
                control_names=self.inputs.names,
            )
        )
        for group in self._groups:  # the lattice: factorised again, and its shed wake started afresh, from here
            vortex = group.solver.vortex
            if vortex is not None:
                vortex.factored.zero_()
                if vortex.shed is not None:
                    vortex.shed.reset(group.model, group.state, vortex.gamma)
        wp.synchronize_device(self.model.device)

    def run(
        self,
        seconds: float,
        on_frame: Callable[[Frame], None] | None = None,
        on_progress: Callable[[float, float, int, float], None] | None = None,
        realtime: bool = False,
        stop: Callable[[], bool] | None = None,
        before: Callable[[int], None] | None = None,
    ) -> RunSummary:
        """Run for ``seconds`` of simulated time, calling ``on_frame`` on the initial and every later frame.

        Frames lie on a fixed grid: frame ``k`` ends after ``k * steps_per_frame`` steps counted from the
        start of the scene; the schedule and gusts act on the step grid, ``before``'s controls at frame starts (see
        :meth:`advance`). A run
        that ends between two grid points emits a last, shorter frame with the next index; a run continued
        from there (after :meth:`restore`) first completes that frame and emits it again under the same index,
        so a run cut in two and continued gives the same frames, bit for bit, as one run. When continuing, the
        current state is not passed to ``on_frame`` again.

        ``on_progress(t, seconds, steps, wall)`` is called at most about 5 times per wall second.
        ``stop()`` is asked before every frame (the CLI's answers True after SIGINT/SIGTERM); True, or a
        ``KeyboardInterrupt``, ends the run there and the summary says ``interrupted``.

        Every frame is checked (:meth:`blowup`) before ``on_frame`` sees it. A bad frame is not passed on:
        the state goes back to the last good frame and :class:`BlowUpError` is raised.
        """
        pace = _Pace(self.dt, realtime, on_progress, seconds)
        start = self.steps_taken
        end = start + int(round(seconds / self.dt))  # as frames() counts
        worst, interrupted = 0.0, False
        frames = self.frames(seconds, before)
        try:
            for frame in frames:
                worst = max(worst, frame.worst_stretch)
                if frame.steps == start:  # the current state: passed on only at the scene's start
                    if on_frame and start == 0:
                        on_frame(frame)
                else:
                    if on_frame:
                        on_frame(frame)
                    pace.after_frame(self.state.time, self.steps_taken - start)
                del frame
                if stop is not None and stop():
                    interrupted = self.steps_taken < end
                    break
        except BlowUpError as err:
            if err.summary is None:  # a frame stepped here (not the state the run started from) was bad
                err.summary = self._summary(self._good.steps - start, worst, pace, blew_up=True)
            raise
        except KeyboardInterrupt:
            interrupted = True
        finally:
            frames.close()
        wp.synchronize_device(self.model.device)
        return self._summary(self.steps_taken - start, worst, pace, interrupted=interrupted)

    def fly(self, seconds: float | None = None, **run) -> Flight:
        """Run for ``seconds`` of simulated time (default: the scene's ``scene.seconds``) as ``warpsim run`` does
        and return its :class:`~warpsim.run.figures.Flight`: the summary and each object's closing figures over
        the run's second half (the sweeps' window), the numbers and the lines the command prints. ``run``: the
        other arguments of :meth:`run`; an ``on_frame`` of yours sees each frame after the figures do. Raises
        :class:`BlowUpError` as :meth:`run` does."""
        seconds = self.settings.scene.seconds if seconds is None else float(seconds)
        start = self.state.time
        figures = FlightFigures(self, start + 0.5 * seconds, start + seconds)
        theirs = run.pop("on_frame", None)

        def on_frame(frame: Frame) -> None:
            figures(frame)
            if theirs is not None:
                theirs(frame)

        return Flight(self.run(seconds, on_frame=on_frame, **run), figures)

    def _summary(self, steps: int, worst: float, pace: _Pace, **flags) -> RunSummary:
        """The :class:`RunSummary` of ``steps`` steps whose worst stretch was ``worst``."""
        return RunSummary(
            steps * self.dt,
            steps,
            pace.wall(),
            worst,
            startup_time=self.startup_time,
            ground_contacts=self.contacts.by_time(),
            **flags,
        )


def _nothing() -> None:
    """A dead weak reference: no frame handed out."""
    return None


def _check_altitudes(model, elevation: float, where: str) -> None:
    """``DescriptorError`` (one line) when an object starts, or the terrain lies, outside the standard atmosphere
    (``elevation`` [m]: the altitude of z = 0)."""
    z = np.asarray(model.particle_q0, dtype=np.float64)[:, 2]
    heights = model.terrain.heights
    for what, value in (
        ("the lowest particle", z.min()),
        ("the highest particle", z.max()),
        ("the terrain's lowest point", float(np.min(heights))),
        ("the terrain's highest point", float(np.max(heights))),
    ):
        try:
            atmosphere.check_altitude(float(value) + elevation, what)
        except ValueError as err:
            raise DescriptorError(f"{where}: [air] elevation = {elevation:g} m: {err}") from None
