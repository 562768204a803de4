"""Every scene file runs; bad descriptors give one clear message naming the file and key."""

from pathlib import Path

import numpy as np
import pytest

from warpsim.cli import main
from warpsim.run.simulation import Simulation
from warpsim.scene.descriptor import defaults, load_text, resolve

SCENES = sorted((Path(__file__).resolve().parent.parent / "scenes").glob("*.toml"))


def test_there_are_scenes():
    assert {p.stem for p in SCENES} >= {"flag", "hang_glider", "parachute", "parachute_no_hoop"}


@pytest.mark.parametrize("path", SCENES, ids=[p.stem for p in SCENES])
def test_scene_runs_two_seconds_without_nan(path):
    descriptor, _, where = resolve(str(path))
    sim = Simulation(descriptor, where=where)
    sim.step(int(round(2.0 / sim.dt)))
    assert np.isfinite(sim.state.positions()).all()


@pytest.mark.parametrize(
    "text, expected",
    [
        ("[flag]\nresolutoin = 4\n", "unknown key flag.resolutoin (did you mean 'resolution'?)"),
        ("[flag]\nresolution = 'four'\n", "flag.resolution must be a whole number"),
        ("[flag]\nresolution = 0\n", "flag.resolution = 0 must be >= 2"),
        ("[flag]\nmass_per_area = -1.0\n", "flag.mass_per_area = -1.0 must be > 0.0"),
        ('[scene]\nobject = "kitten"\n', "scene.object = 'kitten' is not one of"),
        ('[air]\nmodel = "magic"\n', "air.model = 'magic' is not one of paper, plate"),
        ("[solvr]\ndt = 0.01\n", "unknown section [solvr] (did you mean 'solver'?)"),
        ("[solver\n", "not valid TOML"),
        ('[scene]\nobject = "parachute"\n[parachute]\nperson_mass = -80.0\n', "parachute.person_mass"),
    ],
)
def test_bad_descriptor_messages(tmp_path, capsys, text, expected):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match="bad.toml"):
        load_text(text, str(path))
    assert main(["run", str(path), "--seconds", "0.1"]) == 2
    err = capsys.readouterr().err.strip()
    assert expected in err and str(path) in err
    assert len(err.splitlines()) == 1


@pytest.mark.parametrize("name", ["hang-glider", "kite"])
def test_delta_objects_are_built_mirror_symmetric(name):
    """The sail, frame and pilot/rope map exactly onto their mirror images across the keel plane, so any
    turn the object makes comes from its flight dynamics (seeded by rounding), not from its mesh."""
    sim = Simulation(defaults(name))
    model, rec = sim.model, sim.model.objects[0]
    q = sim.state.positions().astype(np.float64)
    tip_l, tip_r = q[rec.tips[0]], q[rec.tips[1]]
    left = (tip_l - tip_r) / np.linalg.norm(tip_l - tip_r)
    mirrored = q - 2.0 * np.outer((q - 0.5 * (tip_l + tip_r)) @ left, left)
    dist = np.linalg.norm(mirrored[:, None, :] - q[None, :, :], axis=2)
    image = dist.argmin(axis=1)
    assert dist.min(axis=1).max() < 1e-4  # float32 positions
    assert not np.array_equal(image, np.arange(len(q)))  # the mirror really swaps the two halves
    ends = model.stick_particles_np
    assert {tuple(e) for e in np.sort(ends, axis=1)} == {tuple(e) for e in np.sort(image[ends], axis=1)}
    tris = model.tri_indices.numpy()
    assert {tuple(sorted(t)) for t in tris} == {tuple(sorted(t)) for t in image[tris]}
    mass = np.asarray(model.particle_mass)
    np.testing.assert_array_equal(mass, mass[image])
    rest = sim.control.stick_rest.numpy()
    index = {tuple(e): i for i, e in enumerate(np.sort(ends, axis=1))}
    mirror_rest = rest[[index[tuple(e)] for e in np.sort(image[ends], axis=1)]]
    np.testing.assert_allclose(rest, mirror_rest, rtol=1e-6)


def test_a_scene_is_one_typed_read_only_value_that_simulation_takes():
    """`warpsim.Scene`: the object, its config, the step, the worlds and their varied values, typed; what it hands
    out are copies (the scene cannot be changed through them); a change is a new, checked scene; a simulation of
    it flies as one of its descriptor, bit for bit."""
    import numpy as np
    import pytest

    import warpsim
    from warpsim.scene.descriptor import DescriptorError

    scene = warpsim.Scene.load("kite")
    assert (scene.kind, scene.section, scene.dt, scene.world_count) == ("kite", "kite", 0.0025, 1)
    assert scene.object_config().tow_point == 0.47 and scene.settings.wind.velocity[0] == 6.0
    tables = scene.descriptor()
    tables["kite"]["tow_point"] = 0.1
    assert scene.object_config().tow_point == 0.47  # a copy
    batch = scene.with_values({"worlds": {"count": 2, "kite": {"tow_point": [0.3, 0.4]}}}, "two kites")
    assert batch.world_count == 2 and batch.varied == {"kite.tow_point": [0.3, 0.4]}
    assert batch.object_config(1).tow_point == 0.4 and batch.world(1).object_config().tow_point == 0.4
    assert scene.world_count == 1  # the first is unchanged
    with pytest.raises(DescriptorError, match="tow_pont"):
        scene.with_values({"kite": {"tow_pont": 0.3}})
    a, b = warpsim.Simulation(scene), warpsim.Simulation(scene.descriptor())
    a.step(200)
    b.step(200)
    np.testing.assert_array_equal(a.state.positions(), b.state.positions())
    assert a.scene.kind == "kite" and a.descriptor == b.descriptor


def test_a_misspelt_wind_key_names_wind_speed_too():
    """`wind.speed` is a key of `[worlds]` and `[sweep]` only (it scales `wind.velocity`), so a misspelt `[wind]`
    key's one-line error names it beside the section's fields (a newcomer's trial looked for it there)."""
    import pytest

    from warpsim.scene.descriptor import DescriptorError, defaults, merge

    with pytest.raises(DescriptorError, match=r"did you mean .*velocity.*wind\.speed \[m/s\]") as err:
        merge("--set", defaults("kite"), {"wind": {"velocty": [3.0, 0.0, 0.0]}})
    assert "\n" not in str(err.value)
