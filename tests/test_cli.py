"""The warpsim command: every command runs; user mistakes give one clear line and exit code 2."""

import re
import subprocess
import sys

import numpy as np
import pytest

from warpsim import Scene
from warpsim.cli import main
from warpsim.scene import descriptor


def test_list(capsys):
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    assert "flag" in out and "built-in objects" in out
    # each scene's folder once, then its name and its summary: after `pip install .` every line held the full
    # site-packages path (issue 55)
    from warpsim.scene.dirs import scene_dirs

    scene_lines = [line for line in out.splitlines() if line.startswith("  ") and ".toml" in line]
    assert scene_lines == [] and any(f"scenes in {d}" in out for d in scene_dirs())
    assert any(
        line.split()[0] == "parachute_ringslot" and "ringslot" in line.split(None, 1)[1]
        for line in out.splitlines()
        if line.strip()
    )


def test_info(capsys):
    assert main(["info", "flag"]) == 0
    out = capsys.readouterr().out
    assert "particles 187, sticks 666, triangles 320, nails 11" in out
    assert "[solver]" in out and "dt = 0.00125" in out and "iterations = 119" in out and 'design = "sheet"' in out
    assert main(["info", "flag_paper"]) == 0
    out = capsys.readouterr().out
    assert "particles 15, sticks 38, triangles 16, nails 3" in out and "iterations = 110" in out


def test_a_design_is_a_preset_applied_first_and_once(capsys):
    """``flag.design`` sets the design's keys, then the other --set keys win whatever their order; setting the design
    in force again changes nothing."""
    from warpsim.scene import descriptor

    for order in (["flag.resolution=9", "flag.design=paper"], ["flag.design=paper", "flag.resolution=9"]):
        assert main(["info", "flag", *[arg for item in order for arg in ("--set", item)]]) == 0
        out = capsys.readouterr().out
        # the paper's cloth (rigid sticks, its 110 iterations) at resolution 9: 9 x 6 particles
        assert "particles 54," in out and "iterations = 110" in out and "cloth_compliance = 0.0" in out, order
    fine = descriptor.merge("t", descriptor.resolve("flag")[0], {"flag": {"resolution": 33}, "solver": {"dt": 5e-4}})
    again = descriptor.merge("t", fine, {"flag": {"design": "sheet"}})
    assert again["flag"]["resolution"] == 33 and again["solver"]["dt"] == 5e-4


def test_run_prints_summary(capsys):
    assert main(["run", "flag_paper", "--seconds", "0.5", "--dt", "0.01", "--iterations", "40", "--fps", "20"]) == 0
    out = capsys.readouterr().out
    assert "simulated 0.500 s in 50 steps" in out
    assert "steps/s" in out and "real-time factor" in out and "worst stick stretch" in out


def test_run_quiet_prints_nothing(capsys):
    assert main(["run", "flag", "--seconds", "0.1", "--quiet", "--set", "wind.velocity=[2,0,0]"]) == 0
    assert capsys.readouterr().out == ""


def test_run_descriptor_file(tmp_path, capsys):
    scene = tmp_path / "my_flag.toml"
    scene.write_text('[scene]\nobject = "flag"\nseconds = 0.2\n[flag]\nresolution = 6\n')
    assert main(["run", str(scene)]) == 0
    assert "simulated 0.200 s" in capsys.readouterr().out


@pytest.mark.parametrize(
    "argv, expected",
    [
        (["run", "no-such-scene"], "unknown scene 'no-such-scene'"),
        (["run", "flg"], "did you mean 'flag'"),
        (["run", "flag", "--dt", "0"], "--dt must be a positive finite number"),
        (["run", "flag", "--dt", "-0.01"], "--dt must be a positive finite number"),
        (["run", "flag", "--iterations", "0"], "--iterations must be a whole number >= 1"),
        (["run", "flag", "--set", "flag.resolutoin=4"], "did you mean 'resolution'"),
        (["run", "flag", "--set", "solver.method=rk4"], "not one of verlet, euler"),
        (["run", "flag", "--set", "nonsense"], "expected section.key=value"),
        (["run", "flag", "--set", "wind.velocity=3"], "must be a list of 3 numbers"),
        (["run", "flag", "--set", "wind.speed=6"], "set wind.velocity=[6,0,0]"),
        (["run", "flag", "--device", "tpu"], "--device tpu is not available"),
        (["info", "missing.toml"], "scene file not found"),
    ],
)
def test_user_errors_exit_2_with_one_line(capsys, argv, expected):
    with pytest.raises(SystemExit) as exc:
        raise SystemExit(main(argv))
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip()
    assert expected in err
    assert len(err.splitlines()) == 1 and "Traceback" not in err


