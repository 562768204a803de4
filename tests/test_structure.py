"""How the code is organised, checked: one source of defaults, and the kernels' naming convention.

The configuration is written once (:mod:`warpsim.physics.config`); the descriptor, the solvers and the Python API read
it, so a TOML user and a Python user get the same numbers. Every kernel names what it writes ``*_out`` and lists
those arguments last (``warpsim/kernels/__init__.py``), so that a launch's ``inputs``/``outputs`` split is
visible in the signature.
"""

import ast
import dataclasses
import inspect
import textwrap
from pathlib import Path

import pytest
import warp as wp

import warpsim as ws
from warpsim.objects import registry
from warpsim.physics import config
from warpsim.physics.kernels import MODULES
from warpsim.run.simulation import Simulation
from warpsim.scene.descriptor import DescriptorError, defaults, merge


@pytest.mark.parametrize("kind", list(registry.OBJECTS))
def test_python_api_and_descriptor_defaults_are_the_same(kind):
    d = defaults(kind)
    spec = registry.OBJECTS[kind]
    # an object with designs: its default design's preset is part of its defaults (e.g. the air model)
    preset = spec.presets.get(getattr(spec.config(), "design", None), {})
    scene_defaults = {s: {**spec.scene_defaults.get(s, {}), **preset.get(s, {})} for s in config.SECTIONS}
    for section, cls in config.SECTIONS.items():
        expected = {**config.as_section(cls()), **scene_defaults.get(section, {})}
        if section == "scene":
            expected["object"] = kind
        assert d[section] == expected, section
    assert d[registry.section(kind)] == config.as_section(registry.OBJECTS[kind].config())
    if kind == "mesh":  # a design of one's own has no default file: the shipped diamond kite's cloth
        d["mesh"]["file"] = str(Path(__file__).resolve().parents[1] / "scenes" / "designs" / "diamond_kite.obj")
    sim = Simulation(d)
    solver_defaults = {**config.as_section(config.SolverConfig()), **scene_defaults.get("solver", {})}
    assert config.as_section(sim.solver.config) == solver_defaults
    assert sim.solver.air == config.AirConfig(**scene_defaults["air"]) and sim.solver.ground == config.GroundConfig()


def test_python_solvers_default_to_the_descriptor_settings():
    b = ws.ModelBuilder()
    b.add_particle((0, 0, 1), 1.0)
    m = b.finalize("cpu")
    euler = ws.make_solver(m, ws.SolverConfig(method="euler"))
    assert isinstance(euler, ws.SolverEuler)
    solver = defaults("flag")["solver"]
    assert (euler.config.spring_stiffness, euler.config.spring_damping) == (
        solver["spring_stiffness"],
        solver["spring_damping"],
    )
    assert ws.SolverVerlet(m).config.chebyshev == solver["chebyshev"] == 0.95


@pytest.mark.parametrize(
    "section, key, value",
    [("solver", "damping", 1.0), ("solver", "chebyshev", 1.0), ("solver", "relaxation", 2.0), ("air", "scale", -1.0)],
)
def test_descriptor_and_config_refuse_the_same_values(section, key, value):
    with pytest.raises(DescriptorError, match=f"{section}.{key} = {value!r} must be"):
        merge("test", defaults("flag"), {section: {key: value}})
    with pytest.raises(ValueError, match=f"{key} must be"):
        config.SECTIONS[section](**{key: value})


def test_choices_come_from_the_enums():
    from warpsim.scene.descriptor import choices

    assert choices("air", "model") == tuple(m.name.lower() for m in ws.AeroModel)
    assert choices("ground", "collision") == tuple(m.name.lower() for m in ws.CollisionMode)
    assert config.AirConfig(model="plate").model is ws.AeroModel.PLATE
    assert config.AirConfig(model=ws.AeroModel.PLATE) == config.AirConfig(model="plate")


def _funcs() -> dict[str, list[str]]:
    """Every ``@wp.func`` of the kernel modules: name -> its parameter names."""
    out = {}
    for module in MODULES:
        for value in vars(module).values():
            if isinstance(value, wp.Function) and value.func is not None:
                out[value.key] = list(inspect.signature(value.func).parameters)
    return out


def _written(tree: ast.AST, params: list[str], funcs: dict[str, list[str]]) -> set[str]:
    """The parameters a kernel or function body writes: subscript stores, atomics, and arguments passed to a
    function's ``*_out`` parameters."""
    written = set()
    for node in ast.walk(tree):
        targets = []
        if isinstance(node, ast.Assign):
            targets = node.targets
        elif isinstance(node, ast.AugAssign):
            targets = [node.target]
        for t in targets:
            if isinstance(t, ast.Subscript) and isinstance(t.value, ast.Name):
                written.add(t.value.id)
        if isinstance(node, ast.Call):
            name = node.func.attr if isinstance(node.func, ast.Attribute) else getattr(node.func, "id", "")
            if name.startswith("atomic_") and node.args and isinstance(node.args[0], ast.Name):
                written.add(node.args[0].id)
            for arg, param in zip(node.args, funcs.get(name, []), strict=False):
                if param.endswith("_out") and isinstance(arg, ast.Name):
                    written.add(arg.id)
    return written & set(params)


