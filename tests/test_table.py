"""`warpsim run --table OUT.parquet|OUT.csv`: the closing figures of every world, read back with pandas."""

import contextlib
import io
import re

import numpy as np
import pytest

from warpsim import Scene
from warpsim.cli import main

pd = pytest.importorskip("pandas")


@pytest.fixture(scope="module")
def kite_tables(tmp_path_factory):
    """Three kites in winds of 4, 6 and 8 m/s for 10 s: the run's figures line and its table in both formats."""
    out = tmp_path_factory.mktemp("table")
    argv = ["run", "kite", "--worlds", "3", "--vary", "wind.speed=4:8", "--seconds", "10"]
    text = io.StringIO()
    with contextlib.redirect_stdout(text):
        assert main([*argv, "--table", str(out / "kites.parquet")]) == 0
    assert main([*argv, "--table", str(out / "kites.csv"), "--quiet"]) == 0
    pytest.importorskip("pyarrow")
    return text.getvalue(), pd.read_parquet(out / "kites.parquet"), pd.read_csv(out / "kites.csv")


def test_one_row_per_world_with_its_varied_setting(kite_tables):
    _, parquet, csv = kite_tables
    for table in (parquet, csv):
        assert list(table["world"]) == [0, 1, 2]
        assert list(table["object"]) == ["kite_w0", "kite_w1", "kite_w2"]
        assert list(table["wind.speed"]) == [4.0, 6.0, 8.0]
        assert (table["window_start"] == 5.0).all() and (table["window_stop"] == 10.0).all()
        assert (table["window_frames"] > 100).all() and (table["airborne"] == 1.0).all()
    # CSV keeps every float to the bit (repr), so both formats hold the same numbers
    pd.testing.assert_frame_equal(parquet, csv, check_dtype=False)


def test_table_matches_the_printed_spread_and_the_sweep(kite_tables):
    """The printed line is the mean, lowest and highest of the table's column; the column is the sweep's metric of
    the same cases (the same frames measured the same way)."""
    from warpsim import sweeps
    from warpsim.scene import descriptor

    out, parquet, _ = kite_tables
    line = next(line for line in out.splitlines() if "(means over" in line)
    printed = [float(v) for v in re.search(r"line angle ([0-9.]+) deg \(([0-9.]+) to ([0-9.]+)\)", line).groups()]
    angles = parquet["line_angle_mean"].to_numpy()
    assert printed == pytest.approx([angles.mean(), angles.min(), angles.max()], abs=0.051)
    assert np.all(np.diff(parquet["line_pull_mean"]) > 0)  # more wind: a stronger pull (the line's angle at 5-10 s
    # still depends on how far each kite has climbed)
    base = descriptor.resolve("kite")[0]
    plan = sweeps.SweepPlan(Scene(base), sweeps.parse_axes(Scene(base), ["wind.speed=4:8:3"]), seconds=10.0)
    rows = sweeps.run_chunk(plan.chunks(3, set(), "cpu", None)[0])
    for name in ("line_angle_mean", "line_pull_max", "altitude_min", "worst_stretch", "airborne"):
        assert parquet[name].to_numpy() == pytest.approx([row[name] for row in rows], rel=1e-9, abs=1e-12), name


def test_bad_table_path_is_a_usage_error_before_the_run(tmp_path, capsys):
    assert main(["run", "kite", "--seconds", "1", "--table", str(tmp_path / "k.txt")]) == 2
    assert "unknown table extension" in capsys.readouterr().err
    assert main(["run", "kite", "--seconds", "1", "--table", str(tmp_path / "missing" / "k.csv")]) == 2
    assert list(tmp_path.iterdir()) == []
