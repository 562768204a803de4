"""Opening a run's outputs, each in one place: the HDF5 recording (:func:`open_recording`, what ``warpsim run``,
the viewer and the sweeps' chunks all call), the USD stage (:func:`open_stage`) and a picture of the last frame
(:func:`open_picture`); every one is an :class:`~warpsim.io.protocol.Output`.

:data:`OUTPUTS` is the table ``warpsim run`` offers them from: each kind's flag, help, path check and opener. A new
format is its module (an ``Output``) and one line there.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path


def open_recording(path, sim, where: str = "", *, scene=None, resume: bool = False, lock=None):
    """The :class:`~warpsim.io.hdf5.H5Recorder` of ``sim``'s run (a :class:`~warpsim.run.simulation.Simulation`):
    its model, its checkpoints, ``scene`` (a :class:`~warpsim.scene.scene.Scene`, default: the simulation's) and
    where the scene came from; ``resume`` appends to the recording at ``path`` (``lock``: its writer's lock, when the
    caller took it already). Raises :class:`~warpsim.io.hdf5.RecordingError` or
    :class:`~warpsim.io.OutputWriteError` as the recorder does."""
    from .hdf5 import H5Recorder

    return H5Recorder(
        path, sim.model, sim.scene if scene is None else scene, sim.checkpoint, where, resume=resume, lock=lock
    )


def open_stage(path, sim):
    """The :class:`~warpsim.io.usd.UsdWriter` of ``sim``'s run: one time sample per frame interval
    (``steps_per_frame * dt`` [s]); written when it closes."""
    from .usd import UsdWriter  # USD loads here, only for a run that writes a stage

    return UsdWriter(path, sim.model, sim.steps_per_frame * sim.dt)


def open_picture(path: str | Path, sim, size: tuple[int, int] = (960, 540), azimuth=-60.0, elevation=20.0):
    """A :class:`~warpsim.io.picture.PictureOutput` of ``sim``'s run: its last frame drawn to the PNG ``path``
    when it closes (``size`` [pixels], view ``azimuth`` and ``elevation`` [deg], as ``warpsim render``)."""
    from .picture import PictureOutput

    return PictureOutput(path, sim.model, sim.scene.kind, size, azimuth, elevation)


@dataclass(frozen=True)
class RunOutputs:
    """What an output of a ``warpsim run`` opens with besides its path and the simulation: the run's
    :class:`~warpsim.scene.scene.Scene` and where it came from (empty when resumed: the recording has it), whether
    the run continues a recording (``resume``) and the writer's lock of the recording, when the command took it."""

    scene: object
    where: str = ""
    resume: bool = False
    lock: object = None


@dataclass(frozen=True)
class OutputKind:
    """One kind of output ``warpsim run`` writes frame by frame.

    Attributes:
        flag: the command-line option (``--usd``); its value is the path. metavar, help: its ``--help``.
        label: what the run's last lines call it (``USD stage``).
        check: ``check(path) -> Path``, raising :class:`~warpsim.io.OutputPathError` for a path it cannot write
            (asked before the run starts, so that a bad name costs nothing).
        open: ``open(path, sim, run: RunOutputs) -> Output``, after the simulation is built.
    """

    flag: str
    metavar: str
    help: str
    label: str
    check: Callable[[str], Path]
    open: Callable[[Path, object, RunOutputs], object]

    @property
    def dest(self) -> str:
        """The attribute argparse keeps the value in (``--h5`` -> ``h5``)."""
        return self.flag.removeprefix("--").replace("-", "_")


def _check_recording(path) -> Path:
    from .hdf5 import check_recording_path

    return check_recording_path(path)


def _check_stage(path) -> Path:
    from . import check_stage_path

    return check_stage_path(path)


def _check_picture(path) -> Path:
    from . import OutputPathError
    from .render import check_picture_path, require_pillow

    checked = check_picture_path(path)
    if checked.suffix.lower() != ".png":
        raise OutputPathError(
            f"{path}: a picture of the last frame is a .png (an animation: record with --h5 REC.h5, then "
            "warpsim render REC.h5 OUT.gif)"
        )
    try:
        require_pillow()
    except RuntimeError as err:  # the [render] extra is not installed: one line before the run, not after it
        raise OutputPathError(str(err)) from None
    return checked


def _open_recording(path, sim, run: RunOutputs):
    return open_recording(path, sim, run.where, scene=run.scene, resume=run.resume, lock=run.lock)


OUTPUTS: tuple[OutputKind, ...] = (
    OutputKind(
        "--h5",
        "OUT.h5",
        "stream a recording (positions, diagnostics, topology, descriptor) frame by frame; "
        "an interrupted run keeps every completed frame",
        "recording",
        _check_recording,
        _open_recording,
    ),
    OutputKind(
        "--usd",
        "OUT",
        "write an animated USD stage (.usda text, .usdc binary, .usdz package), one time sample per frame; "
        "written when the run ends, also on Ctrl-C",
        "USD stage",
        _check_stage,
        lambda path, sim, run: open_stage(path, sim),
    ),
    OutputKind(
        "--png",
        "OUT.png",
        "draw the run's last frame to a PNG when it ends, as warpsim render draws a recording's",
        "picture",
        _check_picture,
        lambda path, sim, run: open_picture(path, sim),
    ),
)
"""The outputs ``warpsim run`` offers, in the order they are opened (the recording first: it holds the lock)."""
