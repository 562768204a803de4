"""`warpsim plot REC.h5 OUT.png --metric ...`: a recording's figures against time, and units on every plot axis."""

import numpy as np
import pytest

from warpsim.cli import main
from warpsim.io.recording import Recording

pytest.importorskip("matplotlib")
Image = pytest.importorskip("PIL.Image")

BLUE = np.array([0x1F, 0x77, 0xB4])  # matplotlib's first line colour


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    path = tmp_path_factory.mktemp("plot") / "para.h5"
    assert main(["run", "parachute", "--seconds", "3", "--h5", str(path), "--quiet"]) == 0
    return path


def test_recording_figures_are_the_recorded_ones_and_the_definitions(recording):
    """The plotted altitude is the recorder's own (the same mass centre); the sink is minus the altitude's rate of
    change over a frame (the definition of FIGURES['sink'] on flat ground); the parachute sinks at about 5-6 m/s."""
    from warpsim.sweeps.plot import recording_series

    time, series, names, kind = recording_series(recording, ["altitude", "sink", "radius", "worst_stretch"])
    assert kind == "parachute" and names == ["parachute"]
    with Recording(recording) as rec:
        altitude = rec.file["diagnostics/altitude"][: rec.frame_count, 0]
        stretch = rec.file["diagnostics/worst_stretch"][: rec.frame_count]
    np.testing.assert_allclose(series["altitude"][:, 0], altitude, rtol=0, atol=1e-9)
    np.testing.assert_allclose(series["worst_stretch"][:, 0], 100 * stretch.astype(float), rtol=1e-12)
    rate = -np.diff(altitude) / np.diff(time)
    np.testing.assert_allclose(series["sink"][1:, 0], rate, rtol=0, atol=1e-6)
    assert 4.0 < series["sink"][-1, 0] < 7.0 and series["radius"][-1, 0] > 2.0


def test_plot_png_has_a_line_per_panel(recording, tmp_path, capsys):
    out = tmp_path / "para.png"
    assert main(["plot", str(recording), str(out), "--metric", "altitude,sink"]) == 0
    assert f"-> {out}" in capsys.readouterr().out
    picture = np.asarray(Image.open(out).convert("RGB")).astype(int)
    line = np.abs(picture - BLUE).max(axis=2) < 40
    rows = np.flatnonzero(line.any(axis=1))
    h = picture.shape[0]
    # a line in each of the two panels (top and bottom half), running across most of the width
    for part in (rows[rows < h / 2], rows[rows >= h / 2]):
        assert len(part) > 20
        cols = np.flatnonzero(line[part].any(axis=0))
        assert cols.max() - cols.min() > 0.6 * picture.shape[1]


def test_plot_recording_errors_are_one_line(recording, tmp_path, capsys):
    assert main(["plot", str(recording), str(tmp_path / "x.png"), "--metric", "glide"]) == 2
    assert "a parachute recording has no such figure; it has altitude, airspeed, sink" in capsys.readouterr().err
    assert main(["plot", str(recording), str(tmp_path / "x.png"), "--metric", "radus"]) == 2
    assert "(did you mean 'radius'?)" in capsys.readouterr().err
    assert main(["plot", str(recording), str(tmp_path / "x.png"), "--metric", "sink", "--x", "wind.speed"]) == 2
    assert "drawn against time" in capsys.readouterr().err
    assert main(["plot", str(tmp_path / "t.csv"), str(tmp_path / "x.png"), "--metric", "sink"]) == 2
    assert "--x KEY" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_axis_units_of_swept_keys():
    from warpsim.sweeps.plot import axis_label, key_unit

    assert key_unit("wind.speed") == "m/s" and key_unit("kite.rope_length") == "m"
    assert key_unit("hang_glider.pilot_mass") == "kg" and key_unit("air.density") == "kg/m^3"
    assert key_unit("kite.tow_point") == "" and key_unit("nosuch.key") == ""
    assert axis_label("wind.speed", "m/s") == "wind.speed [m/s]" and axis_label("glide", "-") == "glide"


def test_a_kite_recording_plots_its_line_pull(tmp_path):
    """The kite's headline figure could not be drawn from its recording (`--metric line_pull`: no such figure): it
    is measured from the rope's sag, so from the recorded positions, as the run itself measures it."""
    from warpsim.io.hdf5 import H5Recorder
    from warpsim.objects.kite import anchor_pull
    from warpsim.physics.config import GRAVITY
    from warpsim.run.simulation import Simulation
    from warpsim.scene.descriptor import defaults
    from warpsim.sweeps.plot import recording_series

    path = tmp_path / "kite.h5"
    sim = Simulation(defaults("kite"))
    pulls = []
    with H5Recorder(path, sim.model, sim.scene, sim.checkpoint, "kite") as recorder:

        def on_frame(frame):
            recorder.write(frame)
            pulls.append(anchor_pull(sim.model.objects[0], frame.positions, sim.model.particle_free_mass, GRAVITY))

        sim.run(12.0, on_frame=on_frame)
    time, series, _, _ = recording_series(path, ["line_pull"])
    late = time >= 8.0
    assert np.nanmean(series["line_pull"][late, 0]) == pytest.approx(np.nanmean(np.array(pulls)[late]), rel=1e-6)
    assert 5.0 < np.nanmean(series["line_pull"][late, 0]) < 30.0
    assert main(["plot", str(path), str(tmp_path / "pull.png"), "--metric", "line_pull"]) == 0
