"""Hostile input, property-based: random descriptors and random command lines.

Whatever comes in, ``warpsim`` answers with exit code 0 (it ran), 2 (one clear error line) or 3 (a run that
blew up, outputs kept); never a traceback, and after exit code 2 no file is left behind.
"""

import contextlib
import io
import json
import math
import os
import tempfile
from pathlib import Path

import pytest
from conftest import fuzz_watchdog
from hypothesis import HealthCheck, event, example, given, settings
from hypothesis import strategies as st

from warpsim.cli import main
from warpsim.objects import registry
from warpsim.physics.config import SECTIONS as SHARED_SECTIONS
from warpsim.run.simulation import BlowUpError, Simulation
from warpsim.scene.descriptor import DescriptorError, defaults, load_text

KINDS = list(registry.OBJECTS)

# WARPSIM_FUZZ_EXAMPLES=5000 for a long hunt; CI runs a fixed (derandomized) sample, see conftest.py
FUZZ = settings(
    max_examples=int(os.environ.get("WARPSIM_FUZZ_EXAMPLES", "150")),
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)

# values a user might write, from plausible to absurd (kept small where a valid value would be slow to run)
SCALARS = st.one_of(
    st.sampled_from([0, 1, 2, 3, -1, 0.5, -0.0, 1e308, -1e308, 10**30, math.nan, math.inf, -math.inf, True, False]),
    st.sampled_from(["", "flag", "kite", "paper", "plate", "verlet", "euler", "procedural", "file", "x" * 300]),
    st.text(max_size=12),
    st.integers(-5, 6),
    st.floats(-1e3, 1e3, allow_nan=False),
)
VALUES = st.one_of(SCALARS, st.lists(SCALARS, max_size=4), st.dictionaries(st.text(max_size=6), SCALARS, max_size=2))

SECTIONS = [*SHARED_SECTIONS, "worlds", *(registry.section(kind) for kind in KINDS)]


def _keys(section: str) -> list[str]:
    """Known keys of a section (any object's), so that the fuzz reaches value checks, not only key checks."""
    keys = set()
    for kind in KINDS:
        keys |= set(defaults(kind).get(section, {}))
    return sorted(keys) or ["count"]


