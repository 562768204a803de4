"""``warpsim run --table OUT.parquet|OUT.csv``: a run's closing figures, one row per world.

Each row holds the world's number, its object's name, the values the batch varies between worlds (``[worlds]``
keys such as ``wind.speed``, one column each, named as in the descriptor), the window ``[window_start,
window_stop]`` [s] and the figures of :class:`warpsim.run.figures.FigureWindow` over it: ``NAME_mean``,
``NAME_min`` and ``NAME_max`` of every figure of :data:`warpsim.run.figures.FIGURES` the object has (in their
units), ``airborne`` (the share of the window's frames off the ground), ``ground_time`` (first ground contact [s],
NaN when none), ``worst_stretch`` [%] and ``window_frames``. The same columns as a sweep's table of
the same cases, so either reads the other's tools (``pandas.read_parquet``, ``pandas.read_csv``).

Parquet needs pandas and pyarrow, CSV only the standard library (the ``sweep`` extra has both). The file is
written whole or not at all (:func:`warpsim.io.replacing`).
"""

from __future__ import annotations

import csv
import importlib.util
import io
import json
from pathlib import Path

from .._extras import install_hint
from . import OutputPathError, check_output_path, replacing

EXTENSIONS = (".parquet", ".pq", ".csv")


def check_table_path(path) -> Path:
    """Check that ``path`` can be written as a table before the run (``OutputPathError`` when it cannot, or when a
    Parquet table's libraries are missing)."""
    out = check_output_path(path, EXTENSIONS, "table")
    if out.suffix.lower() != ".csv":
        missing = [name for name in ("pandas", "pyarrow") if importlib.util.find_spec(name) is None]
        if missing:
            raise OutputPathError(
                f"{out}: a Parquet table needs {' and '.join(missing)}: {install_hint('sweep')} (or write a .csv)"
            )
    return out


def write_world_table(path, figures) -> Path:
    """Write ``figures``' rows (:meth:`warpsim.run.figures.FlightFigures.rows`, after the run) to ``path``
    (.parquet/.pq or .csv); returns the path. A list-valued setting (a wind vector) is a list in Parquet and its
    JSON text in CSV."""
    path = Path(path)
    rows = figures.rows()
    if path.suffix.lower() == ".csv":
        text = io.StringIO()
        writer = csv.DictWriter(text, fieldnames=list(rows[0]) if rows else ["world"], lineterminator="\n")
        writer.writeheader()
        for row in rows:
            writer.writerow({k: json.dumps(v) if isinstance(v, list) else repr(v) if isinstance(v, float) else v
                             for k, v in row.items()})  # fmt: skip
        with replacing(path, "table") as file:
            file.write(text.getvalue().encode("utf-8"))
        return path
    import pandas as pd
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.Table.from_pandas(pd.DataFrame(rows), preserve_index=False)
    with replacing(path, "table") as file:
        pq.write_table(table, file)
    return path
