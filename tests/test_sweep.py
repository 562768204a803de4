"""Sweeps on Dask: the same rows whatever the workers and chunks, a dead worker, Ctrl-C and resume, blow-ups as
rows, bad input as one line, the table and the plot read back as a person would (pandas, a PNG)."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

pd = pytest.importorskip("pandas")
pytest.importorskip("distributed")
pytest.importorskip("pyarrow")

pytestmark = pytest.mark.dask  # the [sweep] extra: Dask clusters, pandas tables

from warpsim import sweeps  # noqa: E402
from warpsim.cli import main  # noqa: E402
from warpsim.run.diagnostics import object_metrics  # noqa: E402
from warpsim.run.simulation import Simulation  # noqa: E402
from warpsim.scene import descriptor as desc_mod  # noqa: E402
from warpsim.sweeps import chunk as sweep_chunk  # noqa: E402
from warpsim.sweeps import cluster as sweep_cluster  # noqa: E402

SECONDS = 12.0  # each case; the window is its second half
AXES = ["wind.gust_seed=1,2", "kite.tow_point=0.25,0.3,0.35"]  # 2 x 3 cases, gusty: each case its own gusts


def _scene() -> dict:
    return desc_mod.merge("test", desc_mod.defaults("kite"), {"wind": {"gust_intensity": 0.25}})


def _plan(seconds: float = SECONDS) -> sweeps.SweepPlan:
    d = _scene()
    return sweeps.SweepPlan(d, sweeps.parse_axes(d, AXES), seconds)


@pytest.fixture(scope="module")
def cluster():
    """A local Dask cluster of two single-threaded worker processes (a nanny restarts one that dies)."""
    import logging

    from dask.distributed import Client, LocalCluster

    with (
        LocalCluster(
            n_workers=2,
            threads_per_worker=1,
            processes=True,
            dashboard_address="127.0.0.1:0",
            silence_logs=logging.CRITICAL,
        ) as local,
        Client(local) as client,
    ):
        yield client


@pytest.fixture(scope="module")
def reference():
    """The 6 rows, every case run in this process as one chunk of 6 worlds (no Dask)."""
    plan = _plan()
    (task,) = plan.chunks(6)
    return pd.DataFrame(sweeps.run_chunk(task), columns=plan.columns)


def _same(table, reference):
    pd.testing.assert_frame_equal(
        table.reset_index(drop=True), reference.reset_index(drop=True), check_exact=True, check_dtype=False
    )


def test_plan_is_the_cartesian_product_and_chunks_group_shared_keys():
    plan = _plan()
    assert plan.columns[:2] == ["wind.gust_seed", "kite.tow_point"]
    assert plan.cases == [(1, 0.25), (1, 0.3), (1, 0.35), (2, 0.25), (2, 0.3), (2, 0.35)]
    assert [t.cases for t in plan.chunks(4)] == [[0, 1, 2, 3], [4, 5]]
    assert plan.chunks(4)[0].descriptor["worlds"]["kite"]["tow_point"] == [0.25, 0.3, 0.35, 0.25]
    # a key one launch cannot vary between worlds (the solver's) splits the chunks
    d = _scene()
    mixed = sweeps.SweepPlan(d, sweeps.parse_axes(d, ["solver.iterations=30,55", "wind.speed=4,8"]), 1.0)
    tasks = mixed.chunks(64)
    assert [t.cases for t in tasks] == [[0, 1], [2, 3]]
    assert [t.descriptor["solver"]["iterations"] for t in tasks] == [30, 55]
    # so does a design, which sets the air model and the step: each chunk is built with its own preset
    designs = sweeps.SweepPlan(d, sweeps.parse_axes(d, ["kite.design=paper,flying", "wind.speed=4,8"]), 1.0)
    tasks = designs.chunks(64)
    assert [t.cases for t in tasks] == [[0, 1], [2, 3]]
    assert [(t.descriptor["air"]["model"], t.descriptor["solver"]["dt"]) for t in tasks] == [
        ("paper", 0.01),
        ("sail", 0.005),
    ]
    assert designs.case_descriptor(0)["kite"]["tow_point"] == 0.35


def test_each_case_measures_what_a_single_run_of_it_shows(reference):
    """Case 4 (seed 2, tow point 0.3) against the same scene run alone by the ordinary runner, its window
    altitude averaged here from the recorded frames."""
    plan = _plan()
    sim = Simulation(plan.case_descriptor(4))
    heights = []

    def on_frame(frame):
        if plan.window[0] - 1e-9 <= frame.time <= plan.window[1] + 1e-9:
            heights.append(object_metrics(sim.model, frame).altitude[0])

    sim.run(SECONDS, on_frame=on_frame)
    row = reference.iloc[4]
    assert row["kite.tow_point"] == 0.3 and row["wind.gust_seed"] == 2
    assert row["window_frames"] == len(heights) > 100
    assert row["altitude_mean"] == pytest.approx(np.mean(heights), rel=1e-12)
    assert row["altitude_min"] == min(heights) and row["altitude_max"] == max(heights)
    # the cases really differ: the gust seed and the tow point each change the flight
    assert reference["altitude_mean"].nunique() == 6
    assert not reference["blew_up"].any()


@pytest.mark.slow
def test_same_rows_bit_for_bit_with_1_or_2_workers_and_chunks_of_1_or_6(cluster, reference, tmp_path):
    plan = _plan()
    two = sweeps.run_sweep(plan, scheduler=cluster, chunk=1)
    assert two.workers == 2 and two.ran == 6 and not two.failures
    _same(two.table, reference)
    # one worker process (the command's own local cluster), chunks of 6
    out = tmp_path / "one.parquet"
    args = ["sweep", "kite", "--set", "wind.gust_intensity=0.25", *sum((["--vary", a] for a in AXES), [])]
    assert main([*args, "--seconds", str(SECONDS), "--workers", "1", "--chunk", "6", "--out", str(out), "--quiet"]) == 0
    _same(pd.read_parquet(out), reference)


@pytest.mark.slow
def test_a_worker_killed_mid_sweep_is_replaced_and_the_rows_are_the_same(cluster, reference):
    pids = cluster.run(os.getpid)
    killed = []

    def on_progress(done, total, wall):
        if not killed:  # both workers are busy with a chunk of one case each: kill one of them
            pid = next(iter(pids.values()))
            os.kill(pid, signal.SIGKILL)
            killed.append(pid)

    outcome = sweeps.run_sweep(_plan(), scheduler=cluster, chunk=1, on_progress=on_progress)
    assert killed and not outcome.failures
    _same(outcome.table, reference)
    cluster.wait_for_workers(2, timeout=30)
    assert killed[0] not in cluster.run(os.getpid).values()  # a new process took the dead one's place


def _cli(tmp_path, *extra, workers: int = 2) -> list[str]:
    vary = sum((["--vary", a] for a in AXES), [])
    return [
        sys.executable,
        "-m",
        "warpsim",
        "sweep",
        "kite",
        "--set",
        "wind.gust_intensity=0.25",
        *vary,
        "--seconds",
        str(SECONDS),
        "--workers",
        str(workers),
        "--chunk",
        "1",
        "--out",
        str(tmp_path / "s.parquet"),
        *extra,
    ]


@pytest.mark.slow
def test_ctrl_c_keeps_the_finished_rows_and_a_rerun_runs_only_the_rest(tmp_path, reference):
    journal = tmp_path / "s.parquet.partial"
    # one worker runs the six chunks one after another (~0.25 s each on 2 cores), so that Ctrl-C after the first
    # row lands well before the last: on two workers the whole sweep once ended before the signal came
    proc = subprocess.Popen(
        _cli(tmp_path, workers=1), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True
    )
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if journal.exists() and len(journal.read_text().splitlines()) >= 2:  # the definition and a first row
            break
        time.sleep(0.02)
    os.killpg(proc.pid, signal.SIGINT)  # what Ctrl-C in a terminal does: the whole group, workers included
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, (out, err)
    assert "Traceback" not in err and "interrupted:" in out
    kept = pd.read_parquet(tmp_path / "s.parquet")
    assert 1 <= len(kept) < 6 and not journal.exists()
    done = subprocess.run(_cli(tmp_path, "--resume"), capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    left = 6 - len(kept)
    assert f"{len(kept)} already in" in done.stdout and f"{left} {'case' if left == 1 else 'cases'} run" in done.stdout
    _same(pd.read_parquet(tmp_path / "s.parquet"), reference)


def test_a_case_that_blows_up_is_a_row_and_leaves_its_chunk_mates_alone():
    d = desc_mod.defaults("kite")
    plan = sweeps.SweepPlan(d, sweeps.parse_axes(d, ["wind.speed=6,60"]), 1.0)
    together = sweeps.run_chunk(plan.chunks(2)[0])
    calm, storm = together
    assert not calm["blew_up"] and math.isnan(calm["blowup_time"]) and calm["blowup_reason"] == ""
    assert storm["blew_up"] and 0 < storm["blowup_time"] <= 1.0
    # the storm tears the kite within its first frames: a stick past solver.max_stretch, or, when the first frame
    # already finds the positions overflowed (60 m/s with the default elastic cloth), a non-finite particle
    reason = storm["blowup_reason"]
    assert ("stretched" in reason and "max_stretch" in reason) or "non-finite" in reason, reason
    assert math.isnan(storm["altitude_mean"]) and storm["window_frames"] == 0
    alone = [sweeps.run_chunk(task)[0] for task in plan.chunks(1)]
    _same(pd.DataFrame([alone[0]]), pd.DataFrame([calm]))  # the storm's world did not disturb its neighbour
    assert alone[1]["blowup_reason"] == storm["blowup_reason"]  # numbered within its world


@pytest.mark.slow
def test_csv_table_and_h5_per_chunk(cluster, tmp_path, reference):
    from warpsim.io.recording import Recording

    out = tmp_path / "s.csv"
    table = sweeps.sweep(_scene(), AXES, seconds=SECONDS, out=out, scheduler=cluster, chunk=4, h5_dir=tmp_path / "rec")
    _same(table, reference)
    back = sweeps.read_csv(out)
    back["blowup_reason"] = back["blowup_reason"].astype(object).where(back["blowup_reason"].notna(), "")
    _same(back, reference)
    files = sorted((tmp_path / "rec").glob("*.h5"))
    assert [f.name for f in files] == ["s.csv-cases-000000-000003.h5", "s.csv-cases-000004-000005.h5"]
    with Recording(files[1]) as recording:
        model = recording.build_model()
        assert [r.name for r in model.objects] == ["kite_w0", "kite_w1"]
        assert recording.time[-1] == pytest.approx(SECONDS) and recording.particle_count == model.particle_count
    # the same sweep again finds every row in the table: nothing runs
    again = sweeps.run_sweep(_plan(), out=out, scheduler=cluster)
    assert again.ran == 0 and again.kept == 6
    _same(again.table, reference)


@pytest.mark.slow
def test_a_grown_sweep_keeps_its_rows_and_another_sweep_is_refused(cluster, tmp_path, reference):
    out = tmp_path / "s.parquet"
    small = sweeps.SweepPlan(_scene(), sweeps.parse_axes(_scene(), ["wind.gust_seed=1", AXES[1]]), SECONDS)
    assert sweeps.run_sweep(small, out=out, scheduler=cluster).ran == 3
    grown = sweeps.run_sweep(_plan(), out=out, scheduler=cluster)
    assert (grown.kept, grown.ran) == (3, 3)
    _same(grown.table, reference)
    other = sweeps.SweepPlan(_scene(), sweeps.parse_axes(_scene(), AXES), SECONDS / 2)
    with pytest.raises(sweeps.SweepError, match="whose --seconds differ"):
        sweeps.run_sweep(other, out=out, scheduler=cluster)


def test_a_journal_cut_by_a_crash_keeps_its_whole_rows(cluster, tmp_path, reference):
    """What `kill -9` of `warpsim sweep` leaves: the journal's whole lines and half a line."""
    import json

    out = tmp_path / "s.parquet"
    journal = tmp_path / "s.parquet.partial"
    rows = reference.iloc[:2].to_dict("records")
    lines = [json.dumps({"definition": _plan().definition()})] + [json.dumps(r) for r in rows]
    journal.write_text("\n".join(lines) + '\n{"wind.gust_seed": 1, "kite.tow')
    address = cluster.scheduler.address  # an address, as --scheduler gives it: the sweep makes its own client
    outcome = sweeps.run_sweep(_plan(), out=out, scheduler=address)
    assert (outcome.kept, outcome.ran) == (2, 4) and not journal.exists()
    _same(pd.read_parquet(out), reference)


