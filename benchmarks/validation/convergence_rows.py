"""The convergence table's cases: each object's headline figure as the step and the iterations are refined
together (and beyond).
"""

from __future__ import annotations

import numpy as np

from warpsim.objects.flag import PRESETS as FLAG_PRESETS
from warpsim.objects.kite import anchor_elevation
from warpsim.run.simulation import Simulation
from warpsim.scene import descriptor

from .common import Row, in_processes
from .glider_rows import fly, glide, window


def _fly_at(scene: str, dt: float, iterations: int, seconds: float, controls=()) -> list[dict]:
    """:func:`fly` of ``scene`` at the time step ``dt`` [s] and ``iterations`` constraint iterations."""
    d = descriptor.merge("convergence", descriptor.resolve(scene)[0], {"solver": {"dt": dt, "iterations": iterations}})
    return fly(d, seconds, controls)


def _glide_and_trim(dt: float, iterations: int) -> tuple[float, float]:
    return glide(window(_fly_at("hang-glider", dt, iterations, 60.0), 10.0, 60.0))


def _turn_rate(dt: float, iterations: int) -> float:
    """Turn rate [deg/s] with the bank held at 20° by a pilot (:func:`benchmarks.validation.handling.turn_flight`)."""
    from benchmarks.validation.handling import turn_flight

    return abs(turn_flight("hang-glider", {"dt": dt, "iterations": iterations}, banks=(20.0,))[20.0]["rate"])


def _phugoid_period(dt: float, iterations: int) -> float:
    """Period [s] of the airspeed's oscillation after a 2 s pulse of bar in (as the phugoid row)."""
    flight = _fly_at("hang-glider", dt, iterations, 60.0, [(20.0, {"pitch": 0.3}), (22.0, {"pitch": 0.0})])
    pulse = window(flight, 23.0, 60.0)
    dv = np.array([f["airspeed"] for f in pulse])
    dv = dv - dv[-100:].mean()
    troughs = [i for i in range(1, len(dv) - 1) if dv[i] < dv[i - 1] and dv[i] <= dv[i + 1] and dv[i] < -0.2]
    return (pulse[troughs[-1]]["t"] - pulse[troughs[0]]["t"]) / (len(troughs) - 1)


def _kite_angle(dt: float, iterations: int) -> float:
    """Mean line elevation at the anchor [deg] of the default kite in 6 m/s, 20-40 s."""
    d = descriptor.merge("convergence", descriptor.resolve("kite")[0], {"solver": {"dt": dt, "iterations": iterations}})
    sim = Simulation(d)
    record, angles = sim.model.objects[0], []
    sim.run(20.0)
    sim.run(20.0, on_frame=lambda frame: angles.append(anchor_elevation(record, frame.positions)))
    return float(np.mean(angles))


def _parachute_descent(dt: float, iterations: int) -> float:
    """Steady descent speed [m/s] of the default parachute (hoop on), 20-30 s."""
    d = descriptor.merge(
        "convergence", descriptor.defaults("parachute"), {"solver": {"dt": dt, "iterations": iterations}}
    )
    sim = Simulation(d)
    record, speeds = sim.model.objects[0], []
    sim.run(20.0)
    sim.run(10.0, on_frame=lambda f: speeds.append(-f.velocities[record.particles, 2].mean()))
    return float(np.mean(speeds))


_FLAPS: dict[tuple[float, int, str], dict] = {}
""":func:`_flag_flap`'s runs by ``(dt, iterations, design)``: the frequency and the amplitude rows share each rung's
run (:func:`flag_convergence` fills it from its processes)."""


def _flag_flap(dt: float, iterations: int, design: str = "sheet") -> dict:
    """The flag's flapping as ``warpsim run flag --seconds 40`` prints it (``design`` "paper": ``warpsim run
    flag_paper --seconds 40``, resolution 5): the swings of its trailing corner over 20-40 s, ``frequency`` [Hz] and
    ``amplitude`` (half the range) [m]."""
    if (dt, iterations, design) not in _FLAPS:
        _FLAPS[dt, iterations, design] = _fly_flag(dt, iterations, design)
    return _FLAPS[dt, iterations, design]


def _fly_flag(dt: float, iterations: int, design: str) -> dict:
    """:func:`_flag_flap`'s run."""
    from warpsim.run.figures import FlightFigures

    d = descriptor.merge(
        "convergence",
        descriptor.resolve("flag")[0],
        {"flag": {"design": design}, "solver": {"dt": dt, "iterations": iterations}},
    )
    sim = Simulation(d)
    figures = FlightFigures(sim, 20.0, 40.0)
    sim.run(40.0, on_frame=figures)
    row = figures.window.row(0)
    return {"frequency": float(row["flap_frequency"]), "amplitude": 0.5 * float(row["flap_max"] - row["flap_min"])}


def _ladder(dt: float, iterations: int = 55) -> tuple[tuple[float, int], ...]:
    """(dt [s], iterations) from the defaults ``(dt, iterations)`` on: iterations doubled, dt halved with them, the
    finest (dt/4 with four times the iterations)."""
    return ((dt, iterations), (dt, 2 * iterations), (dt / 2, 2 * iterations), (dt / 4, 4 * iterations))


_SHEET_SOLVER = FLAG_PRESETS["sheet"]["solver"]  # the default flag's step [s] and iterations

