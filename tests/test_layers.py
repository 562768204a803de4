"""The package's layers: every import (at module level or inside a function) goes down a layer or stays inside its
own package, and no chain of imports closes a loop.

Layers, lowest first: ``_version``/``_interrupt``/``_extras`` (no warpsim imports), ``physics``, ``objects``,
``scene``, ``run``, ``io``, then ``viewer`` and ``sweeps`` (side by side: neither imports the other), ``cli``, and
the package itself (``warpsim/__init__.py``, ``__main__``). See docs/architecture.md.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent.parent / "warpsim"

LAYERS = {
    "_version": 0,
    "_interrupt": 0,
    "_extras": 0,
    "physics": 1,
    "objects": 2,
    "scene": 3,
    "run": 4,
    "io": 5,
    "viewer": 6,
    "sweeps": 6,
    "cli": 7,
    "__main__": 8,
    "": 8,  # warpsim/__init__.py
}


def _modules() -> dict[str, Path]:
    """Every module of the package by dotted name (a package by its own name)."""
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def _imports(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """The warpsim modules that module ``name`` imports, anywhere in its text."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.split(".")[0] == "warpsim")
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] != "warpsim":
                continue
            for alias in node.names:  # `from . import x` imports the module x where there is one
                sub = f"{target}.{alias.name}"
                found.add(sub if sub in modules else target)
    while True:  # an import of a.b.c that is no module (a name inside one) is an import of that module
        fixed = {m if m in modules else m.rpartition(".")[0] for m in found}
        if fixed == found:
            return found - {name}
        found = fixed


def _layer(module: str) -> tuple[str, int]:
    top = module.split(".")[1] if "." in module else ""
    assert top in LAYERS, f"{module}: no layer for warpsim/{top}; add it to LAYERS and to docs/architecture.md"
    return top, LAYERS[top]


def _graph() -> dict[str, set[str]]:
    modules = _modules()
    return {name: _imports(name, path, modules) for name, path in modules.items()}


def test_every_import_goes_down_a_layer():
    wrong = []
    for module, imported in _graph().items():
        top, rank = _layer(module)
        for other in sorted(imported):
            other_top, other_rank = _layer(other)
            if other_top != top and other_rank >= rank:
                wrong.append(f"{module} imports {other} (layer {other_rank} >= {rank})")
    assert not wrong, "imports that go up or across a layer:\n" + "\n".join(wrong)


def test_no_import_loops():
    graph = _graph()
    loops, state = [], {}

    def visit(module, path):
        state[module] = "open"
        for other in sorted(graph.get(module, ())):
            if state.get(other) == "open":
                loops.append(" -> ".join([*path[path.index(other) :], other]))
            elif other not in state:
                visit(other, [*path, other])
        state[module] = "done"

    for module in sorted(graph):
        if module not in state:
            visit(module, [module])
    assert not loops, "import loops:\n" + "\n".join(loops)


def test_the_walk_sees_imports():
    """The walk finds the imports it must judge (a walk that found none would pass every module)."""
    graph = _graph()
    assert "warpsim.physics.model" in graph["warpsim.physics.solver"]
    assert "warpsim.run.simulation" in graph["warpsim.viewer.core"]  # an import inside the module's text
    assert _layer("warpsim.cli.main") == ("cli", 7)


def _docstrings(tree: ast.AST) -> set[int]:
    """The ids of the docstring constants of ``tree``'s module, classes and functions (text, not code)."""
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
                found.add(id(first.value))
    return found


def _kind_names(path: Path, kinds: set[str]) -> list[str]:
    """Where the code of ``path`` names an object kind (a string constant equal to one, docstrings aside)."""
    tree = ast.parse(path.read_text(), str(path))
    docs = _docstrings(tree)
    return [
        f"{path.relative_to(PACKAGE.parent)}:{node.lineno}: {node.value!r}"
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in kinds
        and id(node) not in docs
    ]  # fmt: skip


def _outside(package: str, find) -> list[str]:
    """``find(path)``'s hits over every module of the package outside its sub-package ``package``."""
    return [hit for path in sorted(PACKAGE.rglob("*.py")) if path.relative_to(PACKAGE).parts[0] != package
            for hit in find(path)]  # fmt: skip


