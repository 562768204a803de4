"""The keys an object is steered by in the viewer: each binding says which keys move which of its controls, how
fast, and the line the viewer's help shows for it. The viewer knows no object by name: it reads these from
:attr:`warpsim.objects.registry.ObjectSpec.keys` (key names as in :mod:`warpsim.viewer.backend`)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class AxisKeys:
    """Two held keys that move a control in [-1, 1]: while ``plus`` is held it moves towards +1, while ``minus`` is
    held towards -1, with neither (or both) back towards 0, at ``rate`` [1/s of simulated time]. A frame start at
    which the keys do not move the value leaves the control alone (a schedule may be setting it).

    Attributes: control (its name in :mod:`warpsim.scene.controls`), minus, plus (key names), rate [1/s],
    label (the keys as the help shows them), help (what they do, one line); active: ``active(record) -> bool``,
    whether this object as built has what the control moves (None: always), so that the help offers no key that
    does nothing.
    """

    control: str
    minus: str
    plus: str
    label: str
    help: str
    rate: float = 2.0
    active: Callable | None = None


@dataclass(frozen=True)
class WalkKeys:
    """Four held keys that walk the nailed ground end of a line, the ``(x, y)`` [m] control ``control``:
    ``forward`` towards the object along the ground, ``back`` away, ``left`` and ``right`` across, at ``speed``
    [m/s]. The ground observer (the viewer's ground camera) stands by this anchor.

    Attributes: control, forward, left, back, right (key names), speed [m/s], label, help;
    nail: ``nail(record) -> int``, the anchor's nail (index into ``Control.nail_target``; -1: this object has none,
    and the keys do nothing for it); towards: ``towards(record) -> particle indices`` the forward key walks towards
    (their mean position).
    """

    control: str
    forward: str
    left: str
    back: str
    right: str
    label: str
    help: str
    nail: Callable
    towards: Callable
    speed: float = 2.0


def anchor_nail(record) -> int:
    """The record's ``anchor_nail`` (the nail of its line's ground end), -1 when it has none."""
    return int(getattr(record, "anchor_nail", -1))


def flying_part(*names: str) -> Callable:
    """``towards(record)`` for :class:`WalkKeys`: the particles of the first of the record's parts in ``names``."""

    def towards(record) -> np.ndarray:
        for name in names:
            if name in record.parts:
                return np.asarray(record.parts[name])
        raise KeyError(f"{record.name} has none of the parts {', '.join(names)}")

    return towards


def weight_shift_keys(what: str, active: Callable | None = None) -> tuple[AxisKeys, AxisKeys]:
    """The arrows of a pilot hung under a wing (``what`` names it in the help): Up/Down the bar in and out
    (``pitch``), Left/Right the weight shift (``roll``); ``active`` as in :class:`AxisKeys`."""
    return (
        AxisKeys(
            "pitch", "DOWN", "UP", "Up / Down", f"{what}: bar in (pitch +1: nose down, faster) / out (slower)",
            active=active,
        ),
        AxisKeys(
            "roll", "LEFT", "RIGHT", "Left / Right", f"{what}: weight shift (roll -1 / +1), to turn that way",
            active=active,
        ),
    )  # fmt: skip


def line_walk_keys(what: str, *parts: str) -> WalkKeys:
    """W/A/S/D walk the ground anchor of ``what``'s line (the ``anchor`` control), towards its first part in
    ``parts``."""
    return WalkKeys(
        "anchor",
        "W",
        "A",
        "S",
        "D",
        "W A S D",
        f"{what}: walk the line's ground anchor towards / left of / away from / right of it",
        nail=anchor_nail,
        towards=flying_part(*parts),
    )
