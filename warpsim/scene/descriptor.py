"""Scene descriptors: TOML files -> validated, typed configuration, with clear errors.

A scene is an object + terrain + wind + solver settings (+ control schedules). Every key has a default,
so a descriptor only lists what it changes. Sections and keys (``warpsim info SCENE`` prints them all):

* ``[scene]`` ``object`` (flag, hang-glider, kite, parachute), ``seconds``, ``fps``
* ``[solver]`` ``method`` (verlet | euler), ``dt`` [s], ``iterations``, ``relaxation``, ``chebyshev``,
  ``mass_splitting``, ``damping``, ``max_stretch`` (blow-up limit on ``|l - r|/r``, 0 = off),
  ``spring_stiffness`` [N/m], ``spring_damping`` [N s/m] (euler only)
* ``[air]`` ``model`` (paper | plate), ``scale``, ``density`` [kg/m^3]
* ``[wind]`` ``velocity`` [m/s, 3 numbers], ``shear_exponent``, ``reference_height`` [m],
  ``gust_intensity`` (fraction of the mean, 0 = steady), ``gust_period`` [s], ``gust_seed``
* ``[terrain]`` ``kind`` (flat | procedural | file), ``size`` [m], ``height`` [m], ``amplitude`` [m],
  ``seed``, ``file`` (.npy)
* ``[ground]`` ``collision`` (normal | clamp), ``friction``
* one section per object, named after it (``[flag]``, ...), with the fields of its config class.
* ``[[controls]]`` entries: ``time`` [s], ``ramp`` (true = reach linearly), and any of the scene's
  controls (``pitch``, ``roll``, ``anchor``, ``wind``), see :mod:`warpsim.scene.controls`.
* ``[worlds]`` ``count`` (how many copies of the scene one launch steps, default 1), and per-world values
  as dotted keys holding one value per world: any key of the object's section or of ``[wind]``, plus
  ``wind.speed`` [m/s] (the magnitude of ``wind.velocity``, direction kept), e.g.
  ``wind.speed = [4.0, 6.0, 8.0]`` with ``count = 3``. Solver, air, terrain and ground settings are shared.
* ``[sweep]`` (read by ``warpsim sweep`` only): dotted keys holding the values one key takes across the cases
  of a sweep, a list or a range ``"START:STOP:COUNT"``, e.g. ``kite.tow_point = "0.2:0.5:4"``; any key
  outside ``[scene]``, and ``wind.speed``. ``warpsim run`` runs the scene as written and ignores it.
"""

from __future__ import annotations

import copy
import sys
from pathlib import Path
from typing import Any

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from ..objects import registry
from ..objects.mesh_file import FORMATS as MESH_FORMATS
from ..physics.config import SECTIONS, Bounds, as_section, field_bounds, field_choices, field_entries, plain
from .controls import ControlError, ControlSchedule
from .values import FLOAT_LIMIT, DescriptorError, range_values, suggest


def section_class(section: str):
    """The config dataclass of a descriptor section (shared sections and object sections), or None."""
    return SECTIONS.get(section) or registry.config_of_section(section)


def choices(section: str, key: str) -> tuple[str, ...] | None:
    """The values ``section.key`` may take, when it is a choice (derived from the config classes and enums)."""
    if (section, key) == ("scene", "object"):
        return tuple(registry.OBJECTS)
    cls = section_class(section)
    return field_choices(cls, key) if cls is not None else None


def bounds(section: str, key: str) -> Bounds | None:
    """The :class:`~warpsim.physics.config.Bounds` of ``section.key`` (from its config class), or None."""
    cls = section_class(section)
    return field_bounds(cls, key) if cls is not None else None


BASE_DEFAULTS: dict[str, dict[str, Any]] = {
    **{name: as_section(cls()) for name, cls in SECTIONS.items()},
    "worlds": {"count": 1},
}
"""Every shared section's defaults, as :mod:`warpsim.physics.config` gives them."""

MAX_WORLDS = 65536
VARIABLE_SECTIONS = ("wind",)  # besides the object's own section


