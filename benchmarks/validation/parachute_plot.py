"""The round parachute's swing and descent against time, flat and ringslot canopies (docs/parachute_swing.png)."""

from __future__ import annotations

import numpy as np

from warpsim.objects.parachute import swing_angle
from warpsim.run.simulation import Simulation
from warpsim.scene import descriptor

SCENES = {"flat": "scenes/parachute.toml", "ringslot": "scenes/parachute_ringslot.toml"}


def swing_history(scene: str, overrides: dict | None = None, seconds: float = 60.0) -> dict:
    """Run ``scene`` for ``seconds`` [s] frame by frame (its gusts act at every frame); at every frame: time [s],
    the swing's components towards +x and +y [deg] (the canopy's centre seen from the person), its angle from the
    vertical [deg] and the person's rate of descent since the last frame [m/s]."""
    sim = Simulation(descriptor.merge("plot", descriptor.resolve(scene)[0], overrides or {}))
    record = sim.model.objects[0]
    out = {"t": [], "x": [], "y": [], "angle": [], "descent": []}
    last = []

    def on_frame(frame) -> None:
        q = frame.positions
        v = q[record.parts["canopy"]].mean(axis=0) - q[record.person]
        if last:
            out["t"].append(frame.time)
            out["x"].append(float(np.degrees(np.arctan2(v[0], v[2]))))
            out["y"].append(float(np.degrees(np.arctan2(v[1], v[2]))))
            out["angle"].append(swing_angle(record, q))
            out["descent"].append(float((last[0][1] - q[record.person, 2]) / (frame.time - last[0][0])))
        last[:] = [(frame.time, q[record.person, 2])]

    sim.run(seconds, on_frame=on_frame)
    return {k: np.array(v) for k, v in out.items()}


def plot_parachute_swing(path) -> dict:
    """Plot the swing (its +x component) and the rate of descent of the flat and ringslot canopies over 60 s in
    their scenes' gusty breeze, at their defaults (2.5 ms, 55 iterations) and with the step halved and the
    iterations doubled, with Knacke's bands, to the PNG ``path``; returns the histories."""
    import matplotlib

    from .parachute_rows import FINE

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    runs = {
        (kind, label): swing_history(scene, over)
        for kind, scene in SCENES.items()
        for label, over in (("defaults", {}), (f"dt {FINE['solver']['dt']:g}, 110 it", FINE))
    }
    fig, (top, low) = plt.subplots(2, 1, sharex=True, figsize=(8, 6), gridspec_kw={"height_ratios": [3, 2]})
    top.axhspan(10, 40, color="C0", alpha=0.08, lw=0)
    top.axhspan(-40, -10, color="C0", alpha=0.08, lw=0, label="flat circular ±10-40° (Knacke Table 5-1)")
    top.axhspan(-5, 5, color="C1", alpha=0.15, lw=0, label="ringslot 0 to ±5°")
    for (kind, label), r in runs.items():
        style = "-" if label == "defaults" else "--"
        color = "C0" if kind == "flat" else "C1"
        top.plot(r["t"], r["x"], style, color=color, lw=0.9, label=f"{kind}, {label}")
        low.plot(r["t"], r["descent"], style, color=color, lw=0.8, label=f"{kind}, {label}")
    top.set_ylabel("swing, canopy towards +x [deg]")
    top.legend(fontsize=7, loc="lower left", ncol=2)
    top.set_ylim(-45, 45)
    low.axhspan(5.77, 5.96, color="C0", alpha=0.15, lw=0)
    low.axhspan(6.40, 6.90, color="C1", alpha=0.15, lw=0)
    low.set_ylabel("rate of descent [m/s]")
    low.set_xlabel("time [s] (3 m/s breeze, gusts 10 %)")
    low.set_ylim(4.0, 8.0)
    fig.suptitle(
        "Round parachute, whole-canopy air force: the flat canopy swings, the ringslot hardly does", fontsize=10
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return runs


if __name__ == "__main__":  # python -m benchmarks.validation.parachute_plot docs/parachute_swing.png
    import sys

    plot_parachute_swing(sys.argv[1] if len(sys.argv) > 1 else "docs/parachute_swing.png")
