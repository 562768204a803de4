"""Write the mesh files of the shipped designs that are not built in: ``diamond_kite.obj`` (a two-stick diamond kite
with a bowed spreader) and ``cross_canopy.glb`` (a flat cross parachute canopy), and the built-in kite, glider and
parachute exported by ``warpsim export`` (``exported_kite.obj`` and ``exported_kite.structure.toml``, and so on).
Run it from anywhere: ``python warpsim/scene/files/designs/make_designs.py`` writes the shipped files beside itself,
which the scenes ``diamond_kite.toml``, ``cross_canopy.toml`` and ``exported_kite.toml``, ``exported_hang_glider.toml``
and ``exported_parachute.toml`` beside the shipped scenes fly; ``--out DIR`` writes them all to ``DIR`` instead (a
design of your own drawn from these: leave the shipped ones as they are).

Both are drawn in a design's own axes (x forward, y left, z up, metres) and written by warpsim's own mesh writer, so
that the files and their vertex numbering are the same on every machine (the scenes name vertices by index).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from warpsim.objects.mesh_file import write_mesh

HERE = Path(__file__).resolve().parent

DIAMOND = {"spine": 0.9, "spreader": 0.76, "cross": 0.25, "bow_deg": 10.0, "divisions": 6}
"""The diamond kite: spine and spreader lengths [m], the spreader's place along the spine from the nose, the bow
of the spreader (each half tilted back this much [deg]) and the subdivisions of each of its four panels."""

CROSS = {"length": 0.8 * 22 / 6, "width": 0.8, "cell": 0.8 / 6}
"""The cross canopy: tip-to-tip length of each arm [m] (2.93), the arms' width [m] (W/L = 0.273, in the range
0.264-0.28 of Knacke's cross canopies) and the grid's cell [m] (6 across an arm, 22 along it)."""


def _panel(a, b, c, n, vertices: list, index: dict) -> list[tuple[int, int, int]]:
    """Triangles of triangle (a, b, c) split ``n`` times along each side; vertices shared through ``index``."""
    ids, tris = {}, []
    for i in range(n + 1):
        for j in range(n + 1 - i):
            p = a + (b - a) * i / n + (c - a) * j / n
            key = tuple(np.round(p, 9))
            if key not in index:
                index[key] = len(vertices)
                vertices.append(p)
            ids[i, j] = index[key]
    for i in range(n):
        for j in range(n - i):
            tris.append((ids[i, j], ids[i + 1, j], ids[i, j + 1]))
            if j < n - i - 1:
                tris.append((ids[i + 1, j], ids[i + 1, j + 1], ids[i, j + 1]))
    return tris


def diamond_kite() -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """The diamond kite's vertices, triangles and groups (its four panels)."""
    d = DIAMOND
    half = 0.5 * d["spine"]
    nose, tail = np.array([half, 0.0, 0.0]), np.array([-half, 0.0, 0.0])
    cross = np.array([half - d["cross"] * d["spine"], 0.0, 0.0])
    bow = 0.5 * d["spreader"] * np.tan(np.radians(d["bow_deg"]))
    left = cross + [0.0, 0.5 * d["spreader"], bow]
    right = cross + [0.0, -0.5 * d["spreader"], bow]
    vertices: list = []
    index: dict = {}
    groups, tris = {}, []
    panels = {
        "nose_left": (cross, nose, left),
        "nose_right": (cross, right, nose),
        "tail_left": (cross, left, tail),
        "tail_right": (cross, tail, right),
    }
    for name, (a, b, c) in panels.items():
        start = len(tris)
        tris += _panel(a, b, c, d["divisions"], vertices, index)
        groups[name] = np.arange(start, len(tris))
    return np.array(vertices), np.array(tris), groups