def test_sweep_table_in_a_descriptor(tmp_path):
    scene = tmp_path / "kites.toml"
    scene.write_text('[scene]\nobject = "kite"\n\n[sweep]\nkite.tow_point = "0.25:0.35:3"\nwind.speed = [4, 8]\n')
    d, _, _ = desc_mod.resolve(str(scene))
    assert d["sweep"] == {"kite": {"tow_point": [0.25, 0.3, 0.35]}, "wind": {"speed": [4.0, 8.0]}}
    assert desc_mod.load_text(desc_mod.to_toml(d), "again")["sweep"] == d["sweep"]
    axes = sweeps.parse_axes(d, ["wind.speed=5,6,7"])  # --vary replaces the table's axis of the same key
    assert [(a.name, a.values) for a in axes] == [
        ("kite.tow_point", (0.25, 0.3, 0.35)),
        ("wind.speed", (5.0, 6.0, 7.0)),
    ]
    assert len(sweeps.SweepPlan(d, axes, 1.0).cases) == 9
    assert Simulation(d).world_count == 1  # `warpsim run` runs the scene as written


@pytest.mark.parametrize(
    "args, message",
    [
        (["--vary", "kite.nope=1,2"], "unknown key kite.nope"),
        (["--vary", "scene.seconds=1,2"], "cannot be swept"),
        (["--vary", "kite.tow_point=0.2:0.5"], "a range needs a COUNT"),
        (["--vary", "kite.tow_point=0.5,2"], "kite.tow_point"),
        (["--vary", "kite.tow_point=0.3,0.3"], "lists a value twice"),
        (["--vary", "wind.speed=4,300"], "gives wind.velocity = [300, 0, 0], which must be <= 200"),
        (["--vary", "wind.speed=4,8", "--vary", "wind.velocity=[[4,0,0],[8,0,0]]"], "not both"),
        (["--vary", "wind.speed=4,8", "--metrics", "glide_mean"], "a kite has no metric 'glide_mean'"),
        (["--vary", "wind.speed=4,8", "--window", "5:40", "--seconds", "10"], "must lie within the run"),
        (["--vary", "wind.speed=4,8", "--out", "OUT.txt"], "unknown table extension"),
        (["--vary", "wind.speed=4,8", "--no-out"], "--out OUT.parquet"),
        (["--out", "OUT.parquet"], "nothing to sweep"),
        (["--vary", "wind.speed=4,8", "--resume"], "holds no rows yet"),
        (["--vary", "wind.speed=4,8", "--worlds", "3"], "unrecognized arguments"),
        (["--vary", "wind.speed=4,8", "--workers", "2", "--scheduler", "tcp://127.0.0.1:9"], "--workers sizes"),
        (["--vary", "wind.speed=4,8", "--workers", "1000"], "is more than this machine can run"),
    ],
)
def test_bad_sweeps_end_with_one_line(tmp_path, capsys, args, message):
    if "--no-out" in args:
        args = [a for a in args if a != "--no-out"]
    elif "--out" not in args:
        args = [*args, "--out", str(tmp_path / "s.parquet")]
    args = [str(tmp_path / a) if a == "OUT.txt" else a for a in args]
    try:
        code = main(["sweep", "kite", *args])
    except SystemExit as exit:  # argparse's own errors
        code = exit.code
    assert code == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and err.startswith("warpsim"), err
    assert not list(tmp_path.glob("s.parquet*"))


