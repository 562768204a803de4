"""Opening a run's outputs, each in one place: the HDF5 recording (:func:`open_recording`, what ``warpsim run``,
the viewer and the sweeps' chunks all call), the USD stage (:func:`open_stage`) and a picture of the last frame
(:func:`open_picture`); every one is an :class:`~warpsim.io.protocol.Output`."""

from __future__ import annotations

from pathlib import Path


def open_recording(
    path,
    sim,
    descriptor_text: str = "",
    scene: str = "",
    *,
    descriptor: dict | None = None,
    resume: bool = False,
    lock=None,
):
    """The :class:`~warpsim.io.hdf5.H5Recorder` of ``sim``'s run (a :class:`~warpsim.run.simulation.Simulation`):
    its model, its checkpoints, ``descriptor`` (default: the simulation's), the descriptor's TOML text and where
    the scene came from; ``resume`` appends to the recording at ``path`` (``lock``: its writer's lock, when the
    caller took it already). Raises :class:`~warpsim.io.hdf5.RecordingError` or
    :class:`~warpsim.io.OutputWriteError` as the recorder does."""
    from .hdf5 import H5Recorder

    return H5Recorder(
        path,
        sim.model,
        sim.descriptor if descriptor is None else descriptor,
        sim.checkpoint,
        descriptor_text,
        scene,
        resume=resume,
        lock=lock,
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

    return PictureOutput(path, sim.model, sim.descriptor["scene"]["object"], size, azimuth, elevation)