def cross_canopy() -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """The cross canopy's vertices, triangles and groups (its centre square and four arms), flat at z = 0."""
    c = CROSS
    n = int(round(c["length"] / c["cell"]))
    w = int(round(c["width"] / c["cell"]))
    lo = (n - w) // 2
    grid = np.full((n + 1, n + 1), -1)
    vertices, tris, groups = [], [], {}

    def cell_group(i, j):
        inside_x, inside_y = lo <= i < lo + w, lo <= j < lo + w
        if inside_x and inside_y:
            return "centre"
        if inside_y:
            return "arm_front" if i >= lo + w else "arm_back"
        if inside_x:
            return "arm_left" if j >= lo + w else "arm_right"
        return None

    for i in range(n):
        for j in range(n):
            group = cell_group(i, j)
            if group is None:
                continue
            corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]
            for a, b in corners:
                if grid[a, b] < 0:
                    grid[a, b] = len(vertices)
                    vertices.append((a * c["cell"] - 0.5 * c["length"], b * c["cell"] - 0.5 * c["length"], 0.0))
            v = [grid[a, b] for a, b in corners]
            # alternate the diagonals so that the cloth has no grain
            pair = [(v[0], v[1], v[2]), (v[0], v[2], v[3])] if (i + j) % 2 else [(v[0], v[1], v[3]), (v[1], v[2], v[3])]
            groups.setdefault(group, []).extend(range(len(tris), len(tris) + 2))
            tris += pair
    return np.array(vertices, dtype=np.float64), np.array(tris), {k: np.array(v) for k, v in groups.items()}


def arm_tip_corners(vertices: np.ndarray) -> np.ndarray:
    """The cross canopy's eight arm-tip corners (where its suspension lines are sewn), as vertex indices."""
    half, w = 0.5 * CROSS["length"], 0.5 * CROSS["width"]
    x, y = vertices[:, 0], vertices[:, 1]
    along_x = np.isclose(np.abs(x), half) & np.isclose(np.abs(y), w)
    along_y = np.isclose(np.abs(y), half) & np.isclose(np.abs(x), w)
    tip = along_x | along_y
    return np.flatnonzero(tip)


EXPORTED = ("kite.toml", "hang_glider.toml", "parachute.toml")
"""The shipped scenes whose objects are shipped exported (``exported_kite.toml``, ...): issue 58's round trips."""


def export_builtins(out: Path) -> list[Path]:
    """Export the shipped scenes :data:`EXPORTED` with ``warpsim export`` into ``out`` (``exported_kite.obj`` and
    its structure file, ...); their scenes go to ``out``'s parent, naming the files in ``out`` by their folder's
    name, when ``out`` is this script's folder (the shipped scenes), else beside them. Returns the scenes written.
    (The command is run, not imported: this script sits in the scene layer, below the exporter.)"""
    import subprocess
    import sys

    written = []
    for name in EXPORTED:
        mesh = out / f"exported_{Path(name).stem}.obj"
        command = [sys.executable, "-m", "warpsim", "export", str(HERE.parent / name), str(mesh), "--force"]
        subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
        scene = mesh.with_suffix(".toml")
        if out.resolve() == HERE:
            text = scene.read_text(encoding="utf-8")
            title = (
                f"# The {Path(name).stem} scene flown from its export (designs/{mesh.name} and its structure file): "
                "issue 58's round trip, the built-in's figures from the files.\n"
            )
            text = title + text
            for path in (mesh, mesh.with_name(mesh.stem + ".structure.toml")):
                text = text.replace(f'"{path.name}"', f'"{HERE.name}/{path.name}"')
            scene.unlink()
            scene = HERE.parent / scene.name
            scene.write_text(text, encoding="utf-8")
        written.append(scene)
    return written


def main(argv: list[str] | None = None) -> None:
    """Write both files (beside this script, or to ``--out DIR``) and print the vertex indices the scenes name."""
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=HERE, help="the folder to write to (default: beside this script)")
    out = parser.parse_args(argv).out
    if not out.is_dir():
        parser.error(f"--out {out}: no such folder")
    v, t, g = diamond_kite()
    write_mesh(out / "diamond_kite.obj", v, t, g)
    print(f"diamond_kite.obj: {len(v)} vertices, {len(t)} triangles")
    v, t, g = cross_canopy()
    write_mesh(out / "cross_canopy.glb", v, t, g)
    print(f"cross_canopy.glb: {len(v)} vertices, {len(t)} triangles; arm-tip corners {arm_tip_corners(v).tolist()}")
    for scene in export_builtins(out):
        print(f"{scene.name}: flies {scene.stem.removeprefix('exported_')}.toml's object from its exported files")


if __name__ == "__main__":
    main()
