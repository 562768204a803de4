"""The benchmark suite runs, writes its JSON, and its comparisons measure what they claim (no speed limits here:
speed goals live in the suite's results, not in tests)."""

import json

import pytest

from benchmarks.__main__ import main
from benchmarks.suite import PAPER_FLAG, flag, largest_stable_dt, scene


def test_suite_writes_rows_with_comparisons(tmp_path, capsys):
    out = tmp_path / "results.json"
    assert main(["-k", "hang-glider", "--min-time", "0.05", "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    rows = {r["case"]: r for r in data["results"]}
    # -k matches by substring: the C reference (where a compiler is installed) and run-vs-raw rows come along
    assert set(rows) - {"c-reference-hang-glider"} == {"hang-glider", "numpy-hang-glider", "run-hang-glider"}
    run = rows["run-hang-glider"]  # Simulation.run with its frames against raw stepping of the same scene
    assert run["steps_per_s"] > 0 and run["ratio"] == pytest.approx(run["steps_per_s"] / run["baseline_steps_per_s"])
    glider = rows["hang-glider"]
    assert glider["steps_per_s"] > 0 and glider["particles"] == 52 and glider["iterations"] == 55  # the flying design
    assert glider["baseline_steps_per_s"] == 100.0  # the paper's figure
    rate = glider["sticks"] * glider["iterations"] * glider["steps_per_s"]  # constraint iterations per second
    assert glider["constraint_iterations_per_s"] == pytest.approx(rate)
    assert glider["ratio"] == pytest.approx(glider["steps_per_s"] / 100.0)
    numpy_row = rows["numpy-hang-glider"]
    assert numpy_row["baseline_steps_per_s"] > 0 and numpy_row["ratio"] > 0
    assert data["machine"]["cores"] >= 1 and data["machine"]["warp"]
    table = capsys.readouterr().out
    assert "| hang-glider |" in table and "paper" in table


def test_unknown_case_is_refused(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["-k", "no-such-case"])
    assert exc.value.code == 2
    assert "no case matches" in capsys.readouterr().err


def test_flag_case_has_the_asked_size():
    desc = flag(16)
    assert desc["flag"]["resolution"] == 16 and desc["flag"]["height"] == desc["flag"]["width"]


def test_euler_needs_a_smaller_step_than_verlet():
    """The paper's slide 15: the mass-spring Euler flag needs about ten times more steps than Verlet's (at least
    ten times here: its largest stable dt is ten times smaller or less)."""
    verlet = largest_stable_dt(scene("flag", {"flag": PAPER_FLAG}), "cpu")
    euler = largest_stable_dt(scene("flag", {"flag": PAPER_FLAG, "solver": {"method": "euler"}}), "cpu")
    assert verlet is not None and euler is not None
    assert euler <= verlet / 10


def test_a_run_of_a_few_cases_leaves_the_whole_runs_results_alone(monkeypatch, tmp_path, capsys):
    """`python -m benchmarks -k hang-glider` replaced the tracked benchmarks/results.json with its 4-row subset: a
    selection writes no file unless given --json."""
    import benchmarks.__main__ as runner

    (tmp_path / "benchmarks").mkdir()
    target = tmp_path / "benchmarks" / "results.json"  # where the runner once wrote, relative to the working folder
    target.write_text("the whole run's rows")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(runner, "DEFAULT_JSON", str(target))
    assert main(["-k", "euler-vs-verlet", "--min-time", "0.01"]) == 0
    assert target.read_text() == "the whole run's rows"
