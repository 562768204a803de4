"""The vortex law's shed wake in unsteady flow (issue 52): the lift of a wing set suddenly at an angle of attack,
against Wagner's function.

A flat rectangular wing of high aspect ratio is held in a wind that starts at ``t = 0`` at ``alpha`` (a step in the
angle of attack of a wing whose air was at rest: no circulation, no wake). Its lift, measured from the forces the
kernels hand to the particles, builds up as the starting vortex moves away. Wagner (1925) gave the circulatory lift
of a flat plate of infinite span after such a step, ``L(s) / L(inf) = Phi(s)`` over ``s = 2 U t / c`` half-chords
travelled; R. T. Jones's approximation ``Phi(s) = 1 - 0.165 e^(-0.0455 s) - 0.335 e^(-0.3 s)`` is within 1 % of it
(Bisplinghoff, Ashley & Halfman, *Aeroelasticity*, 1955, section 5-6). The impulse of the added mass at the step
(the first step's spike) is not part of it, and a wing of finite span reaches its own steady lift a little sooner.

    python -m benchmarks.validation.unsteady    # the rows, and the response at the finer and coarser settings
"""

from __future__ import annotations

import math

import numpy as np
import warp as wp

from warpsim.physics.config import AirConfig, WindConfig
from warpsim.physics.kernels.aero import AeroModel
from warpsim.physics.kernels.vortex import VortexScratch, vortex_air_force
from warpsim.physics.kernels.wake import ShedWake

from .common import Row
from .wings import loads, rectangle

WAGNER = (
    "Wagner (1925), the lift build-up after a step in the angle of attack of a flat plate of infinite span, "
    "Phi(s) = 1 - 0.165 exp(-0.0455 s) - 0.335 exp(-0.3 s) (R. T. Jones's approximation, within 1 %; Bisplinghoff, "
    "Ashley & Halfman 1955, 5-6)"
)
STATIONS = (1.0, 2.0, 4.0, 8.0, 16.0)
"""Half-chords travelled where the rows compare."""


def wagner(s: float) -> float:
    """Wagner's function by R. T. Jones's approximation at ``s`` half-chords travelled."""
    return 1.0 - 0.165 * math.exp(-0.0455 * s) - 0.335 * math.exp(-0.3 * s)


