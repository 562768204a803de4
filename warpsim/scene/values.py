"""Values a user writes on the command line: ``--set section.key=VALUE`` and ``--vary section.key=VALUES`` (lists and
``START:STOP:COUNT`` ranges), and :class:`DescriptorError`, the one-line error of every descriptor check."""

from __future__ import annotations

import difflib
import re
import sys

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

FLOAT_LIMIT = 1e30  # [any unit] the simulation is float32 (max 3.4e38): larger numbers are refused outright


def suggest(word: str, options, cutoff: float = 0.6) -> str:
    """`` (did you mean 'X'?)`` for the closest of ``options`` to a mistyped ``word`` (difflib's ratio at least
    ``cutoff``), or nothing: the hint every one-line error about a name gives."""
    close = difflib.get_close_matches(str(word), [str(o) for o in options], n=1, cutoff=cutoff)
    return f" (did you mean '{close[0]}'?)" if close else ""


class DescriptorError(ValueError):
    """A scene descriptor or override a user wrote is invalid; the message says where and what is allowed."""


def _split_assignment(flag: str, text: str, example: str) -> tuple[str, str, str]:
    """Split ``section.key=value`` given to ``flag`` into ``(section, key, raw value)``; ``example`` shows the form."""
    if "=" not in text:
        raise DescriptorError(f"{flag} {text!r}: expected section.key=value, e.g. {example}")
    path, raw = (part.strip() for part in text.split("=", 1))
    if path.count(".") != 1 or not all(path.split(".")):
        raise DescriptorError(f"{flag} {text!r}: the key must be section.key, e.g. {example}")
    section, key = path.split(".")
    return section, key, raw


def parse_override(text: str) -> dict:
    """Turn ``section.key=value`` (value in TOML syntax; bare words are strings) into a nested dict."""
    section, key, raw = _split_assignment("--set", text, "wind.velocity=[8,0,0]")
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw
    return {section: {key: value}}


def parse_vary(text: str, count: int | None, flag: str = "--vary") -> tuple[str, str, list]:
    """Turn ``--vary section.key=VALUES`` into ``(section, key, values)``.

    VALUES is ``START:STOP:COUNT`` (``COUNT`` evenly spaced values, both ends included; whole numbers stay
    whole when both ends are), ``START:STOP`` (spread over ``count`` worlds; an error when ``count`` is None),
    or a comma-separated / TOML list (``4,6,8``, ``flying,paper``, ``a.obj,designs/b.obj`` or ``[[4,0,0],[8,0,0]]``).
    ``flag`` names the option in errors.
    """
    section, key, raw = _split_assignment(flag, text, "wind.speed=4:12:5 or wind.speed=4,8")
    if ":" in raw and not raw.startswith("["):
        return section, key, range_values(f"{flag} {text!r}", raw, count, flag)
    try:
        values = tomllib.loads(f"v = {raw if raw.startswith('[') else f'[{raw}]'}")["v"]
    except tomllib.TOMLDecodeError:
        words = [word.strip() for word in raw.split(",")]
        # a word with a letter in it: a name or a file (2024.obj), never a number
        if raw.startswith("[") or not all(re.fullmatch(r"[\w./+-]*[A-Za-z_][\w./+-]*", word) for word in words):
            raise DescriptorError(
                f"{flag} {text!r}: VALUES must be START:STOP:COUNT or a list like 4,6,8 (or flying,paper, a.obj,b.obj)"
            ) from None
        values = words  # bare words are names or files (design=flying,paper; mesh.file=a.obj,b.obj), as if quoted
    return section, key, values


MAX_RANGE = 100_000  # values one range may make


def range_values(where: str, raw: str, count: int | None, flag: str = "--vary") -> list:
    """The values of a range ``START:STOP[:COUNT]`` (``count`` when COUNT is not written; see :func:`parse_vary`)."""
    parts = [part.strip() for part in raw.split(":")]
    try:
        numbers = [tomllib.loads(f"v = {part}")["v"] for part in parts] if len(parts) in (2, 3) else []
    except tomllib.TOMLDecodeError:
        numbers = []
    if not numbers or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in numbers):
        raise DescriptorError(f"{where}: a range is START:STOP:COUNT with numbers, e.g. 4:12:5")
    if len(numbers) == 3:
        start, stop, count = numbers
        if not isinstance(count, int) or not 1 <= count <= MAX_RANGE:
            raise DescriptorError(f"{where}: COUNT in START:STOP:COUNT must be a whole number from 1 to {MAX_RANGE:,}")
    else:
        start, stop = numbers
        if count is None:
            raise DescriptorError(
                f"{where}: a range needs a COUNT, START:STOP:COUNT (e.g. 4:12:5)"
                + (", or --worlds N to spread START:STOP over N worlds" if flag == "--vary" else "")
            )
    if not all(abs(v) <= FLOAT_LIMIT for v in (start, stop)):
        raise DescriptorError(f"{where}: the range's ends must be finite and at most {FLOAT_LIMIT:g} in size")
    n = max(count - 1, 1)
    values = [start + (stop - start) * k / n for k in range(count)]
    if isinstance(start, int) and isinstance(stop, int):
        values = [round(v) for v in values]
    return values
