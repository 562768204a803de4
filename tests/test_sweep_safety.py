"""Sweeps under attack: hostile command lines, links at the outputs, spoiled journals and tables, full disks, a
recording being written, an intruder at the cluster, signals, failed tasks, a FIFO at the log, a cluster without
workers: each one line or refused, never a traceback, a hang or a lost row."""

from __future__ import annotations

import json
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

from sweep_support import _cli  # noqa: E402

from warpsim import Scene, sweeps  # noqa: E402
from warpsim.cli import main  # noqa: E402
from warpsim.scene import descriptor as desc_mod  # noqa: E402
from warpsim.sweeps import chunk as sweep_chunk  # noqa: E402
from warpsim.sweeps import cluster as sweep_cluster  # noqa: E402

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
    return sweeps.SweepPlan(Scene(d), sweeps.parse_axes(Scene(d), ["wind.speed=4.0,6.0,8.0"]), 0.05).definition()


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


@pytest.mark.slow
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
            winds.append(recording.recorded_scene("test").varied["wind.speed"])
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