def defaults(kind: str = registry.DEFAULT_OBJECT) -> dict[str, dict[str, Any]]:
    """The full default descriptor for an object ``kind``, including the object's own scene defaults."""
    d = copy.deepcopy(BASE_DEFAULTS)
    d["scene"]["object"] = kind
    d[registry.section(kind)] = as_section(registry.OBJECTS[kind].config())
    for section, values in registry.OBJECTS[kind].scene_defaults.items():
        d[section].update(copy.deepcopy(values))
    _apply_preset(d, kind, d[registry.section(kind)].get("design"))
    d["controls"] = []
    return d


def _apply_preset(descriptor: dict, kind: str, design) -> None:
    """Write the values of object ``kind``'s ``design`` preset (if it has one) into ``descriptor``."""
    for section, values in registry.OBJECTS[kind].presets.get(design, {}).items():
        descriptor[section].update(copy.deepcopy(values))


def _check_value(where: str, section: str, key: str, default, value):
    """Coerce ``value`` to the type of ``default`` or raise a DescriptorError naming ``where``."""
    name = f"{section}.{key}"
    cls = section_class(section)
    entries = field_entries(cls, key) if cls is not None else None
    if entries is not None:  # a list of tables (a mesh design's parts), checked by its own parser
        try:
            entries(value)
        except ValueError as err:
            raise DescriptorError(f"{where}: {name}: {err}") from None
        return [dict(e) for e in value]
    if isinstance(default, bool):
        if not isinstance(value, bool):
            raise DescriptorError(f"{where}: {name} must be true or false, got {value!r}")
    elif isinstance(default, int):
        if isinstance(value, bool) or not isinstance(value, int):
            raise DescriptorError(f"{where}: {name} must be a whole number, got {value!r}")
    elif isinstance(default, float):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise DescriptorError(f"{where}: {name} must be a number, got {value!r}")
        value = float(value)
        if not abs(value) <= FLOAT_LIMIT:
            raise DescriptorError(f"{where}: {name} must be finite and at most {FLOAT_LIMIT:g} in size, got {value!r}")
    elif isinstance(default, str):
        if not isinstance(value, str):
            raise DescriptorError(f"{where}: {name} must be a string, got {value!r}")
    elif isinstance(default, list):
        if (
            not isinstance(value, list)
            or len(value) != len(default)
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
        ):
            raise DescriptorError(f"{where}: {name} must be a list of {len(default)} numbers, got {value!r}")
        value = [float(v) for v in value]
        if not all(abs(v) <= FLOAT_LIMIT for v in value):
            raise DescriptorError(
                f"{where}: {name} must hold finite numbers at most {FLOAT_LIMIT:g} in size, got {value!r}"
            )
    options = choices(section, key)
    if options is not None and value not in options:
        raise DescriptorError(
            f"{where}: {name} = {value!r} is not one of {', '.join(options)}{suggest(str(value), options)}"
        )
    limits = bounds(section, key)
    if limits is not None:
        for v in value if isinstance(value, list) else (value,):
            problem = limits.violation(v)
            if problem:
                raise DescriptorError(f"{where}: {name} = {value!r} {problem}")
    return value


def merge(where: str, base: dict, override: dict) -> dict:
    """Validate ``override`` (parsed TOML) against ``base`` (a full descriptor) and merge it in."""
    out = copy.deepcopy(base)
    worlds = sweep = None
    kind = out["scene"]["object"]
    own = override.get(registry.section(kind))
    if isinstance(own, dict) and "design" in own and "design" in out[registry.section(kind)]:
        # a design is a preset of other keys: apply it first, so the override's own keys win; the design in force
        # again changes nothing (its keys as set stay)
        design = _check_value(
            where, registry.section(kind), "design", out[registry.section(kind)]["design"], own["design"]
        )
        if design != out[registry.section(kind)]["design"]:
            _apply_preset(out, kind, design)
    for section, values in override.items():
        if section == "controls":
            out["controls"] = _check_controls(where, values, out["scene"]["object"])
            continue
        if section == "worlds":
            worlds = values  # checked last: its per-world values are checked against the merged sections
            continue
        if section == "sweep":
            sweep = values  # checked last, like [worlds]
            continue
        if section not in out:
            raise DescriptorError(
                f"{where}: unknown section [{section}]{suggest(section, out)}; sections are {', '.join(out)}"
            )
        if not isinstance(values, dict):
            raise DescriptorError(f"{where}: [{section}] must be a table of keys, got {values!r}")
        for key, value in values.items():
            if key not in out[section]:
                speed = (section, key) == ("wind", "speed")  # a key of sweeps and [worlds] only: it scales velocity
                example = value if isinstance(value, (int, float)) and not isinstance(value, bool) else 8
                hint = f"; wind.speed varies only between worlds or sweep cases: set wind.velocity=[{example},0,0]"
                if section == "wind" and not speed:  # the one key of sweeps and [worlds] that is not a field
                    hint = " (and wind.speed [m/s], the magnitude of wind.velocity, between worlds or sweep cases)"
                raise DescriptorError(
                    f"{where}: unknown key {section}.{key}{suggest(key, out[section])}; "
                    f"[{section}] keys are {', '.join(out[section])}" + (hint if section == "wind" else "")
                )
            checked = _check_value(where, section, key, out[section][key], value)
            if (section, key) == ("scene", "object") and checked != out[section][key]:
                raise DescriptorError(
                    f"{where}: scene.object cannot change here (the scene is a {out[section][key]}); "
                    "name the object as SCENE instead, e.g. warpsim run kite"
                )
            out[section][key] = checked
    if worlds is not None:
        out["worlds"] = _check_worlds(where, worlds, out)
    if sweep is not None:
        out["sweep"] = _check_sweep(where, sweep, out)
    return out


