"""Streaming HDF5 recordings: one frame appended at a time, readable while written, resumable.

Layout (``F`` frames, ``N`` particles, ``M`` sticks, ``T`` triangles, ``O`` objects; SI units)::

    /time                        [F]        float64  simulated time of each frame [s]
    /positions                   [F, N, 3]  float64  particle positions [m] (chunk = 1 frame, gzip)
    /diagnostics/worst_stretch   [F]        float32  largest |l - r| / r over all sticks
    /diagnostics/kinetic_energy  [F]        float64  kinetic energy of the free particles [J]
    /diagnostics/centre          [F, O, 3]  float64  mass centre of each object [m]
    /diagnostics/altitude        [F, O]     float64  height of that centre above the terrain [m]
    /diagnostics/airspeed        [F, O]     float32  |mean velocity - wind| of each object [m/s]
    /controls                    [F, C, 3]  float64  the controls in force when each frame's stepping began, one row
                                                     per name of ``/checkpoint`` attr ``control_names`` (a unit
                                                     control in column 0, a vector in its first columns; NaN:
                                                     not set); what a replay sets again (:meth:`Recording.controls`)
    /topology/sticks             [M, 2]     int32    particle indices of each stick
    /topology/stick_rest         [M]        float32  built rest lengths [m]
    /topology/triangles          [T, 3]     int32    particle indices of each air-force triangle
    /topology/particle_mass      [N]        float64  [kg] (inf = nailed)
    /topology/particle_object    [N]        int32    object of each particle (index into attr ``objects``)
    /topology/particle_part      [N]        int32    part of each particle (index into attr ``parts``; -1 none)
    /topology/triangle_part      [T]        int32    part of each triangle (index into attr ``parts``)
    /topology/terrain_heights    [NY, NX]   float64  the terrain's heights [m] (attrs size, origin [m]): resumes and
                                                     conversions never read a terrain file again
    /checkpoint/slot0, slot1                         two copies of the state after a frame, for ``--resume``:
        frame [1] int64, digest [32] uint8 (sha256), and the arrays of :class:`warpsim.run.checkpoint.Checkpoint`

Root attributes: ``format`` (``warpsim-recording``), ``format_version``, ``descriptor`` (the full scene
descriptor as TOML), ``scene`` (where it came from), ``solver`` (JSON), ``warpsim_version``,
``warp_version``, ``dt`` [s], ``steps_per_frame``, ``frame_interval`` [s]; on ``/topology``:
``objects`` and ``parts`` (names, parts as ``object/part``); on ``/checkpoint``: ``control_names``.
Every frame and topology dataset carries HDF5's Fletcher-32 checksum, so damaged data fails to read
instead of reading wrong.

The file is written in HDF5's single-writer/multiple-reader (SWMR) mode: another process can open it
while it grows (``h5py.File(path, "r", swmr=True)``). One writer at a time: a writer holds an exclusive
lock (:class:`warpsim.io.h5safe.WriterLock`) and a second one is refused before it touches the file.

Frames are flushed every ``H5Recorder.sync_interval`` (0.5) wall seconds and when the recorder closes
(which the CLI does on Ctrl-C and SIGTERM), then a checkpoint of the state after the last of them is
written to the older of two slots, with a digest, and flushed. A frame counts once a checkpoint covers it:
readers show frames up to the newest slot whose digest holds, so frames written after it (a run killed
outright, a disk that filled up) are never shown as data, and a resume redoes them. A checkpoint torn by
a kill leaves the other slot. A killed writer also leaves the superblock's "open for writing" flags set:
warpsim reads such a file as it is and ``--resume`` clears them; other tools open it with ``swmr=True``
or after ``h5clear -s``.
"""

from __future__ import annotations

import contextlib
import json
import os
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..run.checkpoint import DIGEST_BYTES, Checkpoint, pack_controls
from ..run.diagnostics import object_metrics
from . import OutputWriteError, reason, with_disk_state
from .h5format import (
    _CHECKSUM,
    _FRAME_DATASETS,
    FORMAT,
    FORMAT_VERSION,
    SLOTS,
    RecordingError,
    _frame_layout,
    _names,
    _newest_checkpoint,
    _reading,
    check_recording_path,
    claim,
    descriptor_digest,
    signals_held,
)
from .h5safe import (
    abandon,
    clear_status_flags,
    extend_to_stored_end,
    open_for_writing,
)
from .protocol import FrameOutput

