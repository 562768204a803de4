"""Sweeps: every combination of a few settings of one scene, run over every core and over machines with Dask.

A *case* is one combination of the swept values (the cartesian product of the axes, first axis slowest). Cases
are cut into *chunks*; a chunk runs as one :class:`~warpsim.run.simulation.Simulation` whose worlds are its cases (the
batched worlds of ``--worlds``, one launch for all), and each chunk is one Dask task. The cluster is a
``LocalCluster`` of single-threaded worker processes, one per core, unless a running scheduler is given.

Every case gives one row: its swept values and its metrics (:data:`METRICS`, from the same
:class:`warpsim.run.diagnostics.Figures` the viewer's heads-up display reads). Worlds never touch each other
and each world's gusts are seeded by its own ``wind.gust_seed``, so a case's row is bit for bit the same
whatever the chunk size, the number of workers or the order they finish in. A case that blows up stops being
measured at that frame and is a row saying when and why; the other cases of its chunk go on.

Rows are kept as they come: with an output file, every finished chunk is appended to a journal beside it
(``OUT.partial``, JSON lines) and the output is written when the sweep ends, is interrupted (Ctrl-C) or fails;
running the same sweep again with the same output runs only the cases it does not hold yet.

This is the only module that imports Dask; pandas and pyarrow come with it (the ``[sweep]`` extra).
"""

from __future__ import annotations

import contextlib
import copy
import itertools
import json
import math
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ..run.diagnostics import FIGURES, FigureWindow, figure_names
from ..scene.descriptor import VARIABLE_SECTIONS, DescriptorError, check_axis, merge, parse_vary, to_toml

__all__ = ["METRICS", "Axis", "ChunkTask", "SweepError", "SweepPlan", "metrics_of", "run_chunk", "sweep"]

EXTRA_HINT = "pip install -e '.[sweep]'"
MAX_CASES = 1_000_000
MAX_CHUNK = 64  # worlds per task when the chunk size is chosen automatically
ONE_THREAD = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}


class SweepError(ValueError):
    """A sweep a user asked for cannot run as given (bad axes, metrics, window or output); one line says why."""


def require(module: str):
    """Import ``module`` of the ``[sweep]`` extra, or raise :class:`SweepError` saying how to install it."""
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError:
        name = {"distributed": "Dask", "dask": "Dask", "cryptography": "cryptography (TLS for the local cluster)"}.get(
            module.split(".")[0], module
        )
        raise SweepError(f"sweeps need {name}: {EXTRA_HINT}") from None


def _metric_table() -> dict[str, tuple[str, tuple[str, ...] | None, str]]:
    table: dict[str, tuple[str, tuple[str, ...] | None, str]] = {}
    for name, (unit, kinds, meaning) in FIGURES.items():
        for reduce in ("mean", "min", "max"):
            table[f"{name}_{reduce}"] = (unit, kinds, f"{reduce} over the window of the {meaning}")
    table.update(
        {
            "airborne": ("-", None, "share of the window's frames in which the object does not touch the terrain"),
            "ground_time": ("s", None, "first time the object touched the terrain (NaN: never), whole run"),
            "worst_stretch": ("-", None, "largest |l - r|/r of the case's sticks over the whole run"),
            "window_frames": ("-", None, "frames measured in the window (fewer when the case blew up in it)"),
            "blew_up": ("-", None, "true when the case blew up (or could not be built); always in the table"),
            "blowup_time": ("s", None, "when it blew up (NaN: it did not); always in the table"),
            "blowup_reason": ("-", None, "what was seen ('' when it did not blow up); always in the table"),
        }
    )
    return table


METRICS = _metric_table()
"""Every metric a sweep can report: name -> (unit, object kinds that have it (None: all), meaning). The
window is ``--window START:STOP`` [s] of simulated time (default: the second half of the run); a frame is
measured ``scene.fps`` times per simulated second. Means, minima and maxima skip frames where a figure is
undefined (a glide ratio while climbing)."""
ALWAYS = ("blew_up", "blowup_time", "blowup_reason")


def metrics_of(kind: str, names: Sequence[str] | None = None) -> tuple[str, ...]:
    """The metric columns of a sweep of ``kind`` objects: ``names`` checked (any order; the blow-up columns
    are added), or every metric the kind has. Raises :class:`SweepError` for a name it does not have."""
    have = tuple(n for n, (_, kinds, _) in METRICS.items() if kinds is None or kind in kinds)
    if names is None or not len(names):
        return have
    for name in names:
        if name not in have:
            import difflib

            close = difflib.get_close_matches(name, have, n=1)
            hint = f" (did you mean '{close[0]}'?)" if close else ""
            raise SweepError(f"--metrics: a {kind} has no metric {name!r}{hint}; it has {', '.join(have)}")
    chosen = set(names) | set(ALWAYS)
    return tuple(n for n in have if n in chosen)


@dataclass(frozen=True)
class Axis:
    """One swept key: ``section.key`` takes each of ``values`` in turn (checked against the descriptor)."""

    section: str
    key: str
    values: tuple

    @property
    def name(self) -> str:
        """``section.key``, also the axis's column in the results."""
        return f"{self.section}.{self.key}"