def _toml(value) -> str:
    """A value in TOML syntax (inline tables for dicts)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return "nan" if value != value else ("inf" if value > 0 else "-inf") if math.isinf(value) else repr(value)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, str):
        return json.dumps(value)  # JSON string escapes are valid TOML basic-string escapes
    if isinstance(value, list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return "{" + ", ".join(f"{json.dumps(k)} = {_toml(v)}" for k, v in value.items()) + "}"


@st.composite
def descriptors(draw) -> str:
    """TOML text: a few sections with known or random keys holding any value, sometimes [[controls]]."""
    lines = []
    kind = draw(st.one_of(st.sampled_from([*KINDS, "glider", 3]), VALUES))
    lines += ["[scene]", f"object = {_toml(kind)}", f"seconds = {draw(st.sampled_from([0.02, 0.05, -1, 0]))}"]
    if draw(st.integers(0, 9)) == 0:  # deep nesting, a byte-order mark
        depth = draw(st.integers(5, 600))
        lines.append(f"deep = {'[' * depth}{']' * depth}")
    if draw(st.integers(0, 9)) == 0:
        lines.insert(0, "\ufeff")
    for section in draw(st.lists(st.sampled_from(SECTIONS + ["nonsense"]), max_size=3, unique=True)):
        lines.append(f"[{section}]")
        keys = draw(st.lists(st.sampled_from(_keys(section) + ["speed", "typo"]), min_size=1, max_size=3, unique=True))
        lines += [f"{key} = {_toml(draw(VALUES))}" for key in keys]
    for _ in range(draw(st.integers(0, 2))):
        lines.append("[[controls]]")
        for key in draw(st.lists(st.sampled_from(["time", "pitch", "roll", "anchor", "wind", "ramp"]), max_size=3)):
            lines.append(f"{key} = {_toml(draw(VALUES))}")
    return "\n".join(lines) + "\n"


@FUZZ
@given(descriptors())
def test_descriptor_loader_accepts_or_explains(text):
    try:
        d = load_text(text, "fuzz.toml")
    except DescriptorError as err:
        message = str(err)
        assert message.startswith("fuzz.toml: ") and "\n" not in message
        return
    assert d["scene"]["object"] in KINDS
    assert 0 < d["solver"]["dt"] <= 1.0 and d["worlds"]["count"] >= 1
    # a valid descriptor builds (or is refused with a clear message) and runs (or reports a blow-up)
    d["scene"]["fps"] = 100.0
    with fuzz_watchdog() as dog:
        _build_and_run(d, "fuzz.toml")
    if dog.fired:
        event("stopped by its watchdog")


def _build_and_run(d: dict, where: str) -> None:
    """Build ``d`` and run it for 0.03 s: refused with one clear line, run, or blown up (said so)."""
    try:
        sim = Simulation(d, where=where)
    except DescriptorError as err:
        assert str(err).startswith(f"{where}: ") and "\n" not in str(err), err
        event("valid, refused at build")
        return
    try:
        sim.run(0.03)
        event("built and ran")
    except BlowUpError as err:
        assert err.object in {r.name for r in sim.model.objects}
        event("built, blew up")


SCENE_FILES = sorted(p for p in Path("scenes").glob("*") if p.is_file())  # not the designs' folder


@FUZZ
@given(text=st.text(max_size=200), cut=st.integers(0, 400), scene=st.sampled_from(SCENE_FILES))
def test_mangled_scene_files_are_refused_clearly(text, cut, scene):
    original = scene.read_text()
    mangled = original[:cut] + text + original[cut + len(text) // 2 :]
    with fuzz_watchdog():
        try:
            load_text(mangled, "mangled.toml")
        except DescriptorError as err:
            assert str(err).startswith("mangled.toml: ")


TOKENS = {
    "scene": [
        "flag",
        "kite",
        "parachute",
        "hang-glider",
        "kite_gusty",
        "nope",
        "scenes/kite.toml",
        "bad.toml",
        "bin.toml",
        ".",
        "",
    ],
    "number": ["0.05", "0", "-1", "nan", "inf", "1e-300", "abc", "", "2", "0.001", "1e9"],
    "count": ["1", "2", "0", "-3", "x", "70000", "3.5"],
    "path": [
        "out.usda",
        "out.usdc",
        "out.h5",
        "rec.h5",
        "out.obj",
        "missing/out.usda",
        "missing/out.h5",
        "",
        "bin.toml",
    ],
    "set": [
        "wind.velocity=[8,0,0]",
        "wind.velocity=[1e308,0,0]",
        "air.density=1e30",
        "flag.resolution=3",
        "solver.iterations=0",
        "x",
        "a.b=c",
        "scene.object=kite",
    ]
    + ["wind.gust_intensity=0.3", "solver.dt=1e-9", "terrain.kind=file", "worlds.count=2", "=", "flag.=1"],
    "vary": ["wind.speed=4:12", "wind.speed=4,5", "kite.rope_length=1:2", "nonsense", "solver.dt=0.01,0.02", "a=1:"],
    "device": ["cpu", "cuda", "cuda:3", "tpu", ""],
}
RUN_FLAGS = [
    ("--seconds", "number"),
    ("--dt", "number"),
    ("--iterations", "count"),
    ("--fps", "number"),
    ("--device", "device"),
    ("--set", "set"),
    ("--worlds", "count"),
    ("--vary", "vary"),
    ("--usd", "path"),
    ("--h5", "path"),
    ("--resume", "path"),
    ("--replay", "path"),
    ("--quiet", None),
]
FLAGS = {  # each command's own options, and one it does not have
    "run": RUN_FLAGS + [("--bogus", None)],
    "info": [("--set", "set"), ("--worlds", "count"), ("--vary", "vary"), ("--h5", "path")],
    "render": [("--frame", "count"), ("--size", "count"), ("--azimuth", "number"), ("--elevation", "number")],
    "view": [
        ("--set", "set"),
        ("--worlds", "count"),
        ("--h5", "path"),
        ("--seconds", "number"),
        ("--screenshot", "path"),
        ("--size", "count"),
        ("--device", "device"),
        ("--bogus", None),
    ],
    "convert": [("--quiet", None)],
    "list": [("--set", "set")],
    "nope": [],
}


@st.composite
def command_lines(draw) -> list[str]:
    command = draw(st.sampled_from(["run", "run", "run", "info", "view", "convert", "render", "list", "nope"]))
    argv = [command]
    if command in ("run", "info", "view"):
        argv += ["--seconds", "0.05"] if command == "run" else []  # fuzzed --seconds below override this
        argv += [draw(st.sampled_from(TOKENS["scene"]))] if draw(st.integers(0, 5)) else []
    elif command in ("convert", "render"):
        argv += [draw(st.sampled_from(["rec.h5", "bin.toml", "missing.h5"]))]
        argv += [draw(st.sampled_from(["out.usda", "out.png", "out.gif", "out.txt", "missing/out.png"]))]
    for flag, kind in draw(st.lists(st.sampled_from(FLAGS[command]), max_size=3)) if FLAGS[command] else []:
        argv.append(flag)
        if kind is not None:
            typed = draw(st.integers(0, 4)) == 0  # now and then anything at all, mostly the listed tokens
            argv.append(draw(st.text(max_size=6) if typed else st.sampled_from(TOKENS[kind])))
    return argv


def _fixture_files(directory: Path) -> None:
    (directory / "bin.toml").write_bytes(bytes(range(256)))
    (directory / "bad.toml").write_text("[scene]\nobject = 'kite'\n[kite]\nrope_length = -3\n")
    assert main(["run", "kite", "--seconds", "0.1", "--quiet", "--h5", str(directory / "rec.h5")]) == 0


@FUZZ
@given(argv=command_lines())
@pytest.mark.slow
def test_command_line_never_tracebacks_and_leaves_nothing_on_error(argv):
    with tempfile.TemporaryDirectory() as tmp:
        directory = Path(tmp)
        _fixture_files(directory)
        before = {p.name: p.stat().st_mtime_ns for p in directory.iterdir()}
        out, err = io.StringIO(), io.StringIO()
        cwd = os.getcwd()
        os.chdir(directory)
        display = os.environ.pop("DISPLAY", None)  # `view` must say "no display", never open a window here
        code = None
        try:
            with fuzz_watchdog() as dog, contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                try:
                    code = main(argv)
                except SystemExit as exit:  # argparse: --help, --version, or a usage error
                    code = exit.code
        finally:
            os.chdir(cwd)
            if display is not None:
                os.environ["DISPLAY"] = display
        errors = err.getvalue()
        event(f"exit {code}")
        assert "Traceback" not in errors and "Error:" not in errors.replace("error:", ""), (argv, errors)
        if dog.fired:  # a legitimately long run (--seconds 1e9) stopped like Ctrl-C: it ran too long, nothing more
            event("stopped by its watchdog")
            assert code in (None, 0, 2, 3, 130), (argv, code, errors)
            return
        assert code in (0, 2, 3), (argv, code, errors)
        if code == 2:
            lines = [line for line in errors.splitlines() if line.strip()]
            assert len(lines) == 1 and "error:" in lines[0], (argv, errors)
            after = {p.name: p.stat().st_mtime_ns for p in directory.iterdir()}
            assert after == before, (argv, errors)  # nothing written, nothing changed
        if code == 3:
            assert "blew up" in errors, (argv, errors)


EDGY = st.sampled_from([0, 1, 2, 3, 4, -1, 0.0, 1e-6, 0.001, 0.5, 1.0, 2.0, 89.9, 1e3, 1e6, 1e30, True, [0.0, 0.0]])


@st.composite
def edgy_objects(draw) -> dict:
    """An object's defaults with up to 3 of its own keys set to edge values (tiny, huge, zero, negative)."""
    kind = draw(st.sampled_from(KINDS))
    section = kind.replace("-", "_")
    keys = draw(st.lists(st.sampled_from(sorted(defaults(kind)[section])), min_size=1, max_size=3, unique=True))
    return {"scene": {"object": kind}, section: {key: draw(EDGY) for key in keys}}


