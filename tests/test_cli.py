"""The warpsim command: every command runs; user mistakes give one clear line and exit code 2."""

import subprocess
import sys

import pytest

from warpsim.cli import main


def test_list(capsys):
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    assert "flag" in out and "built-in objects" in out


def test_info(capsys):
    assert main(["info", "flag"]) == 0
    out = capsys.readouterr().out
    assert "particles 15, sticks 38, triangles 16, nails 3" in out
    assert "[solver]" in out and "iterations = 55" in out


def test_run_prints_summary(capsys):
    assert main(["run", "flag", "--seconds", "0.5", "--dt", "0.01", "--iterations", "40", "--fps", "20"]) == 0
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
    assert "simulated 0.300 s in 30 steps" in result.stdout
    bad = subprocess.run(
        [sys.executable, "-m", "warpsim.cli", "run", "flag", "--dt", "0"], capture_output=True, text=True
    )
    assert bad.returncode == 2 and "Traceback" not in bad.stderr
