"""Sweeps on Dask: the same rows whatever the workers and chunks, a dead worker, Ctrl-C and resume, blow-ups as
rows, bad input as one line, the table and the plot read back as a person would (pandas, a PNG)."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest

pd = pytest.importorskip("pandas")
pytest.importorskip("distributed")
pytest.importorskip("pyarrow")

pytestmark = pytest.mark.dask  # the [sweep] extra: Dask clusters, pandas tables

from sweep_support import AXES, SECONDS, _cli, _plan, _same, _scene  # noqa: E402

from warpsim import Scene, sweeps  # noqa: E402
from warpsim.cli import main  # noqa: E402
from warpsim.run.diagnostics import object_metrics  # noqa: E402
from warpsim.run.simulation import Simulation  # noqa: E402
from warpsim.scene import descriptor as desc_mod  # noqa: E402
from warpsim.sweeps import cluster as sweep_cluster  # noqa: E402


def test_plan_is_the_cartesian_product_and_chunks_group_shared_keys():
    plan = _plan()
    assert plan.columns[:2] == ["wind.gust_seed", "kite.tow_point"]
    assert plan.cases == [(1, 0.25), (1, 0.3), (1, 0.35), (2, 0.25), (2, 0.3), (2, 0.35)]
    assert [t.cases for t in plan.chunks(4)] == [[0, 1, 2, 3], [4, 5]]
    assert plan.chunks(4)[0].scene.varied["kite.tow_point"] == [0.25, 0.3, 0.35, 0.25]
    # a key one launch cannot vary between worlds (the solver's) splits the chunks
    d = _scene()
    mixed = sweeps.SweepPlan(Scene(d), sweeps.parse_axes(Scene(d), ["solver.iterations=30,55", "wind.speed=4,8"]), 1.0)
    tasks = mixed.chunks(64)
    assert [t.cases for t in tasks] == [[0, 1], [2, 3]]
    assert [t.scene.settings.solver.iterations for t in tasks] == [30, 55]
    # so does a design, which sets the air model and the step: each chunk is built with its own preset
    designs = sweeps.SweepPlan(
        Scene(d), sweeps.parse_axes(Scene(d), ["kite.design=paper,flying", "wind.speed=4,8"]), 1.0
    )
    tasks = designs.chunks(64)
    assert [t.cases for t in tasks] == [[0, 1], [2, 3]]
    assert [(t.scene.table("air")["model"], t.scene.dt) for t in tasks] == [
        ("paper", 0.01),
        ("sail", 0.0025),
    ]
    assert designs.case_scene(0).object_config().tow_point == 0.35


def test_each_case_measures_what_a_single_run_of_it_shows(reference):
    """Case 4 (seed 2, tow point 0.3) against the same scene run alone by the ordinary runner, its window
    altitude averaged here from the recorded frames."""
    plan = _plan()
    sim = Simulation(plan.case_scene(4))
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
    plan = sweeps.SweepPlan(Scene(d), sweeps.parse_axes(Scene(d), ["wind.speed=6,100"]), 1.0)
    together = sweeps.run_chunk(plan.chunks(2)[0])
    calm, storm = together
    assert not calm["blew_up"] and math.isnan(calm["blowup_time"]) and calm["blowup_reason"] == ""
    assert storm["blew_up"] and 0 < storm["blowup_time"] <= 1.0
    # the storm tears the kite within its first frames: a stick past solver.max_stretch, or, when the first frame
    # already finds the positions overflowed (100 m/s with the default elastic cloth), a non-finite particle; at
    # 60 m/s the kite at its 2.5 ms/45 defaults holds for 1 s, its sticks 47 % stretched
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
    table = sweeps.sweep(
        Scene(_scene()), AXES, seconds=SECONDS, out=out, scheduler=cluster, chunk=4, h5_dir=tmp_path / "rec"
    )
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
    small = sweeps.SweepPlan(
        Scene(_scene()), sweeps.parse_axes(Scene(_scene()), ["wind.gust_seed=1", AXES[1]]), SECONDS
    )
    assert sweeps.run_sweep(small, out=out, scheduler=cluster).ran == 3
    grown = sweeps.run_sweep(_plan(), out=out, scheduler=cluster)
    assert (grown.kept, grown.ran) == (3, 3)
    _same(grown.table, reference)
    other = sweeps.SweepPlan(Scene(_scene()), sweeps.parse_axes(Scene(_scene()), AXES), SECONDS / 2)
    with pytest.raises(sweeps.SweepError, match="whose --seconds differ"):
        sweeps.run_sweep(other, out=out, scheduler=cluster)


def test_a_journal_cut_by_a_crash_keeps_its_whole_rows(cluster, tmp_path, reference):
    """What `kill -9` of `warpsim sweep` leaves: the journal's whole lines and half a line."""

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
    axes = sweeps.parse_axes(Scene(d), ["wind.speed=5,6,7"])  # --vary replaces the table's axis of the same key
    assert [(a.name, a.values) for a in axes] == [
        ("kite.tow_point", (0.25, 0.3, 0.35)),
        ("wind.speed", (5.0, 6.0, 7.0)),
    ]
    assert len(sweeps.SweepPlan(Scene(d), axes, 1.0).cases) == 9
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
            axes = sweeps.parse_axes(Scene(d), [text])
        except desc_mod.DescriptorError:
            return
        assert len(axes) == 1 and len(axes[0].values) >= 1

    check()


def test_a_case_that_cannot_be_built_is_said_so_not_counted_as_a_blow_up(tmp_path, capsys):
    """A newcomer's trial: sweeping a design's scale moved its vertices out of its parts' boxes, and the summary
    said those cases blew up (at t = 0)."""
    out = tmp_path / "s.csv"
    argv = ["sweep", "diamond_kite", "--vary", "mesh.scale=0.8,1.0", "--seconds", "0.1", "--workers", "1"]
    assert main([*argv, "--out", str(out)]) == 0
    said = capsys.readouterr().out
    assert "0 blew up, 1 not built" in said, said
    table = sweeps.read_csv(out)
    unbuilt = table[table["mesh.scale"] == 0.8].iloc[0]
    assert unbuilt["blew_up"] and math.isnan(unbuilt["blowup_time"]) and "not built" in unbuilt["blowup_reason"]
    assert main([*argv, "--out", str(out)]) == 0  # run again: nothing left, said so
    assert "nothing left to run" in capsys.readouterr().out
