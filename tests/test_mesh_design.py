"""Designs of the user's own from mesh files (issue 58): reading every format with its groups, one line for every bad
mesh or part, the model the builder makes (sticks on edges, masses by area, bending, rigid spars, a line, point
masses and their keys), the shipped designs in flight, and export and back."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from warpsim import Scene
from warpsim.cli import EXIT_USAGE, main
from warpsim.objects import mesh as mesh_design
from warpsim.objects.mesh_file import MeshError, mesh_edges, read_mesh, write_mesh
from warpsim.physics.builder import ModelBuilder
from warpsim.run.simulation import Simulation
from warpsim.scene import descriptor
from warpsim.scene.build import build_model

SCENES = Path(__file__).resolve().parents[1] / "scenes"


def _square(n: int = 4, size: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """A flat square of ``n`` x ``n`` cells in the xy-plane, two triangles a cell."""
    xs = np.linspace(-size / 2, size / 2, n + 1)
    v = np.array([(x, y, 0.0) for y in xs for x in xs])
    t = []
    for j in range(n):
        for i in range(n):
            a, b, c, d = j * (n + 1) + i, j * (n + 1) + i + 1, (j + 1) * (n + 1) + i + 1, (j + 1) * (n + 1) + i
            t += [(a, b, c), (a, c, d)]
    return v, np.array(t)


def _scene(tmp_path: Path, mesh_file: str, mesh_keys: str = "", parts: str = "") -> Path:
    path = tmp_path / "design.toml"
    if "position" not in mesh_keys:
        mesh_keys += "\nposition = [0.0, 0.0, 5.0]"
    path.write_text(
        f'[scene]\nobject = "mesh"\nseconds = 0.5\n[mesh]\nfile = "{mesh_file}"\n{mesh_keys}\n{parts}',
        encoding="utf-8",
    )
    return path


def _one_error(capsys, argv) -> str:
    assert main(argv) == EXIT_USAGE
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


# ---------------------------------------------------------------------------------------------------------- reading
def test_every_format_reads_the_same_surface_with_its_groups(tmp_path):
    v, t = _square(4)
    groups = {"front": np.arange(0, 16), "back": np.arange(16, 32)}
    for suffix in (".obj", ".glb", ".stl"):
        write_mesh(tmp_path / f"s{suffix}", v, t, groups)
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.CreateNew(str(tmp_path / "s.usda"))
    UsdGeom.SetStageMetersPerUnit(stage, 0.01)
    for name, ids in groups.items():  # two prims, the second moved by its transform
        prim = UsdGeom.Mesh.Define(stage, f"/World/{name}")
        prim.CreatePointsAttr([tuple(p * 100.0) for p in v])
        prim.CreateFaceVertexCountsAttr([3] * len(ids))
        prim.CreateFaceVertexIndicesAttr([int(i) for i in t[ids].reshape(-1)])
    UsdGeom.Xformable(stage.GetPrimAtPath("/World/back")).AddTranslateOp().Set((0.0, 0.0, 0.0))
    stage.GetRootLayer().Save()

    area = 1.0
    for suffix in (".obj", ".glb", ".stl", ".usda"):
        m = read_mesh(tmp_path / f"s{suffix}")
        scale = m.meters_per_unit or 1.0
        assert len(m.vertices) == 25 and len(m.triangles) == 32, suffix
        a = np.cross(
            m.vertices[m.triangles[:, 1]] - m.vertices[m.triangles[:, 0]],
            m.vertices[m.triangles[:, 2]] - m.vertices[m.triangles[:, 0]],
        )
        assert 0.5 * np.linalg.norm(a, axis=1).sum() * scale**2 == pytest.approx(area, rel=1e-9), suffix
        if suffix != ".stl":  # STL has no groups
            assert sorted(m.groups) == ["back", "front"], suffix
            assert {k: len(ids) for k, ids in m.groups.items()} == {"front": 16, "back": 16}, suffix
    obj = read_mesh(tmp_path / "s.obj")
    np.testing.assert_array_equal(obj.vertices, v)  # OBJ keeps the file's numbering
    np.testing.assert_array_equal(obj.triangles, t)
    assert read_mesh(tmp_path / "s.usda").meters_per_unit == pytest.approx(0.01)


def test_bad_meshes_are_refused_in_one_line(tmp_path):
    v, t = _square(2)
    cases = {
        "degenerate": (v, np.vstack([t[:-1], [[0, 1, 2]]]), "no area"),
        "twice": (v, np.vstack([t, t[:1]]), "appears twice"),
        "non-manifold": (
            np.vstack([v, [[0.0, 0.0, 1.0]]]),
            np.vstack([t, [[t[0][1], t[0][2], len(v)]]]),  # a fin on the inner edge (1, 4)
            "non-manifold",
        ),
    }
    for name, (vertices, tris, message) in cases.items():
        path = tmp_path / f"{name}.obj"
        write_mesh(path, vertices, tris, {"all": np.arange(len(tris))})
        with pytest.raises(MeshError, match=message) as err:
            read_mesh(path)
        assert "\n" not in str(err.value) and str(path) in str(err.value)
    with pytest.raises(MeshError, match="not found"):
        read_mesh(tmp_path / "missing.obj")
    (tmp_path / "junk.glb").write_bytes(b"not a glTF file at all")
    with pytest.raises(MeshError, match="cannot be read|no triangles"):
        read_mesh(tmp_path / "junk.glb")
    with pytest.raises(MeshError, match="not a mesh file"):
        read_mesh(tmp_path / "design.dxf")


def test_bad_scenes_of_mesh_designs_get_one_line_each(tmp_path, capsys):
    v, t = _square(4)
    write_mesh(tmp_path / "sq.obj", v, t, {"sail": np.arange(len(t))})
    cases = [
        ("", "", "mesh.file is required"),
        ("missing.obj", "", "mesh file not found"),
        ("sq.obj", 'units = "mm"', "spans 0.001 m"),
        ("sq.obj", "scale = 2000.0", "spans 2e+03 m"),
        ("sq.obj", "", '[[mesh.parts]]\nkind = "spar"\nbox = [5.0, 5.0, 5.0, 6.0, 6.0, 6.0]\n', "selects no vertex"),
        ("sq.obj", "", '[[mesh.parts]]\nkind = "spar"\ngroup = "spine"\n', "no group 'spine'"),
        ("sq.obj", "", '[[mesh.parts]]\nkind = "line"\nvertices = [0]\n', "needs anchor"),
        ("sq.obj", "", '[[mesh.parts]]\nkind = "line"\nvertices = [0, 1]\nanchor = [0.0, 0.0]\n', "bridle"),
        (
            "sq.obj",
            "",
            '[[mesh.parts]]\nkind = "mass"\nvertices = [0]\nmass = 1.0\nposition = [0.0, 0.0, -1.0]\ncolour = "red"\n',
            "unknown key 'colour'",
        ),
        ("sq.obj", "", '[[mesh.parts]]\nkind = "nail"\nvertices = [99]\n', "vertex 99 does not exist"),
        ("sq.obj", "", '[[mesh.parts]]\nkind = "strut"\nvertices = [0]\n', "kind = 'strut'"),
        ("sq.obj", "", '[[mesh.parts]]\nkind = "nail"\nvertices = [0]\nbox = [0, 0, 0, 1, 1, 1]\n', "exactly one"),
        ("sq.obj", "position = [0.0, 0.0, 0.1]\nrotation = [90.0, 0.0, 0.0]", "below the terrain"),
    ]
    for entry in cases:
        file, keys, *rest = entry
        parts, message = (rest[0], rest[1]) if len(rest) == 2 else ("", rest[0])
        scene = _scene(tmp_path, file, keys, parts)
        line = _one_error(capsys, ["info", str(scene)])
        assert message in line, (entry, line)


# ---------------------------------------------------------------------------------------------------------- the model
def test_the_cloth_is_a_stick_on_every_edge_with_masses_by_area(tmp_path):
    v, t = _square(4, size=2.0)
    write_mesh(tmp_path / "sq.obj", v, t, {"sail": np.arange(len(t))})
    d = descriptor.resolve(str(_scene(tmp_path, "sq.obj", "mass_per_area = 0.2")))[0]
    model = build_model(d)
    edges, _ = mesh_edges(t)
    assert model.particle_count == 25 and model.stick_count == len(edges) and model.tri_count == len(t)
    mass = model.particle_free_mass
    assert mass.sum() == pytest.approx(0.2 * 4.0, rel=1e-12)
    assert mass[4] == pytest.approx(0.2 * 0.125 / 3.0)  # a corner holds a third of its one triangle (0.125 m^2)
    assert mass[0] == pytest.approx(0.2 * 2 * 0.125 / 3.0)  # the corner the cells' diagonals start from: two
    assert mass[12] == pytest.approx(0.2 * 6 * 0.125 / 3.0)  # an inner vertex, six triangles


def test_bending_hinges_store_a_plates_energy_in_a_bend():
    """A flat strip bent to a cylinder of radius R stores B/2 kappa^2 per area (closed form), on a mesh of any
    triangle orientation: the hinges' energy approaches it as the mesh is refined (the strip's two long edges, whose
    half cells have no hinge, fall off as 1/n)."""
    ratios = []
    for n in (8, 16, 32):
        xs, ys = np.linspace(0.0, 0.5, n // 2 + 1), np.linspace(0.0, 1.0, n + 1)
        v = np.array([(x, y, 0.0) for y in ys for x in xs])
        nx, t = len(xs), []
        for j in range(n):
            for i in range(nx - 1):
                a, b, c, d = j * nx + i, j * nx + i + 1, (j + 1) * nx + i + 1, (j + 1) * nx + i
                t += [(a, b, c), (a, c, d)] if (i + j) % 2 else [(a, b, d), (b, c, d)]
        t = np.array(t)
        builder = ModelBuilder()
        for p in v:
            builder.add_particle(p, 1.0)
        edges, held = mesh_edges(t)
        mesh_design._add_bending(builder, np.arange(len(v)), v, t, edges, held, 0.3, np.zeros(len(v), bool))
        radius = 2.0
        bent = np.c_[v[:, 0], radius * np.sin(v[:, 1] / radius), radius * (1.0 - np.cos(v[:, 1] / radius))]
        energy = 0.0
        for ids, w, k in zip(builder.hinge_particles, builder.hinge_weights, builder.hinge_stiffness, strict=True):
            c = sum(wi * bent[i] for i, wi in zip(ids, w, strict=True))
            energy += 0.5 * k * float(c @ c)
        flat = sum(
            wi * v[i]
            for ids, w in zip(builder.hinge_particles, builder.hinge_weights, strict=True)
            for i, wi in zip(ids, w, strict=True)
        )
        assert np.abs(flat).max() < 1e-9  # no force in the flat rest shape
        ratios.append(energy / (0.5 * 0.3 / radius**2 * 0.5))
    assert ratios[-1] == pytest.approx(1.0, abs=0.04)
    assert abs(1.0 - ratios[-1]) < abs(1.0 - ratios[1]) < abs(1.0 - ratios[0])


def test_a_weight_shift_sets_the_hanging_sticks_and_the_keys_walk_a_line(tmp_path):
    v, t = _square(4, size=2.0)
    write_mesh(tmp_path / "sq.obj", v, t, {"sail": np.arange(len(t))})
    parts = (
        '[[mesh.parts]]\nkind = "mass"\nvertices = [0, 4, 20, 24]\nmass = 2.0\nposition = [0.0, 0.0, -1.0]\n'
        "shift = [0.2, 0.3]\n"
        '[[mesh.parts]]\nkind = "line"\nvertices = [12]\nanchor = [-3.0, 0.0]\nlength = 8.0\nsegments = 4\n'
    )
    d = descriptor.resolve(str(_scene(tmp_path, "sq.obj", "", parts)))[0]
    model = build_model(d)
    record = model.objects[0]
    assert record.anchor_nail >= 0 and len(record.shift_sticks) == 4
    rest = model.stick_rest.numpy().astype(np.float64)
    rope = record.stick_groups["rope"]
    assert rest[rope].sum() == pytest.approx(8.0, rel=1e-6)
    targets = {"stick_rest": rest.copy(), "nail_target": model.nail_target0.copy(), "terrain": model.terrain}
    mesh_design.apply_controls(record, targets, {"pitch": 1.0, "roll": 1.0, "anchor": (4.0, 1.0)})
    q0 = model.particle_q0
    payload = q0[record.payload] + np.array([0.2, -0.3, 0.0])  # forward 0.2 m, right (-y) 0.3 m
    for s, corner in zip(record.shift_sticks, (0, 4, 20, 24), strict=True):
        assert targets["stick_rest"][s] == pytest.approx(np.linalg.norm(q0[corner] - payload), rel=1e-9)
    np.testing.assert_allclose(targets["nail_target"][record.anchor_nail], (4.0, 1.0, 0.0))
    # the viewer offers the arrows for a design with shifting masses, and not for one without (they did nothing there)
    from warpsim.viewer import NullBackend, Viewer

    plain = descriptor.resolve("diamond_kite", [SCENES])[0]
    offered = {}
    for name, scene in (("shifting", d), ("plain", plain)):
        viewer = Viewer(Simulation(scene), NullBackend(), say=lambda line: None)
        offered[name] = [b.control for b in viewer.axis_keys], viewer.walk_keys is not None
        viewer.close()
    assert offered == {"shifting": (["pitch", "roll"], True), "plain": ([], True)}


# ---------------------------------------------------------------------------------------------------------- flights
def _flight(name: str, seconds: float, overrides: dict | None = None):
    d = descriptor.resolve(name, [SCENES])[0]
    d = descriptor.merge("test", d, overrides or {})
    sim = Simulation(d)
    record = sim.model.objects[0]
    rows = []

    def on_frame(frame):
        rows.append((frame.time, frame.positions.copy()))

    sim.run(seconds, on_frame=on_frame)
    return sim, record, rows


def test_the_diamond_kite_flies_steady_on_its_rigid_frame():
    sim, record, rows = _flight("diamond_kite", 30.0)
    spar = [i for i in record.particles if i in set(record.stick_groups["frame"].tolist())]
    q0 = sim.model.particle_q0
    frame_ids = np.unique(sim.model.stick_particles_np[record.stick_groups["frame"]].reshape(-1))
    late = [q for t, q in rows if t >= 15.0]
    angles = []
    for q in late:
        d = q[record.tow] - q[record.anchor_particle]
        angles.append(np.degrees(np.arctan2(d[2], np.hypot(d[0], d[1]))))
        moved = np.linalg.norm(q[frame_ids][:, None] - q[frame_ids][None], axis=2)
        built = np.linalg.norm(q0[frame_ids][:, None] - q0[frame_ids][None], axis=2)
        assert np.abs(moved - built).max() < 0.01 * built.max()  # the frame holds its shape within 1 %
    assert spar
    angles = np.array(angles)
    assert 30.0 < angles.mean() < 60.0 and angles.std() < 2.0  # aloft and steady (docs/designs.md: 45.1 deg)
    sideways = np.array([q[record.parts["cloth"]].mean(axis=0)[1] for q in late])
    assert np.ptp(sideways) < 3.0


def test_the_cross_canopy_inflates_and_descends_at_a_steady_rate():
    sim, record, rows = _flight("cross_canopy", 12.0)
    t = np.array([t for t, _ in rows])
    z = np.array([q[record.payload][2] for _, q in rows])
    late = t >= 6.0
    rate = -np.polyfit(t[late], z[late], 1)[0]
    residual = z[late] - np.polyval(np.polyfit(t[late], z[late], 1), t[late])
    assert 4.5 < rate < 7.5 and np.abs(residual).max() < 0.5  # docs/designs.md: 5.87 m/s, C_D0 0.56
    cloth = record.parts["cloth"]
    q = rows[-1][1]
    assert q[cloth][:, 2].min() > q[record.payload][2] + 0.5  # the canopy above its payload


# ---------------------------------------------------------------------------------------------------------- export
@pytest.mark.parametrize("suffix", [".obj", ".glb"])
def test_export_as_parts_writes_the_cloth_and_a_scene_that_builds_it_again(tmp_path, capsys, suffix):
    """``--parts``: the model read off as [[mesh.parts]], a design to edit, which says what it leaves out."""
    out = tmp_path / f"kite{suffix}"
    assert main(["export", "kite", str(out), "--parts"]) == 0
    said = capsys.readouterr().out
    assert "kite.toml" in said and "left out" in said
    # what the written scene, built again, lacks is said too (the kite's tuned air: why it lands)
    assert "per-triangle air coefficients" in said and "sweep" in said and "drag bodies" in said, said
    built = build_model(descriptor.defaults("kite"))
    scene = descriptor.resolve(str(tmp_path / "kite.toml"))[0]
    again = build_model(scene)
    assert again.tri_count == built.tri_count
    cloth = np.unique(built.tri_indices_np)
    cloth_again = np.unique(again.tri_indices_np)
    # the same cloth in the same place, triangle for triangle
    a = built.particle_q0[built.tri_indices_np].reshape(-1, 9)
    b = again.particle_q0[again.tri_indices_np].reshape(-1, 9)
    np.testing.assert_allclose(np.sort(a, axis=0), np.sort(b, axis=0), atol=1e-6)
    assert len(cloth) == len(cloth_again)
    record = again.objects[0]
    assert record.anchor_nail >= 0 and len(record.parts["rope"]) == len(built.objects[0].parts["rope"])
    # the line hangs from the tow point, where the built-in's does (a glTF once came back renumbered)
    first = built.particle_q0[built.objects[0].parts["rope"][0]]
    np.testing.assert_allclose(again.particle_q0[record.parts["rope"][0]], first, atol=1e-5)
    total = built.particle_free_mass.sum()
    assert again.particle_free_mass.sum() == pytest.approx(total, rel=0.02)
    assert not (tmp_path / "kite.structure.toml").exists()
    for name in ("x.dxf", "nowhere/x.obj"):
        line = _one_error(capsys, ["export", "kite", str(tmp_path / name)])
        assert "x." in line


def test_a_mesh_design_exported_and_read_back_flies_the_same(tmp_path):
    """The round trip of a design of one's own: exported by warpsim, read back, it is the same model and flies the
    same figures."""
    d = descriptor.resolve("diamond_kite", [SCENES])[0]
    from warpsim.io.mesh_export import export_design

    _, scene, _ = export_design(Scene(d), tmp_path / "again.obj")
    back = descriptor.resolve(str(scene))[0]
    for desc in (d, back):
        desc["scene"]["seconds"] = 10.0
    figures = []
    for desc in (d, back):
        sim = Simulation(desc)
        tow, anchor = sim.model.objects[0].tow, sim.model.objects[0].anchor_particle
        q = []
        sim.run(10.0, on_frame=lambda f, q=q, a=tow, b=anchor: q.append(f.positions[a] - f.positions[b]))
        late = np.array(q[len(q) // 2 :])
        figures.append(np.degrees(np.arctan2(late[:, 2], np.hypot(late[:, 0], late[:, 1]))).mean())
    assert figures[1] == figures[0]  # the same model, particle for particle: the same flight, bit for bit


def test_info_list_and_a_sweep_over_the_cloth_work_for_mesh_scenes(tmp_path, capsys):
    assert main(["info", "diamond_kite"]) == 0
    out = capsys.readouterr().out
    assert "object: mesh" in out and "part cloth" in out and "part rope" in out
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    assert "mesh" in out and "diamond_kite" in out and "cross_canopy" in out
    d = descriptor.resolve("diamond_kite", [SCENES])[0]
    two = descriptor.merge("test", d, {"worlds": {"count": 2, "mesh": {"cloth_compliance": [0.0, 1e-3]}}})
    two["scene"]["seconds"] = 1.0
    sim = Simulation(two)
    assert sim.model.world_count == 2
    compliance = sim.model.stick_compliance
    cloth = [np.setdiff1d(r.stick_groups["cloth"], r.stick_groups["frame"]) for r in sim.model.objects]
    assert compliance[cloth[0]].max() == 0.0 and compliance[cloth[1]].min() == pytest.approx(1e-3)
    sim.run(1.0)


def test_an_obj_from_a_cad_tool_keeps_its_groups_and_numbering_and_a_gltf_stands_up(tmp_path):
    """Blender's OBJ has o blocks, materials, texture coordinates and maybe a stray vertex: groups and the file's own
    vertex numbers survive (trimesh 5.2 swapped the groups' names and renumbered). A glTF is y-up by its
    specification: it is read z-up."""
    text = """# a stray vertex first, then two panels
v 9 9 9
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 -1 0
vt 0 0
vt 1 0
vt 1 1
o left
usemtl cloth
f 2/1 3/2 4/3
f -5/1 -3/2 -2/3
o right
usemtl other
f 2//1 6//1 3//1
"""
    (tmp_path / "cad.obj").write_text(text, encoding="utf-8")
    m = read_mesh(tmp_path / "cad.obj")
    assert sorted(m.groups) == ["left", "right"]
    left = m.vertices[np.unique(m.triangles[m.groups["left"]])]
    assert left[:, 1].min() == 0.0 and m.vertices[m.triangles[m.groups["right"]]][:, :, 1].min() == -1.0
    assert m.file_index[0] == -1  # the stray vertex is on no triangle
    listed = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, -1, 0]]
    np.testing.assert_array_equal(m.vertices[m.file_index[1:]], listed)
    scene = _scene(tmp_path, "cad.obj", "scale = 0.5", '[[mesh.parts]]\nkind = "nail"\nvertices = [5]\n')
    model = build_model(descriptor.resolve(str(scene))[0])
    nailed = model.particle_q0[model.nail_particles[0]]
    np.testing.assert_allclose(nailed, [0.0, -0.5, 5.0])  # the file's vertex 5, (0, -1, 0), at half size
    scene = _scene(tmp_path, "cad.obj", "", '[[mesh.parts]]\nkind = "nail"\nvertices = [0]\n')
    with pytest.raises(Exception, match="vertex 0 is on no triangle"):
        build_model(descriptor.resolve(str(scene))[0])

    import trimesh

    flat = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 0, -1]], [[0, 1, 2]], process=False)  # y-up: lies in y = 0
    flat.export(tmp_path / "flat.glb")
    got = read_mesh(tmp_path / "flat.glb").vertices
    np.testing.assert_allclose(np.sort(got[:, 2]), [0.0, 0.0, 0.0], atol=1e-12)  # z-up: lies in z = 0
    np.testing.assert_allclose(np.sort(got[:, 1]), [0.0, 0.0, 1.0], atol=1e-12)  # glTF's -z is our +y


def test_more_bad_parts_get_one_line(tmp_path, capsys):
    v, t = _square(4)
    write_mesh(tmp_path / "sq.obj", v, t, {"sail": np.arange(len(t))})
    cases = [
        ("[[mesh.parts]]\nkind = [1]\nvertices = [0]\n", "is not one of"),
        ('[[mesh.parts]]\nkind = "nail"\nvertices = [99999999999999999999]\n', "vertex indices"),
        ('[[mesh.parts]]\nkind = "line"\nvertices = [0]\nanchor = [0.0, 0.0]\nmass_per_length = 0.0\n', "> 0"),
        ('[[mesh.parts]]\nkind = "line"\nvertices = [0]\nanchor = [0.0, 0.0]\nlength = 1e9\n', "at most"),
        ('[[mesh.parts]]\nkind = "line"\nvertices = [0]\nanchor = [0.0, 0.0]\nsegments = 100000\n', "1 to 1000"),
        ('[[mesh.parts]]\nkind = "mass"\nvertices = [0]\nmass = 1.0\nposition = [0.0, 0.0, -9.0]\n', "below"),
        ("parts = 5\n", "mesh.parts"),
    ]
    for parts, message in cases:
        keys, parts = (parts, "") if parts.startswith("parts") else ("", parts)
        line = _one_error(capsys, ["info", str(_scene(tmp_path, "sq.obj", keys, parts))])
        assert message in line, (parts, line)


def test_a_cloth_folded_back_on_itself_is_refused_for_bending(tmp_path, capsys):
    v = np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, 0.9, 0.001]], dtype=np.float64)
    write_mesh(tmp_path / "fold.obj", v, np.array([[0, 1, 2], [0, 1, 3]]), {"sail": np.arange(2)})
    line = _one_error(capsys, ["info", str(_scene(tmp_path, "fold.obj", "bending_stiffness = 0.01"))])
    assert "folds 180 deg" in line or "folds 179 deg" in line, line


@pytest.mark.dask
def test_a_sweep_over_a_mesh_designs_cloth_stiffness_runs(tmp_path, capsys):
    pandas = pytest.importorskip("pandas")
    out = tmp_path / "sweep.csv"
    argv = ["sweep", "diamond_kite", "--vary", "mesh.cloth_compliance=1e-5,1e-4", "--seconds", "2", "--out", str(out)]
    assert main([*argv, "--workers", "1"]) == 0
    table = pandas.read_csv(out)
    assert list(table["mesh.cloth_compliance"]) == [1e-5, 1e-4]
    assert table["line_angle_mean"].between(10.0, 80.0).all() and (table["line_pull_mean"] > 0.0).all()


def test_export_never_writes_over_what_it_reads_and_asks_before_replacing(tmp_path, capsys):
    """A newcomer's trial: `warpsim export square.toml square.obj` replaced the hand-written design it exported, and
    a second .gltf export to the folder replaced the first's buffer files."""
    assert main(["export", "kite", str(tmp_path / "k.obj")]) == 0
    before = (tmp_path / "k.obj").read_bytes(), (tmp_path / "k.toml").read_text()
    line = _one_error(capsys, ["export", "kite", str(tmp_path / "k.obj")])
    assert "exist already" in line and "--force" in line
    line = _one_error(capsys, ["export", str(tmp_path / "k.toml"), str(tmp_path / "k.obj"), "--force"])
    assert "is what the export reads" in line
    assert ((tmp_path / "k.obj").read_bytes(), (tmp_path / "k.toml").read_text()) == before  # nothing written
    assert main(["export", "kite", str(tmp_path / "k.obj"), "--force"]) == 0
    capsys.readouterr()
    # a scene found by name (./scenes) is never written over, even with --force
    scenes = tmp_path / "scenes"
    scenes.mkdir()
    (scenes / "mine.toml").write_text((tmp_path / "k.toml").read_text())
    (scenes / "k.obj").write_bytes((tmp_path / "k.obj").read_bytes())
    mine = (scenes / "mine.toml").read_text()
    cwd = os.getcwd()
    try:
        os.chdir(tmp_path)
        line = _one_error(capsys, ["export", "mine", str(scenes / "mine.obj"), "--force"])
    finally:
        os.chdir(cwd)
    assert "is what the export reads" in line and (scenes / "mine.toml").read_text() == mine
    # a folder in the way is one line before anything is written; a link is replaced, not written through
    (tmp_path / "dir.obj").mkdir()
    assert "is a folder" in _one_error(capsys, ["export", "kite", str(tmp_path / "dir.obj"), "--force"])
    (tmp_path / "target.toml").write_text("keep me")
    (tmp_path / "l.toml").symlink_to(tmp_path / "target.toml")
    assert "exists already" in _one_error(capsys, ["export", "kite", str(tmp_path / "l.obj")])
    assert main(["export", "kite", str(tmp_path / "l.obj"), "--force"]) == 0
    assert (tmp_path / "target.toml").read_text() == "keep me" and not (tmp_path / "l.toml").is_symlink()
    capsys.readouterr()
    # two glTF exports side by side, each whole in its own file
    assert main(["export", "kite", str(tmp_path / "a.gltf")]) == 0
    assert main(["export", "hang-glider", str(tmp_path / "b.gltf")]) == 0
    assert sorted(p.name for p in tmp_path.iterdir() if p.suffix == ".gltf" or p.suffix == ".bin") == [
        "a.gltf",
        "b.gltf",
    ]
    kite = build_model(descriptor.resolve(str(tmp_path / "a.toml"))[0])
    assert kite.tri_count == build_model(descriptor.defaults("kite")).tri_count
    # a mesh file named where a scene goes: one line saying what to do
    line = _one_error(capsys, ["run", str(tmp_path / "k.obj")])
    assert "a mesh file, not a scene" in line and "--set mesh.file=" in line


def test_an_exported_nailed_flag_keeps_its_free_mass(tmp_path):
    """The design's cloth takes its mass by area and its nails then hold theirs: the export spreads the free mass
    over the free cloth (the flag, nailed along its hoist, came back 3.1 % light)."""
    assert main(["export", "flag", str(tmp_path / "f.obj"), "--parts"]) == 0
    built = build_model(descriptor.defaults("flag"))
    again = build_model(descriptor.resolve(str(tmp_path / "f.toml"))[0])
    assert again.particle_free_mass.sum() == pytest.approx(built.particle_free_mass.sum(), rel=0.002)


def test_a_part_without_a_kind_a_misspelt_kind_an_empty_box_and_a_folder_get_one_line(tmp_path, capsys):
    """A newcomer's trial: `kind = None is not one of ...`, a box of several that selected nothing passed silently,
    and a folder named as the mesh was 'not found'."""
    v, t = _square(2)
    write_mesh(tmp_path / "sq.obj", v, t, {"cloth": np.arange(len(t))})

    def scene(parts: str, file: str = "sq.obj") -> str:
        path = tmp_path / "s.toml"
        path.write_text(f'[scene]\nobject = "mesh"\n[mesh]\nfile = "{file}"\n{parts}', encoding="utf-8")
        return str(path)

    line = _one_error(capsys, ["info", scene("[[mesh.parts]]\nvertices = [0]\n")])
    assert "needs a kind: one of" in line
    line = _one_error(capsys, ["info", scene('[[mesh.parts]]\nkind = "nial"\nvertices = [0]\n')])
    assert "did you mean 'nail'" in line
    boxes = "[[-1, -1, -1, 0.1, 0.1, 0.1], [5, 5, 5, 6, 6, 6]]"
    line = _one_error(capsys, ["info", scene(f'[[mesh.parts]]\nkind = "nail"\nbox = {boxes}\n')])
    assert "box 2 of 2 selects no vertex" in line
    (tmp_path / "folder.obj").mkdir()
    line = _one_error(capsys, ["info", scene("", "folder.obj")])
    assert "a folder, not a mesh file" in line