def test_console_script_runs_in_a_fresh_process():
    result = subprocess.run(
        [sys.executable, "-m", "warpsim.cli", "run", "flag", "--seconds", "0.3"], capture_output=True, text=True
    )
    assert result.returncode == 0, result.stderr
    assert "simulated 0.300 s in 240 steps" in result.stdout  # the flag steps 1.25 ms
    bad = subprocess.run(
        [sys.executable, "-m", "warpsim.cli", "run", "flag", "--dt", "0"], capture_output=True, text=True
    )
    assert bad.returncode == 2 and "Traceback" not in bad.stderr


def _figures_line(capsys, *argv) -> str:
    assert main(["run", *argv]) == 0
    lines = [line for line in capsys.readouterr().out.splitlines() if "(means over" in line]
    assert len(lines) == 1, lines
    return lines[0]


def _figure_value(line: str, name: str) -> float:
    return float(re.search(rf"{name} (-?[0-9.]+)", line).group(1))


def test_run_ends_with_each_objects_flight_figures(capsys):
    """Issue 36: `warpsim run` ends with the figures a pilot or an observer reads, over the second half of the run,
    with the sweeps' definitions: the hands-off glider's glide and airspeed in the validation's bands, the kite's
    line angle in its band and a pull, the parachute's descent within 10 % of Knacke's round canopies (5.77-5.96
    m/s) and its canopy open."""
    glider = _figures_line(capsys, "hang-glider", "--seconds", "30")
    assert "means over 15-30 s" in glider
    assert _figure_value(glider, "glide") >= 8.0 and 9.0 <= _figure_value(glider, "airspeed") <= 13.0
    assert abs(_figure_value(glider, "bank")) < 1.0
    kite = _figures_line(capsys, "kite", "--seconds", "30")
    assert 45.0 <= _figure_value(kite, "line angle") <= 70.0 and _figure_value(kite, "line pull") > 1.0
    chute = _figures_line(capsys, "parachute", "--seconds", "30")
    assert 0.9 * 5.77 <= _figure_value(chute, "sink") <= 1.1 * 5.96 and _figure_value(chute, "radius") > 3.0


def test_run_figures_are_the_sweep_metrics_and_spread_over_worlds(capsys):
    """With --worlds N the line gives the mean over the worlds and the lowest and highest world; each world's figure
    is the sweep's metric of the same case and window, to the digits printed."""
    from warpsim import sweeps
    from warpsim.scene import descriptor

    line = _figures_line(capsys, "kite", "--worlds", "3", "--vary", "wind.speed=4:8", "--seconds", "10")
    assert line.startswith("  3 worlds")
    angles = re.search(r"line angle ([0-9.]+) deg \(([0-9.]+) to ([0-9.]+)\)", line).groups()
    base = descriptor.resolve("kite")[0]
    plan = sweeps.SweepPlan(Scene(base), sweeps.parse_axes(Scene(base), ["wind.speed=4:8:3"]), seconds=10.0)
    rows = sweeps.run_chunk(plan.chunks(3, set(), "cpu", None)[0])
    means = [row["line_angle_mean"] for row in rows]
    assert [float(a) for a in angles] == pytest.approx([np.mean(means), min(means), max(means)], abs=0.051)


def test_bare_warpsim_shows_its_help(capsys):
    """Issue 36: a bare `warpsim` printed an error about a missing COMMAND; it now shows what it can do, and (issue
    55) exits with the usage's code, 2, as a command run without what it needs does."""
    assert main([]) == 2
    out = capsys.readouterr().out
    assert out.startswith("usage: warpsim") and "run" in out and "sweep" in out


