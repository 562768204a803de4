"""A checked scene as one typed, read-only value: what every layer above ``scene/`` takes instead of a descriptor.

A :class:`Scene` holds a validated descriptor (see :mod:`.descriptor` for its sections) and its typed settings; its
attributes say what the layers above need (the object, its config, the time step and frame rate, the worlds'
count, the controls' schedule), and :meth:`Scene.descriptor` hands out a copy of the plain tables for what must
write or merge them (TOML, a recording, a sweep's chunk). Nothing outside ``scene/`` indexes a descriptor.
"""

from __future__ import annotations

import copy
import itertools
import json
from dataclasses import dataclass, field
from pathlib import Path

from ..objects import registry
from ..physics.config import WindConfig, from_section
from .build import Settings, build_model, settings
from .descriptor import FILE_KEYS, check_axis, merge, one_of_batch, resolve, to_toml, world_descriptor

LAUNCH_SECTIONS = ("solver", "air", "terrain", "ground")
"""The sections one launch of the kernels cannot vary between worlds: scenes that differ in them step apart."""


@dataclass(frozen=True, eq=False)
class Scene:
    """A validated scene: its descriptor (kept private; :meth:`descriptor` gives a copy) and typed settings.

    Attributes:
        where: where it came from (a file, ``built-in kite``, a recording), named in errors.
        settings: the shared sections as typed configs (:class:`~warpsim.scene.build.Settings`).
    """

    _tables: dict = field(repr=False)
    where: str = "scene"
    settings: Settings = field(init=False, repr=False)

    def __post_init__(self):
        object.__setattr__(self, "_tables", copy.deepcopy(self._tables))
        object.__setattr__(self, "settings", settings(self._tables))

    @classmethod
    def of(cls, scene: Scene | dict | str, where: str = "scene") -> Scene:
        """``scene`` itself, a validated descriptor (:func:`~warpsim.scene.descriptor.defaults`,
        :func:`~warpsim.scene.descriptor.merge`) as a Scene, or a built-in object, scene name or ``.toml`` path
        (:meth:`load`)."""
        if isinstance(scene, Scene):
            return scene
        if isinstance(scene, str | Path):
            return cls.load(str(scene))
        if not isinstance(scene, dict):
            raise TypeError(f"a scene is a Scene, a descriptor (dict) or a scene's name or path, not {scene!r}")
        return cls(scene, where)

    @classmethod
    def load(cls, name: str) -> Scene:
        """A built-in object, a scene name (``./scenes``, then the shipped ones) or a ``.toml`` path
        (:func:`~warpsim.scene.descriptor.resolve`); ``where`` says which (the file's path, ``built-in kite``)."""
        from .dirs import scene_dirs

        descriptor, _, where = resolve(name, scene_dirs())
        return cls(descriptor, where)

    # ------------------------------------------------------------------ what the layers above read
    @property
    def kind(self) -> str:
        """The object kind (a name of :data:`warpsim.objects.registry.OBJECTS`)."""
        return self.settings.scene.object

    @property
    def section(self) -> str:
        """The object's own section name (``hang-glider`` -> ``hang_glider``)."""
        return registry.section(self.kind)

    @property
    def seconds(self) -> float:
        """How long a run of it lasts [s] (``scene.seconds``)."""
        return self.settings.scene.seconds

    @property
    def dt(self) -> float:
        """The solver's time step [s]."""
        return self.settings.solver.dt

    @property
    def world_count(self) -> int:
        """How many copies of the object one simulation steps (``worlds.count``)."""
        return int(self._tables.get("worlds", {}).get("count", 1))

    @property
    def controls(self) -> list[dict]:
        """The ``[[controls]]`` schedule, a copy (entries: ``time`` [s], ``ramp``, control values)."""
        return copy.deepcopy(self._tables.get("controls", []))

    @property
    def varied(self) -> dict[str, list]:
        """The settings that differ between the worlds, by dotted name (``wind.speed``, ``kite.tow_point``), each
        with one value per world (a copy)."""
        out = {}
        for section, values in self._tables.get("worlds", {}).items():
            if section != "count":
                for key, per_world in values.items():
                    out[f"{section}.{key}"] = copy.deepcopy(per_world)
        return out

    @property
    def sweep(self) -> dict:
        """The ``[sweep]`` table (a copy): section -> key -> values, a list or a range text."""
        return copy.deepcopy(self._tables.get("sweep", {}))

    def object_config(self, world: int = 0):
        """The object's config dataclass in world ``world`` (with that world's ``[worlds]`` values)."""
        return from_section(registry.OBJECTS[self.kind].config, copy.deepcopy(self._world_tables(world)[self.section]))

    def wind_of(self, world: int) -> WindConfig:
        """The ``[wind]`` of world ``world`` (its ``[worlds]`` values in place)."""
        return from_section(WindConfig, copy.deepcopy(self._world_tables(world)["wind"]))

    def build_model(self, device: str | None = "cpu", where: str | None = None, terrain=None, worlds=None):
        """The :class:`~warpsim.physics.model.Model` of this scene's worlds (all, or those of the range ``worlds``):
        :func:`~warpsim.scene.build.build_model`."""
        return build_model(self._tables, device, self.where if where is None else where, terrain, worlds=worlds)

    def _world_tables(self, world: int) -> dict:
        """The tables of world ``world``: its ``[worlds]`` values in place (a batch of one may have them too);
        without any, the scene's own tables, so that a caller copies what it hands out."""
        varied = any(section != "count" for section in self._tables.get("worlds", {}))
        return world_descriptor(self._tables, world) if varied else self._tables

    def world(self, index: int) -> Scene:
        """World ``index`` alone (its ``[worlds]`` values in place, one world)."""
        return Scene(world_descriptor(self._tables, index), self.where)

    def with_values(self, override: dict, origin: str | None = None) -> Scene:
        """This scene, from where it came, with ``override``'s sections merged in and checked: raises
        :class:`~warpsim.scene.values.DescriptorError` naming ``origin`` (default: :attr:`where`), e.g. ``--set
        kite.tow_point=0.3``."""
        return Scene(merge(self.where if origin is None else origin, self._tables, override), self.where)

    # ------------------------------------------------------------------ a sweep's scenes
    def for_sweep(self, seconds: float) -> Scene:
        """This scene as a sweep's base: every case runs ``seconds`` [s], and its ``[sweep]`` table (the axes, read
        by the sweep's plan) is dropped. Raises :class:`~warpsim.scene.values.DescriptorError`."""
        tables = merge("sweep", self._tables, {"scene": {"seconds": seconds}})
        tables.pop("sweep", None)
        return Scene(tables, "sweep")

    def check_axis(self, where: str, section: str, key: str, values) -> list:
        """One sweep axis over this scene, checked: ``section.key`` takes each of ``values`` (a list or a range
        text ``START:STOP:COUNT``); :func:`~warpsim.scene.descriptor.check_axis`."""
        return check_axis(where, self._tables, section, key, values)

    def batch(self, count: int, shared: dict, per_world: dict) -> Scene:
        """``count`` worlds of this scene: ``shared`` (section -> key -> value) set in all of them, ``per_world``
        (section -> key -> ``count`` values) one value per world. Raises
        :class:`~warpsim.scene.values.DescriptorError`."""
        return Scene(merge(self.where, self._tables, {**shared, "worlds": {"count": count, **per_world}}), self.where)

    def one_of_batch(self, world: int) -> Scene:
        """World ``world`` of this batch as a batch of one (its ``[worlds]`` values kept as one-value lists: a
        sweep's case run alone, as its chunk ran it)."""
        return Scene(one_of_batch(self._tables, world), self.where)

    def launch_key(self) -> str:
        """The scene's :data:`LAUNCH_SECTIONS` as canonical JSON: two scenes with the same key compile and launch the
        same kernels."""
        return json.dumps({k: v for k, v in self._tables.items() if k in LAUNCH_SECTIONS}, sort_keys=True)

    # ------------------------------------------------------------------ the plain tables
    def descriptor(self) -> dict:
        """A copy of the plain descriptor (section -> key -> value): what is written or merged."""
        return copy.deepcopy(self._tables)

    def as_mesh_design(self, mesh: dict) -> str:
        """This scene as TOML for its object flown as a design of its own from a mesh file (what ``warpsim export``
        writes beside the mesh): its shared sections, the controls of its schedule a mesh design has, and ``mesh``
        (the mesh section's keys) in place of the object's section."""
        out = {k: copy.deepcopy(v) for k, v in self._tables.items() if k not in ("worlds", "sweep", self.section)}
        out["scene"]["object"] = registry.MESH
        names = set(registry.OBJECTS[registry.MESH].controls) | {"wind", "time", "ramp"}
        out["controls"] = [c for c in self.controls if set(c) <= names]
        out[registry.section(registry.MESH)] = copy.deepcopy(mesh)
        return to_toml(out)

    def files(self) -> list[str]:
        """The files the scene reads besides its own (a terrain's heights, a design's mesh and structure, in any world
        or sweep case; absolute where the scene came from a file), each once."""
        names: list[str] = []
        for section in ("terrain", *(registry.section(kind) for kind in registry.OBJECTS)):
            tables = [self._tables.get(section, {})]
            tables += [self._tables.get(t, {}).get(section, {}) for t in ("worlds", "sweep")]
            for table, key in itertools.product(tables, FILE_KEYS):
                found = table.get(key) if isinstance(table, dict) else None
                for name in found if isinstance(found, list) else [found]:
                    if isinstance(name, str) and name and name not in names:
                        names.append(name)
        return names

    def table(self, section: str) -> dict:
        """A copy of one section's plain table (``solver``...), for what stores it as written."""
        return copy.deepcopy(self._tables[section])

    def toml(self) -> str:
        """The scene as TOML text (read back by :func:`~warpsim.scene.descriptor.load_text`)."""
        return to_toml(self._tables)
