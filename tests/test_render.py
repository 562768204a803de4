"""Preview pictures: `warpsim render REC.h5 OUT.png|OUT.gif`."""

import numpy as np
import pytest
from PIL import Image

from warpsim.cli import main
from warpsim.io.render import Camera
from warpsim.io.usd import COLOURS


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    path = tmp_path_factory.mktemp("render") / "para.h5"
    assert main(["run", "parachute", "--seconds", "1", "--fps", "10", "--h5", str(path), "--quiet"]) == 0
    return path


def _near(image, rgb, tol=60):
    a = np.asarray(image.convert("RGB")).astype(int)
    return (np.abs(a - np.array(rgb) * 255).max(axis=2) < tol).sum()


def test_png_shows_the_canopy_and_the_person(recording, tmp_path):
    out = tmp_path / "para.png"
    assert main(["render", str(recording), str(out), "--size", "320x180"]) == 0
    image = Image.open(out)
    assert image.size == (320, 180)
    assert _near(image, COLOURS["canopy"]) > 500  # the canopy fills a good part of the picture
    assert _near(image, COLOURS["person"], tol=30) > 10
    first = tmp_path / "first.png"
    assert main(["render", str(recording), str(first), "--frame", "0", "--size", "320x180"]) == 0
    assert not np.array_equal(np.asarray(Image.open(first)), np.asarray(image))  # a different frame


def test_gif_has_every_frame(recording, tmp_path):
    out = tmp_path / "para.gif"
    assert main(["render", str(recording), str(out), "--size", "160x90"]) == 0
    gif = Image.open(out)
    assert gif.n_frames == 11  # 1 s at 10 fps plus the initial frame
    assert gif.info["duration"] == 100  # played at simulated speed [ms]


def test_frame_out_of_range(recording, tmp_path, capsys):
    assert main(["render", str(recording), str(tmp_path / "x.png"), "--frame", "99"]) == 2
    assert "frames 0..10" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []  # nothing half-written


def test_bad_size(recording, tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["render", str(recording), str(tmp_path / "x.png"), "--size", "10x10"])
    assert exc.value.code == 2 and "WIDTHxHEIGHT" in capsys.readouterr().err


def test_bad_render_paths(recording, tmp_path, capsys):
    assert main(["render", str(recording), str(tmp_path / "x.jpg")]) == 2
    assert "unknown picture extension" in capsys.readouterr().err
    assert main(["render", str(recording), str(tmp_path / "missing" / "x.png")]) == 2
    not_rec = tmp_path / "not.h5"
    not_rec.write_text("hello")
    assert main(["render", str(not_rec), str(tmp_path / "x.png")]) == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["not.h5"]


def test_camera_projects_right_up_and_depth():
    cam = Camera(azimuth=-90.0, elevation=0.0, distance=10.0, fov=90.0, size=(100, 100))  # looking along +y
    points = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [0.0, 0.0, 0.0]])
    xy, ahead = cam.project(points, np.zeros(3))
    # focal length 50 pixels (90 degrees over 100 pixels); the target 10 m ahead
    np.testing.assert_allclose(xy[0], [55.0, 50.0], atol=1e-9)  # +x is to the right
    np.testing.assert_allclose(xy[1], [50.0, 45.0], atol=1e-9)  # +z is up (image y down)
    np.testing.assert_allclose(xy[2], [50.0, 50.0], atol=1e-9)
    assert ahead[3] == pytest.approx(10.0) and ahead[2] == pytest.approx(9.0)  # -y is towards the viewer
    cam.distance = 20.0
    assert cam.project(np.array([[1.0, 0.0, 0.0]]), np.zeros(3))[0][0, 0] == pytest.approx(52.5)  # perspective
