"""Every output of a run is one interface (warpsim.io.protocol.Output), opened in one place (warpsim.io.outputs):
the recording, the stage and the picture each take the frames of a run through write_frame and keep them."""

import numpy as np
import pytest

from warpsim.io.outputs import open_picture, open_recording, open_stage
from warpsim.io.protocol import Output, write_frame
from warpsim.io.recording import Recording
from warpsim.run.simulation import Simulation
from warpsim.scene.descriptor import defaults


def test_each_output_is_an_output_and_keeps_the_frames(tmp_path):
    pytest.importorskip("PIL")
    d = defaults("kite")
    sim = Simulation(d)
    outputs = [
        open_recording(tmp_path / "a.h5", sim),
        open_stage(tmp_path / "a.usda", sim),
        open_picture(tmp_path / "a.png", sim, size=(64, 48)),
    ]
    assert all(isinstance(o, Output) for o in outputs)
    positions = []
    for index in range(3):
        if index:
            sim.step(sim.steps_per_frame)
        frame = sim.frame(index)
        positions.append(np.array(frame.positions))
        for output in outputs:
            write_frame(output, frame)
    for output in outputs:
        output.close()
        output.close()  # twice is safe
    with Recording(tmp_path / "a.h5") as rec:
        assert rec.frame_count == 3
        np.testing.assert_array_equal(rec.positions(2), positions[2])
    assert "timeSamples" in (tmp_path / "a.usda").read_text()
    from PIL import Image

    with Image.open(tmp_path / "a.png") as picture:
        assert picture.size == (64, 48)
        assert len(np.unique(np.asarray(picture).reshape(-1, 3), axis=0)) > 2  # something drawn, not a blank picture


def test_a_picture_output_without_frames_writes_nothing(tmp_path):
    pytest.importorskip("PIL")
    sim = Simulation(defaults("flag"))
    picture = open_picture(tmp_path / "b.png", sim)
    assert picture.close() is None
    assert not (tmp_path / "b.png").exists()
