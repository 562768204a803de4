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


def _recording(tmp_path_factory, scene: str, seconds: float, *extra: str):
    path = tmp_path_factory.mktemp("render") / f"{scene}.h5"
    assert main(["run", scene, "--seconds", str(seconds), "--h5", str(path), "--quiet", *extra]) == 0
    return path


@pytest.fixture(scope="module")
def kite_recording(tmp_path_factory):
    return _recording(tmp_path_factory, "kite", 3)


def test_picture_has_sky_horizon_ground_and_frames_the_objects(recording, tmp_path):
    """A blue sky at the top, a horizon, ground below it, the canopy drawn large in the middle (not a blob)."""
    out = tmp_path / "para.png"
    assert main(["render", str(recording), str(out), "--size", "320x180"]) == 0
    a = np.asarray(Image.open(out).convert("RGB")).astype(int)
    top, bottom = a[:5, 150:].reshape(-1, 3), a[-5:].reshape(-1, 3)
    assert (top[:, 2] > top[:, 0] + 40).all()  # sky blue
    assert (bottom[:, 1] > bottom[:, 2]).mean() > 0.9  # ground green (hazy)
    canopy = np.abs(a - np.array(COLOURS["canopy"]) * 255).max(axis=2) < 80
    rows, cols = np.nonzero(canopy)
    assert np.ptp(cols) > 0.2 * a.shape[1] and np.ptp(rows) > 0.2 * a.shape[0]  # not a blob: a fifth or more
    assert abs(cols.mean() - a.shape[1] / 2) < 0.15 * a.shape[1]


def test_kite_line_drawn_from_the_anchor_to_the_kite(kite_recording, tmp_path):
    from warpsim.io.recording import Recording
    from warpsim.io.render import Camera, Scene

    with Recording(kite_recording) as rec:
        scene = Scene(rec.build_model(), wide=True)  # the line down to the anchor in the picture
        q = scene.place(rec.positions(rec.frame_count - 1))
    camera = scene.fit([q], Camera(size=(320, 180)))
    a = np.asarray(scene.draw(q, camera).convert("RGB")).astype(int)
    rope = scene.model.objects[0].curves["rope"][0]
    xy, _ = camera.project(q[rope], scene.centre(q))
    dark = a.max(axis=2) < 90
    middles = (xy[1:] + xy[:-1]) / 2  # halfway along each segment
    hits = [dark[int(y) - 1 : int(y) + 2, int(x) - 1 : int(x) + 2].any() for x, y in middles[1:-1]]
    assert len(hits) >= 5 and all(hits), hits  # a line at least 2 pixels wide all along, however far the kite is


def test_default_camera_frames_the_kite_not_its_whole_line(kite_recording, tmp_path):
    """The kite (1.2 m) fills the picture by default (its 30 m line runs out of it); --wide frames the line too."""
    sail = np.array(COLOURS["sail"]) * 255
    spans = {}
    for flags in ((), ("--wide",)):
        out = tmp_path / f"kite{len(flags)}.png"
        assert main(["render", str(kite_recording), str(out), "--size", "320x180", *flags]) == 0
        a = np.asarray(Image.open(out).convert("RGB")).astype(int)
        _, cols = np.nonzero((np.abs(a - sail).max(axis=2) < 80) & (a[..., 0] < 70))  # the sky is blue but paler
        spans[flags] = np.ptp(cols) if len(cols) else 0
    assert spans[()] > 0.4 * 320 and spans[("--wide",)] < 0.15 * 320


def test_flag_pole_and_glider_frame_are_drawn(tmp_path_factory, tmp_path):
    from warpsim.io.recording import Recording
    from warpsim.io.render import Camera, Scene
    from warpsim.objects.drawing import POLE, TUBE

    for scene_name, colour in (("flag", POLE), ("hang-glider", TUBE)):
        path = _recording(tmp_path_factory, scene_name, 0.3)
        with Recording(path) as rec:
            scene = Scene(rec.build_model())
            q = scene.place(rec.positions(rec.frame_count - 1))
        camera = scene.fit([q], Camera(azimuth=-90.0, elevation=5.0, size=(480, 270)))
        a = np.asarray(scene.draw(q, camera).convert("RGB")).astype(int)
        assert _near(Image.fromarray(a.astype(np.uint8)), colour, tol=40) > 30, scene_name
        tubes = [t for t in scene.tubes if t[3] == colour]
        assert tubes and all(np.isfinite(q[[t[0], t[1]]]).all() for t in tubes)


def test_gif_frames_are_simulated_time_apart(kite_recording, tmp_path):
    """The kite records 30 frames a second: a GIF frame every 2 (66.7 ms of simulated time, shown 70 ms: GIF
    counts in 10 ms), not one frame every 420 ms."""
    from warpsim.io.recording import Recording

    out = tmp_path / "kite.gif"
    assert main(["render", str(kite_recording), str(out), "--size", "160x90"]) == 0
    gif = Image.open(out)
    with Recording(kite_recording) as rec:
        interval, count = rec.frame_interval, rec.frame_count
    stride = int(np.ceil(0.05 / interval - 1e-9))
    assert gif.n_frames == len(range(0, count, stride))
    assert gif.info["duration"] == 10 * round(100 * interval * stride) and gif.info["duration"] <= 100
