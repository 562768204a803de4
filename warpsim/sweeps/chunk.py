"""One sweep task: a chunk of cases run as the batched worlds of one simulation, a row per case (what a Dask worker
calls), and the kernels compiled once before the workers start."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..io.protocol import write_frame
from ..scene.descriptor import DescriptorError
from .metrics import SweepError
from .plan import ChunkTask


def _failed_rows(task: ChunkTask, reason: str) -> list[dict]:
    rows = []
    for columns in task.columns:
        row = {name: math.nan for name in task.metrics}
        row.update(columns, blew_up=True, blowup_time=math.nan, blowup_reason=reason)  # it never ran
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
    from ..run.diagnostics import GroundContacts
    from ..run.figures import Figures, FigureWindow, figure_names, oscillations_of
    from ..run.simulation import Simulation

    try:
        sim = Simulation(task.scene, device=task.device, where="sweep case", threads=task.threads)
    except DescriptorError as err:
        if len(task.cases) == 1:
            return _failed_rows(task, f"not built: {err}")
        return [row for k in range(len(task.cases)) for row in run_chunk(task.single(k))]
    model = sim.model
    count = model.world_count
    figures = list(figure_names(sim.scene.kind))
    acc = FigureWindow(count, figures, oscillations_of(sim.scene.kind))
    contacts = GroundContacts(model)
    measure_figures = Figures(model)
    live = np.ones(count, dtype=bool)
    blew = [(math.nan, "")] * count
    recorder = _chunk_recorder(task, sim)
    start, stop = task.window
    eps = 0.25 * sim.dt  # frame times are sums of dt: compare with a margin
    frames = sim.frames(task.seconds, each_world=True)
    try:
        for frame in frames:
            for w, reason in frame.blowups.items():
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
                write_frame(recorder, frame)
            del frame
            if not live.any():
                break
    finally:
        frames.close()
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
    from ..io import OutputWriteError
    from ..io.outputs import open_recording

    path = Path(task.h5)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:  # a file in the way of --h5-dir (checked up front only where no scheduler is given)
        raise OutputWriteError(f"--h5-dir {path.parent}: cannot make the folder ({err.strerror})") from None
    if path.is_symlink():  # the chunk's own name: a link planted there is removed, never written through
        path.unlink()
    # the recorder takes the file's writer lock before it truncates it: a run writing it is never overwritten
    return open_recording(path, sim, "warpsim sweep")


def check_recordings_free(tasks: Sequence[ChunkTask]) -> None:
    """Raise :class:`SweepError` when a run is writing one of the recordings the tasks will write (``--h5-dir``):
    a sweep once deleted a live run's recording and wrote its chunk in its place."""
    from ..io.h5safe import writer_active

    for task in tasks:
        if task.h5 and writer_active(task.h5):
            raise SweepError(f"--h5-dir: {task.h5} is being written by another warpsim run; wait for it to end")


def warm_kernels(tasks: Sequence[ChunkTask], device: str) -> None:
    """Compile (or load) the kernels once here, before the workers start, so that they all read Warp's cache
    instead of compiling the same modules side by side: one world of each kind of chunk (a chunk kind differs
    in solver, air, terrain or ground settings)."""
    from ..physics import _warp

    _warp.init()
    from ..run.simulation import Simulation

    seen = set()
    for task in tasks:
        key = task.scene.launch_key()
        if key in seen:
            continue
        seen.add(key)
        try:
            Simulation(task.single(0).scene, device=device)
        except DescriptorError:  # a case that cannot be built: its row will say so
            pass
