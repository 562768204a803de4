"""Same input, same output: repeated runs and graph replay versus kernel-by-kernel launches."""

import numpy as np

import warpsim as ws
from warpsim.descriptor import defaults
from warpsim.runner import Simulation


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
    for kwargs in ({"iterations": 0}, {"relaxation": 2.5}, {"damping": -0.1}):
        try:
            ws.SolverVerlet(m, **kwargs)
        except ValueError as err:
            assert str(err)
        else:
            raise AssertionError(f"{kwargs} accepted")