@FUZZ
@given(edgy_objects())
def test_object_builders_take_edge_values(override):
    text = "\n".join(f"[{s}]\n" + "\n".join(f"{k} = {_toml(v)}" for k, v in t.items()) for s, t in override.items())
    try:
        d = load_text(text, "edgy.toml")
    except DescriptorError as err:
        assert str(err).startswith("edgy.toml: ") and "\n" not in str(err), err
        event("refused")
        return
    d["scene"]["fps"] = 100.0
    with fuzz_watchdog() as dog:
        _build_and_run(d, "edgy.toml")
    if dog.fired:
        event("stopped by its watchdog")


# Recordings as hostile input: flipped bytes, cuts, foreign HDF5, missing or wrong attributes and datasets.
_PRISTINE: dict[str, bytes] = {}


def _pristine_recording() -> bytes:
    """A short kite recording (made once per test session)."""
    if not _PRISTINE:
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "rec.h5"
            assert main(["run", "kite", "--seconds", "0.3", "--quiet", "--h5", str(path)]) == 0
            _PRISTINE["rec"] = path.read_bytes()
    return _PRISTINE["rec"]


ODD_VALUES = st.sampled_from([-1, 0, 2, 99, 1e300, math.nan, "x", "", b"\xff", [1, 2]])


