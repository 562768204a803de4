"""Hostile input found by hand: each ends in one short error line and exit code 2, within seconds."""

import os
import time

import numpy as np
import pytest

from warpsim.cli import EXIT_USAGE, MAX_LINE, main
from warpsim.run.simulation import Simulation
from warpsim.scene.descriptor import defaults, merge


def _refused(capsys, argv, *words):
    start = time.monotonic()
    assert main([str(a) for a in argv]) == EXIT_USAGE
    assert time.monotonic() - start < 30
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("warpsim ") and len(err[0]) <= MAX_LINE + 60, err
    for word in words:
        assert word in err[0], err
    return err[0]


SCENES = {
    "object_list": ("[scene]\nobject = [1, 2]\n", "scene.object = [1, 2] is not one of"),
    "deep": ("[scene]\nobject = 'kite'\n[kite]\nspan = " + "[" * 500 + "]" * 500 + "\n", "nested"),
    "amplitude": ("[scene]\nobject = 'kite'\n[terrain]\nkind = 'procedural'\namplitude = 1e29\n", "terrain.amplitude"),
    "anchor": ("[scene]\nobject = 'kite'\n[[controls]]\ntime = 0.0\nanchor = [1e308, 0]\n", "anchor components"),
    "wind": ("[scene]\nobject = 'kite'\n[[controls]]\ntime = 0.0\nwind = [0, 1e300, 0]\n", "wind components"),
    "huge_value": ("[scene]\nobject = 'kite'\n[kite]\nspan = '" + "x" * 5_000_000 + "'\n", "may hold at most"),
    "worlds": ("[scene]\nobject = 'kite'\n[worlds]\ncount = 65536\n", "is more than the 1,048,576"),
    "flag": ("[scene]\nobject = 'flag'\n[flag]\nresolution = 2048\n", "is more than the 1,048,576"),
}


@pytest.mark.parametrize("name", sorted(SCENES))
def test_hostile_descriptors(name, tmp_path, capsys):
    text, word = SCENES[name]
    scene = tmp_path / f"{name}.toml"
    scene.write_text(text)
    _refused(capsys, ["run", scene, "--seconds", "0.05"], word)


def test_fps_too_low_for_a_recording(tmp_path, capsys):
    _refused(capsys, ["run", "kite", "--fps", "1e-20", "--h5", tmp_path / "f.h5"], "scene.fps")
    assert list(tmp_path.iterdir()) == []


def _terrain(tmp_path, name, make):
    path = tmp_path / f"{name}.npy"
    make(path)
    scene = tmp_path / f"{name}.toml"
    scene.write_text(f"[scene]\nobject = 'kite'\nseconds = 0.05\n[terrain]\nkind = 'file'\nfile = '{path}'\n")
    return scene


def _lying_header(path):
    """A header announcing 3,000 x 3,000 float64 heights (72 MB), then 16 bytes."""
    with open(path, "wb") as f:
        header = {"descr": "<f8", "fortran_order": False, "shape": (3000, 3000)}
        np.lib.format.write_array_header_1_0(f, header)
        f.write(bytes(16))


TERRAINS = {
    "strings": (lambda p: np.save(p, np.array([["a", "b"], ["c", "d"]])), "real numbers"),
    "complex": (lambda p: np.save(p, np.ones((4, 4), complex)), "real numbers"),
    "objects": (lambda p: np.save(p, np.array([[None, 1], [2, 3]], dtype=object), allow_pickle=True), "real numbers"),
    "nan": (lambda p: np.save(p, np.full((4, 4), np.nan)), "finite"),
    "one_d": (lambda p: np.save(p, np.zeros(16)), "2-D"),
    "header_lies": (_lying_header, "header announces"),
    "fifo": (lambda p: os.mkfifo(p), "not a regular file"),
    "text": (lambda p: p.write_text("hills"), "not a .npy array"),
}


@pytest.mark.parametrize("name", sorted(TERRAINS))
def test_hostile_terrain_files(name, tmp_path, capsys):
    make, word = TERRAINS[name]
    _refused(capsys, ["run", _terrain(tmp_path, name, make)], "terrain.file", word)


def test_a_good_terrain_file_and_a_bom_are_taken(tmp_path, capsys):
    scene = _terrain(tmp_path, "good", lambda p: np.save(p, np.linspace(0, 5, 64).reshape(8, 8).astype(np.float32)))
    scene.write_bytes(b"\xef\xbb\xbf" + scene.read_bytes())  # a byte-order mark, as some editors write
    assert main(["run", str(scene), "--quiet"]) == 0


def test_model_build_is_linear_in_nails():
    """100,000 nails (a 2 x 100,000 flag): the nail check was a list search, 79 s; now a set."""
    # the paper's flag: with bending, cells this small would need a step of ~1e-12 s
    d = merge("test", defaults("flag"), {"flag": {"design": "paper"}})
    d["flag"].update(resolution=2, width=5e-6, height=0.05)
    start = time.monotonic()
    sim = Simulation(d)
    assert sim.model.nail_count >= 10_000
    assert time.monotonic() - start < 60


def test_a_huge_scene_or_stored_descriptor_is_one_line(tmp_path, capsys):
    """An 8 MB scene file (hundreds of thousands of controls) or a 20 MB descriptor stored in a recording kept every
    command busy for minutes: a descriptor holds at most MAX_TEXT characters, refused in one line, exit 2."""
    from warpsim.cli import main
    from warpsim.scene.descriptor import MAX_TEXT

    big = tmp_path / "big.toml"
    rows = "".join(f"[[controls]]\ntime = {k}.0\nwind = [4.0, 0.0, 0.0]\n" for k in range(MAX_TEXT // 40))
    big.write_text('[scene]\nobject = "kite"\n' + rows)
    assert big.stat().st_size > MAX_TEXT
    for argv in (["info", str(big)], ["run", str(big), "--seconds", "0.01"]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert "at most" in err and err.count("\n") == 1, err