def test_local_workers_are_bounded_by_cores_and_memory(monkeypatch):
    """`--workers 1000` took more than 10 GB within a minute: the local cluster takes at most 4 workers per core and
    no more than 80 % of the available memory holds at `WORKER_BYTES` each."""
    from warpsim.physics import memory

    monkeypatch.setattr(sweep_cluster, "available_cores", lambda: 2)
    monkeypatch.setattr(memory, "available_memory", lambda: 100 * sweeps.WORKER_BYTES)
    assert sweeps.max_local_workers() == 8
    monkeypatch.setattr(memory, "available_memory", lambda: 5 * sweeps.WORKER_BYTES)
    assert sweeps.max_local_workers() == 4  # 80 % of 5 workers' worth
    sweeps.check_workers(4)
    with pytest.raises(sweeps.SweepError, match="--workers 5 is more than this machine can run \\(4"):
        sweeps.check_workers(5)
    monkeypatch.setattr(memory, "available_memory", lambda: 0)
    assert sweeps.max_local_workers() == 1  # one worker is always allowed


def test_list_metrics_names_units(capsys):
    assert main(["sweep", "hang-glider", "--list-metrics"]) == 0
    out = capsys.readouterr().out
    lines = {line.split()[0]: line.split()[1] for line in out.splitlines()}
    assert lines["glide_mean"] == "[-]" and lines["bank_max"] == "[deg]" and lines["sink_mean"] == "[m/s]"
    assert "line_angle_mean" not in lines and lines["blowup_reason"] == "[-]"


def _picture(path: Path) -> np.ndarray:
    from PIL import Image

    with Image.open(path) as image:
        return np.asarray(image.convert("RGB")).astype(int)


