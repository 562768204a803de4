"""The recording format shared by its writer (:mod:`.hdf5`) and its reader (:mod:`.recording`): its datasets and
attributes (documented in :mod:`.hdf5`), its error, the writer's lock, and the checkpoint slots."""

from __future__ import annotations

import contextlib
import os
import signal
from pathlib import Path

import numpy as np

from ..run.checkpoint import Checkpoint
from . import check_output_path, reason
from .h5safe import LockedError, WriterLock

EXTENSIONS = (".h5", ".hdf5")


FORMAT = "warpsim-recording"


FORMAT_VERSION = 7


SLOTS = ("slot0", "slot1")


_CHECKSUM = {"fletcher32": True}


def _frame_layout(particles: int, objects: int, controls: int) -> dict[str, tuple[tuple[int, ...], str, int]]:
    """Each frame dataset: ``(shape of one frame, dtype, frames per chunk)``; what a recording is created with
    and what a resume checks before it appends."""
    return {
        "controls": ((controls, 3), "f8", 256),
        "time": ((), "f8", 256),
        "positions": ((particles, 3), "f8", 1),
        "diagnostics/worst_stretch": ((), "f4", 256),
        "diagnostics/kinetic_energy": ((), "f8", 256),
        "diagnostics/centre": ((objects, 3), "f8", 64),
        "diagnostics/altitude": ((objects,), "f8", 64),
        "diagnostics/airspeed": ((objects,), "f4", 64),
    }


_FRAME_DATASETS = tuple(_frame_layout(0, 0, 0))


_TOPOLOGY = (
    "sticks",
    "stick_rest",
    "triangles",
    "particle_mass",
    "particle_object",
    "particle_part",
    "triangle_part",
)


_ATTRIBUTES = ("format_version", "descriptor", "dt", "steps_per_frame", "frame_interval")


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
    """The file is not a readable warpsim recording, is damaged, is being written, or cannot be continued."""


def check_recording_path(path) -> Path:
    """Check that ``path`` can be written as an HDF5 recording (raises ``OutputPathError``)."""
    return check_output_path(path, EXTENSIONS, "HDF5")


def claim(path, create: bool) -> WriterLock:
    """Take the writer's lock of the recording ``path`` (see :class:`warpsim.io.h5safe.WriterLock`).

    Raises :class:`RecordingError` when another run is writing it, when ``path`` is a symbolic link (never written
    through: its target would be truncated) or when it cannot be opened for writing.
    """
    if os.path.islink(path):
        raise RecordingError(
            f"{path}: is a symbolic link; a recording is never written through one (remove the link or name a file)"
        )
    try:
        return WriterLock(path, create)
    except LockedError:
        raise RecordingError(f"{path}: another warpsim run is writing this recording; wait for it to end") from None
    except OSError as err:
        raise RecordingError(f"{path}: cannot be opened for writing ({reason(err)})") from None


def _names(model) -> tuple[list[str], list[str], np.ndarray, np.ndarray, np.ndarray]:
    """Object names, part names (``object/part``), part of each particle, of each triangle, object of each particle."""
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


def _read_checkpoint(group, names: tuple[str, ...]) -> tuple[int, Checkpoint | None]:
    """``(frame, checkpoint)`` of one slot; ``(-1, None)`` when it holds none or its digest does not match."""
    frame = int(group["frame"][0])
    if frame < 0:
        return -1, None
    fields = {name: group[name][()] for name in group if name not in ("frame", "digest")}
    try:
        cp = Checkpoint(**fields, control_names=names)
    except TypeError:  # missing or unknown fields
        return -1, None
    if not np.array_equal(group["digest"][()], cp.digest(frame)):
        return -1, None
    return frame, cp


def _newest_checkpoint(file, path) -> tuple[int, int, Checkpoint | None]:
    """``(frame, slot index, checkpoint)`` of the newest intact checkpoint; frame -1 when there is none.

    Raises :class:`RecordingError` when a slot claims a frame but none is intact (a damaged file)."""
    group = file["checkpoint"]
    names = tuple(str(n) for n in group.attrs["control_names"])
    best = (-1, 0, None)
    claimed = False
    for k, slot in enumerate(SLOTS):
        claimed |= int(group[slot]["frame"][0]) >= 0
        frame, cp = _read_checkpoint(group[slot], names)
        if frame > best[0]:
            best = (frame, k, cp)
    if claimed and best[2] is None:
        raise RecordingError(f"{path}: the recording's checkpoints are damaged (their digests do not match)")
    return best


@contextlib.contextmanager
def _reading(path):
    """Turn what HDF5 and h5py raise on a damaged or foreign file into one-line :class:`RecordingError`."""
    try:
        yield
    except RecordingError:
        raise
    except (OSError, RuntimeError, KeyError, ValueError, TypeError, IndexError, AttributeError) as err:
        raise RecordingError(f"{path}: damaged or not a warpsim recording ({reason(err)})") from None


def descriptor_digest(text: str) -> str:
    """The sha256 (hex) of a recording's descriptor text, stored beside it (``descriptor_sha256``): a descriptor
    edited or swapped afterwards (another object, another wind) no longer matches its frames and is refused."""
    import hashlib

    return hashlib.sha256(text.encode("utf-8")).hexdigest()
