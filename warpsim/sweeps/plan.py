"""A sweep's plan: its axes (swept keys and values, checked against the scene), its cases (the cartesian
product, first axis slowest), each case's key, and the chunks of cases that run as one task each."""

from __future__ import annotations

import itertools
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..scene.descriptor import VARIABLE_SECTIONS, DescriptorError
from ..scene.scene import Scene
from ..scene.values import parse_vary
from .metrics import SweepError, metrics_of

MAX_CASES = 1_000_000
MAX_CHUNK = 64  # worlds per task when the chunk size is chosen automatically

TABLE_FORMAT = 2
"""The sweep table's format: 2 since ``worst_stretch`` is in percent (1 had it as a fraction). A table of
another format is not resumed (its rows' units would mix with the new ones)."""


@dataclass(frozen=True)
class Axis:
    """One swept key: ``section.key`` takes each of ``values`` in turn (checked against the scene)."""

    section: str
    key: str
    values: tuple

    @property
    def name(self) -> str:
        """``section.key``, also the axis's column in the results."""
        return f"{self.section}.{self.key}"


def parse_axes(scene: Scene, items: Sequence[str] | dict, where: str = "--vary") -> list[Axis]:
    """The sweep's axes: the scene's ``[sweep]`` table, then ``items`` (``--vary`` texts
    ``KEY=START:STOP:COUNT`` or ``KEY=V1,V2,...``, or a dict ``{"section.key": values or "START:STOP:COUNT"}``),
    which replace a ``[sweep]`` axis of the same key. Raises :class:`~warpsim.scene.descriptor.DescriptorError`."""
    axes: dict[str, Axis] = {}
    for section, keys in scene.sweep.items():
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
        axes[f"{section}.{key}"] = Axis(section, key, tuple(scene.check_axis(origin, section, key, values)))
    names = set(axes)
    if {"wind.speed", "wind.velocity"} <= names:
        raise DescriptorError(f"{where}: sweep wind.speed or wind.velocity, not both")
    if not axes:
        raise DescriptorError(f"{where}: nothing to sweep: give --vary KEY=VALUES (or a [sweep] table in the scene)")
    return list(axes.values())


def plain(value):
    """A swept value as plain JSON data (NumPy scalars and arrays, as pandas gives them back, included)."""
    if isinstance(value, np.ndarray):
        return [plain(v) for v in value.tolist()]
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    return value


def case_key(values: Sequence) -> str:
    """A case's identity: its swept values as canonical JSON (what resuming matches rows by)."""
    return json.dumps([plain(v) for v in values])


@dataclass
class ChunkTask:
    """One Dask task: the cases ``cases`` (plan indices) run as the worlds of ``scene``.

    Attributes:
        scene: the chunk's :class:`~warpsim.scene.scene.Scene`, its worlds holding each case's values.
        cases: plan indices of the cases, in world order. columns: their swept values, by axis name.
        seconds: simulated time [s]. window: ``(start, stop)`` [s] the window metrics cover.
        metrics: metric columns to report. device: Warp device. h5: recording to write, or None.
        threads: threads stepping the chunk's worlds (:class:`~warpsim.run.simulation.Simulation`).
    """

    scene: Scene
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
        return replace(
            self, scene=self.scene.one_of_batch(k), cases=[self.cases[k]], columns=[self.columns[k]], h5=None
        )


class SweepPlan:
    """The cases of a sweep and how they are cut into tasks.

    Args:
        scene: the :class:`~warpsim.scene.scene.Scene` swept (of one world; its ``[sweep]`` is not read here).
        axes: the swept keys (:func:`parse_axes`).
        seconds: simulated time of every case [s] (default: the scene's).
        window: ``(start, stop)`` [s] of the window metrics (default: the second half of the run).
        metrics: metric names (default: all the object has; see :func:`metrics_of`).
    """

    def __init__(
        self,
        scene: Scene,
        axes: Sequence[Axis],
        seconds: float | None = None,
        window: tuple[float, float] | None = None,
        metrics: Sequence[str] | None = None,
    ):
        if scene.world_count != 1:
            raise SweepError("a sweep makes its own worlds: remove [worlds] from the scene (use --vary instead)")
        self.kind = scene.kind
        self.axes = list(axes)
        self.seconds = float(seconds if seconds is not None else scene.seconds)
        if not (self.seconds > 0 and math.isfinite(self.seconds)):
            raise SweepError(f"--seconds must be a positive number, got {self.seconds}")
        # the same definition whether --seconds or the scene says it; a sweep's [sweep] table is not the cases'
        self.base = scene.for_sweep(self.seconds)
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
        self._terrain = _terrain_digest(scene.settings.terrain)  # read once: a terrain file may be hundreds of MB
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
            "table_format": TABLE_FORMAT,
            "scene": self.base.toml(),
            "terrain": self._terrain,
            "seconds": self.seconds,
            "window": list(self.window),
            "axes": [a.name for a in self.axes],
            "metrics": list(self.metrics),
        }

    def case_scene(self, index: int) -> Scene:
        """The scene of case ``index`` run alone (one world)."""
        return self._chunk_scene([index])

    def _chunk_scene(self, indices: Sequence[int]) -> Scene:
        shared: dict = {}
        worlds: dict = {}
        for a, (axis, per_world) in enumerate(zip(self.axes, self._per_world, strict=True)):
            if per_world:
                worlds.setdefault(axis.section, {})[axis.key] = [self.cases[i][a] for i in indices]
            else:  # one value for the whole chunk: its cases share it (see chunks)
                shared.setdefault(axis.section, {})[axis.key] = self.cases[indices[0]][a]
        return self.base.batch(len(indices), shared, worlds)

    def chunks(
        self,
        size: int,
        skip: set[int] = frozenset(),
        device: str = "cpu",
        h5_dir: Path | None = None,
        h5_prefix: str = "cases",
    ) -> list[ChunkTask]:
        """The tasks of every case not in ``skip``, ``size`` cases each at most. Cases that differ in a key one
        launch cannot vary between worlds (solver, air, terrain, ground) go to different chunks. With ``h5_dir``,
        each task records its chunk there as ``{h5_prefix}-{first case:06d}-{last case:06d}.h5`` (a sweep's prefix
        names its table, so that two sweeps sharing the folder never write each other's recordings)."""
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
                h5 = str(Path(h5_dir) / f"{h5_prefix}-{indices[0]:06d}-{indices[-1]:06d}.h5") if h5_dir else None
                tasks.append(
                    ChunkTask(
                        self._chunk_scene(indices),
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


def _terrain_digest(terrain) -> str | None:
    """sha256 of the file a scene's terrain (a :class:`~warpsim.physics.config.TerrainConfig`) names (None without
    one): a sweep resumed after the heights were edited must not keep rows flown over the old ones (the path alone
    stays the same)."""
    import hashlib

    if terrain.kind != "file" or not terrain.file:
        return None
    digest = hashlib.sha256()
    try:
        with open(terrain.file, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                digest.update(block)
    except OSError:
        return None  # the build says what is wrong with the file
    return digest.hexdigest()


def _object_section(kind: str) -> str:
    from ..objects import registry

    return registry.section(kind)


# ---------------------------------------------------------------------------------------------------- one task


# ---------------------------------------------------------------------------------------------------- the rows


# ---------------------------------------------------------------------------------------------------- Dask


# ---------------------------------------------------------------------------------------------------- the API
