"""What every ``warpsim`` command shares: the exit codes, the one-line usage error, the option types with their
limits, the options that change a scene (given once, added to each command that simulates) and the scene they
make."""

from __future__ import annotations

import argparse
import math
import re
from pathlib import Path

from ..scene.dirs import scene_dirs

EXIT_USAGE = 2
EXIT_BLOWUP = 3
EXIT_OUTPUT = 4
EXIT_INTERRUPTED = 130


class UsageError(Exception):
    """A user mistake: printed as one line, exit code 2."""


MAX_LINE = 600  # characters of an error line; a hostile value must not fill the terminal


def one_line(message: str) -> str:
    """``message`` with every control or line-breaking character escaped (``\\n``, ``\\r``...), so that text a
    user typed cannot break an error line apart, and cut to about ``MAX_LINE`` characters (a value of megabytes
    is not echoed whole)."""
    if len(message) > MAX_LINE:
        message = f"{message[: MAX_LINE - 120]} [... {len(message) - MAX_LINE + 100:,} characters ...] {message[-100:]}"
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in message)


class Parser(argparse.ArgumentParser):
    def error(self, message: str):  # one line, no usage dump
        message = re.sub(r"^argument (\S+): (?=\1 )", "", message)  # our own messages name the option already
        self.exit(EXIT_USAGE, f"{self.prog}: error: {one_line(message)} (see {self.prog} --help)\n")


