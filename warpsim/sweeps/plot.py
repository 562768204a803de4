"""A quick look at a sweep's table: one metric against one swept key (lines) or two (a heat map), as a PNG.

Swept keys are the table's ``section.key`` columns (metrics have no dot in their names). Cases that blew up are
left out of the picture and counted in its title. Needs pandas (and pyarrow for ``.parquet``) and matplotlib:
the ``[sweep]`` extra.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

MAX_LINES = 12  # lines one line plot draws before it asks for --where


class PlotError(ValueError):
    """The table, keys or metric asked for cannot be drawn; the message says why in one line."""


def _require(module: str):
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError:
        raise PlotError(f"plots need {module.split('.')[0]}: pip install -e '.[sweep]'") from None


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
        raise PlotError(f"--metric {metric}: not in {path}; it has {', '.join(metrics)}")
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

    unit = METRICS.get(metric, ("",))[0]
    label = f"{metric} [{unit}]" if unit else metric
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
            axes.set_xlabel(x)
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
            for (row, col), v in np.ndenumerate(grid.to_numpy(float)):
                if np.isfinite(v):
                    axes.text(col, row, f"{v:.3g}", ha="center", va="center", fontsize=7, color="white")
            figure.colorbar(image, ax=axes, label=label)
            axes.set_xlabel(x)
            axes.set_ylabel(y)
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