def test_plot_line_and_heat_map_from_the_table(tmp_path, reference, capsys):
    table = tmp_path / "s.parquet"
    reference.to_parquet(table)
    line, heat = tmp_path / "line.png", tmp_path / "heat.png"
    heat_map = ["plot", str(table), str(heat), "--x", "kite.tow_point", "--y", "wind.gust_seed"]
    assert main(["plot", str(table), str(line), "--x", "kite.tow_point", "--metric", "line_angle_mean"]) == 0
    assert main([*heat_map, "--metric", "altitude_mean"]) == 0
    pixels = _picture(line)
    assert pixels.shape[:2] == (550, 825)
    blue = (pixels[..., 2] > 150) & (pixels[..., 0] < 80)  # the first line (matplotlib's C0 blue)
    orange = (pixels[..., 0] > 200) & (pixels[..., 1] > 100) & (pixels[..., 1] < 160) & (pixels[..., 2] < 60)
    assert blue.sum() > 300 and orange.sum() > 300  # two gust seeds: two lines
    cells = _picture(heat)
    assert len(np.unique(cells.reshape(-1, 3), axis=0)) > 50  # a coloured grid, not an empty frame
    # one swept key too many for a heat map, or a metric the table lacks: one line, exit 2
    wider = reference.assign(**{"wind.speed": 6.0})
    wider.loc[3:, "wind.speed"] = 8.0
    wider.to_parquet(table)
    assert main([*heat_map, "--metric", "altitude_mean"]) == 2
    assert main([*heat_map, "--metric", "altitude_mean", "--where", "wind.speed=8"]) == 0
    assert main(["plot", str(table), str(line), "--x", "kite.tow_point", "--metric", "glide_mean"]) == 2
    # a mistyped metric is named back with the closest the table has, as mistyped scene keys are
    assert main(["plot", str(table), str(line), "--x", "kite.tow_point", "--metric", "line_angel_mean"]) == 2
    assert "(did you mean 'line_angle_mean'?)" in capsys.readouterr().err


def test_the_api_is_exported():
    import warpsim

    assert warpsim.sweep is sweeps.sweep


def test_axes_from_any_text_are_checked_or_refused():
    from hypothesis import given, settings
    from hypothesis import strategies as st

    d = desc_mod.defaults("kite")

    @settings(max_examples=300, deadline=None)
    @given(st.text(max_size=40))
    def check(text):
        try:
            axes = sweeps.parse_axes(d, [text])
        except desc_mod.DescriptorError:
            return
        assert len(axes) == 1 and len(axes[0].values) >= 1

    check()


SWEEP_TOKENS = {
    "scene": ["kite", "kite", "hang-glider", "flag", "kites.toml", "nope", "bad.toml", ""],
    "vary": ["wind.speed=4,8", "kite.tow_point=0.2:0.4:2", "solver.iterations=20,30", "wind.speed=4:8", "x", "a.b=1"]
    + ["kite.tow_point=0.3,0.3", "scene.fps=10,20", "wind.gust_seed=0:1:2", "flag.resolution=3,4", "wind.speed=-1,2"],
    "number": ["0.05", "0.1", "0", "-1", "nan", "abc", ""],
    "window": ["0:0.05", "0.02:0.04", "5:1", "x", "0.01:9"],
    "metrics": ["altitude_mean", "glide_mean,bank_max", "nope", ",", "line_angle_mean,airborne"],
    "count": ["1", "2", "0", "x"],
    "path": ["out.parquet", "out.csv", "out.txt", "missing/out.parquet", "kites.toml", "", "table.parquet"],
    "dir": ["recs", "kites.toml", ""],
    "set": ["wind.gust_intensity=0.2", "kite.mass=-1", "nope=1", "solver.dt=0.02"],
    "scheduler": ["tcp://127.0.0.1:9", "nonsense"],
}
SWEEP_FLAGS = [
    ("--vary", "vary"),
    ("--vary", "vary"),
    ("--seconds", "number"),
    ("--window", "window"),
    ("--metrics", "metrics"),
    ("--workers", "count"),
    ("--chunk", "count"),
    ("--out", "path"),
    ("--h5-dir", "dir"),
    ("--set", "set"),
    ("--resume", None),
    ("--restart", None),
    ("--list-metrics", None),
    ("--scheduler", "scheduler"),
    ("--bogus", None),
]


def _in_process(client, tasks, results, total, started, on_progress):
    """The sweep's tasks run here, one after another: the fuzz exercises everything but Dask itself."""
    for task in tasks:
        results.add(sweeps.run_chunk(task))


def test_sweep_and_plot_command_lines_never_traceback(tmp_path, monkeypatch):
    """Hostile `warpsim sweep` / `warpsim plot` command lines end with 0 or one error line and exit 2, and an
    error leaves the folder as it was (the tasks run in this process: no cluster per example)."""
    import contextlib
    import io

    from conftest import fuzz_watchdog
    from hypothesis import HealthCheck, example, given, settings
    from hypothesis import strategies as st

    monkeypatch.setattr(sweep_cluster, "run_tasks", _in_process)
    monkeypatch.setattr(sweep_cluster, "local_cluster", lambda count, log=None: (None, None))
    monkeypatch.setattr(sweep_cluster, "connect", lambda scheduler, workers: (None, False, workers or 1))
    (tmp_path / "bad.toml").write_text("[scene]\nobject = 'kite'\n[kite]\nrope_length = -3\n")
    (tmp_path / "kites.toml").write_text("[scene]\nobject = 'kite'\n[sweep]\nwind.speed = [4, 6]\n")
    pd.DataFrame({"wind.speed": [4.0, 6.0], "altitude_mean": [1.0, 2.0], "blew_up": [False, True]}).to_parquet(
        tmp_path / "table.parquet"
    )

    @st.composite
    def command_lines(draw):
        if draw(st.integers(0, 3)) == 0:
            argv = ["plot", draw(st.sampled_from(["table.parquet", "kites.toml", "missing.csv"]))]
            argv.append(draw(st.sampled_from(["p.png", "p.png", "p.txt", "missing/p.png"])))
            argv += ["--x", "wind.speed", "--metric", "altitude_mean"] if draw(st.booleans()) else []
            for flag in draw(st.lists(st.sampled_from(["--x", "--y", "--metric", "--where"]), max_size=4)):
                argv += [flag, draw(st.sampled_from(["wind.speed", "altitude_mean", "blew_up", "x", "wind.speed=4"]))]
            return argv
        argv = ["sweep", draw(st.sampled_from(SWEEP_TOKENS["scene"])), "--seconds", "0.05"]
        argv += ["--vary", "wind.speed=4,8", "--out", "out.parquet"] if draw(st.booleans()) else []
        for flag, kind in draw(st.lists(st.sampled_from(SWEEP_FLAGS), max_size=5)):
            argv.append(flag)
            if kind is not None:
                typed = draw(st.integers(0, 5)) == 0
                argv.append(draw(st.text(max_size=6) if typed else st.sampled_from(SWEEP_TOKENS[kind])))
        return argv

    good = ["sweep", "kite", "--seconds", "0.05", "--vary", "wind.speed=4,8", "--out", "out.parquet"]
    plot = ["plot", "table.parquet", "p.png", "--x", "wind.speed", "--metric", "altitude_mean"]

    # explicit examples that must run (exit 0), so the count below does not hang on what the random draws give
    @settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
    @example(argv=good)
    @example(argv=[*good, "--restart"])
    @example(argv=[*good, "--metrics", "altitude_mean", "--window", "0:0.05"])
    @example(argv=plot)
    @example(argv=[*plot, "--where", "wind.speed=4"])
    @given(argv=command_lines())
    def check(argv):
        before = {p.name: p.stat().st_mtime_ns for p in tmp_path.iterdir()}
        out, err = io.StringIO(), io.StringIO()
        cwd = os.getcwd()
        os.chdir(tmp_path)
        code = None
        try:
            with fuzz_watchdog() as dog, contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                try:
                    code = main(argv)
                except SystemExit as exit:
                    code = exit.code
        finally:
            os.chdir(cwd)
        errors = err.getvalue()
        codes.append(code)
        assert "Traceback" not in errors and code in ((0, 2, 130, None) if dog.fired else (0, 2)), (argv, code, errors)
        if code == 2:
            assert len(errors.strip().splitlines()) == 1 and "error:" in errors, (argv, errors)
            assert {p.name: p.stat().st_mtime_ns for p in tmp_path.iterdir()} == before, (argv, errors)
        for made in ("out.parquet", "out.csv", "p.png"):  # each example starts from the same folder
            (tmp_path / made).unlink(missing_ok=True)
        (tmp_path / "out.csv.json").unlink(missing_ok=True)
        import shutil

        shutil.rmtree(tmp_path / "recs", ignore_errors=True)

    codes: list = []
    check()
    assert codes.count(0) >= 5  # some sweeps and plots did run (the explicit examples at least)


