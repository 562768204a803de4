"""The flag's flapping against the time step (issue 35): the validation's resolution-17 flag at dt 0.01, 0.0025 and
0.000625 s, and the same flag handed in mid-flight from dt 0.01 to 0.000625.

    python -m benchmarks.validation.flag_time_step [OUT.png]

Prints each run's frequency and rms sideways motion of the top trailing corner, the handed-over flag's rms in 5 s
windows, and draws the corner's motion (default ``docs/flag_time_step.png``). About 2 minutes on 2 cores.
"""

from __future__ import annotations

import numpy as np

from benchmarks.validation import picture_command, save_picture
from benchmarks.validation.flag_rows import FLAG_TIME_STEPS, flag_corner_series, flag_simulation, peak_frequency


def handed_over(resolution: int, dt_from: float, dt_to: float, before: float, after: float) -> dict:
    """Fly the flag ``before`` seconds at ``dt_from``, carry its positions and velocities over to a flag stepping
    ``dt_to`` [s] and fly that ``after`` seconds: the corner's rms sideways motion [m] in each 5 s window after."""
    first = flag_simulation(resolution, dt_from)
    t0, y0, _ = flag_corner_series(first, before)
    second = flag_simulation(resolution, dt_to)
    second.state.particle_q.assign(first.state.positions())
    second.state.set_velocity(first.state.velocities(dt_from), dt_to)
    second.state.time = first.state.time
    t1, y1, _ = flag_corner_series(second, after)
    windows = [y1[(t1 > t0[-1] + 5.0 * k) & (t1 <= t0[-1] + 5.0 * (k + 1))] for k in range(int(after // 5))]
    return {
        "times": np.concatenate([t0, t1]),
        "ys": np.concatenate([y0, y1]),
        "switch": float(t0[-1]),
        "rms before": float(np.std(y0[t0 > 5.0])),
        "rms after": [float(np.std(w)) for w in windows],
    }


def main(argv: list[str] | None = None) -> int:
    """Entry point: the three runs and the hand-over, printed and drawn."""
    out, plt = picture_command(
        "python -m benchmarks.validation.flag_time_step",
        "The resolution-17 flag's corner at dt 0.01, 0.0025 and 0.000625 s, and handed in mid-flight "
        "from dt 0.01 to 0.000625: frequencies and rms printed, the motion drawn. About 2 minutes on 2 cores.",
        "docs/flag_time_step.png",
        argv,
    )

    runs = {}
    for dt in FLAG_TIME_STEPS:
        t, y, _ = flag_corner_series(flag_simulation(17, dt), 30.0, after=5.0)
        runs[dt] = (t, y)
        print(f"resolution 17, dt {dt:g} s: {peak_frequency(y):.2f} Hz, rms {np.std(y):.2f} m")
    hand = handed_over(17, FLAG_TIME_STEPS[0], FLAG_TIME_STEPS[-1], 20.0, 20.0)
    print(
        f"handed over at {hand['switch']:.0f} s from dt {FLAG_TIME_STEPS[0]:g} to {FLAG_TIME_STEPS[-1]:g}: rms "
        f"{hand['rms before']:.2f} m before, " + ", ".join(f"{r:.2f}" for r in hand["rms after"]) + " m in 5 s windows"
    )
    fig, axes = plt.subplots(len(runs) + 1, 1, figsize=(9, 8), sharex=True)
    for ax, (dt, (t, y)) in zip(axes, runs.items(), strict=False):
        ax.plot(t, y, lw=0.8)
        ax.set_title(f"dt {dt:g} s: {peak_frequency(y):.2f} Hz, rms {np.std(y):.2f} m", fontsize=9)
    ax = axes[-1]
    ax.plot(hand["times"], hand["ys"], lw=0.8)
    ax.axvline(hand["switch"], color="k", ls="--", lw=0.8)
    ax.set_title(f"dt {FLAG_TIME_STEPS[0]:g} s, then {FLAG_TIME_STEPS[-1]:g} s from the dashed line", fontsize=9)
    ax.set_xlabel("time [s]")
    for ax in axes:
        ax.set_ylabel("corner y [m]")
    return save_picture(fig, "The validation's flag at resolution 17: its trailing corner's sideways motion", out)


if __name__ == "__main__":
    raise SystemExit(main())
