"""`warpsim schema`: a JSON Schema of the scene format, generated from the typed settings, that every shipped scene
file and every object's defaults satisfy (checked here key by key: type, bounds, choices), and that refuses what
the descriptor refuses (an unknown key, a number out of its bounds, an unknown choice)."""

import json
import math

import pytest

from warpsim.cli import main
from warpsim.objects import registry
from warpsim.scene.descriptor import DescriptorError, defaults, load_text
from warpsim.scene.dirs import SHIPPED
from warpsim.scene.schema import scene_schema

try:
    import tomllib
except ImportError:  # Python 3.10
    import tomli as tomllib


def _problems(schema: dict, value, where: str = "") -> list[str]:
    """What ``value`` breaks of ``schema`` (the subset of JSON Schema scene_schema writes)."""
    out = []
    if "anyOf" in schema and all(_problems(option, value, where) for option in schema["anyOf"]):
        out.append(f"{where}: {value!r} fits none of {schema['anyOf']}")
    if "enum" in schema and value not in schema["enum"]:
        out.append(f"{where}: {value!r} not in {schema['enum']}")
    kind = schema.get("type")
    checks = {
        "object": lambda v: isinstance(v, dict),
        "array": lambda v: isinstance(v, list),
        "boolean": lambda v: isinstance(v, bool),
        "string": lambda v: isinstance(v, str),
        "integer": lambda v: isinstance(v, int) and not isinstance(v, bool),
        "number": lambda v: isinstance(v, (int, float)) and not isinstance(v, bool),
    }
    if kind is not None and not checks[kind](value):
        return [*out, f"{where}: {value!r} is not {kind}"]
    if kind in ("integer", "number"):
        for key, ok in (
            ("minimum", lambda v, b: v >= b),
            ("maximum", lambda v, b: v <= b),
            ("exclusiveMinimum", lambda v, b: v > b),
            ("exclusiveMaximum", lambda v, b: v < b),
        ):
            if key in schema and not ok(value, schema[key]):
                out.append(f"{where}: {value!r} breaks {key} {schema[key]}")
    if kind == "array":
        if "minItems" in schema and not schema["minItems"] <= len(value) <= schema.get("maxItems", len(value)):
            out.append(f"{where}: {len(value)} items")
        for k, item in enumerate(value):
            out += _problems(schema.get("items", {}), item, f"{where}[{k}]")
    if kind == "object":
        properties = schema.get("properties", {})
        for key, item in value.items():
            if key in properties:
                out += _problems(properties[key], item, f"{where}.{key}")
            elif schema.get("additionalProperties") is False:
                out.append(f"{where}: unknown key {key}")
    return out


def test_the_command_prints_a_schema_naming_every_object(capsys):
    assert main(["schema"]) == 0
    schema = json.loads(capsys.readouterr().out)
    assert schema["$schema"].startswith("https://json-schema.org/")
    assert schema["properties"]["scene"]["properties"]["object"]["enum"] == list(registry.OBJECTS)
    for kind in registry.OBJECTS:
        assert registry.section(kind) in schema["properties"]


@pytest.mark.parametrize("path", sorted(SHIPPED.glob("*.toml")), ids=lambda p: p.stem)
def test_every_shipped_scene_file_satisfies_the_schema(path):
    text = path.read_text()
    load_text(text, str(path))  # the descriptor takes it
    assert _problems(scene_schema(), tomllib.loads(text)) == []


@pytest.mark.parametrize("kind", list(registry.OBJECTS))
def test_every_default_satisfies_the_schema(kind):
    d = defaults(kind)
    d.pop("controls")
    assert _problems(scene_schema(), d) == []


@pytest.mark.parametrize(
    "text",
    [
        "[solver]\nitterations = 40\n",  # an unknown key
        "[solver]\ndt = -0.001\n",  # out of its bounds
        "[air]\nmodel = 'magic'\n",  # an unknown choice
        "[wind]\nvelocity = [1.0, 2.0]\n",  # a vector of the wrong length
    ],
)
def test_the_schema_refuses_what_the_descriptor_refuses(text):
    with pytest.raises(DescriptorError):
        load_text(text, "test")
    assert _problems(scene_schema(), tomllib.loads(text))


def test_bounds_are_numbers_json_can_hold():
    def walk(node):
        if isinstance(node, dict):
            for value in node.values():
                yield from walk(value)
        elif isinstance(node, list):
            for value in node:
                yield from walk(value)
        elif isinstance(node, float):
            yield node

    assert all(math.isfinite(v) for v in walk(scene_schema()))
