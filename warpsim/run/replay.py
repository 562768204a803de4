"""A recorded flight flown again: the controls of each recorded frame set before that frame is stepped."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .simulation import Simulation


class RecordedControls:
    """The controls of a recorded flight, set again frame by frame: pass it as ``before`` to
    :meth:`Simulation.run` or :meth:`Simulation.advance` of a simulation of the recording's descriptor, and the
    run repeats the recorded frames bit for bit (what ``warpsim run --replay`` does).

    Args:
        sim: the simulation to drive. controls: per frame index, the controls in force while that frame was
            stepped (:meth:`warpsim.io.recording.Recording.controls`); frames past the end keep the last ones.
    """

    def __init__(self, sim: Simulation, controls: list[dict]):
        self.sim, self.controls = sim, controls

    def __call__(self, index: int) -> None:
        """Set, before frame ``index`` is stepped, the recorded controls that differ from those in force."""
        if not self.controls:
            return
        values = self.controls[min(index, len(self.controls) - 1)]
        changed = {name: value for name, value in values.items() if self.sim.controls.get(name) != value}
        if changed:
            self.sim.set_controls(**changed)