# ---------------------------------------------------------------------------------------- one owner, nothing lost


def _here(monkeypatch) -> list:
    """Run sweeps' tasks in this process (no cluster); returns the list of the cases each run ran."""
    ran: list = []

    def in_process(client, tasks, results, total, started, on_progress):
        for task in tasks:
            ran.extend(task.cases)
            results.add(sweeps.run_chunk(task))

    monkeypatch.setattr(sweep_cluster, "run_tasks", in_process)
    monkeypatch.setattr(sweep_cluster, "local_cluster", lambda count, log=None: (None, None))
    monkeypatch.setattr(sweep_chunk, "warm_kernels", lambda tasks, device: None)
    return ran


def _quick(out, *extra) -> list[str]:
    return ["sweep", "kite", "--vary", "wind.speed=4.0,6.0,8.0", "--seconds", "0.05", "--out", str(out), *extra]


def test_two_sweeps_on_one_out_the_second_is_refused(tmp_path, monkeypatch, capsys):
    """Two sweeps on one --out both ended 0 and the table kept only the last one's rows: the table is owned by one
    sweep at a time (a lock beside it, taken before anything is read), the second ends with one line, exit 2."""
    from warpsim.io import OutputLock

    ran = _here(monkeypatch)
    out = tmp_path / "t.parquet"
    lock = OutputLock(out)  # what a running sweep on `out` holds
    try:
        assert main(_quick(out, "--quiet")) == 2
        assert "another warpsim sweep is writing this table" in capsys.readouterr().err
        assert ran == [] and not out.exists()
    finally:
        lock.release()
    assert main(_quick(out, "--quiet")) == 0 and ran == [0, 1, 2]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.parquet"]  # the lock file went with the sweep


def test_links_at_the_outputs_are_never_written_through(tmp_path, monkeypatch, capsys):
    """A link planted at the temporary name (or at OUT.partial, then --restart) made the sweep write into the
    linked file and turned OUT into a link to it. Temporaries are made with O_EXCL | O_NOFOLLOW and a planted one is
    removed; a link at OUT.partial is refused, or removed (not followed) by --restart."""
    from warpsim.io import temporary_path

    _here(monkeypatch)
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    out = tmp_path / "t.parquet"
    temporary_path(out).symlink_to(victim)
    assert main(_quick(out, "--quiet")) == 0
    assert victim.read_text() == "precious" and not out.is_symlink() and len(pd.read_parquet(out)) == 3
    assert not temporary_path(out).exists()
    partial = tmp_path / "t.parquet.partial"
    partial.symlink_to(victim)
    assert main(_quick(out, "--quiet", "--vary", "kite.tow_point=0.3,0.4")) == 2
    assert "is a link" in capsys.readouterr().err
    assert main(_quick(out, "--quiet", "--vary", "kite.tow_point=0.3,0.4", "--restart")) == 0
    assert victim.read_text() == "precious" and not out.is_symlink() and len(pd.read_parquet(out)) == 6
    assert not os.path.lexists(partial)


def test_a_csv_sweep_over_a_vector_key_runs_each_case_once(tmp_path, monkeypatch):
    """CSV holds wind.velocity as text; a rerun did not recognise its rows, ran every case again and doubled them."""
    ran = _here(monkeypatch)
    out = tmp_path / "v.csv"
    argv = ["sweep", "kite", "--vary", "wind.velocity=[[4.0,0.0,0.0],[6.0,0.0,0.0]]", "--seconds", "0.05"]
    assert main([*argv, "--out", str(out), "--quiet"]) == 0 and ran == [0, 1]
    assert main([*argv, "--out", str(out), "--quiet"]) == 0 and ran == [0, 1]  # nothing ran again
    table = sweeps.read_csv(out)
    assert len(table) == 2 and list(table["wind.velocity"]) == ["[4.0, 0.0, 0.0]", "[6.0, 0.0, 0.0]"]