def parse_axes(descriptor: dict, items: Sequence[str] | dict, where: str = "--vary") -> list[Axis]:
    """The sweep's axes: the descriptor's ``[sweep]`` table, then ``items`` (``--vary`` texts
    ``KEY=START:STOP:COUNT`` or ``KEY=V1,V2,...``, or a dict ``{"section.key": values or "START:STOP:COUNT"}``),
    which replace a ``[sweep]`` axis of the same key. Raises :class:`~warpsim.scene.descriptor.DescriptorError`."""
    axes: dict[str, Axis] = {}
    for section, keys in descriptor.get("sweep", {}).items():
        for key, values in keys.items():
            axes[f"{section}.{key}"] = Axis(section, key, tuple(values))
    pairs: list[tuple[str, str, object, str]] = []
    if isinstance(items, dict):
        for name, values in items.items():
            parts = name.split(".") if isinstance(name, str) else []
            if len(parts) != 2 or not all(parts):
                raise DescriptorError(f"sweep axis {name!r}: the key must be section.key, e.g. wind.speed")
            pairs.append((parts[0], parts[1], values, f"sweep axis {name}"))
    else:
        for text in items:
            section, key, values = parse_vary(text, None, where)
            pairs.append((section, key, values, f"{where} {text}"))
    for section, key, values, origin in pairs:
        axes[f"{section}.{key}"] = Axis(section, key, tuple(check_axis(origin, descriptor, section, key, values)))
    names = set(axes)
    if {"wind.speed", "wind.velocity"} <= names:
        raise DescriptorError(f"{where}: sweep wind.speed or wind.velocity, not both")
    if not axes:
        raise DescriptorError(f"{where}: nothing to sweep: give --vary KEY=VALUES (or a [sweep] table in the scene)")
    return list(axes.values())


def _plain(value):
    """A swept value as plain JSON data (NumPy scalars and arrays, as pandas gives them back, included)."""
    if isinstance(value, np.ndarray):
        return [_plain(v) for v in value.tolist()]
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def case_key(values: Sequence) -> str:
    """A case's identity: its swept values as canonical JSON (what resuming matches rows by)."""
    return json.dumps([_plain(v) for v in values])


@dataclass
class ChunkTask:
    """One Dask task: the cases ``cases`` (plan indices) run as the worlds of ``descriptor``.

    Attributes:
        descriptor: the chunk's validated descriptor, ``[worlds]`` holding each case's per-world values.
        cases: plan indices of the cases, in world order. columns: their swept values, by axis name.
        seconds: simulated time [s]. window: ``(start, stop)`` [s] the window metrics cover.
        metrics: metric columns to report. device: Warp device. h5: recording to write, or None.
        threads: threads stepping the chunk's worlds (:class:`~warpsim.run.simulation.Simulation`).
    """

    descriptor: dict
    cases: list[int]
    columns: list[dict]
    seconds: float
    window: tuple[float, float]
    metrics: tuple[str, ...]
    device: str = "cpu"
    h5: str | None = None
    threads: int = 1

    def single(self, k: int) -> ChunkTask:
        """The task of this chunk's ``k``-th case alone."""
        worlds = {"count": 1}
        for section, values in self.descriptor["worlds"].items():
            if section != "count":
                worlds[section] = {key: [per[k]] for key, per in values.items()}
        descriptor = copy.deepcopy(self.descriptor)
        descriptor["worlds"] = worlds
        return replace(self, descriptor=descriptor, cases=[self.cases[k]], columns=[self.columns[k]], h5=None)


class SweepPlan:
    """The cases of a sweep and how they are cut into tasks.

    Args:
        descriptor: the scene's validated descriptor (without ``[worlds]``; its ``[sweep]`` is not read here).
        axes: the swept keys (:func:`parse_axes`).
        seconds: simulated time of every case [s] (default: the scene's).
        window: ``(start, stop)`` [s] of the window metrics (default: the second half of the run).
        metrics: metric names (default: all the object has; see :func:`metrics_of`).
    """

    def __init__(
        self,
        descriptor: dict,
        axes: Sequence[Axis],
        seconds: float | None = None,
        window: tuple[float, float] | None = None,
        metrics: Sequence[str] | None = None,
    ):
        if descriptor.get("worlds", {}).get("count", 1) != 1:
            raise SweepError("a sweep makes its own worlds: remove [worlds] from the scene (use --vary instead)")
        self.base = {k: copy.deepcopy(v) for k, v in descriptor.items() if k not in ("sweep",)}
        self.kind = descriptor["scene"]["object"]
        self.axes = list(axes)
        self.seconds = float(seconds if seconds is not None else descriptor["scene"]["seconds"])
        if not (self.seconds > 0 and math.isfinite(self.seconds)):
            raise SweepError(f"--seconds must be a positive number, got {self.seconds}")
        self.base["scene"]["seconds"] = self.seconds  # the same definition whether --seconds or the scene says it
        self.window = (self.seconds / 2, self.seconds) if window is None else (float(window[0]), float(window[1]))
        start, stop = self.window
        if not (0.0 <= start <= stop <= self.seconds):
            raise SweepError(
                f"--window {start:g}:{stop:g} must lie within the run, 0 <= START <= STOP <= {self.seconds:g} s"
            )
        self.metrics = metrics_of(self.kind, metrics)
        count = math.prod(len(a.values) for a in self.axes)
        if count > MAX_CASES:
            raise SweepError(f"{count:,} cases is more than a sweep takes ({MAX_CASES:,}); sweep fewer values")
        self.cases = list(itertools.product(*(a.values for a in self.axes)))
        self._terrain = _terrain_digest(self.base)  # read once: a terrain file may be hundreds of MB
        variable = (_object_section(self.kind), *VARIABLE_SECTIONS)
        # an object's design also sets shared sections (air, solver): like them, it splits the chunks
        self._per_world = [a.section in variable and a.key != "design" for a in self.axes]

    @property
    def columns(self) -> list[str]:
        """The result table's columns: the swept keys, then the metrics."""
        return [a.name for a in self.axes] + list(self.metrics)

    def key(self, index: int) -> str:
        """The identity of case ``index`` (:func:`case_key`)."""
        return case_key(self.cases[index])

    def definition(self) -> dict:
        """What must match for rows of an earlier run to count as rows of this sweep (the swept values aside:
        a sweep may gain values and keep the rows it has)."""
        return {
            "scene": to_toml(self.base),
            "terrain": self._terrain,
            "seconds": self.seconds,
            "window": list(self.window),
            "axes": [a.name for a in self.axes],
            "metrics": list(self.metrics),
        }

    def case_descriptor(self, index: int) -> dict:
        """The descriptor of case ``index`` run alone (one world)."""
        return self._chunk_descriptor([index])

    def _chunk_descriptor(self, indices: Sequence[int]) -> dict:
        shared: dict = {}
        worlds: dict = {"count": len(indices)}
        for a, (axis, per_world) in enumerate(zip(self.axes, self._per_world, strict=True)):
            if per_world:
                worlds.setdefault(axis.section, {})[axis.key] = [self.cases[i][a] for i in indices]
            else:  # one value for the whole chunk: its cases share it (see chunks)
                shared.setdefault(axis.section, {})[axis.key] = self.cases[indices[0]][a]
        return merge("sweep", self.base, {**shared, "worlds": worlds})

    def chunks(
        self, size: int, skip: set[int] = frozenset(), device: str = "cpu", h5_dir: Path | None = None
    ) -> list[ChunkTask]:
        """The tasks of every case not in ``skip``, ``size`` cases each at most. Cases that differ in a key one
        launch cannot vary between worlds (solver, air, terrain, ground) go to different chunks."""
        groups: dict[tuple, list[int]] = {}
        for i, values in enumerate(self.cases):
            if i in skip:
                continue
            shared = tuple(case_key([v]) for v, per in zip(values, self._per_world, strict=True) if not per)
            groups.setdefault(shared, []).append(i)
        tasks = []
        for members in groups.values():
            for start in range(0, len(members), size):
                indices = members[start : start + size]
                columns = [{a.name: self.cases[i][k] for k, a in enumerate(self.axes)} for i in indices]
                h5 = str(Path(h5_dir) / f"cases-{indices[0]:06d}-{indices[-1]:06d}.h5") if h5_dir else None
                tasks.append(
                    ChunkTask(
                        self._chunk_descriptor(indices),
                        indices,
                        columns,
                        self.seconds,
                        self.window,
                        self.metrics,
                        device,
                        h5,
                    )
                )
        return tasks


