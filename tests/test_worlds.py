"""Batched worlds: N copies of a scene in one model, stepped by the same launches."""

import numpy as np
import pytest

from warpsim.cli import main
from warpsim.run.simulation import Simulation
from warpsim.scene import descriptor as desc_mod


def _kite(worlds: dict | None = None, **wind):
    desc = desc_mod.defaults("kite")
    desc = desc_mod.merge("test", desc, {"wind": wind} if wind else {})
    if worlds:
        desc = desc_mod.merge("test", desc, {"worlds": worlds})
    return desc


def test_batched_worlds_equal_single_runs_bit_for_bit(device):
    speeds = [4.0, 6.0, 8.0]
    batch = Simulation(_kite({"count": 3, "wind": {"speed": speeds}}), device=device)
    batch.run(1.0)
    q = batch.state.positions()
    assert [r.name for r in batch.model.objects] == ["kite_w0", "kite_w1", "kite_w2"]
    finals = []
    for k, speed in enumerate(speeds):
        single = Simulation(_kite(velocity=[speed, 0.0, 0.0]), device=device)
        single.run(1.0)
        mine = batch.model.particle_world_np == k
        np.testing.assert_array_equal(q[mine], single.state.positions())
        finals.append(single.state.positions())
    # the worlds really differ: more wind lifts the kite more
    assert np.abs(finals[0] - finals[2]).max() > 0.05


def test_gusty_worlds_resume_bit_for_bit(device):
    desc = _kite({"count": 2, "wind": {"gust_seed": [1, 2]}}, gust_intensity=0.3)
    whole = Simulation(desc, device=device)
    whole.run(1.0)
    first = Simulation(desc, device=device)
    first.run(0.5)
    second = Simulation(desc, device=device)
    second.restore(first.checkpoint())
    second.run(0.5)
    np.testing.assert_array_equal(whole.state.positions(), second.state.positions())
    winds = whole.control.wind.numpy()
    assert winds.shape == (2, 3) and np.abs(winds[0] - winds[1]).max() > 1e-3  # own gusts per world


def test_worlds_section_round_trips_through_toml():
    desc = _kite({"count": 2, "wind": {"speed": [3.0, 5.0]}, "kite": {"rope_length": [20.0, 30.0]}})
    again = desc_mod.load_text(desc_mod.to_toml(desc), "round trip")
    assert again["worlds"] == desc["worlds"]
    w1 = desc_mod.world_descriptor(desc, 1)
    assert w1["kite"]["rope_length"] == 30.0 and np.linalg.norm(w1["wind"]["velocity"]) == pytest.approx(5.0)


@pytest.mark.parametrize(
    "worlds, message",
    [
        ({"count": 3, "wind": {"speed": [1.0, 2.0]}}, "one value per world"),
        ({"count": 2, "solver": {"dt": [0.01, 0.02]}}, "only keys of"),
        ({"count": 2, "kite": {"rope_lenght": [1.0, 2.0]}}, "did you mean 'rope_length'"),
        ({"count": 2, "wind": {"speed": [1.0, -2.0]}}, ">= 0"),
        ({"count": 0}, "from 1 to"),
    ],
)
def test_bad_worlds_are_refused(worlds, message):
    with pytest.raises(desc_mod.DescriptorError, match=message):
        _kite(worlds)


def test_cli_worlds_and_vary(tmp_path, capsys):
    out = tmp_path / "batch.h5"
    code = main(["run", "kite", "--worlds", "3", "--vary", "wind.speed=4:8", "--seconds", "0.2", "--h5", str(out)])
    assert code == 0
    import h5py

    with h5py.File(out, "r") as f:
        names = [str(n) for n in f["topology"].attrs["objects"]]
    assert names == ["kite_w0", "kite_w1", "kite_w2"]
    assert main(["run", "kite", "--vary", "wind.speed=4:8"]) == 2
    err = capsys.readouterr().err
    assert "a range needs a COUNT" in err and "--worlds N" in err
    # START:STOP:COUNT makes its own count
    assert main(["run", "kite", "--vary", "wind.speed=4:8:3", "--seconds", "0.1", "--quiet"]) == 0
