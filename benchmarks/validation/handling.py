"""How the hang glider handles (issue 34), measured from the particles: roll, turns, dive recovery, phugoid.

Each function flies a scene once (a built-in name, a scene file or a descriptor; ``solver`` overrides the time
step and iterations) and returns several figures of that one flight, so a test or a validation row reuses it.
A *pilot* here is a function of the flight state (:func:`warpsim.objects.hang_glider.flight_state`, with its
time ``t`` [s]) that returns the controls to set (or ``None`` to keep them), called every ``every`` seconds.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from warpsim.physics.atmosphere import scene_density
from warpsim.physics.model import GRAVITY
from warpsim.run.simulation import Simulation

from .piloting import bank_holder, body_angles, crossing, fly_piloted, scene_descriptor, wing_loading
from .pitch import (
    delta_pitch_lag,
    jones_recovery_height,
    lag_ratio,
    lift_slope_flight,
    pitch_derivatives,
    point_mass_recovery,
)


def roll_flight(
    scene: str | dict, solver: dict | None = None, level: float = 10.0, steady: float = 8.0, hold: float = 20.0
) -> dict:
    """Full weight shift from level flight, a reversal from a steady turn, and the bar centred in a turn.

    From level trimmed flight at ``level`` [s], ``roll = -1`` until 30° of left bank; a pilot (:func:`bank_holder`)
    then holds 30° left for ``steady`` [s]; then ``roll = +1`` until 30° of right bank (the reversal), and the bar is
    centred for ``hold`` [s]. Returns ``time_to_30`` [s] (level to -30°), ``reversal`` [s] (from the full weight
    shift right in the steady left turn to +30°), ``bank_after_hold`` [deg] (the bank ``hold`` seconds after
    centring), ``bank_min``/``bank_max`` [deg] over the hold, the largest sideslip [deg] at the mass centre
    (:func:`body_angles`) over the roll-in (``beta_roll_in``: level to -30°) and over the reversal (``beta_reversal``),
    the largest keel angle of attack [deg] from the roll-in on (``alpha_max``; beyond 90° the keel flies tail
    first), ``history``.
    """
    phase = {"name": "level"}
    holder = bank_holder(lambda t: -30.0)

    def pilot(s):
        name = phase["name"]
        if name == "level" and s["t"] >= level - 1e-9:
            phase.update(name="left", t=s["t"])
            return {"roll": -1.0}
        if name == "left" and s["bank_deg"] <= -30.0:
            phase.update(name="steady", t_left=s["t"])
        if phase["name"] == "steady":
            if s["t"] < phase["t_left"] + steady - 1e-9:
                return holder(s)
            phase.update(name="right", t_reverse=s["t"])
            return {"roll": 1.0}
        if name == "right" and s["bank_deg"] >= 30.0:
            phase.update(name="hold", t_right=s["t"])
            return {"roll": 0.0}
        return None

    done = lambda s: phase["name"] == "hold" and s["t"] >= phase["t_right"] + hold - 1e-9  # noqa: E731
    history = fly_piloted(
        scene_descriptor(scene, solver), level + steady + 60.0 + hold, pilot, stop=done, watch=body_angles
    )
    t_right = phase.get("t_right", math.inf)
    held = [f for f in history if t_right <= f["t"]]

    def largest_beta(t0: float, t1: float) -> float:
        return max((abs(f["beta"]) for f in history if t0 - 1e-9 <= f["t"] <= t1 + 1e-9), default=math.nan)

    return {
        "beta_roll_in": largest_beta(level, phase.get("t_left", math.inf)),
        "beta_reversal": largest_beta(phase.get("t_reverse", math.inf), t_right),
        "alpha_max": max(abs(f["alpha"]) for f in history if f["t"] >= level - 1e-9),
        "time_to_30": phase.get("t_left", math.inf) - level,
        "reversal": t_right - phase.get("t_reverse", math.inf),
        "history": history,
        "bank_after_hold": held[-1]["bank_deg"] if held and held[-1]["t"] >= t_right + hold - 0.06 else math.nan,
        "bank_min": min((f["bank_deg"] for f in held), default=math.nan),
        "bank_max": max((f["bank_deg"] for f in held), default=math.nan),
    }


def held_shift_flight(
    scene: str | dict, solver: dict | None = None, roll: float = 0.5, level: float = 10.0, seconds: float = 20.0
) -> dict:
    """Weight shift ``roll`` held ``seconds`` [s] from level trimmed flight at ``level`` [s]: the largest sideslip
    [deg] at the mass centre and keel angle of attack [deg] (:func:`body_angles`) while it is held, the bank [deg]
    and airspeed [m/s] at its end and the fastest airspeed [m/s] on the way, and the ``history``."""
    history = fly_piloted(
        scene_descriptor(scene, solver),
        level + seconds,
        lambda s: {"roll": roll} if s["t"] >= level - 1e-9 else None,
        watch=body_angles,
    )
    held = [f for f in history if f["t"] >= level - 1e-9]
    return {
        "beta": max(abs(f["beta"]) for f in held),
        "alpha": max(abs(f["alpha"]) for f in held),
        "bank": held[-1]["bank_deg"],
        "airspeed": held[-1]["airspeed"],
        "fastest": max(f["airspeed"] for f in held),
        "history": history,
    }


def turn_circle(frames: list[dict]) -> dict:
    """The steady turn over ``frames``: mean bank [deg], airspeed [m/s], horizontal speed [m/s], turn rate [deg/s],
    radius V_h / rate [m] and the coordinated turn's V^2 / (g tan bank) [m] (V the airspeed)."""
    heading = np.unwrap([math.atan2(f["velocity"][1], f["velocity"][0]) for f in frames])
    rate = (heading[-1] - heading[0]) / (frames[-1]["t"] - frames[0]["t"])
    bank = float(np.mean([f["bank_deg"] for f in frames]))
    airspeed = float(np.mean([f["airspeed"] for f in frames]))
    horizontal = float(np.mean([np.hypot(*f["velocity"][:2]) for f in frames]))
    return {
        "bank": bank,
        "airspeed": airspeed,
        "rate": math.degrees(rate),
        "radius": horizontal / abs(rate),
        "expected": airspeed**2 / (GRAVITY * math.tan(math.radians(abs(bank)))),
    }


