"""The viewer's heads-up text: time and rates, each object's flight figures (each object's own text from its
:class:`~warpsim.objects.registry.ObjectSpec`), the controls in force, and the help or error overlay."""

from __future__ import annotations

import math

import numpy as np

from ..objects.registry import OBJECTS
from ..run.diagnostics import Frame

KEYS = (
    ("+ / -", "wind speed up / down: 1 m/s a press, 2 m/s a second held, up to the objects' wind limit"),
    ("[ / ]", "wind direction 15 deg anticlockwise / clockwise (seen from above)"),
    ("Space", "pause / go on"),
    (".", "one frame (when paused)"),
    ("R", "restart from the initial state"),
    ("C", "camera: orbit / chase behind the object / ground observer"),
    ("mouse", "drag to orbit, wheel to zoom"),
    ("H or ?", "show / hide this help"),
    ("Esc or Q", "quit"),
)
"""The keys of every scene (the help shows the scene's objects' own keys above them, :func:`key_map`)."""


def key_map(viewer) -> list[tuple[str, str]]:
    """``(keys, what they do)`` for the help: the scene's objects' own key bindings, then :data:`KEYS`."""
    own = [(b.label, b.help) for b in viewer.axis_keys]
    if viewer.walk_keys is not None:
        own.append((viewer.walk_keys.label, viewer.walk_keys.help))
    return own + list(KEYS)


def rates(viewer) -> tuple[float, float]:
    """(real-time factor, steps per wall second) over the last second of ticks."""
    if len(viewer._rate) < 2:
        return 0.0, 0.0
    (w0, t0, s0), (w1, t1, s1) = viewer._rate[0], viewer._rate[-1]
    wall = w1 - w0
    return ((t1 - t0) / wall, (s1 - s0) / wall) if wall > 0 else (0.0, 0.0)


def hud_lines(viewer) -> list[str]:
    """The heads-up lines: time and rates, each object's flight figures, the controls in force."""
    factor, steps = rates(viewer)
    state = "paused" if viewer.paused else f"{factor:.2f}x real time" + (" (machine too slow)" if viewer.behind else "")
    busy = viewer.step_time / max(viewer.step_time + viewer.draw_time, 1e-9)
    lines = [
        f"t = {viewer.sim.state.time:7.2f} s   {state}   {steps:,.0f} steps/s   "
        f"time stepping {100 * busy:.0f}% / drawing {100 - 100 * busy:.0f}%   camera {viewer.camera}"
    ]
    lines += object_lines(viewer.model, viewer.figures(viewer.frame, viewer.sim.solver.tri_force), viewer.frame)[:8]
    wind = viewer.frame.wind[0]  # blowing now (gusts included), in the first world
    heading = math.degrees(math.atan2(wind[1], wind[0]))
    where = " (world 0)" if viewer.model.world_count > 1 else ""
    controls = [f"wind{where} {np.linalg.norm(wind[:2]):.1f} m/s towards {heading:.0f} deg"]
    if viewer.axis_keys:
        values = (f"{b.control} {viewer.sim.controls.get(b.control, 0.0):+.2f}" for b in viewer.axis_keys)
        controls.append("  ".join(values))
    if viewer.walk_keys is not None:
        x, y = viewer._anchor()
        controls.append(f"{viewer.walk_keys.control} ({x:.1f}, {y:.1f}) m")
    lines.append("   ".join(controls))
    if viewer.recorder is not None:
        lines.append(f"recording {viewer.recorder.path.name}")
    lines.append("H: help")
    return lines


def overlay_lines(viewer) -> list[str]:
    """The lines shown in the middle: an error, else the key map while help is on."""
    if viewer.error:
        return ["", viewer.error, "", "R: restart    Esc: quit"]
    if viewer.show_help:
        return [f"{keys:>13}   {what}" for keys, what in key_map(viewer)]
    return []


def object_lines(model, figures: list[dict], frame: Frame) -> list[str]:
    """One heads-up line per object of ``model`` from its ``figures`` (:class:`warpsim.run.figures.Figures`):
    altitude and airspeed, then the object's own text (:attr:`~warpsim.objects.registry.ObjectSpec.hud`), and the
    worst stretch of ``frame``."""
    lines = []
    for record, f in zip(model.objects, figures, strict=True):
        text = f"{record.name}: altitude {f['altitude']:6.1f} m  airspeed {f['airspeed']:5.1f} m/s"
        own = OBJECTS[record.kind].hud
        lines.append(f"{text}  {own(f)}" if own is not None else text)
    lines.append(f"worst stick stretch {100 * frame.worst_stretch:.2f}%")
    return lines
