"""Reading a recording (see :mod:`warpsim.io.hdf5` for its layout), also while another process still writes it:
only frames an intact checkpoint covers are shown, and a damaged or foreign file is one line."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import numpy as np

from ..run.checkpoint import Checkpoint, unpack_controls
from . import reason
from .h5format import (
    _ATTRIBUTES,
    _FRAME_DATASETS,
    _TOPOLOGY,
    FORMAT,
    FORMAT_VERSION,
    RecordingError,
    _frame_layout,
    _newest_checkpoint,
    _reading,
    descriptor_digest,
)
from .h5safe import (
    LockedError,
    WriterLock,
    clear_status_flags,
    open_for_reading,
    probe_metadata,
    status_flags,
    writer_active,
)


class Recording:
    """Read a recording (also while another process is still writing it).

    Only frames covered by an intact checkpoint are shown (see the module notes). Raises
    :class:`RecordingError` with a one-line message for a missing, foreign, damaged or incomplete file,
    within about a second (HDF5's metadata read retries are limited when no writer is running).

    Attributes:
        path: the file. descriptor_text: the scene descriptor (TOML). scene: where it came from.
        time: ``[F]`` frame times [s]. frame_count: ``F``. frame_interval: time between frames [s].
        checkpoint_frame: the frame the newest intact checkpoint follows (-1: none). live: a writer is running.

    ``owner``: the caller holds the recording's writer lock (:func:`claim`, as a resume does), so no one else
    writes it.
    """

    def __init__(self, path, owner: bool = False):
        self.path = Path(path)
        try:
            info = os.stat(self.path)
        except OSError:
            raise RecordingError(f"{path}: no such file") from None
        if not stat.S_ISREG(info.st_mode):
            raise RecordingError(f"{path}: not a regular file")
        self.owner = owner
        self.live = not owner and writer_active(self.path)
        with _reading(path):
            if not self.live:  # a damaged heap can hang HDF5 for ever: read the attributes in a child first
                probe_metadata(self.path)
            try:
                self.file = open_for_reading(self.path, self.live)
            except OSError:
                if not _is_hdf5(self.path):
                    raise RecordingError(f"{path}: not an HDF5 file (expected a warpsim recording)") from None
                if self.live or not _recover_killed_writer(self.path, owner):
                    raise
                self.file = open_for_reading(self.path, False)
        try:
            with _reading(path):
                self._check()
        except BaseException:
            self.file.close()
            raise

    def _check(self) -> None:
        f, path = self.file, self.path
        if f.attrs.get("format") != FORMAT:
            raise RecordingError(f"{path}: an HDF5 file but not a warpsim recording (no format = {FORMAT!r})")
        missing = [a for a in _ATTRIBUTES if a not in f.attrs]
        missing += [n for n in (*_FRAME_DATASETS, *(f"topology/{t}" for t in _TOPOLOGY), "checkpoint") if n not in f]
        if "format_version" in f.attrs and int(f.attrs["format_version"]) != FORMAT_VERSION:
            raise RecordingError(
                f"{path}: recording format version {f.attrs['format_version']}; this warpsim reads version "
                f"{FORMAT_VERSION} (record it again)"
            )
        if missing:
            raise RecordingError(f"{path}: incomplete warpsim recording (missing {', '.join(missing[:4])})")
        self.descriptor_text = str(f.attrs["descriptor"])
        stored = f.attrs.get("descriptor_sha256")  # recordings before 2026-11-28 hold none
        if stored is not None and str(stored) != descriptor_digest(self.descriptor_text):
            raise RecordingError(
                f"{path}: its scene descriptor was changed after its frames were recorded (its sha256 does not "
                "match); the frames belong to the scene they were flown in: record it again"
            )
        self.scene = str(f.attrs.get("scene", ""))
        self.frame_interval = float(f.attrs["frame_interval"])
        if not (np.isfinite(self.frame_interval) and self.frame_interval > 0):
            raise RecordingError(f"{path}: frame_interval {self.frame_interval} is not a positive time")
        n = f["topology/particle_mass"].shape[0]
        positions = f["positions"]
        if positions.ndim != 3 or positions.shape[1:] != (n, 3):
            raise RecordingError(f"{path}: positions are {positions.shape}, expected (frames, {n}, 3)")
        self.checkpoint_frame, self._slot, self._checkpoint = _newest_checkpoint(f, path)
        if self._checkpoint is not None and self._checkpoint.q.shape != (n, 3):
            raise RecordingError(f"{path}: the checkpoint holds {self._checkpoint.q.shape[0]} particles, not {n}")
        written = min(f[name].shape[0] for name in _FRAME_DATASETS)
        # a checkpoint is saved after its frame is written, so one ahead of the frames is a crafted number; while a
        # writer runs, each dataset's length reaches a reader on its own (SWMR), so a reader may see it ahead
        if self.checkpoint_frame >= written and not self.live:
            raise RecordingError(
                f"{path}: its checkpoint is of frame {self.checkpoint_frame:,}, but it holds {written:,} frames"
            )
        self.frame_count = min(written, self.checkpoint_frame + 1)
        self._check_stored(n)
        if self.owner and self.frame_count:  # a resume appends: read what it will rewrite now, not half-way through
            for name in _FRAME_DATASETS:
                f[name].id.get_num_chunks()  # the whole chunk index
                f[name][self.frame_count - 1]  # the chunk the next frames share (its checksum is checked)
        self.time = f["time"][: self.frame_count]
        if not np.isfinite(self.time).all():
            raise RecordingError(f"{path}: frame times are not finite")
        # frames lie on a fixed grid of frame_interval (the last one may be shorter): a time off it (1e308) is not
        # a frame of this recording, and would overflow the stage's time codes
        grid = np.arange(self.frame_count) * self.frame_interval
        if np.any(np.abs(self.time - grid) > 1.001 * self.frame_interval):
            raise RecordingError(f"{path}: frame times do not follow its frame_interval of {self.frame_interval:g} s")

    def _check_stored(self, particles: int) -> None:
        """Trust the declared frame count only as far as the file holds it: every frame dataset must be chunked as
        warpsim writes it (one chunk's rows bounded by the layout) and hold enough stored chunks for every frame
        shown. A crafted file of 187 KB that declared 10 M frames kept `convert` busy for minutes and `--replay`
        at 4 GB; a file must now be about as large as the frames it shows."""
        f, path = self.file, self.path
        objects, controls = len(f["topology"].attrs.get("objects", [])), f["controls"].shape[1:2]
        layout = _frame_layout(particles, objects, controls[0] if controls else 0)
        for name, (frame_shape, _, rows) in layout.items():
            d = f[name]
            if d.shape[1:] != frame_shape or d.chunks is None or d.chunks[0] > rows or d.chunks[1:] != frame_shape:
                raise RecordingError(
                    f"{path}: dataset {name} is not stored as warpsim writes it (shape {d.shape}, chunks {d.chunks})"
                )
            if self.frame_count and d.id.get_num_chunks() * d.chunks[0] < self.frame_count:
                raise RecordingError(
                    f"{path}: declares {self.frame_count:,} frames but dataset {name} holds data for only "
                    f"{d.id.get_num_chunks() * d.chunks[0]:,}"
                )

    @property
    def particle_count(self) -> int:
        """Particles per frame."""
        return int(self.file["positions"].shape[1])

    def positions(self, frame: int | slice = slice(None)) -> np.ndarray:
        """Positions [m] of one frame ``[N, 3]`` (negative: from the end) or a slice of frames ``[F, N, 3]``."""
        with _reading(self.path):
            if isinstance(frame, slice):
                start, stop, step = frame.indices(self.frame_count)
                if step < 0:
                    ids = list(range(start, stop, step))[::-1]  # h5py reads increasing indices only
                    return self.file["positions"][ids][::-1] if ids else self.file["positions"][0:0]
                return self.file["positions"][start:stop:step]
            k = int(frame)
            if not -self.frame_count <= k < self.frame_count:
                raise RecordingError(f"{self.path}: no frame {k}; the recording has frames 0..{self.frame_count - 1}")
            return self.file["positions"][k % self.frame_count]

    def controls(self, frame: int | None = None) -> dict | list[dict]:
        """The controls in force while frame ``frame`` was stepped, by name (those set by then; see
        :meth:`~warpsim.run.simulation.Simulation.set_controls`);
        without ``frame``, those of every frame, in one read."""
        if frame is not None and not 0 <= frame < self.frame_count:
            raise RecordingError(f"{self.path}: no frame {frame}; the recording has frames 0..{self.frame_count - 1}")
        path = self.path
        names = tuple(str(n) for n in self.file["checkpoint"].attrs["control_names"])
        with _reading(self.path):
            tables = self.file["controls"][: self.frame_count] if frame is None else self.file["controls"][frame][None]
        rows = [unpack_controls(names, ~np.isnan(table[:, 0]), table) for table in tables]
        from ..run.inputs import check_value

        for k, row in enumerate(rows):  # a replay sets them again: out-of-range values are the file's fault
            for name, value in row.items():
                try:
                    check_value(name, value)
                except ValueError as err:
                    raise RecordingError(f"{path}: frame {k if frame is None else frame} holds {err}") from None
        return rows if frame is None else rows[0]

    def checkpoint(self) -> Checkpoint:
        """The saved state after frame :attr:`checkpoint_frame`
        (see :meth:`~warpsim.run.simulation.Simulation.restore`)."""
        if self._checkpoint is None:
            raise RecordingError(f"{self.path}: the recording has no frame to resume from")
        return self._checkpoint

    def terrain(self):
        """The recorded terrain (:class:`warpsim.physics.terrain.Heightfield`), or None for a recording made before
        terrains were stored (its ``[terrain]`` section is built then). Its size is checked against the limits of a
        terrain file and the memory available before it is read."""
        from ..physics.memory import available_memory
        from ..physics.terrain import MAX_HEIGHT, MAX_SIDE, Heightfield

        d = self.file["topology"].get("terrain_heights")
        if d is None:
            return None
        path = self.path
        with _reading(path):
            if d.ndim != 2 or not all(2 <= n <= MAX_SIDE for n in d.shape):
                raise RecordingError(f"{path}: its terrain is {list(d.shape)} samples, not 2 to {MAX_SIDE} a side")
            need, available = 16 * d.shape[0] * d.shape[1], available_memory()  # float64, and a float64 copy
            if available is not None and need > 0.5 * available:
                raise RecordingError(
                    f"{path}: its terrain of {d.shape[0]:,} x {d.shape[1]:,} samples needs {need / 1e9:.1f} GB; "
                    f"{available / 1e9:.1f} GB are available"
                )
            heights = d[()]
            size, origin = (tuple(float(v) for v in d.attrs[name]) for name in ("size", "origin"))
            if not np.isfinite(heights).all() or np.abs(heights).max() > MAX_HEIGHT:
                raise RecordingError(f"{path}: its terrain heights are not finite or beyond +-{MAX_HEIGHT:g} m")
            try:
                return Heightfield(heights, size, origin)
            except ValueError as err:
                raise RecordingError(f"{path}: its terrain cannot be used ({err})") from None

    def recorded_scene(self, where: str | None = None):
        """The recorded :class:`~warpsim.scene.scene.Scene`, checked against what the file holds before anything is
        built from it: one world per recorded object (a crafted descriptor of 4,096 worlds was built for minutes
        before its particle count was compared). ``where`` names it in errors (default: the file's descriptor)."""
        from ..scene.descriptor import load_text
        from ..scene.scene import Scene

        where = where or f"{self.path}: descriptor"
        scene = Scene(load_text(self.descriptor_text, where), where)
        objects = len(self.file["topology"].attrs.get("objects", []))
        worlds = scene.world_count
        if worlds != objects:
            raise RecordingError(
                f"{self.path}: its descriptor asks for {worlds:,} worlds, its frames hold {objects:,} objects"
            )
        return scene

    def build_model(self, device: str = "cpu"):
        """The recorded scene's :class:`warpsim.Model`, checked against the recorded particle count."""
        model = self.recorded_scene().build_model(device, str(self.path), self.terrain())
        if model.particle_count != self.particle_count:
            raise RecordingError(
                f"{self.path}: its descriptor builds {model.particle_count} particles, its frames hold "
                f"{self.particle_count}"
            )
        return model

    def close(self) -> None:
        """Close the file."""
        self.file.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def _recover_killed_writer(path: Path, owner: bool) -> bool:
    """Clear the "open for write" flags a writer killed while it held the file in plain (not SWMR) write mode left
    set (a ``run --resume`` killed at start-up, while it checks the layout), which SWMR readers refuse: what
    ``h5clear -s`` does, under the writer's lock (``owner``: the caller holds it). Returns True when cleared;
    raises :class:`RecordingError` saying to run ``h5clear -s`` when the file cannot be changed here."""
    if not status_flags(path):
        return False
    try:
        lock = None if owner else WriterLock(path, create=False)
    except LockedError:  # a writer started meanwhile: its flags are its own
        return False
    except OSError as err:
        raise RecordingError(
            f"{path}: a writer was killed while it had the file open and left it marked open for writing, and it "
            f"cannot be cleared here ({reason(err)}); run `h5clear -s {path}` (HDF5's tool) where it can"
        ) from None
    try:
        return clear_status_flags(path)
    finally:
        if lock is not None:
            lock.release()


def _is_hdf5(path) -> bool:
    """True when ``path`` starts with the HDF5 signature (at 0, 512, 1024, ... as HDF5 looks for it)."""
    from .h5safe import SIGNATURE

    with open(path, "rb") as f:
        for offset in (0, 512, 1024, 2048, 4096):
            f.seek(offset)
            if f.read(8) == SIGNATURE:
                return True
    return False
