"""Where scene files are found by name: ``./scenes`` first, then the scenes shipped inside the package."""

from __future__ import annotations

from pathlib import Path

SHIPPED = Path(__file__).resolve().parent / "files"
"""The scene files installed with warpsim (package data, present in a wheel as in a source checkout)."""


def scene_dirs() -> list[Path]:
    """Where scene files are looked up: ./scenes, then the package's own scene files (:data:`SHIPPED`)."""
    dirs = [Path.cwd() / "scenes", SHIPPED]
    seen, out = set(), []
    for d in dirs:
        if d.is_dir() and d.resolve() not in seen:
            seen.add(d.resolve())
            out.append(d)
    return out
