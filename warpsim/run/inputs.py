"""The inputs of a running scene: the controls in force, the descriptor's schedule and every world's gusts.

:class:`Inputs` turns ``set(pitch=0.5)`` calls (from a script, the schedule or, later, a keyboard) into the
:class:`~warpsim.physics.model.Control` arrays the kernels read, through each object's ``apply_controls``
(:mod:`warpsim.objects.registry`), and saves and restores itself in a :class:`~warpsim.run.checkpoint.Checkpoint`.
"""

from __future__ import annotations

import numpy as np

from ..objects import registry
from ..physics.config import WindConfig
from ..physics.model import Control, Model
from ..scene.controls import ControlSchedule, Gusts, check_value
from .checkpoint import pack_controls, pack_rng, unpack_controls, unpack_rng


def control_names(model: Model) -> tuple[str, ...]:
    """Names of the controls a model's scene accepts (its objects' and ``wind``)."""
    return registry.control_names(record.kind for record in model.objects)


class Inputs:
    """Controls, schedule and gusts of one scene, written into its ``control`` arrays.

    Args:
        model: the scene's model. control: its :class:`~warpsim.physics.model.Control` (written in place).
        winds: the :class:`~warpsim.physics.config.WindConfig` of every world (their velocity is set now; gusts start
            where ``gust_intensity > 0``).
        schedule: the descriptor's :class:`~warpsim.scene.controls.ControlSchedule` (may be empty).
    """

    def __init__(self, model: Model, control: Control, winds: list[WindConfig], schedule: ControlSchedule):
        self.model = model
        self.control = control
        self.names = control_names(model)
        self.schedule = schedule
        # per world: the gusts blowing there (None = steady wind)
        self.gusts: list[Gusts | None] = [
            Gusts(w.velocity, w.gust_intensity, w.gust_period, w.gust_seed) if w.gust_intensity > 0.0 else None
            for w in winds
        ]
        control.set_wind(np.array([w.velocity for w in winds]))
        self.in_force: dict = {}  # every control set so far, by name
        self.scheduled: dict = {}  # the schedule's last values, so that held values are not set again
        self.version = 0  # counts the changes to the controls, gusts and control arrays (what a save must follow)

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
            for gusts in self.gusts:
                if gusts is not None:
                    gusts.mean = np.asarray(values["wind"], dtype=np.float64)
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

    def frame_start(self, time: float, interval: float) -> None:
        """Apply the schedule at ``time`` [s] and advance the gusts by ``interval`` [s] (one frame).

        With gusts, a scheduled ``wind`` sets the mean the gusts blow around. Scheduled controls act on every
        world.
        """
        values = self.schedule.at(time + 1e-9) if self.schedule else {}
        if any(g is not None for g in self.gusts):
            if "wind" in values:
                mean = tuple(float(v) for v in values.pop("wind"))
                if self.scheduled.get("wind") != mean:
                    self.set(wind=mean)
                    self.scheduled["wind"] = mean
            self.version += 1
            winds = self.control.wind.numpy().copy()
            for k, gusts in enumerate(self.gusts):
                if gusts is not None:
                    winds[k] = gusts.advance(interval)
            self.control.set_wind(winds)
        changed = {k: v for k, v in values.items() if self.scheduled.get(k) != v}
        if changed:
            self.set(**changed)
            self.scheduled.update(changed)

    def save(self) -> dict[str, np.ndarray]:
        """The checkpoint fields of the inputs (gusts and controls; see :class:`~warpsim.run.checkpoint.Checkpoint`)."""
        worlds = len(self.gusts)
        out = {
            "gust_active": np.zeros(worlds, dtype=np.uint8),
            "gust_g": np.zeros((worlds, 3), dtype=np.float64),
            "gust_mean": np.zeros((worlds, 3), dtype=np.float64),
            "gust_rng": np.zeros((worlds, 6), dtype=np.uint64),
        }
        for k, gusts in enumerate(self.gusts):
            if gusts is not None:
                out["gust_active"][k] = 1
                out["gust_g"][k], out["gust_mean"][k] = gusts.g, gusts.mean
                out["gust_rng"][k] = pack_rng(gusts.rng.bit_generator.state)
        out["control_set"], out["control_value"] = pack_controls(self.names, self.in_force)
        out["scheduled_set"], out["scheduled_value"] = pack_controls(self.names, self.scheduled)
        return out

    def load(self, checkpoint) -> None:
        """Continue from the inputs saved in ``checkpoint`` (its control arrays are restored by the caller)."""
        self.version += 1
        for k, gusts in enumerate(self.gusts):
            if gusts is not None and checkpoint.gust_active[k]:
                gusts.g = checkpoint.gust_g[k].copy()
                gusts.mean = checkpoint.gust_mean[k].copy()
                gusts.rng.bit_generator.state = unpack_rng(checkpoint.gust_rng[k])
        names = checkpoint.control_names
        self.in_force = unpack_controls(names, checkpoint.control_set, checkpoint.control_value)
        self.scheduled = unpack_controls(names, checkpoint.scheduled_set, checkpoint.scheduled_value)
