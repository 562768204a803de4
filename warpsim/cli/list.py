"""``warpsim list``: the built-in objects and the scene files found."""

from __future__ import annotations

from ..scene.dirs import scene_dirs


def command(args) -> int:
    """Print built-in objects and scene files."""
    from ..objects import registry

    print("built-in objects:")
    for name, spec in registry.OBJECTS.items():
        print(f"  {name:<12} {spec.summary}")
    for directory in scene_dirs():
        files = sorted(directory.glob("*.toml"))
        if files:
            print(f"scenes in {directory}:")
            width = max(len(f.stem) for f in files)
            for f in files:
                print(f"  {f.stem:<{width}}  {_summary(f)}")
    return 0


def _summary(path, width: int = 90) -> str:
    """A scene file's first comment line (its author's summary), cut to ``width`` characters; empty without one.
    The folder is said once above the names (a wheel's scenes sit deep in site-packages)."""
    try:
        with open(path, encoding="utf-8") as file:
            first = file.readline().strip()
    except (OSError, UnicodeDecodeError):
        return ""
    text = first.lstrip("#").strip() if first.startswith("#") else ""
    return text if len(text) <= width else text[: width - 3].rstrip() + "..."


def add_parser(sub) -> None:
    """Add the ``list`` command to the subparsers ``sub``."""
    sub.add_parser(
        "list",
        help="built-in objects and the scene files found",
        description="List built-in objects and the scene files found in ./scenes and those shipped with warpsim.",
    )
