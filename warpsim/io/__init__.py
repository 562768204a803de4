"""Outputs: animated USD stages (:mod:`warpsim.io.usd`) and streaming HDF5 recordings (:mod:`warpsim.io.hdf5`)."""

from __future__ import annotations

from pathlib import Path


class OutputPathError(ValueError):
    """An output path that cannot be written: unknown extension or missing directory."""


def check_output_path(path, extensions: tuple[str, ...], kind: str) -> Path:
    """Check that ``path`` ends in one of ``extensions`` and that its directory exists; returns it as a Path.

    ``kind`` names the format in the message (``USD``, ``HDF5``). Checked before a run starts, so that a
    mistake costs nothing and leaves no file.
    """
    path = Path(path)
    if path.suffix.lower() not in extensions:
        choices = ", ".join(extensions[:-1]) + " or " + extensions[-1] if len(extensions) > 1 else extensions[0]
        raise OutputPathError(f"{path}: unknown {kind} extension {path.suffix!r}; use {choices}")
    if not path.parent.resolve().is_dir():
        raise OutputPathError(f"{path}: directory {path.parent} does not exist")
    return path