@st.composite
def hostile_recordings(draw) -> tuple[str, object]:
    """``(kind, detail)``: how to spoil the pristine recording (see ``_spoil``)."""
    kind = draw(st.sampled_from(["flip", "flip", "cut", "drop", "attr", "foreign", "reshape", "value"]))
    if kind == "value":  # a value a writer would never write, in a frame dataset (a replay sets controls again)
        name = draw(st.sampled_from(["time", "controls", "positions", "diagnostics/altitude"]))
        return kind, (name, draw(st.integers(0, 8)), draw(st.sampled_from([1e308, -1e308, 1e30, -1.0, 1e9, math.nan])))
    if kind == "flip":
        return kind, draw(st.lists(st.tuples(st.integers(0, 10**7), st.integers(1, 255)), min_size=1, max_size=4))
    if kind == "cut":
        return kind, draw(st.floats(0.0, 0.999))
    if kind == "drop":
        names = [
            "time",
            "positions",
            "diagnostics",
            "topology/sticks",
            "topology/particle_mass",
            "checkpoint",
            "checkpoint/slot0",
            "checkpoint/slot1/q",
            "checkpoint/slot0/digest",
        ]
        return kind, draw(st.sampled_from(names + ["@format", "@descriptor", "@frame_interval", "@format_version"]))
    if kind == "attr":
        name = draw(
            st.sampled_from(["format", "format_version", "descriptor", "frame_interval", "dt", "steps_per_frame"])
        )
        return kind, (name, draw(ODD_VALUES))
    if kind == "reshape":
        return kind, draw(st.sampled_from(["positions", "time", "topology/particle_mass", "checkpoint/slot0/q"]))
    return kind, draw(st.dictionaries(st.text("abc", min_size=1, max_size=3), st.integers(-1000, 1000), max_size=3))