def test_a_missing_cuda_device_is_one_line():
    """Issue 36: `--device cuda` on a machine without a CUDA driver printed two raw Warp driver errors before the
    clean line; now only the line (the check asks Warp whether CUDA is there before asking for the device)."""
    import warp as wp

    if wp.is_cuda_available():
        pytest.skip("this machine has CUDA")
    proc = subprocess.run(
        [sys.executable, "-m", "warpsim", "run", "flag", "--device", "cuda", "--seconds", "0.1"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert proc.returncode == 2 and len(lines) == 1 and "--device cuda is not available here" in lines[0], lines


def test_a_bare_built_in_name_is_the_built_in_beside_a_file_of_that_name(tmp_path, monkeypatch, capsys):
    """A folder or file named ``kite`` in the current folder hid the built-in kite ('kite: scene file not
    found'); a bare built-in name is now the built-in, and ``./kite`` the file."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "kite").mkdir()
    (tmp_path / "flag").write_text("not toml [", encoding="utf-8")
    assert descriptor.resolve("kite")[2] == "built-in kite"
    assert descriptor.resolve("flag")[2] == "built-in flag"
    assert main(["run", "./flag", "--seconds", "0.1"]) == 2
    assert "not valid TOML" in capsys.readouterr().err


@pytest.mark.parametrize("argv", [["schema"], ["list"], ["info", "kite"]])
def test_a_full_standard_output_is_one_line_and_exit_4(argv):
    """`warpsim schema > /dev/full` (and list, info) ended in an OSError traceback and exit 1; the documented code
    for an output that cannot be written is 4."""
    import subprocess
    import sys

    with open("/dev/full", "w") as full:
        done = subprocess.run(
            [sys.executable, "-m", "warpsim", *argv], stdout=full, stderr=subprocess.PIPE, text=True, timeout=120
        )
    assert done.returncode == 4, done.stderr
    assert done.stderr.count("\n") == 1 and "could not write to standard output" in done.stderr


def test_a_run_off_a_terminal_says_it_is_alive(monkeypatch, capsys):
    """Off a terminal (a log, CI, `| tee`) `run` printed nothing for its whole length: it now writes a progress line
    at an interval (10 s of wall time; here every call), each on a line of its own, no carriage returns."""
    import warpsim.cli.run as run_command

    monkeypatch.setattr(run_command, "LOG_PROGRESS_INTERVAL", 0.0)
    assert main(["run", "hang-glider", "--seconds", "30"]) == 0  # progress comes at most 5 times a wall second
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if "steps/s" in line and "t =" in line]
    assert lines and "\r" not in err


def test_a_simulation_takes_a_scenes_name_or_path():
    """A newcomer's trial: `warpsim.Simulation("x.toml")` failed with 'string indices must be integers'."""
    from warpsim import Simulation
    from warpsim.scene.dirs import SHIPPED

    assert Simulation(str(SHIPPED / "kite.toml")).scene.kind == "kite"
    assert Simulation("parachute").scene.where == "built-in parachute"
    gusty = Simulation("kite_gusty").scene  # a scene name, found as warpsim run finds it
    assert gusty.where.endswith("kite_gusty.toml") and gusty.kind == "kite"
    with pytest.raises(TypeError, match="a scene is a Scene"):
        Simulation(3)


def test_vary_takes_a_list_of_files_or_names_as_bare_words():
    """A newcomer's trial: `--vary mesh.file=a.obj,b.obj` was refused (only the TOML list form was taken)."""
    from warpsim.scene.descriptor import DescriptorError
    from warpsim.scene.values import parse_vary

    assert parse_vary("mesh.file=a.obj,designs/b.obj", None) == ("mesh", "file", ["a.obj", "designs/b.obj"])
    assert parse_vary("kite.design=flying,paper", None)[2] == ["flying", "paper"]
    assert parse_vary("mesh.file=2024.obj,b.obj", None)[2] == ["2024.obj", "b.obj"]
    assert parse_vary("wind.speed=4,6", None)[2] == [4, 6]
    with pytest.raises(DescriptorError, match="a.obj,b.obj"):
        parse_vary("wind.speed=4,6x", None)
