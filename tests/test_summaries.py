"""What the command line tells a user: start-up apart from the stepping rate, no Warp chatter on a CPU machine,
blow-up and ground-contact lines that fit the run, help text whose examples exist."""

import os
import subprocess
import sys
import time

from warpsim.cli import EXIT_BLOWUP, build_parser, main
from warpsim.objects import registry
from warpsim.run.simulation import Simulation
from warpsim.scene.descriptor import defaults, merge


def test_start_up_is_reported_apart_from_the_stepping_rate(capsys):
    """Building and kernel loading happen in the constructor and are reported there; ``run``'s wall time, and so
    its steps/s, covers the stepping only."""
    before = time.perf_counter()
    sim = Simulation(defaults("flag"))
    built = time.perf_counter()
    assert 0.0 < sim.startup_time <= built - before
    summary = sim.run(0.5)
    ran = time.perf_counter()
    assert summary.startup_time == sim.startup_time and 0.0 < summary.wall_time <= ran - built
    assert summary.steps_per_second == summary.steps / summary.wall_time
    assert "start-up" in summary.text() and f"{summary.steps_per_second:,.0f} steps/s" in summary.text()
    assert main(["run", "flag", "--seconds", "0.2"]) == 0
    assert "s start-up: model and kernels)" in capsys.readouterr().out


def test_a_cpu_run_prints_no_warp_chatter():
    """Warp's banner, module load lines and its CUDA-driver warning stay off the terminal (WARPSIM_VERBOSE shows
    them); only warpsim's own lines remain."""
    env = {k: v for k, v in os.environ.items() if k != "WARPSIM_VERBOSE"}
    run = subprocess.run(
        [sys.executable, "-m", "warpsim", "run", "flag", "--seconds", "0.1"],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
    )
    assert run.returncode == 0 and run.stderr == "", run.stderr
    assert [line.split(":")[0] for line in run.stdout.splitlines()][:2] == ["built-in flag", "done"]
    script = "from warpsim.scene.descriptor import defaults\nfrom warpsim.run.simulation import Simulation\n"
    script += "Simulation(defaults('kite')).run(0.05)\n"
    api = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120, env=env)
    assert api.returncode == 0 and api.stdout == "" and api.stderr == "", api.stderr


def test_euler_blow_up_summary_and_hint(capsys):
    assert main(["run", "flag_paper", "--set", "solver.method=euler", "--dt", "0.01"]) == EXIT_BLOWUP
    captured = capsys.readouterr()
    assert "up to the last good frame" in captured.out
    assert "--iterations" not in captured.err and "sqrt(mass / solver.spring_stiffness)" in captured.err
    # a Verlet blow-up (one iteration, 0.2 s steps, a 60 m/s gale) is told to iterate more instead
    assert (
        main(["run", "flag_paper", "--iterations", "1", "--dt", "0.2", "--set", "wind.velocity=[60,0,0]"])
        == EXIT_BLOWUP
    )
    assert "more --iterations" in capsys.readouterr().err


def test_terrain_contact_is_named_with_its_time():
    """The paper's hang glider (paper air) dives into the procedural terrain: the summary says when."""
    summary = Simulation(merge("test", defaults("hang-glider"), {"hang_glider": {"design": "paper"}})).run(15.0)
    ((name, t),) = summary.ground_contacts
    assert name == "hang_glider" and 10.0 < t < 13.0
    assert f"hang_glider touched the terrain at t = {t:.2f} s" in summary.text()
    assert Simulation(defaults("kite")).run(5.0).ground_contacts == ()  # its rope lies there by design


def test_help_examples_name_keys_that_exist():
    text = build_parser()._subparsers._group_actions[0].choices["run"].format_help()
    examples = [word.rstrip(",") for word in text.replace("\n", " ").split() if "=" in word and "." in word]
    assert len(examples) >= 4, text
    known = {}
    for kind in registry.OBJECTS:
        for section, values in defaults(kind).items():
            if isinstance(values, dict):
                known.setdefault(section, set()).update(values)
    known["wind"].add("speed")
    for example in examples:
        section, key = example.split("=", 1)[0].split(".", 1)
        assert key in known.get(section, ()), example


def test_info_counts_shared_particles_once(capsys):
    assert main(["info", "flag"]) == 0
    out = capsys.readouterr().out
    assert "particles 187," in out and "pole          11 particles,     0.000 kg (11 also in a part above" in out
