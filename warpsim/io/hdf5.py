"""Streaming HDF5 recordings: one frame appended at a time, readable while written, resumable.

Layout (``F`` frames, ``N`` particles, ``M`` sticks, ``T`` triangles, ``O`` objects; SI units)::

    /time                        [F]        float64  simulated time of each frame [s]
    /positions                   [F, N, 3]  float32  particle positions [m] (chunk = 1 frame, gzip)
    /diagnostics/worst_stretch   [F]        float32  largest |l - r| / r over all sticks
    /diagnostics/kinetic_energy  [F]        float64  kinetic energy of the free particles [J]
    /diagnostics/centre          [F, O, 3]  float32  mass centre of each object [m]
    /diagnostics/altitude        [F, O]     float32  height of that centre above the terrain [m]
    /diagnostics/airspeed        [F, O]     float32  |mean velocity - wind| of each object [m/s]
    /topology/sticks             [M, 2]     int32    particle indices of each stick
    /topology/stick_rest         [M]        float32  built rest lengths [m]
    /topology/triangles          [T, 3]     int32    particle indices of each air-force triangle
    /topology/particle_mass      [N]        float64  [kg] (inf = nailed)
    /topology/particle_object    [N]        int32    object of each particle (index into attr ``objects``)
    /topology/particle_part      [N]        int32    part of each particle (index into attr ``parts``; -1 none)
    /topology/triangle_part      [T]        int32    part of each triangle (index into attr ``parts``)
    /checkpoint/...                                  the state after the last frame, for ``--resume``

Root attributes: ``format`` (``warpsim-recording``), ``format_version``, ``descriptor`` (the full scene
descriptor as TOML), ``scene`` (where it came from), ``solver`` (JSON), ``warpsim_version``,
``warp_version``, ``dt`` [s], ``steps_per_frame``, ``frame_interval`` [s]; on ``/topology``:
``objects`` and ``parts`` (names, parts as ``object/part``).

The file is written in HDF5's single-writer/multiple-reader (SWMR) mode: another process can open it
while it grows. Frames are flushed, with a checkpoint of the state after the last of them, every
``H5Recorder.sync_interval`` (0.5) wall seconds and when the recorder closes, which the CLI does on
Ctrl-C and SIGTERM: an interrupted run keeps every completed frame, and a killed one (SIGKILL, power
loss) keeps those of the last sync. On resume, frames after the checkpoint's are dropped and redone.
"""

from __future__ import annotations

import contextlib
import json
import signal
import time
from pathlib import Path

import h5py
import numpy as np

from . import check_output_path

EXTENSIONS = (".h5", ".hdf5")
FORMAT = "warpsim-recording"
FORMAT_VERSION = 1
_TEXT_BYTES = 4096  # checkpoint texts (JSON) are stored zero-padded in fixed-size byte datasets (SWMR-safe)
# the parts of :meth:`warpsim.runner.Simulation.checkpoint`, by how they are stored
_CHECKPOINT_ARRAYS = ("q", "q_prev", "stick_rest", "nail_target", "wind")
_CHECKPOINT_SCALARS = ("time", "steps")
_CHECKPOINT_TEXTS = ("gusts", "controls")


@contextlib.contextmanager
def signals_held():
    """Hold SIGINT/SIGTERM inside the block (they are delivered right after it), so that an interrupted run
    never leaves a frame half-written: without its checkpoint, or in one output and not the other."""
    held = {signal.SIGINT, signal.SIGTERM}
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, held)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


class RecordingError(ValueError):
    """The file is not a warpsim recording, or cannot be continued."""


def check_recording_path(path) -> Path:
    """Check that ``path`` is an HDF5 file name in an existing directory (raises ``OutputPathError``)."""
    return check_output_path(path, EXTENSIONS, "HDF5")


def _names(sim) -> tuple[list[str], list[str], np.ndarray, np.ndarray, np.ndarray]:
    """Object names, part names (``object/part``), part of each particle, of each triangle, object of each particle."""
    model = sim.model
    objects, parts = [], []
    particle_part = np.full(model.particle_count, -1, dtype=np.int32)
    particle_object = np.full(model.particle_count, -1, dtype=np.int32)
    triangle_part = np.full(model.tri_count, -1, dtype=np.int32)
    for k, record in enumerate(model.objects):
        objects.append(record.name)
        particle_object[record.particles] = k
        for part, ids in record.parts.items():
            parts.append(f"{record.name}/{part}")
            particle_part[ids] = len(parts) - 1
        for part, ids in record.tri_parts.items():
            name = f"{record.name}/{part}"
            if name not in parts:
                parts.append(name)
            triangle_part[ids] = parts.index(name)
    return objects, parts, particle_part, triangle_part, particle_object


