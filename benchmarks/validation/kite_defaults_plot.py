"""The kite's flight at its defaults against its former ones (5 ms, 55 iterations, relaxation 1, Chebyshev 0.99), in
6 and 13 m/s: line angle, pull from the rope's sag, the tow point's sideways offset and the nose's height above the
tow point against time, measured from the particles (``scenes/kite.toml``: its anchor walked 10 m downwind at 20-25 s).

    python -m benchmarks.validation.kite_defaults_plot [docs/kite_defaults.png]
"""

from __future__ import annotations

import sys

import numpy as np

from warpsim.objects.kite import anchor_elevation, anchor_pull
from warpsim.run.simulation import Simulation
from warpsim.scene import descriptor

FORMER = {"solver": {"dt": 0.005, "iterations": 55, "relaxation": 1.0, "chebyshev": 0.99}}
"""The kite's solver settings until 2026-12-04."""


def flight(wind: float, overrides: dict, seconds: float = 40.0) -> np.ndarray:
    """``[frames, 5]``: time [s], line angle [deg], pull [N], tow point's sideways offset [m], nose above the tow
    point [m], of ``scenes/kite.toml`` in ``wind`` [m/s] along x with ``overrides`` merged."""
    d = descriptor.merge("plot", descriptor.resolve("scenes/kite.toml")[0], {"wind": {"velocity": [wind, 0.0, 0.0]}})
    sim = Simulation(descriptor.merge("plot", d, overrides) if overrides else d)
    record, mass = sim.model.objects[0], sim.model.particle_free_mass
    rows = []

    def keep(frame) -> None:
        q = frame.positions
        rows.append(
            (
                frame.time,
                anchor_elevation(record, q),
                anchor_pull(record, q, mass),
                q[record.tow, 1] - q[record.anchor_particle, 1],
                q[record.nose, 2] - q[record.tow, 2],
            )
        )

    sim.run(seconds, on_frame=keep)
    return np.array(rows)


def main(out: str = "docs/kite_defaults.png") -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(4, 1, figsize=(9, 10), sharex=True)
    names = ("line angle [deg]", "pull from the rope's sag [N]", "tow point sideways [m]", "nose above tow point [m]")
    for label, overrides in (("former 5 ms/55", FORMER), ("defaults 2.5 ms/45", {})):
        for wind in (6.0, 13.0):
            a = flight(wind, overrides)
            for k, name in enumerate(names):
                axes[k].plot(a[:, 0], a[:, k + 1], label=f"{label}, {wind:g} m/s")
                axes[k].set_ylabel(name)
    axes[0].legend(fontsize=8)
    axes[1].set_ylim(0.0, 80.0)
    axes[-1].set_xlabel("time [s] (the anchor walked 10 m downwind at 20-25 s)")
    fig.tight_layout()
    fig.savefig(out, dpi=80)
    print(f"wrote {out}")


if __name__ == "__main__":
    main(*sys.argv[1:])
