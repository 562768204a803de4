"""The kite's and the parachute's response to frozen turbulence, as a sweep over its intensity: a table and a plot.

    python -m benchmarks.validation.turbulence_response [--seconds S]   # prints the table, writes
                                                                        # docs/turbulence_response.png and .csv

Each flight is measured from the particles over its last two thirds: the kite (defaults, its 6 m/s wind) by its line
angle at the anchor, the line's pull (from the rope's sag; the share of frames with the rope slack) and its sideways
wander; the flat round parachute (scenes/parachute.toml with its gusts off, in the same 3 m/s breeze) by its rate of
descent and its swing. Intensities 0-0.20 span IEC 61400-1's classes (0.12-0.16 at 15 m/s) and a gusty hill; the
length scale is the default 24.5 m.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from warpsim.objects.kite import anchor_pull, line_elevation
from warpsim.objects.parachute import swing_angle
from warpsim.run.simulation import Simulation
from warpsim.scene import descriptor

INTENSITIES = (0.0, 0.05, 0.10, 0.15, 0.20)
ROOT = Path(__file__).resolve().parents[2]


def kite(intensity: float, seconds: float) -> dict:
    """The default kite in turbulence of ``intensity``: means and standard deviations over the last 2/3."""
    d = descriptor.merge("response", descriptor.resolve("kite")[0], {"wind": {"turbulence_intensity": intensity}})
    sim = Simulation(d)
    record = sim.model.objects[0]
    mass = sim.model.particle_free_mass
    angle, pull, side = [], [], []

    def keep(frame) -> None:
        if frame.time >= seconds / 3:
            q = frame.positions
            angle.append(line_elevation(record, q))
            pull.append(anchor_pull(record, q, mass))
            side.append(q[record.particles, 1].mean())

    sim.run(seconds, on_frame=keep)
    pull = np.array(pull)
    return {
        "line_angle_deg": np.mean(angle),
        "line_angle_std_deg": np.std(angle),
        # the pull from the rope's sag assumes a rope at rest: noisy while it whips, so the median and the 10-90 %
        # range; frames where the rope hangs slack have no pull from its sag (NaN)
        "line_pull_n": np.nanmedian(pull),
        "line_pull_p10_n": np.nanpercentile(pull, 10),
        "line_pull_p90_n": np.nanpercentile(pull, 90),
        "slack_share": float(np.mean(~np.isfinite(pull))),
        "sideways_std_m": np.std(side),
    }


def parachute(intensity: float, seconds: float) -> dict:
    """The flat round canopy in a 3 m/s breeze with turbulence of ``intensity`` (no gusts)."""
    d = descriptor.merge(
        "response",
        descriptor.resolve("scenes/parachute.toml")[0],
        {"wind": {"gust_intensity": 0.0, "turbulence_intensity": intensity}},
    )
    sim = Simulation(d)
    record = sim.model.objects[0]
    times, heights, swings = [], [], []

    def keep(frame) -> None:
        if frame.time >= seconds / 3:
            times.append(frame.time)
            heights.append(frame.positions[record.person, 2])
            swings.append(swing_angle(record, frame.positions))

    sim.run(seconds, on_frame=keep)
    rate = -np.diff(heights) / np.diff(times)
    return {
        "descent_m_s": (heights[0] - heights[-1]) / (times[-1] - times[0]),
        "descent_std_m_s": np.std(rate),
        "swing_max_deg": np.max(swings),
        "swing_rms_deg": np.sqrt(np.mean(np.square(swings))),
    }


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="each flight's length [s] (default 60)")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "turbulence_response.png")
    args = parser.parse_args(argv)
    import pandas as pd

    rows = []
    for intensity in INTENSITIES:
        row = {"intensity": intensity, **kite(intensity, args.seconds), **parachute(intensity, args.seconds)}
        rows.append(row)
        print(", ".join(f"{k} {v:.3g}" for k, v in row.items()), flush=True)
    table = pd.DataFrame(rows)
    table.to_csv(args.out.with_suffix(".csv"), index=False, float_format="%.4g")
    plot(table, args.out, args.seconds)
    print(table.to_string(index=False, float_format=lambda v: f"{v:.3g}"))


def plot(table, out: Path, seconds: float) -> None:
    """Two panels: the kite's line angle (mean ± one standard deviation), pull (median, 10-90 %) and wander, the
    parachute's descent (mean ± the standard deviation of its rate) and swing, against the intensity."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    i = table["intensity"]
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    a.errorbar(i, table["line_angle_deg"], table["line_angle_std_deg"], marker="o", capsize=3, label="line angle [°]")
    spread = [table["line_pull_n"] - table["line_pull_p10_n"], table["line_pull_p90_n"] - table["line_pull_n"]]
    a.errorbar(i, table["line_pull_n"], spread, marker="s", capsize=3, label="line pull [N] (median, 10-90 %)")
    a.set(
        xlabel="turbulence intensity σ/U",
        ylabel="line angle [°], line pull [N]",
        title=f"kite in 6 m/s, L = 24.5 m ({seconds:g} s each)",
    )
    a.set_ylim(0.0, 1.6 * max(80.0, float(table["line_pull_p90_n"].max())))  # room above the points for the legends
    a.legend(loc="upper left", fontsize="small")
    a2 = a.twinx()
    a2.plot(i, table["sideways_std_m"], "g^-", label="sideways wander [m, std]")
    a2.set_ylabel("sideways wander [m]")
    a2.set_ylim(0.0, 1.6 * max(1.0, float(table["sideways_std_m"].max())))
    a2.legend(loc="upper left", bbox_to_anchor=(0.0, 0.84), fontsize="small")
    b.errorbar(i, table["descent_m_s"], table["descent_std_m_s"], marker="o", capsize=3, label="descent [m/s]")
    b2 = b.twinx()
    b2.plot(i, table["swing_max_deg"], "r^-", label="largest swing [°]")
    b2.plot(i, table["swing_rms_deg"], "rv--", label="rms swing [°]")
    b.set(
        xlabel="turbulence intensity σ/U",
        ylabel="descent [m/s]",
        title="flat round parachute, 3 m/s breeze, no gusts",
    )
    b2.set_ylabel("swing [°]")
    b.set_ylim(4.8, 7.0)  # room below the points for the legends
    b2.set_ylim(10.0, 34.0)
    b.legend(loc="lower left", fontsize="small")
    b2.legend(loc="lower right", fontsize="small")
    fig.savefig(out, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    main()