def number_type(
    name: str, what: str = "a positive finite number", low: float = 0.0, high: float = math.inf, closed=False
):
    """argparse type for ``name``: a finite float above ``low`` (``closed``: or equal to it) and at most ``high``;
    the error says it must be ``what``."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be a number, got {text!r}") from None
        above = value >= low if closed else value > low
        if not (above and value <= high and math.isfinite(value)):
            raise argparse.ArgumentTypeError(f"{name} must be {what}, got {text}")
        return value

    return parse


def iterations_type(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--iterations must be a whole number >= 1, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"--iterations must be a whole number >= 1, got {value}")
    return value


def size_type(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        w = h = 0
    if not (16 <= w <= 8192 and 16 <= h <= 8192):
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT in pixels (16..8192), e.g. 960x540, got {text!r}")
    return w, h


def window_type(text: str) -> tuple[float, float]:
    try:
        start, stop = (float(v) for v in text.split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected START:STOP in simulated seconds, e.g. 10:30, got {text!r}"
        ) from None
    if not (math.isfinite(start) and math.isfinite(stop) and 0.0 <= start <= stop):
        raise argparse.ArgumentTypeError(f"expected 0 <= START <= STOP, got {text!r}")
    return start, stop


def names_type(text: str) -> list[str]:
    names = [n.strip() for n in text.split(",") if n.strip()]
    if not names:
        raise argparse.ArgumentTypeError(f"expected names separated by commas, got {text!r}")
    return names


def add_scene_options(parser, worlds: bool = True) -> None:
    """The options that change the scene a command simulates: time step, iterations, frame rate, device,
    ``--set`` and (``worlds``) ``--worlds``/``--vary``."""
    parser.add_argument(
        "--dt", type=number_type("--dt"), help="time step [s] (default: the scene's; `warpsim info SCENE` shows it)"
    )
    parser.add_argument(
        "--iterations",
        type=iterations_type,
        help="constraint iterations per step (default: the scene's; 55 in the glider and parachute scenes, 45 in the "
        "kite's (over-relaxed and accelerated at its 2.5 ms step), 119 "
        "in the flag's (7 per particle along it: a finer flag.resolution needs more), 110 in flag_paper.toml; "
        "`warpsim info SCENE` shows it)",
    )
    parser.add_argument("--fps", type=number_type("--fps"), help="output frames per simulated second")
    parser.add_argument("--device", default="cpu", help="Warp device: cpu (default) or cuda[:N]")
    parser.add_argument(
        "--threads",
        type=world_count_type,
        metavar="N",
        help="threads stepping the worlds, each a group of them, on the CPU (default: every core this process may "
        "use; in a sweep, the cores per worker process); the frames are the same, bit for bit, for any N",
    )
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a descriptor value, e.g. --set wind.velocity=[8,0,0] (repeatable)",
    )
    if worlds:
        add_world_options(parser)


def add_world_options(parser) -> None:
    parser.add_argument(
        "--worlds",
        type=world_count_type,
        metavar="N",
        help="simulate N copies of the scene in one model, stepped by the same launches (default: scene's, 1)",
    )
    parser.add_argument(
        "--vary",
        action="append",
        default=[],
        metavar="KEY=VALUES",
        help="a value that differs between worlds: START:STOP spread over the N worlds, or one value per "
        "world, e.g. --vary wind.speed=4:12, --vary wind.gust_seed=0:255, --vary kite.rope_length=20,30 "
        "(keys of [wind] or of the object's section; repeatable)",
    )


def load_scene(args, worlds_from_vary: bool = True):
    """The :class:`~warpsim.scene.scene.Scene` of ``args`` with its ``--set``, ``--dt``, ``--iterations``,
    ``--fps``, ``--seconds`` and (with ``worlds_from_vary``) ``--worlds``/``--vary`` applied, each checked as it is
    applied and named in its error: ``(scene, source text)``; ``scene.where`` says where it came from."""
    from ..scene.descriptor import resolve
    from ..scene.scene import Scene
    from ..scene.values import parse_override, parse_vary

    descriptor, text, where = resolve(args.scene, scene_dirs())
    scene = Scene(descriptor, where)
    overrides = [(item, parse_override(item)) for item in args.set]
    # a design is a preset of other keys: its --set applies first, so that the others win in any order
    overrides.sort(key=lambda pair: not any("design" in keys for keys in pair[1].values()))
    for item, override in overrides:
        scene = scene.with_values(override, f"--set {item}")
    count = getattr(args, "worlds", None)
    worlds: dict = {}
    for item in getattr(args, "vary", []) if worlds_from_vary else []:
        section, key, values = parse_vary(item, count)
        count = count or len(values)
        worlds.setdefault(section, {})[key] = values
    if count is not None:
        worlds["count"] = count
    if worlds:
        flags = " ".join([f"--worlds {count}"] + [f"--vary {v}" for v in args.vary])
        scene = scene.with_values({"worlds": worlds}, flags)
    overrides = {
        ("solver", "dt", "--dt"): getattr(args, "dt", None),
        ("solver", "iterations", "--iterations"): getattr(args, "iterations", None),
        ("scene", "fps", "--fps"): getattr(args, "fps", None),
        ("scene", "seconds", "--seconds"): getattr(args, "seconds", None),
    }
    for (section, key, flag), value in overrides.items():
        if value is not None:  # checked against the scene's bounds like any other value
            scene = scene.with_values({section: {key: value}}, f"{flag} {value:g}")
    return scene, text


def world_count_type(text: str) -> int:
    from ..scene.descriptor import MAX_WORLDS

    try:
        value = int(text)
    except ValueError:
        value = 0
    if not 1 <= value <= MAX_WORLDS:
        raise argparse.ArgumentTypeError(f"must be a whole number from 1 to {MAX_WORLDS}, got {text!r}")
    return value


def check_device(name: str) -> str:
    import warp as wp

    available = ", ".join(str(d) for d in wp.get_devices())
    # without a CUDA driver, asking Warp for a cuda device prints two raw driver errors first: say it in one line
    if name.startswith("cuda") and not wp.is_cuda_available():
        raise UsageError(f"--device {name} is not available here (no CUDA driver); available: {available}")
    try:
        wp.get_device(name)
    except (ValueError, RuntimeError):
        raise UsageError(f"--device {name} is not available here; available: {available}") from None
    return name


def checked_output(check, value: str | None, flag: str) -> Path | None:
    """``check(value)`` for an output option given as ``flag``; a bad path becomes a usage error."""
    from ..io import OutputPathError

    if not value:
        return None
    try:
        return check(value)
    except OutputPathError as err:
        raise UsageError(f"{flag} {err}") from None


def same_file_check(sources, outputs: dict, what: str = "the scene file") -> None:
    """Refuse an output that would overwrite what the command reads: ``sources``, a path or a list of paths (see
    :func:`scene_sources`), each that exists against each output (``{flag: path}``) that exists."""
    from ..io import same_file

    for source in [sources] if isinstance(sources, str | Path) else sources:
        if not Path(source).is_file():
            continue
        for flag, path in outputs.items():
            if path is not None and Path(path).exists() and same_file(source, path):
                raise UsageError(f"{flag} {path} is {what} itself ({source}); choose another output name")


def scene_sources(scene) -> list[str]:
    """The files a :class:`~warpsim.scene.scene.Scene` was read from and reads: its own file (found by path or by
    name) and its meshes and terrain, in any world (:meth:`~warpsim.scene.scene.Scene.files`)."""
    return [scene.where, *scene.files()]


def plural(n: int, noun: str) -> str:
    """``n`` and ``noun``, plural unless ``n`` is 1 ("1 case", "2 cases")."""
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"
