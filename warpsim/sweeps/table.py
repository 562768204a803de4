"""A sweep's rows: those an earlier run left in the table and its journal (checked to be this sweep's), those this
run adds (journalled line by line as they come), and the table written whole at the end (Parquet or CSV)."""

from __future__ import annotations

import contextlib
import json
import math
import os
from pathlib import Path

from .metrics import SweepError, require
from .plan import SweepPlan, case_key, plain


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
    """True for what a swept value may be in a row: a finite number, a boolean, text, or a short list of them."""
    if isinstance(value, float):
        return math.isfinite(value)
    if isinstance(value, (bool, int, str)):
        return True
    return isinstance(value, list) and depth < 2 and len(value) <= 16 and all(_plain_value(v, depth + 1) for v in value)


_METRIC_TYPES = {"window_frames": (int,), "blew_up": (bool,), "blowup_reason": (str,)}
"""The metrics that are not a number (or None, NaN): what each row must hold in them, so the table can be written."""


def _metric_value(name: str, value) -> bool:
    """True when ``value`` fits metric ``name``'s column (an int that is not a bool, a bool, text, or a number)."""
    types = _METRIC_TYPES.get(name)
    if types is None:  # a measured figure: a number, None or NaN
        return value is None or (isinstance(value, (int, float)) and not isinstance(value, bool))
    if types == (int,):
        return isinstance(value, int) and not isinstance(value, bool)
    return isinstance(value, types)


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
            problem = "has a swept value that is not a finite number, text or list"
        elif not all(_metric_value(m, row[m]) for m in metrics):
            problem = "has a metric that is not of its column's type"
    if problem:
        raise SweepError(
            f"{source}: row {number + 1} {problem}; the file is not this sweep's or is spoiled: choose another "
            "--out, or --restart to replace it"
        )


class Results:
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
        for key in ("table_format", "seconds", "window", "axes", "metrics", "scene", "terrain"):  # most telling first
            if found.get(key) != definition[key]:
                what = {
                    "table_format": "table format (the units of its metrics, an older warpsim's)",
                    "scene": "scene or settings",
                    "axes": "swept keys",
                    "terrain": "terrain heights",
                }.get(key, f"--{key}")
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
        return found, [{k: plain(v) for k, v in row.items()} for row in frame.to_dict("records")]

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
            row = {k: plain(v) for k, v in row.items()}
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