SPOILS = {
    "definition not a dict": lambda d, rows: ['{"definition": [1, 2]}'],
    "row missing an axis": lambda d, rows: [d, json.dumps({k: v for k, v in rows[0].items() if k != "wind.speed"})],
    "axis of the wrong type": lambda d, rows: [d, json.dumps({**rows[0], "wind.speed": {"a": 1}})],
    "metric missing": lambda d, rows: [d, json.dumps({k: v for k, v in rows[0].items() if k != "altitude_mean"})],
    "row not a dict": lambda d, rows: [d, "[1, 2, 3]"],
    # issue 55: these passed the check and ended the sweep in a 43-52-line traceback after all its cases ran
    "window frames NaN": lambda d, rows: [d, json.dumps({**rows[0], "window_frames": float("nan")})],
    "window frames text": lambda d, rows: [d, json.dumps({**rows[0], "window_frames": "abc"})],
    "metric text in a number column": lambda d, rows: [d, json.dumps({**rows[0], "altitude_mean": "high"})],
    "blew_up text": lambda d, rows: [d, json.dumps({**rows[0], "blew_up": "maybe"})],
    "axis value NaN": lambda d, rows: [d, json.dumps({**rows[0], "wind.speed": float("nan")})],
}


@pytest.mark.parametrize("spoil", [*SPOILS, "deeply nested", "a directory", "empty"])
def test_a_spoiled_journal_is_one_line_before_anything_runs(spoil, tmp_path, monkeypatch, capsys):
    """Spoiled journals ended in tracebacks, some only after every case had run, and again on every rerun."""
    import json

    ran = _here(monkeypatch)
    out = tmp_path / "t.parquet"
    partial = tmp_path / "t.parquet.partial"
    assert main(_quick(out, "--quiet")) == 0
    rows = pd.read_parquet(out).to_dict("records")
    rows = [{k: (v.item() if hasattr(v, "item") else v) for k, v in r.items()} for r in rows]
    out.unlink()
    ran.clear()
    definition = json.dumps({"definition": _quick_definition()})
    if spoil == "deeply nested":
        lines = [definition, "[" * 100_000 + "]" * 100_000]
    elif spoil in SPOILS:
        lines = SPOILS[spoil](definition, rows)
    if spoil == "a directory":
        partial.mkdir()
    elif spoil == "empty":
        partial.write_text("")
    else:
        partial.write_text("\n".join(lines) + "\n")
    code = main(_quick(out, "--quiet"))
    err = capsys.readouterr().err
    if spoil in ("deeply nested", "empty"):  # a line that cannot be read is where a crash cut the journal
        assert code == 0 and ran == [0, 1, 2], err
        return
    assert code == 2 and ran == [] and err.count("\n") == 1 and "Traceback" not in err, err
    assert str(partial) in err


def _quick_definition() -> dict:
    d = desc_mod.defaults("kite")
    return sweeps.SweepPlan(d, sweeps.parse_axes(d, ["wind.speed=4.0,6.0,8.0"]), 0.05).definition()


@pytest.mark.parametrize("where", ["journal", "table"])
def test_a_full_disk_under_the_sweep_is_exit_4_and_one_line(where, tmp_path, monkeypatch, capsys):
    """A write that fails (a file-size limit here, as a full disk fails it) ended in exit 1 and a traceback; now
    exit 4, one line naming the file and what is kept, and a rerun once there is room finishes the sweep."""
    import resource

    ran = _here(monkeypatch)
    out = tmp_path / "t.parquet"
    limit = 2500 if where == "journal" else 9000  # the journal's definition fits 2,500 bytes; the table does not
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    previous = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (limit, hard))
    try:
        code = main(_quick(out, "--quiet"))
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
        signal.signal(signal.SIGXFSZ, previous)
    err = capsys.readouterr().err
    assert code == 4 and err.count("\n") == 1 and "Traceback" not in err, err
    assert "File too large" in err and "run the same command again" in err
    assert str(tmp_path / "t.parquet.partial") in err
    assert ("writing the sweep's journal failed" in err) == (where == "journal")
    assert not out.exists() and not [p for p in tmp_path.iterdir() if ".tmp" in p.name]
    first = len(ran)
    assert main(_quick(out, "--quiet")) == 0
    assert len(pd.read_parquet(out)) == 3
    if where == "table":  # every row was in the journal: the rerun only writes the table
        assert first == 3 and len(ran) == 3
    else:  # the journal kept the rows before the failed one; the rerun runs the others
        assert 3 <= len(ran) and len(ran) - first >= 1


def test_h5_dir_never_touches_a_recording_a_run_is_writing(tmp_path, monkeypatch, capsys):
    """With `run --h5 DIR/t.parquet-cases-000000-000002.h5` writing, a sweep with --h5-dir DIR removed that file and
    wrote its chunk in its place. The sweep now looks for a writer's lock before it starts (and each chunk's recorder
    takes the lock before it truncates); a folder under a file is said before anything runs."""
    from warpsim.io.hdf5 import claim

    ran = _here(monkeypatch)
    rec_dir = tmp_path / "recs"
    rec_dir.mkdir()
    live = rec_dir / "t.parquet-cases-000000-000002.h5"
    live.write_bytes(b"a live run's frames")
    lock = claim(live, create=False)  # what `warpsim run --h5` holds while it writes
    try:
        assert main(_quick(tmp_path / "t.parquet", "--chunk", "3", "--h5-dir", str(rec_dir), "--quiet")) == 2
        err = capsys.readouterr().err
        assert "is being written by another warpsim run" in err and err.count("\n") == 1
        assert live.read_bytes() == b"a live run's frames" and ran == []
    finally:
        lock.release()
    (tmp_path / "file").write_text("")
    for bad, message in ((tmp_path / "file" / "recs", "lies under"), (tmp_path / "file", "is not a folder")):
        assert main(_quick(tmp_path / "t.parquet", "--h5-dir", str(bad), "--quiet")) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, err
    assert main(_quick(tmp_path / "t.parquet", "--chunk", "3", "--h5-dir", str(rec_dir), "--quiet")) == 0
    from warpsim.io.recording import Recording

    with Recording(live) as recording:  # no run holds it any more: the sweep's chunk is written there
        assert recording.frame_count > 1