def _check_worlds(where: str, worlds, descriptor: dict) -> dict:
    """Validate a ``[worlds]`` table against the merged ``descriptor``: a count and per-world value lists."""
    if not isinstance(worlds, dict):
        raise DescriptorError(f"{where}: [worlds] must be a table of keys, got {worlds!r}")
    out = copy.deepcopy(descriptor.get("worlds", {"count": 1}))
    if "count" in worlds:
        count = worlds["count"]
        if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= MAX_WORLDS:
            raise DescriptorError(f"{where}: worlds.count must be a whole number from 1 to {MAX_WORLDS}, got {count!r}")
        out["count"] = count
    count = out["count"]
    variable = (registry.section(descriptor["scene"]["object"]), *VARIABLE_SECTIONS)
    for section, values in worlds.items():
        if section == "count":
            continue
        if section not in variable:
            raise DescriptorError(
                f"{where}: worlds.{section}: only keys of [{'], ['.join(variable)}] can differ between worlds "
                "(one launch steps every world with the same solver, air, terrain and ground settings)"
            )
        if not isinstance(values, dict):
            raise DescriptorError(f"{where}: worlds.{section} must name a key, e.g. worlds.wind.speed = [4.0, 8.0]")
        if "design" in values and section == variable[0]:
            raise DescriptorError(
                f"{where}: worlds.{section}.design cannot differ between worlds (a design also sets the air model, "
                "which every world shares); vary the keys it sets instead, or run each design as its own scene"
            )
        keys = {**descriptor[section], **({"speed": 0.0} if section == "wind" else {})}
        for key, per_world in values.items():
            name = f"worlds.{section}.{key}"
            if key not in keys:
                raise DescriptorError(
                    f"{where}: unknown key {name}{suggest(key, keys)}; [{section}] keys are {', '.join(keys)}"
                )
            if not isinstance(per_world, list) or len(per_world) != count:
                raise DescriptorError(f"{where}: {name} must list one value per world ({count}), got {per_world!r}")
            checked = [_check_value(where, section, key, keys[key], v) for v in per_world]
            if section == "wind" and key == "speed":
                _check_speeds(where, name, descriptor, checked)
            out.setdefault(section, {})[key] = checked
    return out


def _wind_direction(velocity) -> list[float]:
    """The unit vector of ``velocity`` (+x when it is zero): what ``wind.speed`` scales."""
    norm = sum(v * v for v in velocity) ** 0.5
    return [v / norm for v in velocity] if norm > 0 else [1.0, 0.0, 0.0]


def _check_speeds(where: str, name: str, descriptor: dict, speeds: list) -> None:
    """Each wind speed [m/s] of ``speeds`` must be >= 0 and give a ``wind.velocity`` within its bounds."""
    if min(speeds) < 0.0:
        raise DescriptorError(f"{where}: {name} must be >= 0 (a wind speed in m/s), got {min(speeds)}")
    direction = _wind_direction(descriptor["wind"]["velocity"])
    limits = bounds("wind", "velocity")
    for speed in speeds:
        velocity = [speed * d for d in direction]
        problem = next(filter(None, (limits.violation(v) for v in velocity)), None) if limits else None
        if problem:
            shown = ", ".join(f"{v:g}" for v in velocity)
            raise DescriptorError(f"{where}: {name} = {speed:g} gives wind.velocity = [{shown}], which {problem}")


