"""A 360° turn and a reversal flown with the arrow keys in the real viewer window (issue 53), as a person flies it.

Run on an X display (a virtual one: ``xvfb-run -a python -m benchmarks.validation.keys_flight [SCENE] [OUT_DIR]``;
needs ``xdotool`` and the ``[viewer]`` and ``[sweep]`` extras). The keys are injected with xdotool into the focused
window; the viewer is given its own clock, one frame interval per tick, so the flight does not depend on how fast
the machine draws. The pilot in this script looks at the bank and the heading only, as a pilot does:

* from level trimmed flight (after 8 s), the left arrow held until 30° of left bank;
* the turn held between 25° and 38° of bank by holding the left or the right arrow, until the flight path has
  turned 360°;
* the right arrow held until 30° of right bank (the reversal), then both released for 10 s.

It writes ``keys_flight.png`` (bank, sideslip at the mass centre and airspeed against time, with the keys held),
``keys_chase.png`` (the chase camera in the turn), ``keys_flight.h5`` (the recording; ``warpsim run --replay``
flies it again) and ``keys_flight.json`` (the figures, also printed).
"""

from __future__ import annotations

import contextlib
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np

SIZE = (960, 540)
MAX_FRAMES = 10_000
"""Frames after which the flight is given up (a glider that never reaches a bank it is flown to)."""


def _xdotool(*args: str) -> str:
    return subprocess.run(["xdotool", *args], check=True, capture_output=True, text=True, timeout=20).stdout


def fly(scene: str = "scenes/hang_glider_lattice.toml", out: Path = Path("docs")) -> dict:
    """Fly ``scene``'s glider through the turn and the reversal with keys; the figures, and the files in ``out``."""
    from PIL import Image

    from benchmarks.validation.piloting import body_angles
    from warpsim.objects.hang_glider import bank
    from warpsim.run.simulation import Simulation
    from warpsim.scene.descriptor import resolve
    from warpsim.scene.dirs import scene_dirs
    from warpsim.viewer.core import Viewer
    from warpsim.viewer.gl import PygletBackend

    out.mkdir(parents=True, exist_ok=True)
    descriptor, _, where = resolve(scene, scene_dirs())
    title = "warpsim-keys-flight"
    backend = PygletBackend(SIZE, keep_pictures=True)
    record = out / "keys_flight.h5"
    record.unlink(missing_ok=True)
    viewer = Viewer(Simulation(descriptor), backend, title, record, where, say=lambda line: None)
    viewer.camera = "chase"
    window = _xdotool("search", "--sync", "--name", title).split()[0]
    _xdotool("windowfocus", "--sync", window)
    glider = viewer.model.objects[0]
    mass = viewer.model.particle_free_mass[glider.particles]
    now = 0.0
    viewer.tick(now)
    held: set[str] = set()
    rows: list[dict] = []

    def press(*keys: str) -> None:
        for key in held - set(keys):
            _xdotool("keyup", key)
            held.discard(key)
        for key in set(keys) - held:
            _xdotool("keydown", key)
            held.add(key)

    def release() -> None:
        for key in ("Left", "Right"):
            with contextlib.suppress(Exception):
                _xdotool("keyup", key)
        held.clear()

    def frame() -> dict:
        nonlocal now
        if len(rows) >= MAX_FRAMES:
            raise RuntimeError(f"the flight did not end within {MAX_FRAMES} frames")
        now += viewer.frame_interval
        if not viewer.tick(now) or viewer.paused or viewer.error:
            raise RuntimeError(f"the viewer stopped at {viewer.sim.state.time:.2f} s: {viewer.error or 'closed'}")
        sim = viewer.sim
        q, q_prev = sim.state.positions(), sim.state.particle_q_prev.numpy()
        velocity = mass @ (q[glider.particles] - q_prev[glider.particles]) / (mass.sum() * sim.dt)
        state = {"cg_velocity": velocity}
        body_angles(sim, state)
        wind = sim.control.wind.numpy()[0].astype(float)
        row = {
            "t": float(sim.state.time),
            "bank": bank(glider, q),
            "beta": state["beta"],
            "alpha": state["alpha"],
            "airspeed": float(np.linalg.norm(velocity - wind)),
            "heading": math.degrees(math.atan2(velocity[1], velocity[0])),
            "roll": float(sim.controls.get("roll", 0.0)),
            "keys": sorted(held),
        }
        rows.append(row)
        return row

    try:
        row = frame()
        while row["t"] < 8.0:
            row = frame()
        phases = {"roll_in": row["t"]}
        press("Left")
        while row["bank"] > -30.0 and row["t"] < 30.0:
            row = frame()
        phases["at_30"] = row["t"]
        turned, last = 0.0, row["heading"]
        shot = None
        while abs(turned) < 360.0 and row["t"] < 120.0:
            if row["bank"] > -25.0:
                press("Left")
            elif row["bank"] < -38.0:
                press("Right")
            else:
                press()
            row = frame()
            turned += (row["heading"] - last + 180.0) % 360.0 - 180.0
            last = row["heading"]
            if shot is None and abs(turned) >= 180.0:
                shot = backend.screenshot()
        phases["turned_360"] = row["t"]
        press("Right")
        while row["bank"] < 30.0 and row["t"] < 150.0:
            row = frame()
        phases["reversed"] = row["t"]
        press()
        end = row["t"] + 10.0
        while row["t"] < end:
            row = frame()
    finally:  # never leave a key held down on the X server, nor the window open
        release()
        viewer.close()
    if shot is not None:
        Image.fromarray(shot).save(out / "keys_chase.png")
    turn = [r for r in rows if phases["at_30"] <= r["t"] <= phases["turned_360"]]
    figures = {
        "scene": scene,
        "phases": phases,
        "time_to_30": phases["at_30"] - phases["roll_in"],
        "turned_deg": abs(turned),  # 360 unless the turn was cut off at 120 s
        "turn_360_s": phases["turned_360"] - phases["at_30"],
        "reversal_s": phases["reversed"] - phases["turned_360"],
        "beta_max": max(abs(r["beta"]) for r in rows if r["t"] >= phases["roll_in"]),
        "alpha_max": max(abs(r["alpha"]) for r in rows if r["t"] >= phases["roll_in"]),
        "turn_bank_mean": float(np.mean([r["bank"] for r in turn])) if turn else math.nan,
        "turn_airspeed": [min(r["airspeed"] for r in turn), max(r["airspeed"] for r in turn)] if turn else [],
        "frames": len(rows),
    }
    _plot(rows, phases, out / "keys_flight.png", figures)
    (out / "keys_flight.json").write_text(json.dumps(figures, indent=1))
    return figures


