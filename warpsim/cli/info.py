"""``warpsim info``: a scene's counts, masses and settings."""

from __future__ import annotations

from .common import add_world_options, load_scene


def command(args) -> int:
    """Print counts, masses and settings of a scene."""
    import numpy as np

    from ..objects import registry

    scene, _ = load_scene(args)
    where = scene.where
    model = scene.build_model("cpu")
    kind = scene.kind
    print(f"scene: {where} (object: {kind})")
    print(
        f"  particles {model.particle_count}, sticks {model.stick_count}, triangles {model.tri_count}, "
        f"nails {model.nail_count}"
    )
    for record in model.objects:
        mass = model.particle_mass[record.particles]
        print(f"  {record.name}: total mass {mass[mass != float('inf')].sum():.3f} kg (nailed particles excluded)")
        earlier: set[int] = set()  # parts may share particles (the flag's pole column is cloth too)
        for part, ids in record.parts.items():
            pm = model.particle_mass[ids]
            finite = pm[pm != float("inf")]
            shared = len(earlier.intersection(int(i) for i in ids))
            nailed = int(np.isinf(pm).sum())
            notes = ([f"{shared} also in a part above"] if shared else []) + ([f"{nailed} nailed"] if nailed else [])
            note = f" ({', '.join(notes)})" if notes else ""
            print(f"    part {part:<10} {len(ids):5d} particles, {finite.sum():9.3f} kg{note}")
            earlier.update(int(i) for i in ids)
        paper = registry.OBJECTS[record.kind].paper_counts
        if paper:
            print(
                f"  the paper's model: particles {paper['particles']}, sticks {paper['sticks']}, "
                f"triangles {paper['triangles']} (see docs/objects.md)"
            )
    print(f"  terrain: {model.terrain}")
    print("settings:")
    print("  " + scene.toml().replace("\n", "\n  ").rstrip())
    return 0


def add_parser(sub) -> None:
    """Add the ``info`` command to the subparsers ``sub``."""
    info = sub.add_parser(
        "info",
        help="counts, masses and settings of a scene",
        description="Print a scene's particle/stick/triangle counts, masses and settings.",
    )
    info.add_argument("scene", metavar="SCENE")
    info.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a descriptor value, e.g. --set flag.resolution=8 (repeatable)",
    )
    add_world_options(info)