def world_descriptor(descriptor: dict, world: int) -> dict:
    """The descriptor of world ``world`` (0-based): the shared one with that world's ``[worlds]`` values."""
    out = copy.deepcopy(descriptor)
    for section, values in descriptor.get("worlds", {}).items():
        if section == "count":
            continue
        for key, per_world in values.items():
            if section == "wind" and key == "speed":
                direction = _wind_direction(out["wind"]["velocity"])
                out["wind"]["velocity"] = [per_world[world] * v for v in direction]
            else:
                out[section][key] = copy.deepcopy(per_world[world])
    out["worlds"] = {"count": 1}
    return out


def one_of_batch(descriptor: dict, world: int) -> dict:
    """The descriptor of a batch of one: world ``world`` (0-based) of ``descriptor``, its ``[worlds]`` values kept
    as one-value lists (a sweep's case run alone, as its chunk ran it)."""
    worlds: dict = {"count": 1}
    for section, values in descriptor.get("worlds", {}).items():
        if section != "count":
            worlds[section] = {key: [per[world]] for key, per in values.items()}
    out = copy.deepcopy(descriptor)
    out["worlds"] = worlds
    return out


def _check_controls(where: str, entries, kind: str) -> list[dict]:
    """Validate ``[[controls]]`` entries for an object ``kind``; returns them as plain tables."""
    if not isinstance(entries, list):
        raise DescriptorError(f"{where}: controls must be [[controls]] entries (an array of tables), got {entries!r}")
    allowed = registry.control_names([kind])
    try:
        ControlSchedule(entries, allowed, where)
    except ControlError as err:
        raise DescriptorError(str(err)) from None
    return [dict(e) for e in entries]


SWEEP_FIXED = ("scene", "worlds", "controls", "sweep")  # sections a sweep cannot vary


def check_axis(where: str, descriptor: dict, section: str, key: str, values) -> list:
    """Validate one sweep axis over a merged ``descriptor``: ``section.key`` takes each of ``values`` (a list,
    or a range string ``START:STOP:COUNT``). Any key but those of ``[scene]`` may vary, and ``wind.speed``
    [m/s] (the magnitude of ``wind.velocity``, direction kept). Returns the checked values."""
    name = f"{section}.{key}"
    if section in SWEEP_FIXED or section not in descriptor:
        sections = [s for s in descriptor if s not in SWEEP_FIXED]
        raise DescriptorError(
            f"{where}: {name} cannot be swept: sweep keys of {', '.join(f'[{s}]' for s in sections)}"
            + (" (the sweep's --seconds sets how long every case runs)" if section == "scene" else "")
            + suggest(section, sections)
        )
    keys = {**descriptor[section], **({"speed": 0.0} if section == "wind" else {})}
    if key not in keys:
        raise DescriptorError(
            f"{where}: unknown key {name}{suggest(key, keys)}; [{section}] keys are {', '.join(keys)}"
        )
    if isinstance(values, str):
        values = range_values(f"{where}: {name} = {values!r}", values, None, "sweep")
    if not isinstance(values, list) or not values:
        raise DescriptorError(f"{where}: {name} must list the values to sweep or be a range 'START:STOP:COUNT'")
    checked = [_check_value(where, section, key, keys[key], v) for v in values]
    if section == "wind" and key == "speed":
        _check_speeds(where, name, descriptor, checked)
    if len({repr(v) for v in checked}) != len(checked):
        whole = " (a range with whole-number ends stays whole: write 4.0:11.0:64 for fractions)"
        raise DescriptorError(
            f"{where}: {name} lists a value twice ({values!r}){whole if isinstance(values[0], int) else ''}"
        )
    return checked