def test_plot_on_a_full_disk_keeps_the_old_picture_and_a_text_metric_is_one_line(tmp_path, reference, capsys):
    """`warpsim plot` wrote in place: on a full disk a traceback and the previous PNG replaced by a cut one. It now
    writes a temporary and renames it (exit 4, one line, the old picture intact); `--metric blowup_reason` (text)
    was a TypeError traceback."""
    import resource

    table, png = tmp_path / "s.parquet", tmp_path / "p.png"
    reference.to_parquet(table)
    argv = ["plot", str(table), str(png), "--x", "kite.tow_point", "--metric", "altitude_mean"]
    assert main(argv) == 0
    before = png.read_bytes()
    assert main([*argv[:-1], "line_angle_mean"]) == 0 and png.read_bytes() != before  # it does redraw
    before = png.read_bytes()
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    previous = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (4096, hard))
    try:
        code = main(argv)
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
        signal.signal(signal.SIGXFSZ, previous)
    err = capsys.readouterr().err
    assert code == 4 and err.count("\n") == 1 and "File too large" in err and str(png) in err, err
    assert png.read_bytes() == before and sorted(p.name for p in tmp_path.iterdir()) == ["p.png", "s.parquet"]
    assert main([*argv[:-1], "blowup_reason"]) == 2
    err = capsys.readouterr().err
    assert "--metric blowup_reason is not a number" in err and err.count("\n") == 1


def test_a_sweep_over_an_edited_terrain_file_is_not_resumed(tmp_path, monkeypatch, capsys):
    """A sweep's resume check stored only the terrain's path, so rows flown over old heights were kept after the
    file changed; the definition now holds the heights' digest, and the file is found beside its scene."""
    _here(monkeypatch)
    np.save(tmp_path / "hills.npy", np.random.default_rng(3).normal(0.0, 2.0, (32, 32)))
    scene = tmp_path / "hills.toml"
    scene.write_text("[scene]\nobject = 'kite'\n[terrain]\nkind = 'file'\nfile = 'hills.npy'\nsize = 200\n")
    monkeypatch.chdir(ROOT_DIR)  # not the scene's folder
    argv = ["sweep", str(scene), "--vary", "wind.speed=4.0,6.0", "--seconds", "0.05", "--quiet"]
    out = tmp_path / "t.parquet"
    assert main([*argv, "--out", str(out)]) == 0
    assert main([*argv, "--out", str(out)]) == 0  # the same heights: nothing to run, accepted
    np.save(tmp_path / "hills.npy", np.zeros((32, 32)))
    assert main([*argv, "--out", str(out)]) == 2
    assert "whose terrain heights differ" in capsys.readouterr().err
    assert main([*argv, "--out", str(out), "--restart"]) == 0


ROOT_DIR = Path(__file__).resolve().parent.parent


INTRUDER = """
import sys
from dask.distributed import Client
from distributed.security import Security
address, how = sys.argv[1], sys.argv[2]
kwargs = {"security": Security.temporary()} if how == "own-credentials" else {}
try:
    client = Client(address, timeout="3s", **kwargs)
    print("JOINED", client.submit(sum, [1, 2, 3]).result(timeout=10))
except Exception as err:
    print("REFUSED", type(err).__name__)
"""


def test_the_local_cluster_cannot_be_joined_by_another_process():
    """The default LocalCluster listened on 127.0.0.1 without TLS or authentication, and another local process ran
    its own function on a worker. Now every connection is mutual TLS with credentials made for this cluster: a
    plain client, a TCP client and a client with credentials of its own, each in a process of its own as an
    intruder would be, are all refused; the sweep's own client runs code."""
    client, cluster = sweep_cluster.local_cluster(1)
    try:
        address = cluster.scheduler_address
        assert address.startswith("tls://127.0.0.1:")
        assert client.submit(sum, [1, 2, 3]).result(timeout=30) == 6
        for target, how in (
            (address, "plain"),
            (address.replace("tls://", "tcp://"), "tcp"),
            (address, "own-credentials"),
        ):
            run = subprocess.run(
                [sys.executable, "-c", INTRUDER, target, how], capture_output=True, text=True, timeout=120
            )
            assert "JOINED" not in run.stdout, (how, run.stdout)
            # refused with an error from Dask's client (a crash of the intruder itself, as an ImportError, fails)
            assert run.returncode == 0 and "REFUSED" in run.stdout, (how, run.stdout, run.stderr[-2000:])
        assert client.submit(sum, [4, 5]).result(timeout=30) == 9  # the cluster still serves its own client
    finally:
        sweep_cluster.close(client, cluster)


