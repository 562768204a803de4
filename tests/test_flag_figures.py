"""The flag's closing figures: its trailing corner's flap and the frequency of its swings, measured from the
particles and checked against the spectrum of the same motion."""

import contextlib
import io
import math
import re

import numpy as np
import pytest

from warpsim import Scene
from warpsim.cli import main
from warpsim.run.figures import FlightFigures, swing_frequency
from warpsim.run.simulation import Simulation
from warpsim.scene.descriptor import defaults, merge

PAPER = {"flag": {"design": "paper"}}  # the paper's cloth: cheap to fly, and it flaps at any wind


def test_swing_frequency_of_a_sine_with_jitter_and_of_a_still_figure():
    rng = np.random.default_rng(1)
    t = np.arange(0.0, 20.0, 1.0 / 30.0)
    wave = 0.3 + 0.4 * np.sin(2 * np.pi * 1.3 * t + 0.7) + 0.02 * rng.standard_normal(t.size)
    assert swing_frequency(t, wave) == pytest.approx(1.3, rel=0.01)
    wave[::7] = np.nan  # frames where the figure is undefined are skipped
    assert swing_frequency(t, wave) == pytest.approx(1.3, rel=0.01)
    assert math.isnan(swing_frequency(t, np.full(t.size, 2.0)))
    assert math.isnan(swing_frequency(t[:40], np.sin(2 * np.pi * 0.1 * t[:40])))  # less than one swing
    wave[100] = 50.0  # a one-frame spike does not set the band
    assert swing_frequency(t, wave) == pytest.approx(1.3, rel=0.01)
    jitter = 0.002 * rng.standard_normal(t.size)  # 2 mm of noise on a still figure is not a swing
    assert swing_frequency(t, jitter) > 1.0 and math.isnan(swing_frequency(t, jitter, least=0.01))


def test_a_flag_in_a_near_calm_does_not_flap():
    """In 0.5 m/s the flag hangs: its flap frequency is NaN, not the frequency of its jitter. (It settles from the
    launch by a slow 0.23 Hz swing, lightly damped at the paper's flag's steps: ±8.9 cm over 10-20 s, ±2.5 cm over
    20-30 s, ±0.65 cm over 30-40 s.)"""
    sim = Simulation(merge("test", defaults("flag"), {**PAPER, "wind": {"velocity": [0.5, 0.05, 0.0]}}))
    figures = FlightFigures(sim, 30.0, 45.0)
    sim.run(45.0, on_frame=figures)
    row = figures.window.row(0)
    assert 0.5 * (row["flap_max"] - row["flap_min"]) < 0.01 and math.isnan(row["flap_frequency"])


def test_flag_flap_frequency_is_the_peak_of_its_corner_spectrum():
    """The run's ``flap`` frequency against an FFT of the top trailing corner's sideways position, taken from the
    frames' particles (the corner found from the positions as built, not from the figure's own code)."""
    sim = Simulation(merge("test", defaults("flag"), PAPER))
    q0 = sim.state.positions()
    cloth = sim.model.objects[0].parts["cloth"]
    corner = cloth[np.argmax(q0[cloth, 0] + 1e-3 * q0[cloth, 2])]  # farthest from the pole, top row
    figures = FlightFigures(sim, 5.0, 30.0)
    times, sideways = [], []

    def on_frame(frame):
        figures(frame)
        if frame.time >= 5.0 - 1e-9:
            times.append(frame.time)
            sideways.append(frame.positions[corner, 1])  # the wind blows along +x (and 0.5 m/s along +y)

    sim.run(30.0, on_frame=on_frame)
    times, sideways = np.array(times), np.array(sideways)
    spacing = float(np.mean(np.diff(times)))
    spectrum = np.abs(np.fft.rfft((sideways - sideways.mean()) * np.hanning(sideways.size)))
    peak = np.fft.rfftfreq(sideways.size, spacing)[np.argmax(spectrum[1:]) + 1]
    row = figures.window.row(0)
    assert 0.5 < row["flap_frequency"] < 5.0
    assert row["flap_frequency"] == pytest.approx(peak, rel=0.05)  # measured 1.93 Hz against 1.92 Hz
    amplitude = 0.5 * (row["flap_max"] - row["flap_min"])
    assert amplitude == pytest.approx(0.5 * np.ptp(sideways), rel=0.1)  # the pole's plane is tilted 7 deg off x
    line = figures.lines()[0]
    printed = re.search(r"flap ±([0-9.]+) m at ([0-9.]+) Hz", line)
    assert printed, line
    assert float(printed.group(2)) == pytest.approx(row["flap_frequency"], abs=0.006)


def test_run_prints_the_flap_and_sweeps_have_its_frequency():
    from warpsim.sweeps import METRICS, metrics_of

    text = io.StringIO()
    with contextlib.redirect_stdout(text):
        assert main(["run", "flag_paper", "--seconds", "10"]) == 0
    assert re.search(r"flag: .*flap ±[0-9.]+ m at [0-9.]+ Hz", text.getvalue()), text.getvalue()
    # the figure is said to be the mesh's, naming the resolution it was run at (the validation's rows: 5 and 9
    # converged in dt flap at f L/U 0.96 and 1.36)
    assert "note: the flap's frequency and size are those of this mesh (resolution 5)" in text.getvalue()
    text = io.StringIO()
    with contextlib.redirect_stdout(text):
        assert main(["run", "flag_paper", "--seconds", "6", "--set", "flag.resolution=9"]) == 0
    assert "(resolution 9), not a real flag's" in text.getvalue(), text.getvalue()
    text = io.StringIO()
    with contextlib.redirect_stdout(text):
        assert main(["run", "parachute", "--seconds", "1"]) == 0
    assert "note:" not in text.getvalue(), text.getvalue()
    assert "flap_frequency" in metrics_of("flag") and METRICS["flap_frequency"][0] == "Hz"
    assert "flap_frequency" not in metrics_of("kite")


def test_flag_sweep_rows_are_the_same_whatever_the_chunk():
    """A case's flap and its frequency are its own: the same to the bit in chunks of 1 and of 3 worlds."""
    from warpsim import sweeps
    from warpsim.scene import descriptor

    base = merge("test", descriptor.resolve("flag")[0], PAPER)
    plan = sweeps.SweepPlan(Scene(base), sweeps.parse_axes(Scene(base), ["wind.speed=0.5,3,6"]), seconds=12.0)
    alone = [sweeps.run_chunk(task)[0] for task in plan.chunks(1, set(), "cpu", None)]
    together = sweeps.run_chunk(plan.chunks(3, set(), "cpu", None)[0])
    names = ("flap_mean", "flap_min", "flap_max", "flap_frequency")
    for one, batched in zip(alone, together, strict=True):
        for name in names:
            assert one[name] == batched[name] or (math.isnan(one[name]) and math.isnan(batched[name])), name
    assert all(row["flap_frequency"] > 0.3 for row in together[1:])  # 3 and 6 m/s: it flaps
