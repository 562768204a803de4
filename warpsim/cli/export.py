"""``warpsim export``: a scene's cloth written as a mesh file, with a scene beside it that flies it as a design of
its own (:mod:`warpsim.io.mesh_export`)."""

from __future__ import annotations

from .._interrupt import interruptible
from .common import UsageError

SUFFIXES = (".obj", ".glb", ".gltf", ".stl")


def command(args) -> int:
    """Export the scene's object as a mesh file and a mesh scene."""
    from pathlib import Path

    from ..io.mesh_export import export_design
    from .common import load_scene

    out = Path(args.output)
    if out.suffix.lower() not in SUFFIXES:
        raise UsageError(f"{out}: the mesh file must end in {', '.join(SUFFIXES)}")
    if not out.parent.is_dir():
        raise UsageError(f"{out}: its folder {out.parent} does not exist")
    scene, _ = load_scene(args, worlds_from_vary=False)
    _check_outputs(out, scene, args.scene, args.force)
    interruptible()  # the files are written next
    try:
        mesh, scene, left_out = export_design(scene, out)
    except ValueError as err:
        raise UsageError(str(err)) from None
    print(f"{args.scene} -> {mesh} and {scene}")
    for item in left_out:
        print(f"  left out: {item}")
    return 0


def _check_outputs(out, scene, source: str, force: bool) -> None:
    """Refuse to write over what the export reads (the scene file, its mesh or terrain) at all, and over other files
    that exist unless ``force``: an export once replaced a hand-written design it was asked to export."""
    import os
    from pathlib import Path

    written = [out, out.with_suffix(".toml")]
    read = [Path(source)] if Path(source).is_file() else []
    read += [Path(name) for name in scene.files()]
    for path in written:
        for other in read:
            if os.path.abspath(path) == os.path.abspath(other) or (
                path.exists() and other.exists() and os.path.samefile(path, other)
            ):
                raise UsageError(f"{path}: is what the export reads ({source}); write the export under another name")
    existing = [str(p) for p in written if p.exists()]
    if existing and not force:
        raise UsageError(f"{' and '.join(existing)} exist already: give --force to replace them, or another name")


def add_parser(sub) -> None:
    """Add the ``export`` command to the subparsers ``sub``."""
    from .common import add_scene_options

    export = sub.add_parser(
        "export",
        help="write a scene's cloth as a mesh file and a scene that flies it",
        description="Write the object of SCENE (its first world, as built) as a mesh file (OBJ with its parts as "
        "groups, glTF/GLB with a node per part, or STL) and, beside it, OUT.toml: a scene of your own design "
        "(scene.object = 'mesh') with the cloth's density and compliance and its nails, spars, line and point masses "
        "as [[mesh.parts]]. Edit the mesh in any CAD tool and fly it with `warpsim run OUT.toml`. The export says "
        "what it leaves out (a whole-canopy air law, bending hinges, particles' own masses).",
    )
    export.add_argument("scene", metavar="SCENE")
    export.add_argument("output", metavar="OUT.obj|.glb|.gltf|.stl")
    export.add_argument(
        "--force", action="store_true", help="replace OUT and OUT.toml where they exist (never the scene exported)"
    )
    add_scene_options(export, worlds=False)
