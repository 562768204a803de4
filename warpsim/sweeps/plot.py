"""Quick looks as PNGs: a sweep's table, one metric against one swept key (lines) or two (a heat map)
(:func:`plot_sweep`); a recording, its objects' figures against simulated time (:func:`plot_recording`).

Swept keys are the table's ``section.key`` columns (metrics have no dot in their names). Cases that blew up are
left out of the picture and counted in its title. Every axis carries its unit (a metric's from
:data:`warpsim.sweeps.METRICS`, a key's from its config class, :func:`key_unit`). Needs pandas (and pyarrow for
``.parquet``) and matplotlib: the ``[sweep]`` extra.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._extras import install_hint
from ..scene.values import suggest

MAX_LINES = 12  # lines one line plot draws before it asks for --where


class PlotError(ValueError):
    """The table, keys or metric asked for cannot be drawn; the message says why in one line."""


def _require(module: str):
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError:
        raise PlotError(f"plots need {module.split('.')[0]}: {install_hint('sweep')}") from None


def read_table(path) -> object:
    """A sweep's table (``.parquet`` or ``.csv``) as a pandas DataFrame; raises :class:`PlotError`."""
    pd = _require("pandas")
    path = Path(path)
    if not path.is_file():
        raise PlotError(f"{path}: no such file")
    try:
        if path.suffix.lower() in (".parquet", ".pq"):
            _require("pyarrow")
            return pd.read_parquet(path)
        if path.suffix.lower() == ".csv":
            from .table import read_csv

            return read_csv(path)
    except (OSError, ValueError) as err:
        raise PlotError(f"{path}: cannot be read as a table ({err})") from None
    raise PlotError(f"{path}: a sweep's table is a .parquet or .csv file")


def _value(table, key: str, text: str):
    """``text`` as a value of column ``key`` (matched against the values it holds)."""
    for value in table[key].unique():
        if str(value) == text:
            return value
        try:
            if float(value) == float(text):
                return value
        except (TypeError, ValueError):
            pass
    held = ", ".join(str(v) for v in sorted(table[key].unique(), key=str)[:12])
    raise PlotError(f"--where {key}={text}: {key} never takes that value; it takes {held}")


def _select(table, where) -> tuple[object, list[str]]:
    chosen = []
    for item in where:
        if "=" not in item:
            raise PlotError(f"--where {item!r}: expected KEY=VALUE, e.g. wind.speed=8")
        key, text = (part.strip() for part in item.split("=", 1))
        if key not in table:
            raise PlotError(f"--where {key}: no such column; swept keys are {', '.join(_keys(table))}")
        table = table[table[key] == _value(table, key, text)]
        chosen.append(f"{key} = {text}")
    return table, chosen


def cell_labels(cells: np.ndarray, colour_of) -> list[tuple[int, int, str, str]]:
    """The heat map's labels: ``(row, column, text, text colour)`` for each finite cell of ``cells``. Every label
    has the same number of decimals, three significant digits of the largest value, so that 54.0 and 55.5 read
    alike; the text is white on a dark cell and black on a light one (the luma of ``colour_of(value)``, an RGBA
    colour in 0-1)."""
    finite = cells[np.isfinite(cells)]
    largest = float(np.abs(finite).max()) if finite.size else 0.0
    decimals = max(0, 2 - int(np.floor(np.log10(largest)))) if largest > 0 else 2
    labels = []
    for (row, col), v in np.ndenumerate(cells):
        if np.isfinite(v):
            r, g, b = colour_of(v)[:3]
            colour = "white" if 0.299 * r + 0.587 * g + 0.114 * b < 0.5 else "black"
            labels.append((row, col, f"{v:.{decimals}f}", colour))
    return labels


def _text(value) -> str:
    return f"{value:g}" if isinstance(value, (float, np.floating)) else str(value)


def _keys(table) -> list[str]:
    return [c for c in table.columns if "." in c]


