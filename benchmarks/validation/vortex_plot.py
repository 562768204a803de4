"""``python -m benchmarks.validation.vortex_plot [OUT.png]``: the hang glider's vortex lattice in flight, each panel
coloured by its circulation, and the wake legs it sheds from its trailing edge (docs/vortex_wake.png)."""

from __future__ import annotations

import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

from warpsim.run.simulation import Simulation  # noqa: E402

from .vortex_rows import glider_on_vortex  # noqa: E402


def plot(path: str = "docs/vortex_wake.png", seconds: float = 12.0, wake_length: float = 12.0) -> dict:
    """Fly the glider on the vortex law for ``seconds`` [s] hands off and draw its lattice and wake (legs drawn
    ``wake_length`` [m] long); returns the figures written in the title."""
    sim = Simulation(glider_on_vortex())
    sim.run(seconds)
    m, sc = sim.model, sim.solver.vortex
    lat = m.lattice
    q = sim.state.positions()
    gamma = sc.gamma.numpy()
    wake = sc.wake.numpy()[0, :3].astype(np.float64)
    tris = m.tri_indices_np[lat.panel_tri]
    centre = q[tris].reshape(-1, 3).mean(axis=0)
    pts = q - centre
    fig = plt.figure(figsize=(9, 6))
    ax = fig.add_subplot(projection="3d")
    norm = plt.Normalize(vmin=float(gamma.min()), vmax=float(gamma.max()))
    cmap = plt.get_cmap("viridis")
    polys = Poly3DCollection(pts[tris], facecolors=cmap(norm(gamma)), edgecolors="k", linewidths=0.3, alpha=0.95)
    ax.add_collection3d(polys)
    shed = np.flatnonzero(lat.panel_trailing)
    for p in shed:
        for e in range(3):
            if (lat.panel_trailing[p] >> e) & 1:
                for end in (tris[p][e], tris[p][(e + 1) % 3]):
                    a = pts[end]
                    b = a + wake * wake_length
                    ax.plot(*zip(a, b, strict=True), color="tab:red", linewidth=0.8)
    rec = m.objects[0]
    pilot = pts[rec.pilot]
    ax.scatter(*pilot, color="tab:orange", s=40, label="pilot")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    span = 6.0
    ax.set_xlim(-span - wake_length * 0.8, span)
    ax.set_ylim(-span, span)
    ax.set_zlim(-span, span)
    ax.view_init(elev=40, azim=-50)
    sm = plt.cm.ScalarMappable(norm=norm, cmap=cmap)
    fig.colorbar(sm, ax=ax, shrink=0.6, label="ring circulation Γ [m²/s]")
    moved = q[rec.particles] - sim.state.particle_q_prev.numpy()[rec.particles]
    speed = float(np.linalg.norm(moved.mean(axis=0))) / sim.dt
    ax.set_title(
        f"hang glider on the vortex law, {seconds:g} s hands off, {speed:.1f} m/s: 64 vortex rings, "
        f"wake legs along the relative wind (red)",
        fontsize=9,
    )
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    return {"speed": speed, "gamma": (float(gamma.min()), float(gamma.max()))}


if __name__ == "__main__":
    print(plot(*sys.argv[1:2]))