@pytest.mark.slow
def test_sigterm_stops_a_sweep_like_ctrl_c(tmp_path):
    """SIGTERM to `warpsim sweep` killed it by the signal (143), leaving only the journal and a 'leaked semaphore'
    warning; it now stops like Ctrl-C: workers stopped, the finished rows written to the table, exit 130."""
    journal = tmp_path / "s.parquet.partial"
    proc = subprocess.Popen(_cli(tmp_path, workers=1), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if journal.exists() and len(journal.read_text().splitlines()) >= 2:
            break
        time.sleep(0.02)
    proc.send_signal(signal.SIGTERM)  # the sweep's own process only, as `kill PID` or a batch system does
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, (out, err)
    assert "Traceback" not in err and "leaked" not in err and "interrupted:" in out, err
    kept = pd.read_parquet(tmp_path / "s.parquet")
    assert 1 <= len(kept) <= 6 and not journal.exists()


def test_a_failed_task_is_one_line_naming_dasks_log(tmp_path, monkeypatch, capsys):
    """A killed scheduler ended in exit 1 with 36 lines (a Dask traceback, a literal \\n in the error line) and
    "done:" on stdout; Dask's ERROR lines reached the terminal. Now Dask logs into a file beside the table, and the
    sweep says "failed:", then one line that names the file."""
    import logging

    def fail(client, tasks, results, total, started, on_progress):
        results.add(sweeps.run_chunk(tasks[0]))
        logging.getLogger("distributed.client").error("Couldn't gather keys\nTraceback (most recent call last): ...")
        try:
            raise RuntimeError("warpsim-cases-1-1 cancelled for reason: scheduler-connection-lost.\nmore\nlines")
        except RuntimeError as err:
            raise sweep_cluster.TaskFailedError() from err

    monkeypatch.setattr(sweep_cluster, "run_tasks", fail)
    monkeypatch.setattr(sweep_cluster, "local_cluster", lambda count, log=None: (None, None))
    monkeypatch.setattr(sweep_chunk, "warm_kernels", lambda tasks, device: None)
    client = logging.getLogger("distributed.client")
    saved = client.handlers[:], client.propagate, client.disabled
    client.addHandler(logging.StreamHandler(sys.stderr))  # as Dask's own configuration gives it one
    try:
        assert main(_quick(tmp_path / "t.parquet", "--chunk", "1")) == 1
    finally:
        client.handlers, client.propagate, client.disabled = saved
        for logger in sweep_cluster.dask_loggers():  # the command turned them off for the rest of its process
            logger.disabled = False
    captured = capsys.readouterr()
    log = tmp_path / "t.parquet.dask.log"
    assert captured.err == (
        "warpsim sweep: error: a task failed: warpsim-cases-1-1 cancelled for reason: scheduler-connection-lost.; "
        f"the finished rows are kept; Dask's log: {log}\n"
    )
    assert "failed: 1 case run" in captured.out and "done:" not in captured.out
    assert "Couldn't gather keys" in log.read_text()
    assert len(pd.read_parquet(tmp_path / "t.parquet")) == 1


def test_a_spoiled_table_is_one_line_before_anything_runs(tmp_path, monkeypatch, capsys):
    """The table's rows are checked as the journal's are: one without a metric column of this sweep (a table
    edited by hand, or written by another tool with the sweep's metadata kept) is one line, exit 2, before any case
    runs, and again on a rerun until --restart."""
    import pyarrow.parquet as pq

    ran = _here(monkeypatch)
    out = tmp_path / "t.parquet"
    assert main(_quick(out, "--quiet")) == 0
    table = pq.read_table(out)
    pq.write_table(table.drop(["altitude_mean"]).replace_schema_metadata(table.schema.metadata), out)
    ran.clear()
    for _ in range(2):
        assert main(_quick(out, "--quiet")) == 2
        err = capsys.readouterr().err
        assert f"{out}: row 1 lacks altitude_mean" in err and err.count("\n") == 1 and ran == [], err
    assert main(_quick(out, "--quiet", "--restart")) == 0 and ran == [0, 1, 2]
    assert "altitude_mean" in pq.read_table(out).column_names


def test_heat_map_labels_share_their_decimals_and_read_on_their_cells():
    """A newcomer's tour heat map printed 54 beside 55.5, in white on yellow: every label now has the decimals that
    give the largest value three significant digits, white on dark cells and black on light ones."""
    import matplotlib

    from warpsim.sweeps.plot import cell_labels

    cmap, cells = matplotlib.colormaps["viridis"], np.array([[36.9, 54.0], [np.nan, 55.5]])
    labels = cell_labels(cells, lambda v: cmap((v - 36.9) / (55.5 - 36.9)))
    assert [(r, c, t) for r, c, t, _ in labels] == [(0, 0, "36.9"), (0, 1, "54.0"), (1, 1, "55.5")]
    assert [colour for *_, colour in labels] == ["white", "black", "black"]  # viridis: dark purple to yellow
    assert [t for *_, t, _ in cell_labels(np.array([[0.0123, 0.5]]), lambda v: (0, 0, 0, 1))] == ["0.012", "0.500"]


def test_two_sweeps_sharing_an_h5_dir_keep_their_own_recordings(tmp_path, monkeypatch):
    """Two sweeps with different --out and the same --h5-dir wrote `cases-000000-000002.h5` each, the second over the
    first's: each sweep's recordings are named after its table."""
    from warpsim.io.recording import Recording

    _here(monkeypatch)
    rec_dir = tmp_path / "recs"
    assert main(_quick(tmp_path / "a.parquet", "--chunk", "3", "--h5-dir", str(rec_dir), "--quiet")) == 0
    argv = ["sweep", "kite", "--vary", "wind.speed=5.0,7.0,9.0", "--seconds", "0.05", "--out", str(tmp_path / "b.csv")]
    assert main([*argv, "--chunk", "3", "--h5-dir", str(rec_dir), "--quiet"]) == 0
    names = sorted(f.name for f in rec_dir.glob("*.h5"))
    assert names == ["a.parquet-cases-000000-000002.h5", "b.csv-cases-000000-000002.h5"]
    winds = []
    for name in names:
        with Recording(rec_dir / name) as recording:
            winds.append(recording.descriptor("test")["worlds"]["wind"]["speed"])
    assert winds == [[4.0, 6.0, 8.0], [5.0, 7.0, 9.0]]


def test_a_fifo_at_the_dask_log_is_one_line_not_a_hang(tmp_path, monkeypatch, capsys):
    """A FIFO planted at OUT.dask.log blocked the sweep for ever in open(), holding OUT's lock: one line, exit 2."""
    _here(monkeypatch)
    out = tmp_path / "t.parquet"
    os.mkfifo(tmp_path / "t.parquet.dask.log")
    assert main(_quick(out, "--quiet")) == 2
    err = capsys.readouterr().err
    assert "dask.log" in err and "not a regular file" in err and err.count("\n") == 1



def test_a_cluster_without_workers_is_given_up_after_its_grace(monkeypatch):
    """Killing the local cluster's workers again and again left no worker, and the sweep waited silently for ever:
    a cluster that has had no worker for NO_WORKER_GRACE seconds stops the sweep (its finished rows kept, one line
    naming the cause); a worker back in time resets the watch."""
    from warpsim.sweeps import cluster

    monkeypatch.setattr(cluster, "NO_WORKER_GRACE", 0.2)
    monkeypatch.setattr(cluster, "WATCH_INTERVAL", 0.0)

    class Client:
        workers: dict = {}

        def nthreads(self):
            return self.workers

    client, watch = Client(), {}
    cluster._watch_workers(client, watch)  # none: the watch starts
    time.sleep(0.1)
    client.workers = {"tcp://127.0.0.1:1": 1}
    cluster._watch_workers(client, watch)  # one came back in time
    client.workers = {}
    cluster._watch_workers(client, watch)
    time.sleep(0.1)
    cluster._watch_workers(client, watch)  # 0.1 s without one since it left: still waiting
    time.sleep(0.15)
    with pytest.raises(cluster.NoWorkerError, match="no worker for 0.2 s"):
        cluster._watch_workers(client, watch)