def _check_sweep(where: str, sweep, descriptor: dict) -> dict:
    """Validate a ``[sweep]`` table (``section.key = [values]`` or ``"START:STOP:COUNT"``) against the merged
    ``descriptor``."""
    if not isinstance(sweep, dict):
        raise DescriptorError(f"{where}: [sweep] must be a table of keys, e.g. wind.speed = [4.0, 8.0]")
    out: dict = {}
    for section, values in sweep.items():
        if not isinstance(values, dict):
            raise DescriptorError(f"{where}: sweep.{section} must name a key, e.g. sweep.wind.speed = [4.0, 8.0]")
        for key, axis in values.items():
            out.setdefault(section, {})[key] = check_axis(where, descriptor, section, key, axis)
    if "speed" in out.get("wind", {}) and "velocity" in out.get("wind", {}):
        raise DescriptorError(f"{where}: sweep wind.speed or wind.velocity, not both")
    return out


MAX_DEPTH = 8  # a descriptor's deepest nesting is 4 ([worlds] -> wind -> velocity -> numbers)
MAX_TEXT = 1 << 20
"""The most characters a descriptor's text may hold (a scene file, or the one a recording stores)."""


def _depth(value, level: int = 0) -> int:
    """Nesting depth of parsed TOML (iterative: hostile input may nest thousands deep)."""
    deepest, stack = level, [(value, level)]
    while stack:
        item, depth = stack.pop()
        deepest = max(deepest, depth)
        if deepest > MAX_DEPTH:
            return deepest
        children = item.values() if isinstance(item, dict) else item if isinstance(item, list) else ()
        stack += [(child, depth + 1) for child in children]
    return deepest


def load_text(text: str, where: str) -> dict:
    """Parse and validate descriptor ``text``; ``where`` names its origin in error messages."""
    text = text.removeprefix("\ufeff")  # a UTF-8 byte-order mark, as some editors write
    if len(text) > MAX_TEXT:  # an 8 MB scene (hundreds of thousands of controls) kept every command busy for minutes
        raise DescriptorError(
            f"{where}: {len(text):,} characters; a scene descriptor may hold at most {MAX_TEXT:,} (a longer schedule "
            "or world list belongs in a sweep)"
        )
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise DescriptorError(f"{where}: not valid TOML: {err}") from None
    except RecursionError:
        raise DescriptorError(f"{where}: arrays or tables nested too deep") from None
    if _depth(raw) > MAX_DEPTH:
        raise DescriptorError(f"{where}: arrays or tables nested deeper than {MAX_DEPTH} levels")
    scene = raw.get("scene")
    kind = scene.get("object", registry.DEFAULT_OBJECT) if isinstance(scene, dict) else registry.DEFAULT_OBJECT
    if not isinstance(kind, str) or kind not in registry.OBJECTS:
        choices = tuple(registry.OBJECTS)
        raise DescriptorError(
            f"{where}: scene.object = {kind!r} is not one of {', '.join(choices)}{suggest(str(kind), choices)}"
        )
    return merge(where, defaults(kind), raw)


def load_scene(scene: str) -> dict:
    """The checked descriptor of ``scene``: a built-in object (``"kite"``), a scene name (``"kite_gusty"``, from
    ``./scenes`` or the shipped ones) or a ``.toml`` path. Raises :class:`DescriptorError` with one line."""
    from .dirs import scene_dirs

    return resolve(scene, scene_dirs())[0]


def resolve(scene: str, search_dirs: list[Path] | None = None) -> tuple[dict, str, str]:
    """Find a scene by built-in name or path; returns ``(descriptor, source text, where)``.

    A built-in name (``flag``, ``hang-glider``, ...) gives that object's defaults; a path (or a name
    found as ``NAME.toml`` in ``search_dirs``) is read and validated. A bare built-in name is the built-in
    even where the current folder holds a file or folder of that name (write ``./kite`` for the file).
    """
    path = Path(scene)
    bare = path.suffix != ".toml" and len(path.parts) == 1 and scene in registry.OBJECTS
    if path.suffix.lower() in MESH_FORMATS and path.is_file():  # a natural first try with a design's mesh
        mesh = registry.section(registry.MESH)
        raise DescriptorError(
            f"{scene}: a mesh file, not a scene: a design flies from a scene (.toml) whose [{mesh}] names it "
            f"(docs: Fly your own design), or try warpsim run {registry.MESH} --set {mesh}.file={scene}"
        )
    if not bare and (path.suffix == ".toml" or path.exists()):
        if not path.is_file():
            raise DescriptorError(f"{scene}: scene file not found")
        text = _read_text(path)
        return _files_beside(load_text(text, str(path)), path), text, str(path)
    if scene in registry.OBJECTS:
        return defaults(scene), "", f"built-in {scene}"
    for directory in search_dirs or []:
        candidate = Path(directory) / f"{scene.replace('-', '_')}.toml"
        if candidate.is_file():
            text = _read_text(candidate)
            return _files_beside(load_text(text, str(candidate)), candidate), text, str(candidate)
    names = list(registry.OBJECTS)
    for directory in search_dirs or []:
        names += [p.stem for p in sorted(Path(directory).glob("*.toml"))]
    raise DescriptorError(
        f"unknown scene '{scene}'{suggest(scene, names)}: use a built-in object ({', '.join(registry.OBJECTS)}), "
        "a scene name from `warpsim list`, or a path to a .toml descriptor"
    )


