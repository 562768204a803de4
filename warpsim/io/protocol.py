"""The one interface every output of a run implements (after Newton's viewer protocol): an output is opened with
the run's :class:`~warpsim.physics.model.Model` (its constructor, or :mod:`warpsim.io.outputs`), then takes each
frame as ``begin_frame(time)``, ``log_state(frame)``, ``end_frame()``, and is finished by ``close()``.

The HDF5 recorder, the USD stage and the picture implement it; ``warpsim run``, the viewer and the sweeps' chunks
write frames through :func:`write_frame` and nothing else.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable


@runtime_checkable
class Output(Protocol):
    """An output of a run. ``frame`` is a :class:`warpsim.run.diagnostics.Frame` (time [s], positions [m],
    velocities, wind, stretch; copied from the device only when first read). A failed write raises
    :class:`warpsim.io.OutputWriteError` naming what the output keeps."""

    def begin_frame(self, time: float) -> None:
        """A frame at simulated ``time`` [s] begins."""

    def log_state(self, frame) -> None:
        """Take the frame's state."""

    def end_frame(self) -> None:
        """The frame is complete."""

    def close(self):
        """Finish the output (safe to call twice)."""


class FrameOutput:
    """Base of the outputs that take a whole frame at once in :meth:`log_state`: the frame's beginning and end need
    nothing of them."""

    def begin_frame(self, time: float) -> None:
        """Nothing to do: the frame comes whole to :meth:`log_state`."""

    def log_state(self, frame) -> None:
        raise NotImplementedError

    def end_frame(self) -> None:
        """Nothing to do: :meth:`log_state` wrote the frame."""


def write_frame(output: Output, frame) -> None:
    """Hand ``frame`` to ``output``: ``begin_frame``, ``log_state``, ``end_frame``."""
    output.begin_frame(frame.time)
    output.log_state(frame)
    output.end_frame()