def test_no_module_outside_objects_names_an_object_kind():
    """Each object's knowledge is in `objects/` (its module and its registry entry): the layers above reach an
    object through `objects.registry.OBJECTS`, never by its name, so a new object touches no other package."""
    from warpsim.objects.registry import OBJECTS

    kinds = set(OBJECTS) | {kind.replace("-", "_") for kind in OBJECTS}
    named = _outside("objects", lambda path: _kind_names(path, kinds))
    assert not named, "object kinds named outside objects/:\n" + "\n".join(named)
    assert _kind_names(PACKAGE / "objects" / "registry.py", kinds)  # the search finds names where they are


DESCRIPTOR_NAMES = re.compile(r"descriptor|^(d|base|scene|tables)$")
"""What a descriptor is called where it travels (``descriptor``, ``sim.descriptor``, ``world_descriptor(...)``,
``d``): the receivers whose section reads count (a colour table's ``"terrain"``, a control's ``"wind"`` do not)."""


def _section_reads(path: Path, sections: set[str]) -> list[str]:
    """Where the code of ``path`` reads a descriptor's section by name: ``descriptor["solver"]``,
    ``d.get("worlds", ...)``."""
    tree = ast.parse(path.read_text(), str(path))
    hits = []
    for node in ast.walk(tree):
        key, receiver = None, None
        if isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant):
            key, receiver = node.slice.value, node.value
        elif (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute)
            and node.func.attr in ("get", "setdefault", "pop")
            and node.args
            and isinstance(node.args[0], ast.Constant)
        ):
            key, receiver = node.args[0].value, node.func.value
        if isinstance(key, str) and key in sections and DESCRIPTOR_NAMES.search(ast.unparse(receiver)):
            hits.append(f"{path.relative_to(PACKAGE.parent)}:{node.lineno}: {ast.unparse(node)[:80]}")
    return hits


def test_no_module_outside_scene_indexes_a_descriptor():
    """A scene travels above `scene/` as a `warpsim.scene.scene.Scene` (typed settings, the object, its config, the
    worlds, the controls); only `scene/` reads a descriptor's sections by name, so its layout can change in one
    package."""
    from warpsim.objects.registry import OBJECTS, section
    from warpsim.physics.config import SECTIONS

    sections = {*SECTIONS, *(section(kind) for kind in OBJECTS), "worlds", "controls", "sweep"}
    reads = _outside("scene", lambda path: _section_reads(path, sections))
    assert not reads, "descriptor sections read outside scene/:\n" + "\n".join(reads)
    assert _section_reads(PACKAGE / "scene" / "build.py", sections)  # the search finds reads where they are


def _descriptor_parameters(path: Path) -> list[str]:
    """Where the code of ``path`` takes a descriptor: a function's parameter or a class's field called
    ``descriptor`` (or ``*_descriptor``), or one annotated as a plain ``dict`` of a scene (``scene: dict``)."""
    tree = ast.parse(path.read_text(), str(path))
    hits = []
    for node in ast.walk(tree):
        names = []
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            a = node.args
            names = [(arg.arg, arg.annotation) for arg in (*a.posonlyargs, *a.args, *a.kwonlyargs)]
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names = [(node.target.id, node.annotation)]
        for name, annotation in names:
            plain = annotation is not None and "dict" in ast.unparse(annotation) and name in ("scene", "tables")
            if name == "descriptor" or name.endswith("_descriptor") or plain:
                hits.append(f"{path.relative_to(PACKAGE.parent)}:{node.lineno}: {name}")
    return hits


def test_no_module_outside_scene_takes_a_descriptor():
    """Above `scene/`, what travels is a `Scene`: no function takes a descriptor dict and no record keeps one (the
    recorder, the outputs, the sweep's plan and its tasks, the exporter all take a Scene). `Simulation` still takes
    a descriptor as a convenience of the façade: it turns it into a Scene first thing."""
    takes = _outside("scene", _descriptor_parameters)
    allowed = {"warpsim/run/simulation.py"}  # Simulation(scene: Scene | dict), documented
    wrong = [hit for hit in takes if hit.split(":")[0] not in allowed]
    assert not wrong, "descriptors taken outside scene/:\n" + "\n".join(wrong)
    assert _descriptor_parameters(PACKAGE / "scene" / "descriptor.py")  # the search finds them where they are