def _spoil(path: Path, kind: str, detail) -> None:
    import warnings

    import h5py
    import numpy as np

    data = bytearray(_pristine_recording())
    if kind == "flip":
        for offset, mask in detail:
            data[offset % len(data)] ^= mask
    elif kind == "cut":
        data = data[: int(len(data) * detail)]
    path.write_bytes(bytes(data))
    if kind in ("drop", "attr", "reshape", "value"):
        with h5py.File(path, "r+") as f:
            if kind == "value":
                name, index, value = detail
                d = f[name]
                with np.errstate(over="ignore"), warnings.catch_warnings():  # 1e308 in a float32: inf, as meant
                    warnings.simplefilter("ignore", RuntimeWarning)
                    d[index % d.shape[0]] = value
            elif kind == "drop" and detail.startswith("@"):
                del f.attrs[detail[1:]]
            elif kind == "drop":
                del f[detail]
            elif kind == "attr":
                name, value = detail
                f.attrs[name] = np.void(value) if isinstance(value, bytes) else value
            else:
                old = f[detail][()]
                del f[detail]
                f[detail] = np.zeros(old.shape[:-1] + (old.shape[-1] + 1,) if old.ndim else (2,), old.dtype)
    elif kind == "foreign":
        with h5py.File(path, "w") as f:
            for key, value in detail.items():
                f[key] = value


@settings(max_examples=int(os.environ.get("WARPSIM_FUZZ_EXAMPLES", "60")), deadline=None)
@given(hostile_recordings(), st.sampled_from(["convert", "render", "resume", "replay"]))
@example(spoil=("value", ("controls", 1, 1e300)), command="replay")  # was a ControlError traceback
@example(spoil=("value", ("time", 1, 1e308)), command="convert")  # was an OverflowError traceback
def test_hostile_recordings_are_refused_clearly(spoil, command):
    """Whatever a recording holds, reading it ends in exit 0, or 2 with one line, within seconds (its watchdog
    fails the example, or ends the test run with a stack dump if HDF5 hangs where Ctrl-C cannot reach)."""
    kind, detail = spoil
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "rec.h5"
        _spoil(path, kind, detail)
        argv = {
            "convert": ["convert", str(path), str(Path(tmp) / "out.usda")],
            "render": ["render", str(path), str(Path(tmp) / "out.png")],
            "resume": ["run", "--resume", str(path), "--seconds", "0.06", "--quiet"],
            "replay": ["run", "--replay", str(path), "--seconds", "0.06", "--quiet"],
        }[command]
        out, err = io.StringIO(), io.StringIO()
        code = None
        with fuzz_watchdog() as dog, contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = main(argv)
        event(f"{kind}: exit {code}")
        assert not dog.fired, (spoil, command, "a recording kept a reader busy for the whole watchdog")
        errors = [line for line in err.getvalue().splitlines() if line.strip()]
        assert code in (0, 2), (spoil, command, code, errors)
        if code == 2:
            assert len(errors) == 1 and "error:" in errors[0], (spoil, errors)
        else:
            assert errors == [], (spoil, errors)


def test_the_watchdog_stops_a_legitimately_endless_example():
    """The fuzz drew `run --seconds 0.05 hang-glider --seconds 1e9` (a valid 10^9-second run) and the hunt hung
    for 49 minutes; each example now has a watchdog that stops it like Ctrl-C (exit 130, outputs kept)."""
    import time

    started = time.perf_counter()
    out, err = io.StringIO(), io.StringIO()
    with tempfile.TemporaryDirectory() as tmp:
        rec = Path(tmp) / "long.h5"
        with fuzz_watchdog(1.0) as dog, contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = main(["run", "--seconds", "0.05", "flag", "--seconds", "1e9", "--quiet", "--h5", str(rec)])
        assert dog.fired and code == 130, (code, err.getvalue())
        assert "Traceback" not in err.getvalue()
        assert 1.0 < time.perf_counter() - started < 15.0
        from warpsim.io.recording import Recording

        with Recording(rec) as recording:
            assert recording.frame_count > 1  # it was running, and keeps what it ran
    with fuzz_watchdog(5.0) as quiet:  # an example that ends in time is left alone
        assert main(["list"]) == 0
    assert not quiet.fired