def object_diagnostics(sim, positions: np.ndarray, velocities: np.ndarray) -> dict:
    """Per-object mass centre [m], altitude above the terrain [m] and airspeed [m/s] of one frame."""
    model = sim.model
    mass = model.particle_free_mass
    wind = sim.control.wind.numpy()
    centre, altitude, airspeed = [], [], []
    for record in model.objects:
        ids = record.particles
        m = mass[ids]
        total = m.sum() if m.sum() > 0 else 1.0
        c = (m[:, None] * positions[ids]).sum(axis=0) / total
        v = (m[:, None] * velocities[ids]).sum(axis=0) / total
        centre.append(c)
        altitude.append(c[2] - float(model.terrain.height(c[0], c[1])))
        airspeed.append(np.linalg.norm(v - wind[record.world]))
    return {"centre": np.array(centre), "altitude": np.array(altitude), "airspeed": np.array(airspeed)}


class H5Recorder:
    """Append the frames of a :class:`warpsim.runner.Simulation` to an HDF5 recording.

    Args:
        path: the ``.h5`` file to create (``resume=False``) or to continue (``resume=True``).
        sim: the simulation being recorded.
        descriptor_text: the full descriptor as TOML (see :func:`warpsim.descriptor.to_toml`).
        scene: where the scene came from (a path or ``built-in NAME``), stored as an attribute.
        resume: open an existing recording and append after its checkpoint's frame.

    Use as a context manager, or call :meth:`close`; call :meth:`write` with each frame.
    """

    sync_interval = 0.5  # [s] of wall time between checkpoints/flushes

    def __init__(self, path, sim, descriptor_text: str = "", scene: str = "", resume: bool = False):
        import warp as wp

        from .. import __version__

        self.path = Path(path)
        self.sim = sim
        model = sim.model
        n, objects = model.particle_count, len(model.objects)
        if resume:
            self.file = h5py.File(self.path, "r+", libver="latest")
            last = int(self.file["checkpoint/frame"][0])
            for name in _FRAME_DATASETS:
                self.file[name].resize(last + 1, axis=0)
            self.frames = last + 1
            self.file.swmr_mode = True
            self._cache()
            return
        self.file = h5py.File(self.path, "w", libver="latest")
        f = self.file
        try:
            object_names, parts, particle_part, triangle_part, particle_object = _names(sim)
            f.attrs.update(
                {
                    "format": FORMAT,
                    "format_version": FORMAT_VERSION,
                    "descriptor": descriptor_text,
                    "scene": scene,
                    "solver": json.dumps(sim.descriptor["solver"]),
                    "warpsim_version": __version__,
                    "warp_version": wp.config.version,
                    "dt": sim.dt,
                    "steps_per_frame": sim.steps_per_frame,
                    "frame_interval": sim.steps_per_frame * sim.dt,
                }
            )
            top = f.create_group("topology")
            top.attrs["objects"] = object_names
            top.attrs["parts"] = parts
            top["sticks"] = model.stick_particles_np
            top["stick_rest"] = model.stick_rest.numpy()
            top["triangles"] = model.tri_indices_np
            top["particle_mass"] = model.particle_mass
            top["particle_object"] = particle_object
            top["particle_part"] = particle_part
            top["triangle_part"] = triangle_part
            gz = {"compression": "gzip", "compression_opts": 4, "shuffle": True}
            f.create_dataset("time", (0,), maxshape=(None,), dtype="f8", chunks=(256,))
            f.create_dataset("positions", (0, n, 3), maxshape=(None, n, 3), dtype="f4", chunks=(1, n, 3), **gz)
            d = f.create_group("diagnostics")
            d.create_dataset("worst_stretch", (0,), maxshape=(None,), dtype="f4", chunks=(256,))
            d.create_dataset("kinetic_energy", (0,), maxshape=(None,), dtype="f8", chunks=(256,))
            shape3 = {"maxshape": (None, objects, 3), "chunks": (64, objects, 3)}
            d.create_dataset("centre", (0, objects, 3), dtype="f4", **shape3)
            d.create_dataset("altitude", (0, objects), maxshape=(None, objects), dtype="f4", chunks=(64, objects))
            d.create_dataset("airspeed", (0, objects), maxshape=(None, objects), dtype="f4", chunks=(64, objects))
            c = f.create_group("checkpoint")
            c.create_dataset("frame", data=np.array([-1], dtype=np.int64))  # -1: no frame checkpointed yet
            cp = sim.checkpoint()  # shapes and types of what later checkpoints write
            for name in _CHECKPOINT_ARRAYS:
                c.create_dataset(name, data=cp[name])
            for name in _CHECKPOINT_SCALARS:
                c.create_dataset(name, data=np.array([cp[name]]))
            for name in _CHECKPOINT_TEXTS:
                c.create_dataset(name, (_TEXT_BYTES,), dtype="u1")
            self.frames = 0
            f.swmr_mode = True
            self._cache()
        except BaseException:
            self.file.close()
            self.path.unlink(missing_ok=True)
            raise

    def _cache(self) -> None:
        self._datasets = {name: self.file[name] for name in _FRAME_DATASETS}
        self._checkpoint = {name: self.file[f"checkpoint/{name}"] for name in self.file["checkpoint"]}
        self._unsaved: tuple[int, int] | None = None
        self._last_sync = -float("inf")

    def write(self, frame) -> None:
        """Store one :class:`warpsim.runner.Frame` as row ``frame.index`` (the next row, or the last one again
        when a resumed run completes a shorter last frame).

        The frame is flushed, and the simulation's state saved as the checkpoint, at most every
        ``sync_interval`` wall seconds and always by :meth:`close` (which the CLI reaches on Ctrl-C and
        SIGTERM too); a frame written after the last checkpoint stays readable and is redone by a resume.
        """
        k = int(frame.index)
        if not self.frames - 1 <= k <= self.frames:
            raise ValueError(f"frame {k} does not follow the recording's last frame {self.frames - 1}")
        diag = object_diagnostics(self.sim, frame.positions, frame.velocities)
        with signals_held():
            d = self._datasets
            if k == self.frames:
                for name in _FRAME_DATASETS:
                    d[name].resize(k + 1, axis=0)
            d["time"][k] = frame.time
            d["positions"][k] = frame.positions
            d["diagnostics/worst_stretch"][k] = frame.worst_stretch
            d["diagnostics/kinetic_energy"][k] = frame.kinetic_energy
            d["diagnostics/centre"][k] = diag["centre"]
            d["diagnostics/altitude"][k] = diag["altitude"]
            d["diagnostics/airspeed"][k] = diag["airspeed"]
            self.frames = k + 1
            self._unsaved = (k, self.sim.steps_taken)
            now = time.monotonic()
            if now - self._last_sync >= self.sync_interval:
                self._save_checkpoint()
                self._last_sync = now

    def _save_checkpoint(self) -> None:
        """Write the simulation's current state as the checkpoint of the last written frame, and flush."""
        if self._unsaved is None:
            return
        k, steps = self._unsaved
        if steps == self.sim.steps_taken:  # the simulation is still at that frame
            cp = self.sim.checkpoint()
            c = self._checkpoint
            for name in _CHECKPOINT_ARRAYS:
                c[name][...] = cp[name]
            for name in _CHECKPOINT_SCALARS:
                c[name][0] = cp[name]
            for name in _CHECKPOINT_TEXTS:
                c[name][...] = _pad(cp[name])
            c["frame"][0] = k
        self._unsaved = None
        self.file.flush()

    def close(self) -> None:
        """Save the checkpoint, flush and close the file (safe to call twice)."""
        if self.file.id.valid:
            with signals_held():
                self._save_checkpoint()
                self.file.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