def _kernels():
    for module in MODULES:
        for value in vars(module).values():
            if isinstance(value, wp.Kernel):
                yield module.__name__, value


@pytest.mark.parametrize("module, kernel", list(_kernels()), ids=lambda v: getattr(v, "key", v))
def test_kernels_name_and_order_their_outputs(module, kernel):
    params = list(inspect.signature(kernel.func).parameters)
    tree = ast.parse(textwrap.dedent(inspect.getsource(kernel.func)))
    written = _written(tree, params, _funcs())
    outputs = [p for p in params if p.endswith("_out")]
    assert written == set(outputs), f"{module}.{kernel.key} writes {sorted(written)}, names {outputs} as outputs"
    assert params[len(params) - len(outputs) :] == outputs, f"{module}.{kernel.key}: outputs must come last"


def test_functions_name_what_they_write():
    funcs = _funcs()
    for module in MODULES:
        for value in vars(module).values():
            if isinstance(value, wp.Function) and value.func is not None:
                params = funcs[value.key]
                tree = ast.parse(textwrap.dedent(inspect.getsource(value.func)))
                arrays = {p for p in params if "array" in str(inspect.signature(value.func).parameters[p].annotation)}
                written = _written(tree, params, funcs) & arrays
                assert all(p.endswith("_out") for p in written), f"{value.key} writes {sorted(written)}"


def test_every_config_field_is_documented_with_its_unit_or_meaning():
    for cls in [*config.SECTIONS.values(), *(spec.config for spec in registry.OBJECTS.values())]:
        doc = inspect.getdoc(cls)
        for f in dataclasses.fields(cls):
            assert f"{f.name}:" in doc or f"{f.name}," in doc, f"{cls.__name__}.{f.name} is not documented"


def test_kernels_compare_enums_by_member_not_by_number():
    """A kernel argument holding an enum (``mode``, ``aero_model``) is compared with ``CollisionMode.NORMAL``,
    ``AeroModel.PAPER``..., never with a bare number that would silently change meaning if the enum did."""
    sources = [v.func for _, v in _kernels()]
    sources += [v.func for m in MODULES for v in vars(m).values() if isinstance(v, wp.Function) and v.func]
    for func in sources:
        for node in ast.walk(ast.parse(textwrap.dedent(inspect.getsource(func)))):
            if isinstance(node, ast.Compare):
                names = [n.id for n in (node.left, *node.comparators) if isinstance(n, ast.Name)]
                numbers = [n for n in (node.left, *node.comparators) if isinstance(n, ast.Constant)]
                enum_like = [n for n in names if n.endswith(("mode", "model"))]
                assert not (enum_like and numbers), f"{func.__name__} compares {enum_like} with a number"


def test_a_design_is_a_preset_and_keys_beside_it_win(capsys):
    """``hang_glider.design = "paper"`` brings back the paper's glider (its suspension, flat untensioned sail and
    air law) in one --set; keys given beside it win; setting the flying design again restores the defaults."""
    flying = defaults("hang-glider")
    paper = merge("test", flying, {"hang_glider": {"design": "paper"}})
    assert paper["air"]["model"] == "paper" and paper["hang_glider"]["suspension"] == "sticks"
    assert paper["hang_glider"]["sail_tension"] == 0.0 and not paper["hang_glider"]["keel_pocket"]
    mixed = merge("test", flying, {"hang_glider": {"sail_tension": 0.02, "design": "paper"}, "air": {"model": "plate"}})
    assert mixed["hang_glider"]["sail_tension"] == 0.02 and mixed["air"]["model"] == "plate"
    assert merge("test", paper, {"hang_glider": {"design": "flying"}}) == flying
    kite = merge("test", defaults("kite"), {"kite": {"design": "paper"}})
    assert (kite["air"]["model"], kite["solver"]["dt"], kite["kite"]["tow_point"]) == ("paper", 0.01, 0.35)
    with pytest.raises(DescriptorError, match="design cannot differ between worlds"):
        merge("test", flying, {"worlds": {"count": 2, "hang_glider": {"design": ["flying", "paper"]}}})
    from warpsim.cli import main

    assert main(["info", "hang-glider", "--set", "hang_glider.design=paper"]) == 0
    assert "particles 49, sticks 180, triangles 64" in capsys.readouterr().out  # the paper's 49 particles