CONVERGENCE = {
    # figure: (measure(dt, iterations), default dt [s], unit, band: the defaults' largest distance from the finest,
    # default iterations)
    "glider glide ratio": (lambda dt, it: _glide_and_trim(dt, it)[0], 0.01, "", 0.04, 55),
    "glider trim speed": (lambda dt, it: _glide_and_trim(dt, it)[1], 0.01, " m/s", 0.04, 55),
    "glider turn rate, bank held at 20°": (_turn_rate, 0.01, " °/s", 0.10, 55),
    "glider phugoid period": (_phugoid_period, 0.01, " s", 0.10, 55),
    "kite line angle at the anchor": (
        _kite_angle,
        descriptor.defaults("kite")["solver"]["dt"],
        "°",
        0.05,
        descriptor.defaults("kite")["solver"]["iterations"],
    ),
    "parachute descent": (_parachute_descent, descriptor.defaults("parachute")["solver"]["dt"], " m/s", 0.05, 55),
    "flag flapping frequency": (
        lambda dt, it: _flag_flap(dt, it)["frequency"],
        _SHEET_SOLVER["dt"],
        " Hz",
        0.05,
        _SHEET_SOLVER["iterations"],
    ),
    "flag flapping amplitude": (
        lambda dt, it: _flag_flap(dt, it)["amplitude"],
        _SHEET_SOLVER["dt"],
        " m",
        0.10,
        _SHEET_SOLVER["iterations"],
    ),
    "paper's flag flapping frequency (resolution 5)": (
        lambda dt, it: _flag_flap(dt, it, "paper")["frequency"],
        0.00125,
        " Hz",
        0.10,
        110,
    ),
    "paper's flag flapping amplitude (resolution 5)": (
        lambda dt, it: _flag_flap(dt, it, "paper")["amplitude"],
        0.00125,
        " m",
        0.10,
        110,
    ),
}
"""The flight figures whose convergence the validation measures (issue 33)."""

LIMITS: dict[str, str] = {}
"""Figures known not to converge, and why: a row outside its band shows as a model limit with this note."""


BEYOND_NOTES = {
    "kite line angle at the anchor": "with the sail's cloth and the frame elastic (the defaults); with rigid sticks "
    "(the paper's) the kite flies to one side of the wind window at dt/8 (52.4°), as every rigid run above "
    "sqrt(k)/dt ~57k /s does (row 'kite in 6 m/s, 0.5° crosswind, time step')",
}
"""Notes of the rows beyond the ladder, by figure."""


def convergence_figures(names=None, beyond: bool = False, ends_only: bool = False) -> list[Row]:
    """Each figure of :data:`CONVERGENCE` (or of ``names``) at its default dt and iterations (55 but for the flags'
    119 and 110), with the iterations doubled, dt halved with them, and dt quartered with four times the iterations (the
    finest). With ``beyond``, also a row that checks the finest rung against dt/8 with the same iterations: whether
    the finest rung stands for the limit. With ``ends_only``, only the defaults and the finest rung (what the band
    compares; a quarter less work)."""
    rows = []
    for name in names or CONVERGENCE:
        measure, dt, unit, band, iterations = CONVERGENCE[name]
        ladder = _ladder(dt, iterations)
        if ends_only:
            ladder = (ladder[0], ladder[-1])
        values = [measure(*key) for key in ladder]
        finest = values[-1]
        off = abs(values[0] / finest - 1.0)
        limit = LIMITS.get(name, "") if off > band else ""
        rows.append(
            Row(
                f"{name}, convergence",
                "at dt/iterations " + ", ".join(f"{d:g}/{it}" for d, it in ladder),
                f"{finest:.3f}{unit} (the finest)",
                "the model's own limit as dt -> 0 and iterations -> inf (a figure set by the numerics moves as they "
                "are refined)",
                ", ".join(f"{v:.3f}" for v in values),
                f"defaults within {100 * band:.0f} % of the finest",
                off <= band,
                model_limit=bool(limit),
                note=f"defaults {100 * (values[0] / finest - 1):+.1f} % from the finest"
                + (f"; {limit}" if limit else ""),
            )
        )
        if beyond:
            past = (ladder[-1][0] / 2.0, ladder[-1][1])
            further = measure(*past)
            moved = further / finest - 1.0
            rows.append(
                Row(
                    f"{name}, beyond the ladder",
                    f"at dt/8 with four times the iterations ({past[0]:g}/{past[1]}) against the finest rung "
                    f"({ladder[-1][0]:g}/{ladder[-1][1]})",
                    f"{finest:.3f}{unit} (the finest)",
                    "the finest rung stands for the model's limit only if a finer step leaves the figure where it is",
                    f"{further:.3f}{unit}",
                    f"within {50 * band:g} % of the finest (half the defaults' band)",
                    abs(moved) <= band / 2.0,
                    note=f"{100 * moved:+.1f} % from the finest"
                    + (f"; {BEYOND_NOTES[name]}" if name in BEYOND_NOTES else ""),
                )
            )
    return rows


def flag_convergence() -> list[Row]:
    """The default flag's convergence rows (:data:`CONVERGENCE`), its four rungs one process per core (10 min on 2
    cores, most of it the finest rung, dt/4 with 476 iterations). No rung beyond the ladder: its finest step,
    0.3125 ms, is already finer than the 'sheet flag' rows' 0.5 and 0.25 ms, and dt/8 would take 9 min alone."""
    figures = ["flag flapping frequency", "flag flapping amplitude"]
    _, dt, _, _, iterations = CONVERGENCE[figures[0]]
    jobs = {(d, it): (d, it, "sheet") for d, it in _ladder(dt, iterations) if (d, it, "sheet") not in _FLAPS}
    runs = in_processes(_flag_flap, jobs, lambda d, it, _: it / d) if jobs else {}
    _FLAPS.update({(d, it, "sheet"): run for (d, it), run in runs.items()})
    return convergence_figures(figures)