FILE_KEYS = ("file", "structure")
"""The keys of a section that name a file read beside the scene (``terrain.file``, ``mesh.file``,
``mesh.structure``)."""


def _files_beside(descriptor: dict, scene: Path) -> dict:
    """``descriptor`` read from the file ``scene`` with a relative ``terrain.file``, ``mesh.file`` or
    ``mesh.structure`` made absolute against the scene file's folder (where its author put it), not the current
    directory, so that the scene runs from anywhere."""
    import os

    folder = os.path.dirname(os.path.abspath(scene))

    def beside(name):
        return (
            os.path.abspath(os.path.join(folder, name))
            if isinstance(name, str) and name and not os.path.isabs(name)
            else name
        )

    for section in ("terrain", *(registry.section(kind) for kind in registry.OBJECTS)):  # the sections naming a file
        for key in FILE_KEYS:
            if descriptor.get(section, {}).get(key):
                descriptor[section][key] = beside(descriptor[section][key])
            for table in ("worlds", "sweep"):  # a file per world or per case
                values = descriptor.get(table, {}).get(section, {}).get(key)
                if isinstance(values, list):
                    descriptor[table][section][key] = [beside(v) for v in values]
    return descriptor


def _read_text(path: Path) -> str:
    """A scene file's text; unreadable or non-UTF-8 files are descriptor errors."""
    try:
        if path.stat().st_size > 4 * MAX_TEXT:  # not read at all: no text of that many bytes can pass
            raise DescriptorError(
                f"{path}: {path.stat().st_size:,} bytes; a scene descriptor may hold at most {MAX_TEXT:,} characters"
            )
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise DescriptorError(f"{path}: not a text file (a scene descriptor is UTF-8 TOML)") from None
    except OSError as err:
        raise DescriptorError(f"{path}: cannot be read: {err.strerror or err}") from None


def _toml_value(value) -> str:
    """One value as inline TOML: scalars (strings escaped) by ``tomli_w``, arrays inline."""
    import tomli_w

    if isinstance(value, list):
        return f"[{', '.join(_toml_value(v) for v in value)}]"
    if isinstance(value, dict):  # an inline table (a mesh design's part)
        return "{" + ", ".join(f"{k} = {_toml_value(v)}" for k, v in value.items()) + "}"
    return tomli_w.dumps({"v": value})[4:].rstrip("\n")


def to_toml(descriptor: dict) -> str:
    """Write a descriptor back as TOML text (all keys, for recording with outputs and for ``warpsim info``).

    Values are written by ``tomli_w`` (every string escaped), so ``load_text(to_toml(d))`` gives ``d`` back.
    """
    descriptor = plain(descriptor)
    lines = []
    for section, values in descriptor.items():
        if section == "controls":
            continue
        lines.append(f"[{section}]")
        for key, value in values.items():
            if isinstance(value, dict):  # [worlds] per-world values: dotted keys
                lines += [f"{key}.{sub} = {_toml_value(v)}" for sub, v in value.items()]
            else:
                lines.append(f"{key} = {_toml_value(value)}")
        lines.append("")
    for entry in descriptor.get("controls", []):
        lines.append("[[controls]]")
        lines += [f"{key} = {_toml_value(value)}" for key, value in entry.items()]
        lines.append("")
    return "\n".join(lines)
