"""Control schedules and wind gusts: what changes the inputs of a running scene over time.

A descriptor may hold ``[[controls]]`` entries, each a time and any of the object's controls::

    [[controls]]
    time = 2.0           # [s]
    pitch = 0.8          # hang glider, in [-1, 1]
    ramp = true          # reach this value linearly from the previous entry (default false: jump at time)

    [[controls]]
    time = 5.0
    anchor = [20.0, 0.0] # kite: ground end of the rope, (x, y) [m]; z follows the terrain
    wind = [8.0, 0.0, 0.0]

Each control keeps its last value until an entry changes it. ``ramp = true`` on an entry makes every
control it names move linearly from its value at the previous entry naming it, so that it arrives at
``time``; otherwise the value jumps at ``time``. The runner applies the schedule on the solver's step grid: an
entry at the first step at or after its time, a ramp every ``warpsim.run.inputs.SCHEDULE_INTERVAL`` (never at
output frames, so the frame rate does not change a flight).

Gusts (``[wind] gust_intensity > 0``) are stepped with the solver: see :class:`warpsim.physics.model.Gusts`.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

import numpy as np

UNIT_CONTROLS = ("pitch", "roll")
"""Controls whose values are dimensionless numbers in [-1, 1]."""

VECTOR_CONTROLS = {"anchor": 2, "wind": 3}
"""Controls whose values are vectors: name -> number of components ([m] for anchor, [m/s] for wind)."""

VECTOR_LIMITS = {"anchor": 1e7, "wind": 200.0}
"""Largest allowed magnitude of each component: [m] (the largest terrain), [m/s] (twice the strongest gusts
measured on Earth); beyond them a run could only blow up."""


class ControlError(ValueError):
    """A control value or schedule entry is invalid; the message names the entry and key."""


def check_value(name: str, value, where: str = "control"):
    """Validate one control value; returns a float (unit controls) or a tuple of floats (vectors)."""
    if name in UNIT_CONTROLS:
        if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
            raise ControlError(f"{where}: {name} must be a number in [-1, 1], got {value!r}")
        value = float(value)
        if not -1.0 <= value <= 1.0:  # also refuses NaN
            raise ControlError(f"{where}: {name} = {value!r} must be in [-1, 1]")
        return value
    if name in VECTOR_CONTROLS:
        size = VECTOR_CONTROLS[name]
        try:
            vector = tuple(float(v) for v in value)
        except (TypeError, ValueError):
            raise ControlError(f"{where}: {name} must be a list of {size} numbers, got {value!r}") from None
        if len(vector) != size or any(isinstance(v, bool) for v in value):
            raise ControlError(f"{where}: {name} must be a list of {size} numbers, got {value!r}")
        if not all(math.isfinite(v) for v in vector):
            raise ControlError(f"{where}: {name} must hold finite numbers, got {value!r}")
        limit = VECTOR_LIMITS[name]
        if any(abs(v) > limit for v in vector):
            raise ControlError(f"{where}: {name} components must be within +-{limit:g}, got {value!r}")
        return vector
    raise ControlError(f"{where}: unknown control {name!r}")


@dataclass(frozen=True)
class Keyframe:
    """One ``[[controls]]`` entry: at ``time`` [s] the controls take ``values``; ``ramp`` = reached linearly."""

    time: float
    values: dict
    ramp: bool = False


class ControlSchedule:
    """Time-ordered keyframes; :meth:`at` gives the control values at a time.

    Args:
        entries: ``[[controls]]`` tables (``time``, ``ramp`` and control values).
        allowed: control names the scene accepts (the object's own plus ``wind``).
        where: origin for error messages (the descriptor file).
    """

    def __init__(self, entries: list[dict], allowed: tuple[str, ...], where: str = "scene"):
        frames = []
        for k, entry in enumerate(entries):
            label = f"{where}: [[controls]] entry {k + 1}"
            if not isinstance(entry, dict):
                raise ControlError(f"{label} must be a table, got {entry!r}")
            if "time" not in entry:
                raise ControlError(f"{label} needs a time (seconds)")
            t = entry["time"]
            if isinstance(t, bool) or not isinstance(t, (int, float)) or not math.isfinite(t) or t < 0:
                raise ControlError(f"{label}: time must be a number of seconds >= 0, got {t!r}")
            ramp = entry.get("ramp", False)
            if not isinstance(ramp, bool):
                raise ControlError(f"{label}: ramp must be true or false, got {ramp!r}")
            values = {}
            for name, value in entry.items():
                if name in ("time", "ramp"):
                    continue
                if name not in allowed:
                    raise ControlError(
                        f"{label}: unknown control {name!r}; this scene's controls are {', '.join(allowed)}"
                    )
                values[name] = check_value(name, value, f"{label}")
            if not values:
                raise ControlError(f"{label} sets no control; give one of {', '.join(allowed)}")
            frames.append(Keyframe(float(t), values, ramp))
        times = [f.time for f in frames]
        if times != sorted(times):
            raise ControlError(f"{where}: [[controls]] entries must be in time order, got times {times}")
        self.keyframes = frames
        self._by_name: dict[str, list[Keyframe]] = {}
        for f in frames:
            for name in f.values:
                self._by_name.setdefault(name, []).append(f)

    def __bool__(self) -> bool:
        return bool(self.keyframes)

    def change_times(self, interval: float) -> np.ndarray:
        """The times [s] at which :meth:`at` may change: every entry's time, and every ``interval`` [s] from the
        start of a ramp to its end (sorted, possibly repeated)."""
        times = [f.time for f in self.keyframes]
        for frames in self._by_name.values():
            for a, b in zip(frames, frames[1:], strict=False):
                if b.ramp and b.time > a.time:
                    times.extend(np.arange(a.time, b.time, interval).tolist())
        return np.sort(np.asarray(times, dtype=np.float64))

    def at(self, t: float) -> dict:
        """Control values at time ``t`` [s]; controls no entry has set yet are absent."""
        out = {}
        for name, frames in self._by_name.items():
            k = bisect.bisect_right([f.time for f in frames], t)  # frames[:k] are at or before t
            if k == 0:
                continue
            a = frames[k - 1]
            if k < len(frames) and frames[k].ramp:
                b = frames[k]
                out[name] = _lerp(a.values[name], b.values[name], (t - a.time) / (b.time - a.time))
            else:
                out[name] = a.values[name]
        return out


def _lerp(a, b, s: float):
    if isinstance(a, tuple):
        return tuple(x + (y - x) * s for x, y in zip(a, b, strict=True))
    return a + (b - a) * s