def turn_flight(scene: str | dict, solver: dict | None = None, banks=(20.0, 40.0), settle=10.0, hold=10.0) -> dict:
    """Steady turns held by :func:`bank_holder` at each of ``banks`` [deg] in turn (from 10 s, ``settle`` + ``hold``
    seconds each); :func:`turn_circle` over each ``hold``, keyed by the bank."""
    start = 10.0
    span = settle + hold

    def target(t):
        k = int((t - start) // span)
        return None if t < start or k >= len(banks) else banks[k]

    history = fly_piloted(scene_descriptor(scene, solver), start + span * len(banks), bank_holder(target))
    out = {"history": history}
    for k, b in enumerate(banks):
        t0 = start + k * span + settle
        out[b] = turn_circle([f for f in history if t0 <= f["t"] <= t0 + hold + 1e-9])
    return out


def dive_flight(
    scene: str | dict,
    solver: dict | None = None,
    nose_down: float = 60.0,
    seconds: float = 12.0,
    bar: float = 0.0,
    watch: Callable[[Simulation, dict], None] | None = None,
) -> dict:
    """Released from rest with the nose ``nose_down`` [deg] below the horizon (R.T. Jones 1977), the bar at
    ``bar`` from the release (0: hands off; -1: pushed full out, the pilot pulling out at the highest lift, as
    Jones's constant-C_L analysis assumes; it reaches the stop in 0.5 s, the arms' slew): the height [m] lost
    until the flight path is level again (the sail's mean vertical velocity back to 0), the time [s] it takes,
    the fastest airspeed [m/s] and the lowest pitch [deg] on the way."""
    d = scene_descriptor(scene, solver, {"speed": 0.0, "nose_up": -nose_down})
    history = fly_piloted(d, seconds, pilot=(lambda state: {"pitch": bar}) if bar else None, every=0.02, watch=watch)
    start = history[0]["altitude"]
    moving = [f for f in history if f["velocity"][2] < -1.0]
    t_level = crossing(history, moving[0]["t"] if moving else 0.0, lambda f: f["velocity"][2] >= 0.0)
    lowest = min((f for f in history if f["t"] <= t_level), key=lambda f: f["altitude"])
    return {
        "height": start - lowest["altitude"],
        "time": t_level,
        "fastest": max(f["airspeed"] for f in history if f["t"] <= t_level),
        "lowest_pitch": min(f["pitch_deg"] for f in history if f["t"] <= t_level),
        "history": history,
    }


def phugoid_flight(
    scene: str | dict, solver: dict | None = None, watch: Callable[[Simulation, dict], None] | None = None
) -> dict:
    """A 2 s pulse of bar in (pitch 0.3) at 20 s from trim, then hands off to 60 s: the airspeed's period [s] from
    its troughs, damping ratio, the trim airspeed [m/s] before the pulse and Lanchester's period
    pi sqrt(2) V / g [s].

    The airspeed is taken at the trim's density (``V sqrt(rho / rho_trim)``, an equivalent airspeed): in the
    standard atmosphere the trim speed falls as the glider sinks into denser air (0.3 % in 60 m), and that drift
    would otherwise read as a slower decay."""

    def pilot(s):
        if abs(s["t"] - 20.0) < 1e-6:
            return {"pitch": 0.3}
        if abs(s["t"] - 22.0) < 1e-6:
            return {"pitch": 0.0}
        return None

    history = fly_piloted(scene_descriptor(scene, solver), 60.0, pilot, every=0.1, watch=watch)
    trim = float(np.mean([f["airspeed"] for f in history if 10.0 <= f["t"] <= 20.0]))
    rho = float(np.mean([f["density"] for f in history if 10.0 <= f["t"] <= 20.0]))
    pulse = [f for f in history if f["t"] >= 23.0 - 1e-9]
    dv = np.array([f["airspeed"] * math.sqrt(f["density"] / rho) for f in pulse]) - trim
    troughs = [i for i in range(1, len(dv) - 1) if dv[i] < dv[i - 1] and dv[i] <= dv[i + 1] and dv[i] < -0.2]
    lanchester = math.pi * math.sqrt(2.0) * trim / GRAVITY
    if len(troughs) < 2:
        return {"period": math.nan, "zeta": math.nan, "trim": trim, "lanchester": lanchester}
    period = (pulse[troughs[-1]]["t"] - pulse[troughs[0]]["t"]) / (len(troughs) - 1)
    decrement = math.log(dv[troughs[0]] / dv[troughs[-1]]) / (len(troughs) - 1)
    return {
        "period": period,
        "zeta": decrement / math.hypot(2.0 * math.pi, decrement),
        "trim": trim,
        "lanchester": lanchester,
        "troughs": len(troughs),
        "history": history,
    }


def stall_flight(scene: str | dict, solver: dict | None = None) -> dict:
    """Full bar out (pitch -1) from 15 s, released at 25 s, flown to 40 s: the time [s] to fly at 9 m/s again, the
    largest |pitch| [deg] after the release, the lowest airspeed [m/s] and highest pitch [deg] while held."""

    def pilot(s):
        if abs(s["t"] - 15.0) < 1e-6:
            return {"pitch": -1.0}
        if abs(s["t"] - 25.0) < 1e-6:
            return {"pitch": 0.0}
        return None

    history = fly_piloted(scene_descriptor(scene, solver), 40.0, pilot, every=0.1)
    held = [f for f in history if 15.0 < f["t"] <= 25.05]
    after = [f for f in history if f["t"] > 25.05]
    return {
        "recovery": crossing(after, 25.0, lambda f: f["airspeed"] >= 9.0) - 25.0,
        "max_pitch": max(abs(f["pitch_deg"]) for f in after),
        "slowest": min(f["airspeed"] for f in held),
        "nose_up": max(f["pitch_deg"] for f in held),
        "history": history,
    }


def glide_flight(scene: str | dict, solver: dict | None = None) -> dict:
    """Hands off for 60 s: glide ratio and mean airspeed [m/s] over 10-60 s, the airspeed's spread and the largest
    |bank| [deg]."""
    history = fly_piloted(scene_descriptor(scene, solver), 60.0, every=0.1)
    frames = [f for f in history if f["t"] >= 10.0 - 1e-9]
    distance = sum(float(np.hypot(*f["velocity"][:2])) * 0.1 for f in frames[1:])
    speeds = np.array([f["airspeed"] for f in frames])
    return {
        "glide": distance / (frames[0]["altitude"] - frames[-1]["altitude"]),
        "speed": float(speeds.mean()),
        "spread": float(np.abs(speeds / speeds.mean() - 1.0).max()),
        "max_bank": max(abs(f["bank_deg"]) for f in frames),
        "history": history,
    }


def dive_band(
    scene: str | dict,
    trim_speed: float,
    glide_ratio: float,
    max_lift: float = 1.0,
    lift_slope: float | None = None,
    static_margin: float | None = None,
    period_ratio: float | None = None,
) -> dict:
    """The band of the dive recovery height [m] from R.T. Jones (1977) at ``scene``'s wing loading and air density:
    from his closed form at the maximum lift coefficient ``max_lift`` (his 1.0: the wing pulls out at once at its
    highest lift, the least height) to the point mass holding the trim lift coefficient
    ``2 (m/S) g / (rho V^2)`` (``trim_speed`` [m/s]) with the drag of the measured ``glide_ratio`` (a wing held at its
    trim angle of attack through the pull-out). Returns ``wing_loading``, ``density``, ``trim_cl``, ``low``,
    ``jones_trim`` (the closed form at the trim C_L) and ``high``.

    With ``lift_slope`` a [1/rad] and ``static_margin`` [m] it adds what a rigid tailless wing of the scene's planform
    does hands off (:func:`delta_pitch_lag`, :func:`lag_ratio`): ``rigid_lag`` (c, Pistolesi's three-quarter chord) and
    ``thin_lag`` (c, Pistolesi's point with thin-aerofoil theory's quarter-chord pitch-damping moment,
    ``quarter_chord_moment`` of :func:`delta_pitch_lag`), ``panel_lag`` (c, each strip's angle of attack where its lift
    acts) and ``pieces_lag`` (c, every piece of each chord
    lifting alone, as a sail of triangles each under its own air law does), the heights ``rigid``, ``panel`` and
    ``pieces`` [m] of that point mass with those lags, and ``rigid_period`` (and so on), the ratios ``sqrt(1 + c)``
    of their phugoid periods to Lanchester's. With ``period_ratio`` (a measured phugoid period
    over Lanchester's) it adds ``lag`` = ``period_ratio^2 - 1`` and ``predicted`` [m], the point mass with that lag."""
    d = scene_descriptor(scene)
    rho = scene_density(d["air"], d["hang_glider"]["altitude"])  # where it is launched
    load = wing_loading(d)
    cl = 2.0 * load * GRAVITY / (rho * trim_speed**2)
    out = {
        "wing_loading": load,
        "density": rho,
        "trim_cl": cl,
        "low": jones_recovery_height(load, max_lift, rho),
        "jones_trim": jones_recovery_height(load, cl, rho),
        "high": point_mass_recovery(load, cl, glide_ratio, rho),
    }
    if lift_slope is not None and static_margin is not None:
        g = d["hang_glider"]
        for key, at, moment in (
            ("rigid", 0.75, False),
            ("thin", 0.75, True),
            ("panel", 0.25, False),
            ("pieces", None, False),
        ):
            k = delta_pitch_lag(g["span"], g["chord"], static_margin, sample_at=at, quarter_chord_moment=moment)["k"]
            lag = lag_ratio(k, lift_slope, load, rho)
            out[f"{key}_lag"] = lag
            out[key] = point_mass_recovery(load, cl, glide_ratio, rho, lag=lag)
            out[f"{key}_period"] = math.sqrt(1.0 + lag)
    if period_ratio is not None:
        out["lag"] = period_ratio**2 - 1.0
        out["predicted"] = point_mass_recovery(load, cl, glide_ratio, rho, lag=out["lag"])
    return out


def summary(scene: str | dict = "hang-glider", solver: dict | None = None) -> dict:
    """Every handling figure of ``scene`` (one flight each), without the histories."""
    r, hs, t, dv, dvb, p, s, g, a, pd = (
        roll_flight(scene, solver),
        held_shift_flight(scene, solver),
        turn_flight(scene, solver),
        dive_flight(scene, solver),
        dive_flight(scene, solver, bar=-1.0),
        phugoid_flight(scene, solver),
        stall_flight(scene, solver),
        glide_flight(scene, solver),
        lift_slope_flight(scene, solver),
        pitch_derivatives(scene, solver),
    )
    return {
        "time_to_30": r["time_to_30"],
        "reversal": r["reversal"],
        "bank_after_hold": r["bank_after_hold"],
        "hold_range": (r["bank_min"], r["bank_max"]),
        "beta_roll_in": r["beta_roll_in"],
        "beta_reversal": r["beta_reversal"],
        "alpha_max": r["alpha_max"],
        "half_shift": {k: v for k, v in hs.items() if k != "history"},
        "turn20": {k: v for k, v in t[20.0].items()},
        "turn40": {k: v for k, v in t[40.0].items()},
        "dive_height": dv["height"],
        "dive_time": dv["time"],
        "dive_fastest": dv["fastest"],
        "dive_lowest_pitch": dv["lowest_pitch"],
        "dive_bar_out_height": dvb["height"],
        "dive_bar_out_time": dvb["time"],
        "phugoid": {k: v for k, v in p.items() if k != "history"},
        "stall": {k: v for k, v in s.items() if k != "history"},
        "glide": {k: v for k, v in g.items() if k != "history"},
        "lift_slope": a["slope"],
        "static_margin": a["static_margin"],
        "pitch": {k: float(v) for k, v in pd.items()},
    }


def plot_roll_reversal(path, scene: str | dict = "hang-glider") -> dict:
    """Plot bank [deg], the pilot's roll and airspeed [m/s] against time [s] of :func:`roll_flight` (defaults and dt
    0.005/110) to the PNG ``path``; returns the flights."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    flights = {"dt 0.01, 55 iterations": roll_flight(scene), "dt 0.005, 110": roll_flight(scene, FINE)}
    fig, (top, mid, low) = plt.subplots(3, 1, sharex=True, figsize=(8, 7), gridspec_kw={"height_ratios": [3, 1, 2]})
    for (label, r), style in zip(flights.items(), ("-", "--"), strict=True):
        h = [f for f in r["history"] if f["t"] >= 8.0]
        t = [f["t"] for f in h]
        top.plot(t, [f["bank_deg"] for f in h], style, color="C0", label=f"bank, {label}")
        mid.plot(t, [f["roll"] for f in h], style, color="C2", label=label)
        low.plot(t, [f["airspeed"] for f in h], style, color="C1", label=label)
    r = flights["dt 0.01, 55 iterations"]
    for y in (-30.0, 30.0):
        top.axhline(y, color="grey", lw=0.6)
    fine = flights["dt 0.005, 110"]
    top.text(
        0.02,
        0.96,
        f"level to -30°: {r['time_to_30']:.1f} s ({fine['time_to_30']:.1f} s)\n"
        f"reversal -30° to +30°: {r['reversal']:.1f} s ({fine['reversal']:.1f} s)\n"
        f"bar centred at +30°: {r['bank_after_hold']:.0f}° ({fine['bank_after_hold']:.0f}°) 20 s later",
        transform=top.transAxes,
        va="top",
        fontsize=8,
        bbox={"facecolor": "white", "alpha": 0.8, "edgecolor": "none"},
    )
    top.set_ylabel("bank [deg] (+ right)")
    top.legend(fontsize=8, loc="lower right")
    top.set_title("Hang glider: full weight shift from level, reversal from a steady 30° turn, bar centred")
    mid.set_ylabel("roll (bar)")
    mid.set_ylim(-1.15, 1.15)
    low.set_ylabel("airspeed [m/s]")
    low.set_xlabel("time [s]")
    low.legend(fontsize=8, loc="upper right")
    for ax in (top, mid, low):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return flights


FINE = {"dt": 0.005, "iterations": 110}
"""The finer numerics every handling band must also hold at (issue 34)."""


if __name__ == "__main__":  # python -m benchmarks.validation.handling [scene] [dt iterations] [key=value ...]
    import json
    import sys

    args = sys.argv[1:]
    scene = args.pop(0) if args and "=" not in args[0] and not args[0][0].isdigit() else "hang-glider"
    solver = {"dt": float(args.pop(0)), "iterations": int(args.pop(0))} if args and "=" not in args[0] else None
    glider = {k: json.loads(v) for k, v in (a.split("=", 1) for a in args)}
    d = scene_descriptor(scene, None, glider or None)
    print(json.dumps(summary(d, solver), indent=1, default=float))
