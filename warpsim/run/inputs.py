"""The inputs of a running scene: the controls in force, the descriptor's schedule and every world's gusts, all on
the solver's step grid.

:class:`Inputs` turns ``set(pitch=0.5)`` calls (from a script, the schedule or, later, a keyboard) into the
:class:`~warpsim.physics.model.Control` arrays the kernels read, through each object's ``apply_controls``
(:mod:`warpsim.objects.registry`), and saves and restores itself in a :class:`~warpsim.run.checkpoint.Checkpoint`.
"""

from __future__ import annotations

import numpy as np

from ..objects import registry
from ..physics.config import WindConfig
from ..physics.model import Control, Gusts, Model, Turbulence
from ..scene.controls import ControlSchedule, check_value
from .checkpoint import pack_controls, unpack_controls


def control_names(model: Model) -> tuple[str, ...]:
    """Names of the controls a model's scene accepts (its objects' and ``wind``)."""
    return registry.control_names(record.kind for record in model.objects)


SCHEDULE_INTERVAL = 0.02
"""How often [s] of simulated time a ramped schedule entry moves its controls (between its entries' own times, at
which a schedule always acts); the object's own ramps (``solver.control_rate``) smooth the steps between."""


class Inputs:
    """Controls, schedule and gusts of one scene, written into its ``control`` arrays.

    The schedule acts on the solver's step grid, never on the output frames': an entry takes effect at the first
    step at or after its time, and a ramp moves every :data:`SCHEDULE_INTERVAL`. The gusts advance with every step
    (:class:`~warpsim.physics.model.Gusts`). So a flight is the same whatever its frame rate.

    Args:
        model: the scene's model. control: its :class:`~warpsim.physics.model.Control` (written in place; its
            ``gusts`` are started here where some world has ``gust_intensity > 0``).
        winds: the :class:`~warpsim.physics.config.WindConfig` of every world (their velocity is set now).
        schedule: the descriptor's :class:`~warpsim.scene.controls.ControlSchedule` (may be empty).
        dt: the solver's step [s] (the grid the schedule acts on).
    """

    def __init__(self, model: Model, control: Control, winds: list[WindConfig], schedule: ControlSchedule, dt: float):
        self.model = model
        self.control = control
        self.names = control_names(model)
        self.schedule = schedule
        self.dt = float(dt)
        control.gusts = Gusts.start(winds, model.device)
        control.turbulence = Turbulence.start(winds, model.device)
        control.set_wind(np.array([w.velocity for w in winds]))
        self.in_force: dict = {}  # every control set so far, by name
        self.scheduled: dict = {}  # the schedule's last values, so that held values are not set again
        self.version = 0  # counts the changes to the controls and control arrays (what a save must follow)
        times = schedule.change_times(SCHEDULE_INTERVAL) if schedule else np.zeros(0)
        self.change_steps = np.unique(np.ceil(np.asarray(times) / self.dt - 1e-6).astype(np.int64))
        """The steps at which the schedule changes something (sorted)."""
        self._changes = set(self.change_steps.tolist())

    def set(self, **values) -> None:
        """Set controls (see :meth:`warpsim.run.simulation.Simulation.set_controls`); ``ValueError`` for a control this
        scene does not have or a value out of range."""
        for name, value in values.items():
            if name not in self.names:
                raise ValueError(f"this scene has no control {name!r}; its controls are: {', '.join(self.names)}")
            values[name] = check_value(name, value)
        self.version += 1
        if "wind" in values:
            self.control.set_wind(values["wind"])
            if self.control.gusts is not None:  # the mean the gusts blow around
                mean = np.tile(np.asarray(values["wind"], dtype=np.float32), (self.control.wind.shape[0], 1))
                self.control.gusts.mean.assign(mean)
        self.in_force.update(values)
        if set(values) <= {"wind"}:
            return
        object_values = {k: v for k, v in self.in_force.items() if k != "wind"}
        c = self.control  # controls set where the ramps go (SolverConfig.control_rate, nail_rate)
        rest = c.stick_rest if c.stick_rest_target is None else c.stick_rest_target
        nails = c.nail_target if c.nail_target_goal is None else c.nail_target_goal
        targets = {
            "stick_rest": rest.numpy().copy(),
            "nail_target": nails.numpy().copy(),
            "terrain": self.model.terrain,
        }
        for record in self.model.objects:
            spec = registry.OBJECTS[record.kind]
            if spec.apply_controls is not None:
                spec.apply_controls(record, targets, object_values)
        rest.assign(targets["stick_rest"])
        nails.assign(targets["nail_target"])

    def apply_schedule(self, step: int) -> None:
        """At a solver step where the schedule changes something, apply it as it stands then (time
        ``step * dt``): the controls whose scheduled value differs from the last one it set (scheduled controls act
        on every world). At any other step nothing is done: a ramp moves on its own grid, not at frame starts."""
        if step not in self._changes:
            return
        values = self.schedule.at((step + 1e-6) * self.dt)  # the same margin as the change steps
        changed = {k: v for k, v in values.items() if self.scheduled.get(k) != v}
        if changed:
            self.set(**changed)
            self.scheduled.update(changed)

    def next_change(self, step: int) -> int | None:
        """The first step after ``step`` at which the schedule changes something, or None."""
        k = int(np.searchsorted(self.change_steps, step, side="right"))
        return int(self.change_steps[k]) if k < len(self.change_steps) else None

    def save(self) -> dict[str, np.ndarray]:
        """The checkpoint fields of the inputs (gusts and controls; see :class:`~warpsim.run.checkpoint.Checkpoint`)."""
        worlds = self.control.wind.shape[0]
        gusts = self.control.gusts
        out = {
            "gust_active": np.zeros(worlds, dtype=np.uint8),
            "gust_g": np.zeros((worlds, 3), dtype=np.float64),
            "gust_mean": np.zeros((worlds, 3), dtype=np.float32),
            "gust_step": np.zeros(worlds, dtype=np.int32),
            "turbulence_shift": self.control.turbulence.data.shift.numpy().astype(np.float64),
        }
        if gusts is not None:
            out["gust_active"][:] = gusts.intensity.numpy() > 0.0
            out["gust_g"][:] = gusts.g.numpy()
            out["gust_mean"][:] = gusts.mean.numpy()
            out["gust_step"][:] = gusts.step.numpy()
        out["control_set"], out["control_value"] = pack_controls(self.names, self.in_force)
        out["scheduled_set"], out["scheduled_value"] = pack_controls(self.names, self.scheduled)
        return out

    def load(self, checkpoint) -> None:
        """Continue from the inputs saved in ``checkpoint`` (its control arrays are restored by the caller)."""
        self.version += 1
        gusts = self.control.gusts
        if gusts is not None:
            gusts.g.assign(checkpoint.gust_g)
            gusts.mean.assign(checkpoint.gust_mean)
            gusts.step.assign(checkpoint.gust_step)
        self.control.turbulence.data.shift.assign(checkpoint.turbulence_shift)
        names = checkpoint.control_names
        self.in_force = unpack_controls(names, checkpoint.control_set, checkpoint.control_value)
        self.scheduled = unpack_controls(names, checkpoint.scheduled_set, checkpoint.scheduled_value)