_FRAME_DATASETS = (
    "time",
    "positions",
    "diagnostics/worst_stretch",
    "diagnostics/kinetic_energy",
    "diagnostics/centre",
    "diagnostics/altitude",
    "diagnostics/airspeed",
)


def _pad(text: str) -> np.ndarray:
    data = text.encode("utf-8")
    if len(data) > _TEXT_BYTES:
        raise ValueError(f"checkpoint text too long ({len(data)} bytes)")
    out = np.zeros(_TEXT_BYTES, dtype=np.uint8)
    out[: len(data)] = np.frombuffer(data, dtype=np.uint8)
    return out


def _unpad(data: np.ndarray) -> str:
    return bytes(np.asarray(data, dtype=np.uint8)).rstrip(b"\0").decode("utf-8")


class Recording:
    """Read a recording (also while another process is still writing it).

    Attributes:
        path: the file. descriptor_text: the scene descriptor (TOML). scene: where it came from.
        time: ``[F]`` frame times [s]. frame_count: ``F``. frame_interval: time between frames [s].
    """

    def __init__(self, path):
        self.path = Path(path)
        if not self.path.is_file():
            raise RecordingError(f"{path}: no such file")
        try:
            self.file = h5py.File(self.path, "r", libver="latest", swmr=True)
        except OSError:
            raise RecordingError(f"{path}: not an HDF5 file (expected a warpsim recording)") from None
        if self.file.attrs.get("format") != FORMAT:
            self.file.close()
            raise RecordingError(f"{path}: an HDF5 file but not a warpsim recording (no format = {FORMAT!r})")
        self.descriptor_text = str(self.file.attrs["descriptor"])
        self.scene = str(self.file.attrs.get("scene", ""))
        self.frame_interval = float(self.file.attrs["frame_interval"])
        self.time = self.file["time"][:]
        self.frame_count = len(self.time)

    def positions(self, frame: int | slice = slice(None)) -> np.ndarray:
        """Positions [m] of one frame ``[N, 3]`` or a slice of frames ``[F, N, 3]``."""
        return self.file["positions"][frame]

    def checkpoint(self) -> dict:
        """The saved state after the last checkpointed frame (see :meth:`warpsim.runner.Simulation.restore`)."""
        c = self.file["checkpoint"]
        frame = int(c["frame"][0])
        if frame < 0:
            raise RecordingError(f"{self.path}: the recording has no frame to resume from")
        out = {"frame": frame}
        out.update({name: c[name][:] for name in _CHECKPOINT_ARRAYS})
        out.update({name: c[name][0].item() for name in _CHECKPOINT_SCALARS})
        out.update({name: _unpad(c[name][:]) for name in _CHECKPOINT_TEXTS})
        return out

    def close(self) -> None:
        """Close the file."""
        self.file.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
