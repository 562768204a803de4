"""A JSON Schema (draft 2020-12) of the scene file format, generated from the typed settings: every section and
key, its type, default, bounds and choices as :mod:`warpsim.physics.config` and each object's config class give
them. Editors that read JSON Schema (for TOML through Taplo / Even Better TOML) then complete and check scene files.

It describes what a file may hold; the descriptor (:mod:`.descriptor`) still checks what a schema cannot say (a
design's preset, per-world lists as long as ``worlds.count``, wind speeds against ``wind.velocity``'s bounds).
"""

from __future__ import annotations

import dataclasses
import typing
from typing import Any

from ..objects import registry
from ..physics.config import SECTIONS, as_section, field_bounds, field_choices
from .descriptor import FLOAT_LIMIT, MAX_WORLDS, SWEEP_FIXED, VARIABLE_SECTIONS

SCHEMA_ID = "https://warpsim.invalid/scene.schema.json"


def _number_schema(bounds, integer: bool) -> dict[str, Any]:
    """A number's schema: its bounds, and for a float an unbounded side at the descriptor's ``FLOAT_LIMIT``."""
    out: dict[str, Any] = {"type": "integer" if integer else "number"}
    low = None if bounds is None else bounds.low
    high = None if bounds is None else bounds.high
    if low is not None:
        out["exclusiveMinimum" if bounds.low_open else "minimum"] = low
    elif not integer:
        out["minimum"] = -FLOAT_LIMIT
    if high is not None:
        out["exclusiveMaximum" if bounds.high_open else "maximum"] = high
    elif not integer:
        out["maximum"] = FLOAT_LIMIT
    return out


def _key_schema(cls, field: dataclasses.Field, default) -> dict[str, Any]:
    """The schema of one key of a section: its choices, or its number type and bounds (per element for a vector),
    or a boolean or string; with its default."""
    if "schema" in field.metadata:  # a list of tables with its own schema (a mesh design's parts)
        return {**field.metadata["schema"], "default": default}
    options = field_choices(cls, field.name)
    if options is not None:
        return {"enum": list(options), "default": default}
    if isinstance(default, bool):
        return {"type": "boolean", "default": default}
    if isinstance(default, str):
        return {"type": "string", "default": default}
    bounds = field_bounds(cls, field.name)
    if isinstance(default, list):
        return {
            "type": "array",
            "items": _number_schema(bounds, False),
            "minItems": len(default),
            "maxItems": len(default),
            "default": default,
        }
    hint = typing.get_type_hints(cls).get(field.name)
    integer = hint is int if hint is not None else isinstance(default, int)  # a float field may default to 0
    return {**_number_schema(bounds, integer), "default": default}


def _section_schema(cls, values: dict[str, Any] | None = None) -> dict[str, Any]:
    """A section of config class ``cls`` (``values``: its defaults, when they differ from the class's own)."""
    defaults = values if values is not None else as_section(cls())
    doc = (cls.__doc__ or "").strip().splitlines()
    return {
        "type": "object",
        "description": doc[0] if doc else cls.__name__,
        "properties": {f.name: _key_schema(cls, f, defaults[f.name]) for f in dataclasses.fields(cls)},
        "additionalProperties": False,
    }


def scene_schema() -> dict[str, Any]:
    """The JSON Schema of a scene file (a dict ready for ``json.dumps``)."""
    properties: dict[str, Any] = {name: _section_schema(cls) for name, cls in SECTIONS.items()}
    properties["scene"]["properties"]["object"] = {"enum": list(registry.OBJECTS), "default": registry.DEFAULT_OBJECT}
    for kind, spec in registry.OBJECTS.items():
        properties[registry.section(kind)] = _section_schema(spec.config)
    variable = sorted({*VARIABLE_SECTIONS, *(registry.section(k) for k in registry.OBJECTS)})
    properties["worlds"] = {
        "type": "object",
        "description": "N copies of the scene in one model; keys of the object's section or [wind] listed per world",
        "properties": {
            "count": {"type": "integer", "minimum": 1, "maximum": MAX_WORLDS, "default": 1},
            **{name: {"type": "object", "additionalProperties": {"type": "array"}} for name in variable},
        },
        "additionalProperties": False,
    }
    properties["controls"] = {
        "type": "array",
        "description": "control schedule: [[controls]] entries, each a time [s] and the controls set from then on",
        "items": {"type": "object", "required": ["time"], "properties": {"time": {"type": "number", "minimum": 0}}},
    }
    properties["sweep"] = {
        "type": "object",
        "description": "swept keys: {section: {key: [values] or 'START:STOP:COUNT'}} (not "
        + ", ".join(f"[{s}]" for s in SWEEP_FIXED)
        + ")",
        "additionalProperties": {"type": "object"},
    }
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": SCHEMA_ID,
        "title": "warpsim scene",
        "description": "A warpsim scene descriptor (TOML): sections of settings, one per object kind and shared ones.",
        "type": "object",
        "properties": properties,
        "additionalProperties": False,
    }
