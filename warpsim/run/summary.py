"""What a run reports: its summary (:class:`RunSummary`), the error that ends a run that blew up
(:class:`BlowUpError`), the wall-clock pacing of a real-time run, and the cores a run may use."""

from __future__ import annotations

import os
import time
from dataclasses import dataclass


def available_cores() -> int:
    """The CPU cores this process may run on (``os.sched_getaffinity``; ``os.cpu_count`` where there is none):
    the default number of threads of the command line."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


class BlowUpError(RuntimeError):
    """The simulation blew up: a position or velocity became NaN/Inf, or a stick stretched past
    ``solver.max_stretch``. Raised by :meth:`Simulation.run` after the state has been put back to the
    last good frame (so a recorder closed afterwards checkpoints that frame).

    Attributes:
        step: the solver step count at the bad frame. time: its simulated time [s].
        object: the name of the object where it happened. reason: what was seen.
        last_good_frame: index of the last good frame; last_good_time: its time [s].
        summary: the :class:`RunSummary` of the run up to the last good frame (None when raised by
            :meth:`Simulation.advance`, which does not know where a run started).
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
        wall = f"wall {self.wall_time:.2f} s (+ {self.startup_time:.2f} s start-up: model and kernels)"
        if self.blew_up:  # the steps kept end at the last good frame, before the step that blew up; no rate
            text = (
                f"blew up: kept {self.simulated_time:.3f} s ({self.steps} steps) up to the last good frame, {wall}\n"
                f"  worst stick stretch {100 * self.worst_stretch:.3f}% over the frames kept"
            )
        else:
            status = "interrupted" if self.interrupted else "done"
            text = (
                f"{status}: simulated {self.simulated_time:.3f} s in {self.steps} steps, {wall}\n"
                f"  {self.steps_per_second:,.0f} steps/s, real-time factor {self.realtime_factor:.1f}x, "
                f"worst stick stretch {100 * self.worst_stretch:.3f}%"
            )
        contacts = self.ground_contacts
        if 0 < len(contacts) <= 3:
            text += "".join(f"\n  {name} touched the terrain at t = {t:.2f} s" for name, t in contacts)
        elif contacts:
            name, t = contacts[0]
            text += f"\n  {len(contacts)} objects touched the terrain, the first ({name}) at t = {t:.2f} s"
        return text


class _Pace:
    """Real-time pacing and progress reports of a run that started at wall time ``start`` [s]."""

    def __init__(self, dt: float, realtime: bool, on_progress, seconds: float):
        self.dt, self.realtime, self.on_progress, self.seconds = dt, realtime, on_progress, seconds
        self.start = self.last_report = time.perf_counter()

    def after_frame(self, t: float, steps: int) -> None:
        """Sleep until wall time catches up with ``steps`` simulated steps (``realtime``), and report progress at
        most about 5 times per wall second."""
        now = time.perf_counter()
        if self.realtime:
            ahead = steps * self.dt - (now - self.start)
            if ahead > 0:
                time.sleep(ahead)
        if self.on_progress and now - self.last_report > 0.2:
            self.on_progress(t, self.seconds, steps, now - self.start)
            self.last_report = now

    def wall(self) -> float:
        """Wall seconds since the start [s]."""
        return time.perf_counter() - self.start
