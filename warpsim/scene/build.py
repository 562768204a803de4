"""From a validated scene descriptor to what runs it: typed settings, the terrain and the model of every world.

:func:`settings` reads a descriptor's sections into the config dataclasses of :mod:`warpsim.physics.config`;
:func:`build_model` builds ``worlds.count`` copies of the scene's object, each with its own ``[worlds]``
values, into one :class:`~warpsim.physics.model.Model`. Outputs and readers of recordings build models here too.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..objects import registry
from ..physics.builder import ModelBuilder
from ..physics.config import (
    AirConfig,
    GroundConfig,
    SceneConfig,
    SolverConfig,
    TerrainConfig,
    WindConfig,
    from_section,
)
from ..physics.memory import check_memory
from ..physics.model import Model
from ..physics.terrain import Heightfield
from .descriptor import DescriptorError, world_descriptor


@dataclass(frozen=True)
class Settings:
    """A descriptor's shared sections as typed configs (the object's own section and ``[worlds]`` aside)."""

    scene: SceneConfig
    solver: SolverConfig
    air: AirConfig
    wind: WindConfig
    terrain: TerrainConfig
    ground: GroundConfig


def settings(descriptor: dict) -> Settings:
    """The typed :class:`Settings` of a validated descriptor."""
    return Settings(
        scene=from_section(SceneConfig, descriptor["scene"]),
        solver=from_section(SolverConfig, descriptor["solver"]),
        air=from_section(AirConfig, descriptor["air"]),
        wind=from_section(WindConfig, descriptor["wind"]),
        terrain=from_section(TerrainConfig, descriptor["terrain"]),
        ground=from_section(GroundConfig, descriptor["ground"]),
    )


def make_terrain(cfg: TerrainConfig, where: str = "scene") -> Heightfield:
    """The terrain a :class:`~warpsim.physics.config.TerrainConfig` describes (``where`` names it in errors)."""
    if cfg.kind == "flat":
        return Heightfield.flat(size=cfg.size, height=cfg.height)
    if cfg.kind == "procedural":
        return Heightfield.procedural(size=cfg.size, amplitude=cfg.amplitude, seed=cfg.seed, base_height=cfg.height)
    if not cfg.file:
        raise DescriptorError(f"{where}: terrain.kind = 'file' needs terrain.file (a .npy array of heights)")
    try:
        return Heightfield.load(Path(cfg.file), size=cfg.size)
    except (ValueError, OSError) as err:
        raise DescriptorError(f"{where}: terrain.file: {err}") from None


def world_name(name: str, world: int, world_count: int) -> str:
    """An object's name in a batch of ``world_count`` worlds: ``kite`` alone, ``kite_w007`` in world 7."""
    if world_count == 1:
        return name
    return f"{name}_w{world:0{len(str(world_count - 1))}d}"


def build_model(
    descriptor: dict,
    device: str | None = "cpu",
    where: str = "scene",
    terrain: Heightfield | None = None,
    worlds: range | None = None,
) -> Model:
    """Build the model of a validated descriptor on ``device``: ``worlds.count`` copies of its object, each
    with its own ``[worlds]`` values, in one model (they share the terrain and never touch each other).

    ``terrain``: the heights to use instead of the ``[terrain]`` section's (a recording's own, so that a resumed
    or converted recording does not depend on a terrain file that may have changed or moved). ``worlds`` (default:
    all) builds only those worlds of the batch, numbered from 0 in the model but each with its own values and
    name, as in the whole batch: a part of a batch that threads step apart from the rest.
    """
    kind = descriptor["scene"]["object"]
    builder = ModelBuilder()
    if terrain is None:
        terrain = make_terrain(from_section(TerrainConfig, descriptor["terrain"]), where)
    builder.set_terrain(terrain)
    spec = registry.OBJECTS[kind]
    count = descriptor["worlds"]["count"]
    worlds = range(count) if worlds is None else worlds
    builder.world_count = len(worlds)
    for world in worlds:
        builder.current_world = world - worlds.start
        values = world_descriptor(descriptor, world)[registry.section(kind)]
        try:
            record = spec.build(builder, from_section(spec.config, values), terrain)
            if world == worlds.start and count > 1:  # the first world tells the size of all: refuse what cannot fit
                check_memory(
                    builder.particle_count * len(worlds),
                    f"{len(worlds):,} worlds of {builder.particle_count:,} particles",
                )
        except ValueError as err:
            at = f" (world {world})" if count > 1 else ""
            raise DescriptorError(f"{where}: [{registry.section(kind)}]{at}: {err}") from None
        record.name = world_name(record.name, world, count)
    try:
        return builder.finalize(device)
    except ValueError as err:
        raise DescriptorError(f"{where}: [{registry.section(kind)}]: {err}") from None