def _terrain_digest(descriptor: dict) -> str | None:
    """sha256 of the terrain file a descriptor names (None without one): a sweep resumed after the heights were
    edited must not keep rows flown over the old ones (the path alone stays the same)."""
    import hashlib

    terrain = descriptor.get("terrain", {})
    if terrain.get("kind") != "file" or not terrain.get("file"):
        return None
    digest = hashlib.sha256()
    try:
        with open(terrain["file"], "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                digest.update(block)
    except OSError:
        return None  # the build says what is wrong with the file
    return digest.hexdigest()


def _object_section(kind: str) -> str:
    from ..objects import registry

    return registry.section(kind)


# ---------------------------------------------------------------------------------------------------- one task


def _failed_rows(task: ChunkTask, reason: str) -> list[dict]:
    rows = []
    for columns in task.columns:
        row = {name: math.nan for name in task.metrics}
        row.update(columns, blew_up=True, blowup_time=0.0, blowup_reason=reason)
        if "window_frames" in row:
            row["window_frames"] = 0
        rows.append(row)
    return rows


def run_chunk(task: ChunkTask) -> list[dict]:
    """Run one chunk and return one row per case (swept values and metrics, see :data:`METRICS`), in the
    order of ``task.cases``. What a Dask worker calls; also callable directly, in this process.

    A chunk that cannot be built (a case whose values make an unsound object) is run case by case, so only the
    faulty case is a row saying so; a case that blows up stops being measured at that frame.
    """
    from ..physics import _warp

    _warp.init()
    from ..run.diagnostics import Figures, GroundContacts, world_blowups
    from ..run.simulation import Simulation

    try:
        sim = Simulation(task.descriptor, device=task.device, where="sweep case", threads=task.threads)
    except DescriptorError as err:
        if len(task.cases) == 1:
            return _failed_rows(task, f"not built: {err}")
        return [row for k in range(len(task.cases)) for row in run_chunk(task.single(k))]
    model = sim.model
    count = model.world_count
    figures = list(figure_names(sim.descriptor["scene"]["object"]))
    acc = FigureWindow(count, figures)
    contacts = GroundContacts(model)
    max_stretch = sim.settings.solver.max_stretch
    measure_figures = Figures(model)
    live = np.ones(count, dtype=bool)
    blew = [(math.nan, "")] * count
    recorder = _chunk_recorder(task, sim)
    total = int(round(task.seconds / sim.dt))
    spf = sim.steps_per_frame
    start, stop = task.window
    eps = 0.25 * sim.dt  # frame times are sums of dt: compare with a margin
    index = 0
    try:
        frame = sim.frame(0)
        while True:
            problems = world_blowups(model, frame, max_stretch)
            for w, reason in problems.items():
                if live[w]:
                    live[w] = False
                    blew[w] = (frame.time, f"{reason} (at t = {frame.time:.4f} s)")
            # each world's worst stretch as the device measured it (what a run's summary reports)
            acc.worst = np.where(live, np.maximum(acc.worst, frame.world_stretch), acc.worst)
            found = measure_figures(frame, sim.solver.tri_force)
            values = np.array([[f[name] for f in found] for name in figures], dtype=np.float64)
            in_window = start - eps <= frame.time <= stop + eps
            acc.add(values, live, in_window, contacts.touching(frame), frame.time)
            if recorder is not None:
                recorder.write(frame)
            if sim.steps_taken >= total or not live.any():
                break
            sim.apply_schedule()
            sim.step(min(spf, total - sim.steps_taken))
            index += 1
            frame = sim.frame(index)
    finally:
        if recorder is not None:
            recorder.close()
    rows = []
    for k, columns in enumerate(task.columns):
        row = {**columns, **acc.row(k)}
        row["blew_up"] = not bool(live[k])
        row["blowup_time"], row["blowup_reason"] = blew[k]
        rows.append({name: row[name] for name in (*columns, *task.metrics)})
    return rows


def _chunk_recorder(task: ChunkTask, sim):
    """The chunk's recording (``--h5-dir``), written afresh (a retried task starts it again), or None."""
    if not task.h5:
        return None
    from ..io.hdf5 import H5Recorder

    path = Path(task.h5)
    path.parent.mkdir(parents=True, exist_ok=True)
    # the recorder takes the file's writer lock before it truncates it: a run writing it is never overwritten
    return H5Recorder(path, sim.model, sim.descriptor, sim.checkpoint, to_toml(sim.descriptor), "warpsim sweep")


# ---------------------------------------------------------------------------------------------------- the rows


def _check_plain_file(path: Path, links: bool = False) -> None:
    """Raise :class:`SweepError` when ``path`` exists and is not a regular file (a folder, a FIFO, or unless
    ``links``, a link)."""
    import stat

    try:
        info = os.lstat(path)
    except FileNotFoundError:
        return
    except OSError as err:
        raise SweepError(f"{path}: cannot be read ({err.strerror or err})") from None
    if stat.S_ISLNK(info.st_mode) and not links:
        raise SweepError(f"{path} is a link; a sweep never writes through one: remove it, or choose another --out")
    if not (stat.S_ISREG(info.st_mode) or stat.S_ISLNK(info.st_mode)):
        raise SweepError(f"{path} is not a regular file; remove it, or choose another --out")


def _plain_value(value, depth: int = 0) -> bool:
    """True for what a swept value may be in a row: a number, a boolean, text, or a short list of them."""
    if isinstance(value, (bool, int, float, str)):
        return True
    return isinstance(value, list) and depth < 2 and len(value) <= 16 and all(_plain_value(v, depth + 1) for v in value)


def _check_row(row, axes: list[str], metrics: tuple[str, ...], source: Path, number: int) -> None:
    """Raise :class:`SweepError` unless ``row`` (the ``number``-th of ``source``) is a row of this sweep."""
    problem = None
    if not isinstance(row, dict):
        problem = "is not a row"
    else:
        missing = [c for c in (*axes, *metrics) if c not in row]
        if missing:
            problem = f"lacks {', '.join(missing[:3])}"
        elif not all(_plain_value(row[a]) for a in axes):
            problem = "has a swept value that is not a number, text or list"
        elif not all(row[m] is None or isinstance(row[m], (bool, int, float, str)) for m in metrics):
            problem = "has a metric that is not a number or text"
    if problem:
        raise SweepError(
            f"{source}: row {number + 1} {problem}; the file is not this sweep's or is spoiled: choose another "
            "--out, or --restart to replace it"
        )


class _Results:
    """The rows of a sweep: those an earlier run of it left in ``out`` (and its journal), and those this run
    adds. Without ``out`` they live in memory only."""

    def __init__(self, out: Path | None, plan: SweepPlan, restart: bool = False):
        self.out, self.plan = out, plan
        self.rows: dict[str, dict] = {}
        self.journal = None
        self.restart, self.added = restart, 0
        self.journal_size = 0  # bytes of whole lines in an earlier run's journal (a crash may cut the last)
        if out is None:
            return
        self.format = _format_of(out)
        if self.format == "parquet":
            require("pyarrow")
        self.partial = out.with_name(out.name + ".partial")
        self.sidecar = out.with_name(out.name + ".json")
        definition = plan.definition()
        for path in (out, self.partial, self.sidecar):  # outputs are never written or read through links
            _check_plain_file(path, links=restart)  # --restart replaces a link; it never reads or writes through it
        if restart:  # the old rows are not read; the files are replaced once this run has rows of its own
            return
        if out.exists():
            found, rows = self._read_output()
            self._check(found, definition, out)
            self._keep(rows, out)
        if self.partial.exists():
            found, rows = self._read_journal()
            if self.journal_size:  # an empty journal (a sweep stopped before its first line) holds nothing
                self._check(found, definition, self.partial)
                self._keep(rows, self.partial)

    def _keep(self, rows: list[dict], source: Path | None = None) -> None:
        """Keep ``rows`` by case; rows read from ``source`` are checked first: every column of this sweep, swept
        values of JSON's plain types, metrics numbers, booleans or text (a spoiled file is one line, at once)."""
        names = [a.name for a in self.plan.axes]
        for number, row in enumerate(rows):
            if source is not None:
                _check_row(row, names, self.plan.metrics, source, number)
            self.rows[case_key([row[n] for n in names])] = row

    @staticmethod
    def _check(found: dict | None, definition: dict, path: Path) -> None:
        if not isinstance(found, dict):
            raise SweepError(f"{path} is not the output of a warpsim sweep; choose another --out")
        for key in ("seconds", "window", "axes", "metrics", "scene", "terrain"):  # the most telling first
            if found.get(key) != definition[key]:
                what = {"scene": "scene or settings", "axes": "swept keys", "terrain": "terrain heights"}.get(
                    key, f"--{key}"
                )
                raise SweepError(
                    f"{path} holds a sweep whose {what} differ from this one's; choose another --out, or --restart "
                    "to replace it"
                )

    def _read_output(self) -> tuple[dict | None, list[dict]]:
        require("pandas")
        try:
            if self.format == "parquet":
                import pyarrow.parquet as pq

                table = pq.read_table(self.out)
                meta = (table.schema.metadata or {}).get(b"warpsim.sweep")
                frame = table.to_pandas()
                found = json.loads(meta) if meta else None
            else:
                frame = read_csv(self.out)
                found = json.loads(self.sidecar.read_text(encoding="utf-8")) if self.sidecar.exists() else None
        except (OSError, ValueError) as err:
            raise SweepError(f"{self.out} cannot be read as a sweep's table ({err}); choose another --out") from None
        if found is not None and "blowup_reason" in frame:
            reasons = frame["blowup_reason"]
            frame["blowup_reason"] = [r if isinstance(r, str) else "" for r in reasons]  # CSV: '' reads as NaN
        if self.format == "csv":  # CSV holds a vector value (wind.velocity) as text: read it back as the list
            for axis in self.plan.axes:
                if axis.name in frame:
                    frame[axis.name] = [_vector(v) for v in frame[axis.name]]
        return found, [{k: _plain(v) for k, v in row.items()} for row in frame.to_dict("records")]

    def _read_journal(self) -> tuple[dict | None, list[dict]]:
        found, rows = None, []
        try:
            journal = open(self.partial, "rb")  # noqa: SIM115
        except OSError as err:
            raise SweepError(f"{self.partial}: cannot be read ({err.strerror or err}); choose another --out") from None
        with journal:
            for number, line in enumerate(journal):
                try:
                    item = json.loads(line) if line.endswith(b"\n") else None
                except (ValueError, RecursionError):  # RecursionError: JSON nested thousands deep
                    item = None
                if item is None:  # a line cut by a crash: the rows before it are whole
                    break
                self.journal_size += len(line)
                if number == 0:
                    found = item.get("definition") if isinstance(item, dict) else None
                else:
                    rows.append(item)
        return found, rows

    def _append(self, item: dict) -> None:
        """Write ``item`` as the journal's next line, synced; a failed write (disk full) raises
        :class:`~warpsim.io.OutputWriteError` saying what is kept."""
        from ..io import OutputWriteError, reason, with_disk_state

        try:
            self._write_line(item)
        except OSError as err:
            kept = len(self.rows) - 1  # the row being written is not in the journal
            raise OutputWriteError(
                f"{self.partial}: writing the sweep's journal failed ({with_disk_state(reason(err), self.partial)}); "
                f"the sweep stopped with {kept} rows kept; run the same command again to continue once fixed"
            ) from None

    def _write_line(self, item: dict) -> None:
        if self.journal is None:  # opened with the first rows: a sweep that never starts leaves no file
            fresh = self.restart or self.journal_size == 0
            nofollow = getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
            if fresh:  # a file (or link) left there is removed, never written through
                self.partial.unlink(missing_ok=True)
                fd = os.open(self.partial, os.O_RDWR | os.O_CREAT | os.O_EXCL | nofollow, 0o666)
            else:
                fd = os.open(self.partial, os.O_RDWR | nofollow)
            self.journal = open(fd, "r+", encoding="utf-8")  # noqa: SIM115
            if fresh:
                self._append({"definition": self.plan.definition()})
            else:
                self.journal.truncate(self.journal_size)
                self.journal.seek(self.journal_size)
        self.journal.write(json.dumps(item) + "\n")
        self.journal.flush()
        os.fsync(self.journal.fileno())

    def done(self, index: int) -> bool:
        """True when case ``index`` of the plan has a row already."""
        return self.plan.key(index) in self.rows

    def add(self, rows: list[dict]) -> None:
        """Keep ``rows`` (and journal them, so that a crash loses none)."""
        for row in rows:
            row = {k: _plain(v) for k, v in row.items()}
            self._keep([row])
            self.added += 1
            if self.out is not None:
                self._append(row)

    def frame(self):
        """The rows as a pandas DataFrame: the plan's cases in plan order, then rows of values no longer swept."""
        pd = require("pandas")
        order = {self.plan.key(i): i for i in range(len(self.plan.cases))}
        keys = sorted(self.rows, key=lambda k: (k not in order, order.get(k, 0)))
        table = pd.DataFrame([self.rows[k] for k in keys], columns=self.plan.columns)
        if "window_frames" in table:
            table["window_frames"] = table["window_frames"].astype("int64")
        table["blew_up"] = table["blew_up"].astype(bool)
        table.attrs["warpsim.sweep"] = self.plan.definition()
        return table

    def finish(self):
        """Write the output (atomically: a temporary file renamed over it) and drop the journal; returns the
        DataFrame."""
        from ..io import OutputWriteError

        table = self.frame()
        if self.journal is not None:
            with contextlib.suppress(OSError):  # after a failed write: its error is reported already
                self.journal.close()
            self.journal = None
        if self.out is not None and (self.added or self.journal_size):  # else the output stays as it was
            try:
                self._write_output(table)
            except OutputWriteError as err:
                raise OutputWriteError(
                    f"{err}; the rows are kept in {self.partial}: run the same command again once fixed"
                ) from None
            self.partial.unlink(missing_ok=True)
        return table

    def _write_output(self, table) -> None:
        """Write ``table`` (and a CSV's definition beside it), each whole or not at all."""
        from ..io import replacing

        meta = json.dumps(self.plan.definition())
        if self.format == "parquet":
            import pyarrow as pa
            import pyarrow.parquet as pq

            arrow = pa.Table.from_pandas(table, preserve_index=False)
            arrow = arrow.replace_schema_metadata({**(arrow.schema.metadata or {}), b"warpsim.sweep": meta})
            with replacing(self.out, "table") as file:
                pq.write_table(arrow, file)
        else:
            with replacing(self.sidecar, "table's definition") as file:
                file.write(meta.encode("utf-8"))
            with replacing(self.out, "table") as file:
                table.to_csv(file, index=False)


def _vector(value):
    """``value`` read from a CSV cell: a list when it is the text of one (``[4.0, 0.0, 0.0]``), else itself."""
    if isinstance(value, str) and value.startswith("["):
        try:
            parsed = json.loads(value)
        except ValueError:
            return value
        if isinstance(parsed, list):
            return parsed
    return value


def read_csv(path):
    """A sweep's CSV table as a DataFrame, every float read back to the bit it was written with (pandas 3 does
    that by default; pandas 2 needs ``float_precision='round_trip'``)."""
    pd = require("pandas")
    if int(pd.__version__.split(".")[0]) < 3:
        return pd.read_csv(path, float_precision="round_trip")
    return pd.read_csv(path)


def _format_of(out: Path) -> str:
    suffix = out.suffix.lower()
    if suffix in (".parquet", ".pq"):
        return "parquet"
    if suffix == ".csv":
        return "csv"
    raise SweepError(f"--out {out}: write a .parquet (pandas, polars, DuckDB, Spark read it) or a .csv table")


# ---------------------------------------------------------------------------------------------------- Dask


def _ignore_interrupt_plugin(log: Path | None = None):
    """A worker plugin for the local cluster: Ctrl-C in the terminal reaches every process of its group, the
    workers included; they ignore it, and the sweep itself stops them cleanly. With ``log``, what the worker's Dask
    logs goes there (see :func:`_dask_log`) instead of the terminal."""
    from dask.distributed import WorkerPlugin

    class IgnoreInterrupt(WorkerPlugin):
        name = "warpsim-ignore-interrupt"

        def __init__(self, log: str | None):
            self.log = log

        def setup(self, worker):
            import signal
            import threading

            if threading.current_thread() is threading.main_thread():
                signal.signal(signal.SIGINT, signal.SIG_IGN)
            if self.log:
                _log_to(self.log)

    return IgnoreInterrupt(str(log) if log else None)


_DASK_LOGGERS = ("distributed", "tornado", "asyncio")


def _log_to(path) -> list:
    """Send what Dask and its network layers log in this process to ``path`` (appended; a link there is never
    followed) instead of the terminal; returns what to give back to :func:`_restore_logging`."""
    import logging

    flags = os.O_WRONLY | os.O_CREAT | os.O_APPEND | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
    handler = logging.StreamHandler(open(os.open(path, flags, 0o666), "a", encoding="utf-8"))  # noqa: SIM115
    handler.setFormatter(logging.Formatter("%(asctime)s %(process)d %(name)s %(levelname)s: %(message)s"))
    saved = []
    for logger in _dask_loggers():
        saved.append((logger, logger.handlers[:], logger.propagate))
        logger.handlers = [handler]
        logger.propagate = False
    return [handler, saved]


def _dask_loggers() -> list:
    """Dask's loggers and those of its network layers: the top ones, and every one below them that Dask gave a
    handler of its own (``distributed.client`` has one)."""
    import logging

    names = set(_DASK_LOGGERS)
    for name, logger in list(logging.root.manager.loggerDict.items()):
        if name.split(".")[0] in _DASK_LOGGERS and getattr(logger, "handlers", None):
            names.add(name)
    return [logging.getLogger(name) for name in sorted(names)]


def silence_dask() -> None:
    """Turn off Dask's logging in this process for good: for a command whose sweep is over, whose client may still
    be tearing down connections (a killed scheduler gave 36 lines of tracebacks after the sweep had ended)."""
    for logger in _dask_loggers():
        logger.disabled = True


def _restore_logging(state: list) -> None:
    handler, saved = state
    for logger, handlers, propagate in saved:
        logger.handlers, logger.propagate = handlers, propagate
    handler.close()


@contextlib.contextmanager
def _dask_log(path: Path | None):
    """Inside the block, Dask's log lines (a lost worker, "Couldn't gather keys", a scheduler gone: dozens of lines
    and tracebacks) go to ``path`` beside the table, not the terminal; yields ``path`` (None without one). The file is
    removed when nothing was logged. Without ``path`` logging is left as it is."""
    if path is None:
        yield None
        return
    with contextlib.suppress(FileNotFoundError):
        if os.path.islink(path):
            path.unlink()
    state = _log_to(path)
    try:
        yield path
    finally:
        _restore_logging(state)
        with contextlib.suppress(OSError):
            if os.path.getsize(path) == 0:
                path.unlink()


def _check_recordings_free(tasks: Sequence[ChunkTask]) -> None:
    """Raise :class:`SweepError` when a run is writing one of the recordings the tasks will write (``--h5-dir``):
    a sweep once deleted a live run's recording and wrote its chunk in its place."""
    from ..io.h5safe import writer_active

    for task in tasks:
        if task.h5 and writer_active(task.h5):
            raise SweepError(f"--h5-dir: {task.h5} is being written by another warpsim run; wait for it to end")


def _warm_kernels(tasks: Sequence[ChunkTask], device: str) -> None:
    """Compile (or load) the kernels once here, before the workers start, so that they all read Warp's cache
    instead of compiling the same modules side by side: one world of each kind of chunk (a chunk kind differs
    in solver, air, terrain or ground settings)."""
    from ..physics import _warp

    _warp.init()
    from ..run.simulation import Simulation

    seen = set()
    for task in tasks:
        key = json.dumps({k: v for k, v in task.descriptor.items() if k in _SHARED})
        if key in seen:
            continue
        seen.add(key)
        try:
            Simulation(task.single(0).descriptor, device=device)
        except DescriptorError:  # a case that cannot be built: its row will say so
            pass


_SHARED = ("solver", "air", "terrain", "ground")


@dataclass
class SweepOutcome:
    """What :func:`run_sweep` did. ``table``: the rows (pandas DataFrame); ``ran``: cases run now;
    ``kept``: cases already done before; ``wall``: seconds; ``workers``: worker threads used;
    ``interrupted``: stopped by Ctrl-C (the rows finished so far are kept); ``failures``: the exceptions of tasks
    that failed for good; ``log``: the file Dask's log lines went to, when there were any."""

    table: object
    ran: int
    kept: int
    wall: float
    workers: int
    interrupted: bool = False
    failures: list = field(default_factory=list)
    log: Path | None = None  # Dask's log of this sweep, when it logged anything (see _dask_log)


def run_sweep(
    plan: SweepPlan,
    out: Path | None = None,
    workers: int | None = None,
    scheduler=None,
    chunk: int | None = None,
    device: str = "cpu",
    h5_dir: Path | None = None,
    restart: bool = False,
    on_progress: Callable[[int, int, float], None] | None = None,
    threads: int | None = None,
) -> SweepOutcome:
    """Run the cases of ``plan`` that ``out`` does not hold yet on a Dask cluster and keep their rows.

    Args:
        plan: the sweep. out: ``.parquet`` or ``.csv`` table (None: keep the rows in memory only).
        workers: worker processes of the local cluster (default: one per core); not with ``scheduler``.
        scheduler: address of a running Dask scheduler (``tcp://HOST:8786``) or a ``distributed.Client``.
        chunk: cases per task (default: about four tasks per worker, at most :data:`MAX_CHUNK`).
        device: Warp device of the workers. h5_dir: write one recording per chunk there.
        restart: forget the rows ``out`` holds and run every case again.
        on_progress: ``(cases done, cases to run, wall seconds)``, after every chunk.
        threads: threads stepping each chunk's worlds (default: on the local cluster, the cores per worker
            process, so that the workers' threads fill the cores; on a ``scheduler``'s cluster, 1).

    Ctrl-C (``KeyboardInterrupt``) stops the sweep: the finished rows are written and the outcome says
    ``interrupted``.
    """
    require("distributed")
    if scheduler is None:
        check_workers(workers)
    with _owning(out), _dask_log(out.with_name(out.name + ".dask.log") if out is not None else None) as log:
        outcome = _run_owned(plan, out, workers, scheduler, chunk, device, h5_dir, restart, on_progress, log, threads)
    outcome.log = log if log is not None and log.exists() else None
    return outcome


@contextlib.contextmanager
def _owning(out: Path | None):
    """Hold ``out``'s :class:`~warpsim.io.OutputLock` inside the block (one sweep per table and journal: two sweeps
    on one ``--out`` each wrote the table, and the last to finish kept only its own rows)."""
    if out is None:
        yield
        return
    from ..io import OutputLock, OutputLockedError, reason

    try:
        lock = OutputLock(out)
    except OutputLockedError:
        raise SweepError(f"--out {out}: another warpsim sweep is writing this table; wait for it to end") from None
    except OSError as err:
        raise SweepError(f"--out {out}: cannot be locked for writing ({reason(err)})") from None
    try:
        yield
    finally:
        lock.release()


def _run_owned(
    plan, out, workers, scheduler, chunk, device, h5_dir, restart, on_progress, log, threads=None
) -> SweepOutcome:
    """:func:`run_sweep` once ``out`` is this sweep's own."""
    from ..io import OutputWriteError

    failed_write = None
    results = _Results(out, plan, restart)
    todo = [i for i in range(len(plan.cases)) if not results.done(i)]
    started = time.perf_counter()
    interrupted, failures = False, []
    client = cluster = None
    own_client, used = False, 0
    try:
        if todo:
            client, own_client, used = _connect(scheduler, workers)
            size = chunk or max(1, min(MAX_CHUNK, math.ceil(len(todo) / (4 * max(used, 1)))))
            tasks = plan.chunks(size, set(range(len(plan.cases))) - set(todo), device, h5_dir)
            _check_recordings_free(tasks)
            if threads is None:
                cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
                threads = 1 if scheduler is not None else max(1, cores // max(used, 1))
            tasks = [replace(task, threads=threads) for task in tasks]
            if client is None:  # the local cluster: kernels compiled once, here, then the workers start
                _warm_kernels(tasks, device)
                client, cluster = _local_cluster(used, log)
                own_client = True
            _run_tasks(client, tasks, results, len(todo), started, on_progress)
    except KeyboardInterrupt:
        interrupted = True
    except _TaskFailedError as err:  # e.g. a task that killed its workers again and again
        failures.append(err.__cause__)
    except OutputWriteError as err:  # the journal could not be written (disk full): stop, keep what is kept
        failed_write = err
    finally:
        if own_client:
            _close(client, cluster)
        try:
            table = results.finish()
        except OutputWriteError as err:
            raise (failed_write or err) from None
    if failed_write is not None:
        raise failed_write
    ran = sum(1 for i in todo if results.done(i))
    wall = time.perf_counter() - started
    return SweepOutcome(table, ran, len(plan.cases) - len(todo), wall, used, interrupted, failures)


WORKER_BYTES = 384 << 20
"""Memory [bytes] one local worker process takes: about 220 MB at rest (Python, Warp, NumPy, Dask, pandas;
measured RSS of a worker running kite chunks on the CPU) and room for a chunk of up to :data:`MAX_CHUNK` worlds."""

WORKERS_PER_CORE = 4
"""Most local worker processes per core: each is single-threaded and CPU-bound, so more only time-slice."""


def cores() -> int:
    """Cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def max_local_workers() -> int:
    """Most worker processes a local cluster may start here: :data:`WORKERS_PER_CORE` per core, and no more than
    80 % of the available memory holds at :data:`WORKER_BYTES` each (at least 1)."""
    from ..physics.builder import available_memory

    limit = WORKERS_PER_CORE * cores()
    available = available_memory()
    if available is not None:
        limit = min(limit, int(0.8 * available) // WORKER_BYTES)
    return max(1, limit)


def check_workers(workers: int | None) -> None:
    """Raise :class:`SweepError` when ``workers`` local processes are more than :func:`max_local_workers` (a
    thousand workers took more than 10 GB within a minute; 64 ended in Dask tracebacks)."""
    if workers is None:
        return
    limit = max_local_workers()
    if workers > limit:
        raise SweepError(
            f"--workers {workers} is more than this machine can run ({limit}: {WORKERS_PER_CORE} per core on "
            f"{cores()} cores, about {WORKER_BYTES >> 20} MB each of the memory available); use --workers {limit} "
            "or fewer, or a --scheduler with workers on more machines"
        )


def _connect(scheduler, workers: int | None):
    """``(client, whether this sweep made it, worker threads)`` for a running ``scheduler``; ``(None, False,
    worker processes to start)`` for the local cluster."""
    if scheduler is None:
        if workers is not None:
            return None, False, workers
        return None, False, min(cores(), max_local_workers())
    from dask.distributed import Client

    if workers is not None:
        raise SweepError("--workers sizes the local cluster; a --scheduler's cluster has the workers it has")
    if isinstance(scheduler, Client):
        return scheduler, False, sum(scheduler.nthreads().values())
    try:
        client = Client(scheduler, timeout="5s")
    except (OSError, TimeoutError, ValueError) as err:
        raise SweepError(f"--scheduler {scheduler}: cannot connect ({err})") from None
    return client, True, sum(client.nthreads().values())


def _local_cluster(count: int, log: Path | None = None):
    """A ``LocalCluster`` of ``count`` single-threaded worker processes (NumPy/BLAS on one thread each), and
    its client (``log``: where the workers' Dask logs go, see :func:`_dask_log`). Nobody else can join it: every
    connection is TLS with mutual authentication by temporary credentials made for this cluster
    (``Security.temporary()``), which only this process and its workers hold; without them any local process could
    connect to the scheduler on 127.0.0.1 and run its own code on a worker as the sweep's user."""
    import logging

    from dask.distributed import Client, LocalCluster
    from distributed.security import Security

    security = Security.temporary()  # needs `cryptography` (the [sweep] extra)
    cluster = LocalCluster(
        n_workers=count,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        protocol="tls://",
        security=security,
        dashboard_address="127.0.0.1:0",  # the HTTP server always starts: on a free port
        silence_logs=logging.ERROR,
        env=ONE_THREAD,
    )
    client = Client(cluster, security=security)
    client.register_plugin(_ignore_interrupt_plugin(log))
    return client, cluster


POLL = 0.02
"""[s] how long a running sweep waits, when no chunk has finished, before it looks again (Ctrl-C wakes it)."""


def _run_tasks(client, tasks: list[ChunkTask], results: _Results, total: int, started: float, on_progress) -> None:
    import uuid

    from dask.distributed import as_completed

    token = uuid.uuid4().hex[:8]  # task keys unique on a shared scheduler
    futures = [
        client.submit(run_chunk, task, key=f"warpsim-cases-{task.cases[0]}-{task.cases[-1]}-{token}", retries=2)
        for task in tasks
    ]
    finished, done = as_completed(futures), 0
    try:
        with _ctrl_c_flag() as stop:
            while not finished.is_empty():
                batch = finished.next_batch(block=False)
                for future in batch:  # rows that are done are kept, even when Ctrl-C came meanwhile
                    try:
                        rows = future.result()
                    except Exception as err:
                        raise _TaskFailedError() from err
                    results.add(rows)
                    done += len(rows)
                    if on_progress is not None:
                        on_progress(done, total, time.perf_counter() - started)
                if stop.is_set():
                    raise KeyboardInterrupt
                if not batch:
                    stop.wait(POLL)
    finally:
        client.cancel(futures)


@contextlib.contextmanager
def _ctrl_c_flag():
    """While inside, Ctrl-C (SIGINT) or SIGTERM sets the event this yields instead of raising ``KeyboardInterrupt``
    wherever the main thread happens to be (inside Dask's client code it could be lost); the sweep's loop raises it
    when it looks next, at once if it was waiting. Off the main thread (where no signal lands) the event is never
    set."""
    import signal
    import threading

    stop = threading.Event()
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return
    # SIGTERM too: a sweep asked to end (by a scheduler, `kill`) stops like Ctrl-C and keeps its rows
    previous = {sig: signal.signal(sig, lambda *_: stop.set()) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield stop
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


class _TaskFailedError(Exception):
    """A Dask task failed for good; its cause is the task's exception."""


def _close(client, cluster) -> None:
    """Close this sweep's client and local cluster (quietly: they may be half gone after Ctrl-C)."""
    if client is not None:
        with contextlib.suppress(Exception):
            client.close(timeout=5)
    if cluster is not None:
        with contextlib.suppress(Exception):
            cluster.close(timeout=10)


# ---------------------------------------------------------------------------------------------------- the API


def sweep(
    scene: str | dict,
    axes: dict | Sequence[str] = (),
    *,
    seconds: float | None = None,
    window: tuple[float, float] | None = None,
    metrics: Sequence[str] | None = None,
    out: str | Path | None = None,
    workers: int | None = None,
    scheduler=None,
    chunk: int | None = None,
    device: str = "cpu",
    h5_dir: str | Path | None = None,
    restart: bool = False,
):
    """Sweep a scene over every combination of ``axes`` and return one row per case (a pandas DataFrame).

    Args:
        scene: a built-in object name, a scene name or ``.toml`` path, or a validated descriptor (dict).
        axes: ``{"section.key": [values] or "START:STOP:COUNT"}`` or ``--vary`` texts
            (``"kite.tow_point=0.2:0.5:4"``); added to the scene's ``[sweep]`` table.
        seconds: simulated time of every case [s] (default: the scene's).
        window: ``(start, stop)`` [s] of simulated time the window metrics cover (default: the second half).
        metrics: metric names (default: all, see :data:`METRICS`).
        out: ``.parquet`` / ``.csv`` file that keeps the rows; cases it already holds are not run again.
        workers, scheduler, chunk, device, h5_dir, restart: see :func:`run_sweep`.

    Example: ``warpsim.sweep("kite", {"kite.tow_point": "0.2:0.5:4", "wind.speed": [4, 8, 12]}, seconds=20)``.
    Raises :class:`SweepError` or :class:`~warpsim.scene.descriptor.DescriptorError` for a sweep that cannot run, and
    ``KeyboardInterrupt`` after keeping the finished rows when interrupted.
    """
    if isinstance(scene, str):
        from ..scene.descriptor import resolve
        from ..scene.dirs import scene_dirs

        descriptor = resolve(scene, scene_dirs())[0]
    else:
        descriptor = scene
    plan = SweepPlan(descriptor, parse_axes(descriptor, axes), seconds, window, metrics)
    outcome = run_sweep(plan, Path(out) if out else None, workers, scheduler, chunk, device, h5_dir, restart)
    if outcome.interrupted:
        raise KeyboardInterrupt
    if outcome.failures:
        raise outcome.failures[0]
    return outcome.table