def lift_build_up(
    aspect_ratio: float = 20.0,
    span_panels: int = 40,
    chord_panels: int = 8,
    steps_per_chord: int = 8,
    chords: float = 8.0,
    rows: int | None = None,
    alpha_deg: float = 5.0,
    steps_per_row: int = 1,
) -> tuple[np.ndarray, np.ndarray]:
    """The wing's lift after the step, ``(s, C_L(s) / C_L(steady))`` at every step: a rectangle of chord 1 m and
    ``span_panels x chord_panels`` cells in a wind of 1 m/s, ``steps_per_chord`` steps (and rows shed) per chord
    travelled, a row shed every ``steps_per_row`` steps (``air.wake_interval``, over which the unsteady term's rate is
    smoothed too), for ``chords`` chords; the wake keeps ``rows`` rows (default: all it sheds). ``C_L(steady)`` is the
    quasi-steady wake's, at the same angle. Step ``k`` (from 0) is ``t = k dt``: it solves with the vorticity shed
    ``k`` steps before, carried ``k dt`` downstream, and step 0 is the start, with no wake yet."""
    wing = rectangle(aspect_ratio, span_panels, chord_panels)
    m = wing.model
    dt = 1.0 / steps_per_chord
    steps = int(round(chords * steps_per_chord)) + 1
    steady = loads(wing, alpha_deg)["CL"]
    a = math.radians(alpha_deg)
    wind = np.array([math.cos(a), 0.0, math.sin(a)])  # the air towards +x and up: the wing flies to -x at +alpha
    state, control = m.state(dt), m.control()
    state.particle_q.assign(m.particle_q0)
    state.particle_q_prev.assign(m.particle_q0)
    control.wind.assign(np.array([wind], dtype=np.float32))
    control.air_density.fill_(1.0)
    scratch = VortexScratch(m)
    scratch.shed = ShedWake(m, rows or steps // steps_per_row + 1, steps_per_row * dt)
    air = AirConfig(model=AeroModel.VORTEX, density=1.0, vortex_interval=10.0)  # a rigid wing: factorised once
    lift_dir = np.array([-wind[2], 0.0, wind[0]])
    ratio = np.zeros(steps)
    tri_force = wp.zeros(m.tri_count, dtype=wp.vec3, device=m.device)
    particle = wp.zeros(m.particle_count, dtype=wp.vec3, device=m.device)
    for k in range(steps):
        vortex_air_force(m, state, control, dt, air, WindConfig(), scratch, tri_force, particle)
        f = particle.numpy().astype(np.float64)
        np.add.at(f, m.tri_indices_np.reshape(-1), np.repeat(tri_force.numpy().astype(np.float64), 3, axis=0))
        ratio[k] = f.sum(0) @ lift_dir / (0.5 * wing.area) / steady
    s = 2.0 * dt * np.arange(steps)
    return s, ratio


def at(s: np.ndarray, ratio: np.ndarray, station: float) -> float:
    """The response at ``station`` half-chords (a step ends there)."""
    k = int(np.argmin(np.abs(s - station)))
    assert abs(s[k] - station) < 1e-9, (station, s[k])
    return float(ratio[k])


def wagner_rows() -> list[Row]:
    """The lift build-up of an aspect-ratio-20 wing at 5° against Wagner's function at 1, 2, 4, 8 and 16
    half-chords, within 10 % at each."""
    s, ratio = lift_build_up()
    got = [at(s, ratio, x) for x in STATIONS]
    worst = max(abs(g / wagner(x) - 1.0) for g, x in zip(got, STATIONS, strict=True))
    return [
        Row(
            "lift build-up after a step in the angle of attack (shed wake)",
            "C_L(s)/C_L(steady) of a flat wing of aspect ratio 20 (40 x 8 cells) set at 5° at t = 0, at s = "
            + ", ".join(f"{x:g}" for x in STATIONS)
            + " half-chords, 8 steps and rows a chord",
            ", ".join(f"{wagner(x):.3f}" for x in STATIONS),
            WAGNER,
            ", ".join(f"{g:.3f}" for g in got) + f" (worst {100 * worst:.1f} %)",
            "within 10 % at each",
            worst <= 0.1,
        )
    ]


def main() -> None:
    for row in wagner_rows():
        print(f"{row.status:5s} {row.case}: {row.measured} vs {row.expected} [{row.band}]")
    for label, kwargs in (
        ("aspect ratio 20, 40 x 4 cells, 4 steps a chord", {"chord_panels": 4, "steps_per_chord": 4}),
        ("aspect ratio 20, 40 x 8 cells, 8 steps a chord", {}),
        (
            "aspect ratio 40, 80 x 4 cells, 4 steps a chord",
            {"aspect_ratio": 40.0, "span_panels": 80, "chord_panels": 4, "steps_per_chord": 4},
        ),
        ("aspect ratio 8, 16 x 8 cells, 8 steps a chord", {"aspect_ratio": 8.0, "span_panels": 16}),
        ("aspect ratio 20, 40 x 16 cells, 16 steps a chord", {"chord_panels": 16, "steps_per_chord": 16}),
        ("aspect ratio 20, 40 x 8 cells, 16 steps a chord", {"steps_per_chord": 16}),
        (
            "aspect ratio 20, 40 x 8 cells, 16 steps a chord, a row every 2",
            {"steps_per_chord": 16, "steps_per_row": 2},
        ),
    ):
        s, ratio = lift_build_up(**kwargs)
        print(f"{label}: " + ", ".join(f"s={x:g} {at(s, ratio, x):.3f}" for x in STATIONS))


if __name__ == "__main__":
    main()