def _plot(rows: list[dict], phases: dict, path: Path, figures: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = [r["t"] for r in rows]
    fig, (top, mid, low) = plt.subplots(3, 1, sharex=True, figsize=(9, 8), gridspec_kw={"height_ratios": [3, 2, 2]})
    top.plot(t, [r["bank"] for r in rows], color="C0", label="bank (right tip down +)")
    top.plot(t, [r["roll"] * 30.0 for r in rows], color="C2", lw=0.8, label="bar: roll × 30 (keys ramped)")
    for y in (-30.0, 30.0):
        top.axhline(y, color="grey", lw=0.5)
    top.set_ylabel("degrees")
    top.legend(loc="upper right", fontsize=8)
    mid.plot(t, [r["beta"] for r in rows], color="C3", label="sideslip at the mass centre")
    mid.plot(t, [r["alpha"] for r in rows], color="C4", lw=0.8, label="keel angle of attack")
    for y in (-15.0, 15.0):
        mid.axhline(y, color="grey", lw=0.5, ls="--")
    mid.set_ylabel("degrees")
    mid.legend(loc="upper right", fontsize=8)
    low.plot(t, [r["airspeed"] for r in rows], color="C1", label="airspeed")
    low.set_ylabel("m/s")
    low.set_xlabel("simulated time [s]")
    low.legend(loc="upper right", fontsize=8)
    for ax in (top, mid, low):
        for name in ("roll_in", "at_30", "turned_360", "reversed"):
            ax.axvline(phases[name], color="k", lw=0.4, ls=":")
    top.set_title(
        f"{Path(figures['scene']).stem}, flown with the arrow keys: 30° in {figures['time_to_30']:.1f} s, 360° in "
        f"{figures['turn_360_s']:.1f} s, reversal in {figures['reversal_s']:.1f} s",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    args = sys.argv[1:]
    result = fly(*(args[:1] or []), *([Path(args[1])] if len(args) > 1 else []))
    print(json.dumps(result, indent=1))
