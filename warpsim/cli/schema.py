"""``warpsim schema``: the JSON Schema of the scene file format, for editors to check and complete scene files."""

from __future__ import annotations

import json


def command(args) -> int:
    """Print the scene format's JSON Schema."""
    from ..scene.schema import scene_schema

    print(json.dumps(scene_schema(), indent=2))
    return 0


def add_parser(sub) -> None:
    """Add the ``schema`` command to the subparsers ``sub``."""
    sub.add_parser(
        "schema",
        help="print the JSON Schema of the scene file format",
        description="Print a JSON Schema (draft 2020-12) of scene files, generated from the typed settings (types, "
        "defaults, bounds and choices of every key), for editors that check and complete TOML with a schema: "
        "warpsim schema > scene.schema.json.",
    )