def plot_sweep(path, out, x: str, metric: str, y: str | None = None, where=()) -> Path:
    """Draw ``metric`` of the sweep table ``path`` against swept key ``x`` (one line per combination of the
    other swept keys) or, with ``y``, as a heat map over ``x`` and ``y``; write ``out`` (a PNG). ``where``:
    ``KEY=VALUE`` texts keeping only those cases. Returns the path written; raises :class:`PlotError`."""
    from ..io import OutputPathError, check_output_path
    from .metrics import METRICS

    try:
        out = check_output_path(out, (".png",), "PNG")
    except OutputPathError as err:
        raise PlotError(str(err)) from None
    table = read_table(path)
    keys = _keys(table)
    for flag, key in (("--x", x), ("--y", y)):
        if key is not None and key not in keys:
            raise PlotError(f"{flag} {key}: not a swept key of {path}; they are {', '.join(keys) or 'none'}")
    if metric not in table.columns or metric in keys:
        metrics = [c for c in table.columns if c not in keys]
        raise PlotError(
            f"--metric {metric}: not in {path}{suggest(metric, metrics, cutoff=0.75)}; it has {', '.join(metrics)}"
        )
    if x == y:
        raise PlotError("--x and --y must be two different swept keys")
    table, chosen = _select(table, where)
    if not len(table):
        raise PlotError("no case is left after --where")
    pd = _require("pandas")
    if not (pd.api.types.is_numeric_dtype(table[metric]) or pd.api.types.is_bool_dtype(table[metric])):
        raise PlotError(f"--metric {metric} is not a number (it holds text); choose a metric with a unit")
    blew = table["blew_up"].astype(bool) if "blew_up" in table else np.zeros(len(table), dtype=bool)
    values = table[metric].astype(float).where(~blew)
    others = [k for k in keys if k not in (x, y) and table[k].nunique() > 1]
    matplotlib = _require("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    label = axis_label(metric, METRICS.get(metric, ("",))[0])
    figure, axes = plt.subplots(figsize=(7.5, 5.0), dpi=110)
    try:
        if y is None:
            groups = list(table.groupby(others, sort=True)) if others else [((), table)]
            if len(groups) > MAX_LINES:
                raise PlotError(
                    f"{len(groups)} lines (one per combination of {', '.join(others)}): fix some with --where KEY=VALUE"
                )
            for name, part in groups:
                part = part.sort_values(x)
                name = name if isinstance(name, tuple) else (name,)
                text = ", ".join(f"{k} = {_text(v)}" for k, v in zip(others, name, strict=True))
                axes.plot(part[x], values.loc[part.index], marker="o", label=text or None)
            if others:
                axes.legend(fontsize=8)
            axes.set_xlabel(axis_label(x, key_unit(x)))
            axes.set_ylabel(label)
            axes.grid(True, alpha=0.3)
        else:
            if others:
                raise PlotError(
                    f"a heat map shows two keys; {', '.join(others)} also vary: fix them with --where KEY=VALUE"
                )
            grid = values.groupby([table[y], table[x]]).mean().unstack(x)
            cmap = plt.get_cmap("viridis").with_extremes(bad="lightgrey")
            image = axes.imshow(np.ma.masked_invalid(grid.to_numpy(float)), origin="lower", aspect="auto", cmap=cmap)
            axes.set_xticks(range(len(grid.columns)), [_text(v) for v in grid.columns])
            axes.set_yticks(range(len(grid.index)), [_text(v) for v in grid.index])
            for row, col, text, colour in cell_labels(grid.to_numpy(float), lambda v: cmap(image.norm(v))):
                axes.text(col, row, text, ha="center", va="center", fontsize=8, color=colour)
            figure.colorbar(image, ax=axes, label=label)
            axes.set_xlabel(axis_label(x, key_unit(x)))
            axes.set_ylabel(axis_label(y, key_unit(y)))
        title = f"{metric} ({len(table)} cases"
        title += f", {int(blew.sum())} blew up: not drawn)" if blew.any() else ")"
        if chosen:
            title += "\n" + ", ".join(chosen)
        axes.set_title(title, fontsize=10)
        figure.tight_layout()
        from ..io import replacing

        with replacing(out, "plot") as file:  # whole or not at all: a full disk leaves the old picture as it was
            figure.savefig(file, format="png")
    finally:
        plt.close(figure)
    return out


def key_unit(key: str) -> str:
    """The unit of a descriptor key ``section.key`` (``wind.speed`` -> ``m/s``) as its config class's docstring
    writes it (the first ``[...]`` of the key's entry holding a letter); ``""`` when it has none (a fraction)."""
    import inspect
    import re

    from ..scene.descriptor import section_class

    section, _, name = key.partition(".")
    if key == "wind.speed":
        return "m/s"
    try:
        doc = inspect.getdoc(section_class(section)) or ""
    except Exception:  # noqa: BLE001 - an unknown section (a table from another version): no unit
        return ""
    entry = re.search(rf"(?:^|\s){re.escape(name)}:(.*?)(?=\n\s*\w+(?:, \w+)*:|\Z)", doc, re.S)
    if entry is None:
        return ""
    for unit in re.findall(r"\[([^\[\]]+)\]", entry.group(1)):
        if re.search(r"[A-Za-z]", unit) and "," not in unit:
            return unit
    return ""


def axis_label(name: str, unit: str) -> str:
    """``name [unit]``, or ``name`` alone for a dimensionless quantity."""
    return f"{name} [{unit}]" if unit and unit != "-" else name


RECORDED = {
    "worst_stretch": ("%", "largest |l - r| / r over all sticks (the recording's own, in percent)"),
    "kinetic_energy": ("J", "kinetic energy of the free particles (the recording's own)"),
}
"""Metrics a recording stores for the whole frame, besides the figures of each object."""


def recording_metrics(kind: str) -> dict[str, tuple[str, str]]:
    """What ``warpsim plot REC.h5 --metric`` draws for an object of ``kind``: name -> (unit, meaning): its
    :data:`warpsim.run.figures.FIGURES` (all measured from positions, the kite's line pull from its rope's sag),
    then :data:`RECORDED`."""
    from ..run.figures import FIGURES, figure_names

    out = {name: (FIGURES[name][0], FIGURES[name][2]) for name in figure_names(kind)}
    return {**out, **RECORDED}


class _RecordedFrame:
    """What :class:`warpsim.run.figures.Figures` reads of a frame, from a recording: positions [m], velocities
    [m/s] from the positions one frame before (the first frame: one frame after), each world's wind [m/s]."""

    def __init__(self, positions: np.ndarray, velocities: np.ndarray, wind: np.ndarray):
        self.positions, self.velocities, self.wind = positions, velocities, wind


def recording_series(path, metrics) -> tuple[np.ndarray, dict[str, np.ndarray], list[str], str]:
    """Each of ``metrics`` (names of :func:`recording_metrics`) of every frame of the recording ``path``:
    ``(time [F] [s], {name: values [F, K]}, object names [K], object kind)``; a whole-frame metric has ``K = 1``.

    The figures are measured from the recorded positions as the heads-up display and ``warpsim run`` measure them
    (:class:`warpsim.run.figures.Figures`), with velocities over one frame interval and the wind the scene sets
    at the reference height (each world's, and the wind control where one was recorded; gusts are not recorded
    and are left out)."""
    from ..io.h5format import RecordingError
    from ..io.recording import Recording
    from ..run.figures import Figures

    with Recording(path) as recording:
        count = recording.frame_count
        if count == 0:
            raise RecordingError(f"{path}: the recording has no frames")
        scene = recording.recorded_scene()
        kind = scene.kind
        known = recording_metrics(kind)
        for name in metrics:
            if name not in known:
                raise PlotError(
                    f"--metric {name}: a {kind} recording has no such figure{suggest(name, known, cutoff=0.75)}; "
                    f"it has {', '.join(known)}"
                )
        model = recording.build_model()
        names = [record.name for record in model.objects]
        time = np.asarray(recording.time[:count], dtype=np.float64)
        out: dict[str, np.ndarray] = {}
        if "worst_stretch" in metrics:
            out["worst_stretch"] = 100.0 * recording.file["diagnostics/worst_stretch"][:count].astype(float)[:, None]
        if "kinetic_energy" in metrics:
            out["kinetic_energy"] = recording.file["diagnostics/kinetic_energy"][:count].astype(float)[:, None]
        wanted = [name for name in metrics if name not in RECORDED]
        if wanted:
            winds = np.array([scene.wind_of(w).velocity for w in range(model.world_count)], dtype=float)
            figures = Figures(model)
            q = recording.positions()
            values = {name: np.full((count, len(names)), np.nan) for name in wanted}
            for k in range(count):
                j = k - 1 if k > 0 else min(k + 1, count - 1)
                gap = time[k] - time[j]
                velocities = (q[k] - q[j]) / gap if gap != 0 else np.zeros_like(q[k])
                wind = winds
                recorded = recording.controls(k).get("wind")
                if recorded is not None:
                    wind = np.tile(np.asarray(recorded, dtype=float), (model.world_count, 1))
                found = figures(_RecordedFrame(q[k], velocities, wind))
                for name in wanted:
                    values[name][k] = [f[name] for f in found]
            out.update(values)
    return time, {name: out[name] for name in metrics}, names, kind


def plot_recording(path, out, metrics) -> Path:
    """Draw ``metrics`` (names of :func:`recording_metrics`, one panel each, stacked over a shared time axis)
    of the recording ``path`` against simulated time, one line per object (each world's), axes labelled with
    their units; write ``out`` (a PNG). Returns the path written; raises :class:`PlotError`."""
    from ..io import OutputPathError, check_output_path
    from ..io.h5format import RecordingError

    try:
        out = check_output_path(out, (".png",), "PNG")
    except OutputPathError as err:
        raise PlotError(str(err)) from None
    metrics = [m for m in metrics if m]
    if not metrics:
        raise PlotError("--metric: name at least one, e.g. --metric altitude,airspeed")
    try:
        time, series, names, kind = recording_series(path, metrics)
    except (RecordingError, OSError) as err:
        raise PlotError(str(err)) from None
    matplotlib = _require("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    units = recording_metrics(kind)
    figure, panels = plt.subplots(len(metrics), 1, sharex=True, figsize=(7.5, 1.0 + 2.4 * len(metrics)), dpi=110)
    panels = np.atleast_1d(panels)
    try:
        for axes, name in zip(panels, metrics, strict=True):
            values = series[name]
            labels = names if values.shape[1] == len(names) else ["all objects"]
            for column, label in enumerate(labels):
                axes.plot(time, values[:, column], label=label if len(labels) > 1 else None)
            if len(labels) > 1:
                axes.legend(fontsize=7)
            axes.set_ylabel(axis_label(name.replace("_", " "), units[name][0]))
            axes.grid(True, alpha=0.3)
        panels[-1].set_xlabel(axis_label("simulated time", "s"))
        panels[0].set_title(f"{Path(path).name}: {kind}, {len(time)} frames", fontsize=10)
        figure.tight_layout()
        from ..io import replacing

        with replacing(out, "plot") as file:
            figure.savefig(file, format="png")
    finally:
        plt.close(figure)
    return out