__all__ = ["H5Recorder", "RecordingError", "check_recording_path", "claim", "signals_held"]


class H5Recorder(FrameOutput):
    """Append the frames of a run to an HDF5 recording.

    Args:
        path: the ``.h5`` file to create (``resume=False``) or to continue (``resume=True``).
        model: the :class:`warpsim.Model` whose frames are recorded.
        scene: the run's :class:`~warpsim.scene.scene.Scene`: its TOML, time step and frame rate are stored.
        checkpoint: returns the run's :class:`warpsim.run.checkpoint.Checkpoint` now (e.g.
            :meth:`warpsim.run.simulation.Simulation.checkpoint`); asked when a frame is made durable.
        where: where the scene came from (a path or ``built-in NAME``), stored as the ``scene`` attribute.
        resume: open an existing recording and append after its checkpoint's frame.
        lock: the path's :func:`claim`, when the caller took it already (a resume reads the recording under
            it); taken here otherwise. Released when the recorder closes.

    Raises :class:`RecordingError` when another run writes ``path``. Use as a context manager, or call
    :meth:`close`; call :meth:`write` with each frame. A failed write (disk full) raises
    :class:`warpsim.io.OutputWriteError` naming the last frame kept; the file stays readable and resumable.
    """

    sync_interval = 0.5  # [s] of wall time between checkpoints/flushes

    def __init__(
        self,
        path,
        model,
        scene,
        checkpoint: Callable[[], Checkpoint],
        where: str = "",
        *,
        resume: bool = False,
        lock=None,
    ):
        self.path = Path(path)
        self.model = model
        self.scene = scene
        self.checkpoint = checkpoint
        self.file = None
        self.failed: OutputWriteError | None = None
        self.lock = None
        existed = resume or os.path.lexists(self.path)
        try:
            # the claim inside: a Ctrl-C or SIGTERM landing just after the lock created the file, before it was
            # held here, left a 0-byte file that every reader called 'not an HDF5 file'
            self.lock = lock if lock is not None else claim(self.path, create=not resume)
            if resume:
                self._open_existing()
            else:
                self._create(where)
        except BaseException as err:
            if self.file is not None:
                with contextlib.suppress(Exception):
                    self.file.close()
            ours = self.lock is not None or not (existed or isinstance(err, RecordingError))
            if not resume and ours:  # never another run's file (RecordingError: it holds the lock)
                self.path.unlink(missing_ok=True)
            if self.lock is not None:
                self.lock.release()
            if isinstance(err, OSError | RuntimeError):
                raise OutputWriteError(f"{self.path}: cannot write the recording ({reason(err)})") from None
            raise
        self._datasets = {name: self.file[name] for name in _FRAME_DATASETS}
        self._slots = [
            {name: self.file[f"checkpoint/{slot}/{name}"] for name in self.file[f"checkpoint/{slot}"]} for slot in SLOTS
        ]
        self._control_names = tuple(str(n) for n in self.file["checkpoint"].attrs["control_names"])
        self._unsaved: tuple[int, int, float] | None = None
        self._last_sync = -float("inf")

    def _open_existing(self) -> None:
        clear_status_flags(self.path)  # a killed writer's flags; we hold the lock
        extend_to_stored_end(self.path)  # a write that failed part-way left it short
        with _reading(self.path):
            self.file = open_for_writing(self.path, swmr=False)
            frame, slot, _ = _newest_checkpoint(self.file, self.path)
            self._check_layout()
            if frame < 0:
                raise RecordingError(f"{self.path}: the recording has no frame to resume from")
            for name in _FRAME_DATASETS:
                self.file[name].resize(frame + 1, axis=0)
            self.committed = (frame, float(self.file["time"][frame]))
            self.file.close()
            self.file = open_for_writing(self.path)
        self.frames = frame + 1
        self._next_slot = 1 - slot

    def _check_layout(self) -> None:
        """Raise :class:`RecordingError` unless every dataset a resume writes has the shape, type and growth this
        simulation writes (a recording edited or damaged since could not take its frames)."""
        model, f, cp = self.model, self.file, self.checkpoint()
        layout = _frame_layout(model.particle_count, len(model.objects), len(cp.control_names))
        for name, (frame_shape, dtype, _) in layout.items():
            d = f[name]
            if (
                d.shape[1:] != frame_shape
                or d.dtype != np.dtype(dtype)
                or d.chunks is None
                or d.maxshape[0] is not None
            ):
                raise RecordingError(f"{self.path}: dataset {name} is {d.dtype}{list(d.shape)}; cannot append to it")
        arrays = cp.arrays()
        for slot in SLOTS:
            group = f[f"checkpoint/{slot}"]
            for name, data in arrays.items():
                d = group.get(name)
                if d is None or d.shape != data.shape or d.dtype != data.dtype:
                    raise RecordingError(f"{self.path}: checkpoint/{slot}/{name} does not fit this scene")
            for name, shape in (("frame", (1,)), ("digest", (DIGEST_BYTES,))):
                if name not in group or group[name].shape != shape:
                    raise RecordingError(f"{self.path}: checkpoint/{slot}/{name} is missing or damaged")

    def _create(self, where: str) -> None:
        import warp as wp

        from .._version import __version__

        model, spec = self.model, self.scene
        descriptor_text = spec.toml()
        dt = spec.dt
        steps_per_frame = spec.settings.scene.steps_per_frame(dt)
        n, objects = model.particle_count, len(model.objects)
        cp = self.checkpoint()  # shapes and types of what later checkpoints write
        self.file = f = open_for_writing(self.path, create=True)
        object_names, parts, particle_part, triangle_part, particle_object = _names(model)
        f.attrs.update(
            {
                "format": FORMAT,
                "format_version": FORMAT_VERSION,
                "descriptor": descriptor_text,
                "descriptor_sha256": descriptor_digest(descriptor_text),
                "scene": where,
                "solver": json.dumps(spec.table("solver")),
                "warpsim_version": __version__,
                "warp_version": wp.config.version,
                "dt": dt,
                "steps_per_frame": steps_per_frame,
                "frame_interval": steps_per_frame * dt,
            }
        )
        top = f.create_group("topology")
        top.attrs["objects"] = object_names
        top.attrs["parts"] = parts
        topology = {
            "sticks": model.stick_particles_np,
            "stick_rest": model.stick_rest.numpy(),
            "triangles": model.tri_indices_np,
            "particle_mass": model.particle_mass,
            "particle_object": particle_object,
            "particle_part": particle_part,
            "triangle_part": triangle_part,
        }
        for name, data in topology.items():
            data = np.asarray(data)
            top.create_dataset(
                name, data=data, chunks=data.shape if data.size else None, **(_CHECKSUM if data.size else {})
            )
        terrain = model.terrain  # the heights themselves: a resume or a convert never reads a terrain file again
        heights = top.create_dataset(
            "terrain_heights",
            data=terrain.heights,
            chunks=(min(256, terrain.heights.shape[0]), terrain.heights.shape[1]),
            compression="gzip",
            compression_opts=4,
            shuffle=True,
            **_CHECKSUM,
        )
        heights.attrs["size"] = np.asarray(terrain.size, dtype=np.float64)
        heights.attrs["origin"] = np.asarray(terrain.origin, dtype=np.float64)
        gz = {"compression": "gzip", "compression_opts": 4, "shuffle": True}
        for name, (frame_shape, dtype, rows) in _frame_layout(n, objects, len(cp.control_names)).items():
            f.create_dataset(
                name,
                (0, *frame_shape),
                maxshape=(None, *frame_shape),
                dtype=dtype,
                chunks=(rows, *frame_shape),
                **(gz if name == "positions" else {}),
                **_CHECKSUM,
            )
        c = f.create_group("checkpoint")
        c.attrs["control_names"] = list(cp.control_names)
        for slot in SLOTS:
            g = c.create_group(slot)
            g.create_dataset("frame", data=np.array([-1], dtype=np.int64))  # -1: no frame checkpointed yet
            g.create_dataset("digest", data=np.zeros(DIGEST_BYTES, dtype=np.uint8))
            for name, data in cp.arrays().items():
                g.create_dataset(name, data=data)
        f.close()
        self.file = open_for_writing(self.path)  # in SWMR mode with bounded reads (see open_for_writing)
        self.frames = 0
        self.committed = (-1, float("nan"))
        self._next_slot = 0

    def write(self, frame) -> None:
        """Store one :class:`warpsim.run.diagnostics.Frame` as row ``frame.index`` (the next row, or the last one again
        when a resumed run completes a shorter last frame).

        The frame is flushed, and the simulation's state saved as the checkpoint, at most every
        ``sync_interval`` wall seconds and always by :meth:`close` (which the CLI reaches on Ctrl-C and
        SIGTERM too); a frame written after the last checkpoint is not shown to readers and is redone by a
        resume. Raises :class:`warpsim.io.OutputWriteError` when the file cannot be written (and after that).
        """
        if self.failed is not None:
            raise self.failed
        k = int(frame.index)
        if not self.frames - 1 <= k <= self.frames:
            raise ValueError(f"frame {k} does not follow the recording's last frame {self.frames - 1}")
        metrics = object_metrics(self.model, frame)
        with signals_held(), self._guard():
            sets = self._datasets
            if k == self.frames:
                for name in _FRAME_DATASETS:
                    sets[name].resize(k + 1, axis=0)
            sets["time"][k] = frame.time
            sets["controls"][k] = pack_controls(self._control_names, frame.controls)[1]
            sets["positions"][k] = frame.positions
            sets["diagnostics/worst_stretch"][k] = frame.worst_stretch
            sets["diagnostics/kinetic_energy"][k] = frame.kinetic_energy
            sets["diagnostics/centre"][k] = metrics.centre
            sets["diagnostics/altitude"][k] = metrics.altitude
            sets["diagnostics/airspeed"][k] = metrics.airspeed
            self.frames = k + 1
            self._unsaved = (k, frame.steps, float(frame.time))
            now = time.monotonic()
            if now - self._last_sync >= self.sync_interval:
                self._save_checkpoint()
                self._last_sync = now

    def log_state(self, frame) -> None:
        """The :class:`~warpsim.io.protocol.Output` step: :meth:`write` the frame."""
        self.write(frame)

    @contextlib.contextmanager
    def _guard(self):
        """Turn a failed HDF5 write into :class:`OutputWriteError`, leaving the file as the last sync left it."""
        try:
            yield
        except (OSError, RuntimeError) as err:
            abandon(self.file)
            self.lock.release()
            frame, t = self.committed
            kept = f"frames 0-{frame} (t = {t:.3f} s)" if frame >= 0 else "no frame"
            self.failed = OutputWriteError(
                f"{self.path}: writing failed ({with_disk_state(reason(err), self.path)}); the recording keeps {kept}"
                + (f"; continue it with `warpsim run --resume {self.path}` once fixed" if frame >= 0 else "")
            )
            raise self.failed from None

    def _save_checkpoint(self) -> None:
        """Flush the frames, then write the run's state as the checkpoint of the last written frame into the
        older slot (with its digest), and flush again: a kill at any moment leaves one whole checkpoint."""
        if self._unsaved is None:
            return
        k, steps, t = self._unsaved
        self._unsaved = None
        self.file.flush()
        cp = self.checkpoint()
        if int(cp.steps[0]) != steps:  # the run has moved on since that frame
            return
        slot = self._slots[self._next_slot]
        for name, data in cp.arrays().items():
            slot[name][...] = data
        slot["frame"][0] = k
        slot["digest"][...] = cp.digest(k)
        self.file.flush()
        self.committed = (k, t)
        self._next_slot = 1 - self._next_slot

    def close(self) -> None:
        """Save the checkpoint, flush and close the file, release the lock (safe to call twice).

        Raises :class:`warpsim.io.OutputWriteError` when the last writes fail (the file keeps the last sync)."""
        if self.file is not None and self.file.id.valid and self.failed is None:
            with signals_held():
                with self._guard():
                    self._save_checkpoint()
                    self.file.close()
        self.lock.release()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
