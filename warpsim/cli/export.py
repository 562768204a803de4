"""``warpsim export``: a scene's cloth written as a mesh file, with a scene beside it that flies it as a design of
its own (:mod:`warpsim.io.mesh_export`)."""

from __future__ import annotations

from .._interrupt import interruptible
from .common import UsageError

SUFFIXES = (".obj", ".glb", ".gltf", ".stl")


def command(args) -> int:
    """Export the scene's object as a mesh file and a mesh scene."""
    from pathlib import Path

    from ..io.mesh_export import export_design, structure_path, writes_structure
    from .common import load_scene

    out = Path(args.output)
    if out.suffix.lower() not in SUFFIXES:
        raise UsageError(f"{out}: the mesh file must end in {', '.join(SUFFIXES)}")
    if not out.parent.is_dir():
        raise UsageError(f"{out}: its folder {out.parent} does not exist")
    scene, _ = load_scene(args, worlds_from_vary=False)
    structured = writes_structure(scene, args.parts)
    _check_outputs(out, scene, args.force, structured)
    interruptible()  # the files are written next
    try:
        mesh, scene, left_out = export_design(scene, out, parts=args.parts)
    except ValueError as err:
        raise UsageError(str(err)) from None
    also = f", {structure_path(mesh)}" if structured else ""
    print(f"{args.scene} -> {mesh}{also} and {scene}")
    for item in left_out:
        print(f"  left out: {item}")
    return 0


def _check_outputs(out, scene, force: bool, structured: bool) -> None:
    """Refuse, before anything is written, to write over what the export reads (:func:`~.common.same_file_check`:
    the scene's file, found by name or path, its meshes or terrain, in any world) at all, over a folder, and over
    other files or links that exist unless ``force`` (a link is then removed, never written through): an export once
    replaced a hand-written design it was asked to export. ``structured``: a structure file is written too."""
    from ..io.mesh_export import structure_path
    from .common import same_file_check, scene_sources

    written = {"export": out, "its scene": out.with_suffix(".toml")}
    if structured:
        written["its structure"] = structure_path(out)
    same_file_check(scene_sources(scene), written, "what the export reads")
    for path in written.values():
        if path.is_dir():
            raise UsageError(f"{path}: is a folder; give the export another name")
    existing = [str(p) for p in written.values() if p.exists() or p.is_symlink()]
    if existing and not force:
        verb = "exists" if len(existing) == 1 else "exist"
        raise UsageError(f"{' and '.join(existing)} {verb} already: give --force to replace, or another name")
    for path in written.values():
        if path.is_symlink():  # replaced, not written through
            path.unlink()


def add_parser(sub) -> None:
    """Add the ``export`` command to the subparsers ``sub``."""
    from .common import add_scene_options

    export = sub.add_parser(
        "export",
        help="write a scene's cloth as a mesh file and a scene that flies it",
        description="Write the object of SCENE (its first world, as built) as a mesh file (OBJ with its parts as "
        "groups, glTF/GLB with a node per part, or STL) and, beside it, OUT.toml: a scene of your own design "
        "(scene.object = 'mesh') that flies it. A built-in object's whole model beyond its triangles (its particles "
        "off the cloth, every stick, mass and per-triangle air, a canopy's air, nails) goes into OUT.structure.toml, "
        "so that it flies from the files as it flies built in; move or reshape the mesh's vertices in any CAD tool and "
        "fly it with `warpsim run OUT.toml`. With --parts the model is read off as [[mesh.parts]] instead (nails, "
        "spars, a line, point masses): a design to edit freely, which keeps the shape but not every setting. The "
        "export says what it leaves out.",
    )
    export.add_argument("scene", metavar="SCENE")
    export.add_argument("output", metavar="OUT.obj|.glb|.gltf|.stl")
    export.add_argument(
        "--force",
        action="store_true",
        help="replace OUT, OUT.toml and OUT.structure.toml where they exist (never what the export reads)",
    )
    export.add_argument(
        "--parts",
        action="store_true",
        help="write the model as [[mesh.parts]] (nails, spars, a line, point masses) to edit, not as a structure file",
    )
    add_scene_options(export, worlds=False)
