"""Same input, same output: repeated runs and graph replay versus kernel-by-kernel launches."""

import numpy as np
import pytest

import warpsim as ws
from warpsim.run.simulation import Simulation
from warpsim.scene.descriptor import defaults


def _run(use_graph: bool, steps: int = 150):
    d = defaults("flag")
    d["flag"]["resolution"] = 8
    d["wind"]["velocity"] = [6.0, 1.5, 0.5]
    sim = Simulation(d, device="cpu", use_graph=use_graph)
    sim.step(steps)
    return sim.state.positions(), sim.state.particle_q_prev.numpy().copy()


def test_two_runs_are_bit_identical():
    a, b = _run(True), _run(True)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])


def test_graph_replay_equals_kernel_by_kernel():
    graph, plain = _run(True), _run(False)
    np.testing.assert_array_equal(graph[0], plain[0])
    np.testing.assert_array_equal(graph[1], plain[1])
    assert np.abs(graph[0] - _initial()).max() > 0.1  # it really moved


def _initial():
    d = defaults("flag")
    d["flag"]["resolution"] = 8
    return Simulation(d).model.particle_q0


def test_control_change_is_seen_by_captured_graph():
    sim = Simulation(defaults("flag"))
    sim.control.set_wind((0.0, 0.0, 0.0))
    sim.step(50)
    calm = sim.state.positions()
    sim2 = Simulation(defaults("flag"))
    sim2.control.set_wind((0.0, 0.0, 0.0))
    sim2.step(25)
    sim2.control.set_wind((0.0, 9.0, 0.0))  # after the graph was captured
    sim2.step(25)
    assert np.abs(sim2.state.positions() - calm)[:, 1].max() > 0.05


def test_solver_rejects_bad_settings():
    b = ws.ModelBuilder()
    b.add_particle((0, 0, 1), 1.0)
    m = b.finalize("cpu")
    refused = {
        "iterations must be >= 1, got 0": {"iterations": 0},
        "relaxation must be < 2.0, got 2.5": {"relaxation": 2.5},
        "damping must be >= 0.0, got -0.1": {"damping": -0.1},
        "damping must be < 1.0, got 1.0": {"damping": 1.0},
        "iterations must be a whole number": {"iterations": 2.5},
        "method must be one of verlet, euler": {"method": "rk4"},
    }
    for message, kwargs in refused.items():
        with pytest.raises(ValueError, match=message):
            ws.SolverVerlet(m, **kwargs)


def test_separate_processes_record_the_same_frames(tmp_path):
    """Two fresh processes (own kernel loads, own gust generators) write bit-identical recordings; resume and
    batched worlds are checked in test_outputs.py and test_worlds.py."""
    import subprocess
    import sys

    import h5py

    paths = [tmp_path / f"run{k}.h5" for k in range(2)]
    for path in paths:
        cmd = [sys.executable, "-m", "warpsim", "run", "kite_gusty", "--seconds", "1.5", "--h5", str(path), "--quiet"]
        subprocess.run(cmd, check=True, capture_output=True, timeout=120)
    with h5py.File(paths[0], "r") as a, h5py.File(paths[1], "r") as b:
        assert a["positions"].shape[0] == 44  # 1.5 s in frames of 35 ms (7 kite steps of 5 ms), and frame 0
        np.testing.assert_array_equal(a["positions"][:], b["positions"][:])
    from warpsim.io.recording import Recording

    with Recording(paths[0]) as a, Recording(paths[1]) as b:  # the newest checkpoints (slots follow wall time)
        np.testing.assert_array_equal(a.checkpoint().q_prev, b.checkpoint().q_prev)
