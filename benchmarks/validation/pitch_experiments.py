"""Issue 34's pitch experiments: is the pilot's rigid link what makes the flying glider's pitch lag, its inertia and
its long phugoid? Each variant flies the glide, the phugoid pulse and the dive of :mod:`.handling` once.

``python -m benchmarks.validation.pitch_experiments [dt iterations]`` prints one line a variant:

* ``rigid``: the glider as built (the pilot on the strap holding the bar: strap and two arms, three sticks, fix him
  to the frame);
* ``free``: the arms' sticks given weight 0 (hands off the bar: the pilot a point pendulum on the strap);
* ``at hang point``: the pilot's mass moved onto the hang point (what a free pendulum adds to the wing, quasi
  statically), the arms kept;
* other hang points beside them.

Variants change the builder only through :func:`warpsim.objects.hang_glider._hang_strap`, restored afterwards.
"""

from __future__ import annotations

import contextlib
import json
import math
import sys

import numpy as np

from benchmarks.validation import handling as h
from benchmarks.validation import piloting


@contextlib.contextmanager
def suspension(kind: str):
    """Build the strap suspension as ``kind`` (``rigid``, ``free``, ``at hang point``) inside the block."""
    import warpsim.objects.hang_glider as hg

    original = hg._hang_strap

    def patched(builder, cfg, *args, **kwargs):
        out = original(builder, cfg, *args, **kwargs)
        pilot, arms, *_, extra = out
        if kind == "free":
            for s in arms:
                builder.stick_weight[s] = 0.0
        elif kind == "at hang point":
            hang = int(extra["control_frame"][0])
            builder.particle_mass[hang] += cfg.pilot_mass - 1.0
            builder.particle_mass[pilot] = 1.0
        return out

    hg._hang_strap = patched if kind != "rigid" else original
    try:
        yield
    finally:
        hg._hang_strap = original


def released_phugoid(d: dict, solver: dict | None = None, start: float = 16.0, seconds: float = 45.0) -> dict:
    """The phugoid hands off from a ``start`` [m/s] launch (no bar pulse: a free pilot cannot move the bar): the
    airspeed's period from its troughs after 2 s over Lanchester's at the trim (the mean of the last 10 s), the
    damping ratio over its first three troughs, and the pilot's fore-and-aft swing (standard deviation after 20 s)
    [m]."""
    history = piloting.fly_piloted(piloting.scene_descriptor(d, solver, {"speed": start}), seconds, every=0.1)
    t = np.array([f["t"] for f in history])
    v = np.array([f["airspeed"] for f in history])
    trim = float(v[t > seconds - 10.0].mean())
    dv, tt = v[t > 2.0] - trim, t[t > 2.0]
    troughs = [i for i in range(1, len(dv) - 1) if dv[i] < dv[i - 1] and dv[i] <= dv[i + 1] and dv[i] < -0.1]
    if len(troughs) < 2:
        return {"period/Lanchester": math.nan, "zeta": math.nan}
    n = min(3, len(troughs) - 1)
    decrement = math.log(dv[troughs[0]] / dv[troughs[n]]) / n
    period = (tt[troughs[-1]] - tt[troughs[0]]) / (len(troughs) - 1)
    swing = np.array([f["pilot_forward"] for f in history])[t > 20.0]
    return {
        "period/Lanchester": round(period / (math.pi * math.sqrt(2.0) * trim / h.GRAVITY), 3),
        "zeta": round(decrement / math.hypot(2.0 * math.pi, decrement), 3),
        "trim": round(trim, 2),
        "swing": round(float(swing.std()), 3),
    }


def measure(glider: dict, kind: str = "rigid", solver: dict | None = None) -> dict:
    """Glide, trim speed, speed spread, phugoid period over Lanchester's, damping (and Lanchester's), dive recovery
    height and its band's top (:func:`.handling.dive_band`) of the default glider with ``glider`` keys."""
    with suspension(kind):
        d = piloting.scene_descriptor("hang-glider", None, glider)
        g = h.glide_flight(d, solver)
        p = h.phugoid_flight(d, solver)
        dive = h.dive_flight(d, solver)
        released = released_phugoid(d, solver)
    band = h.dive_band(d, g["speed"], g["glide"])
    return {
        "glide": round(g["glide"], 2),
        "trim": round(g["speed"], 2),
        "spread": round(g["spread"], 3),
        "period/Lanchester": round(p["period"] / p["lanchester"], 3),
        "zeta": round(p["zeta"], 3),
        "zeta_Lanchester": round(1.0 / (2**0.5 * g["glide"]), 3),
        "dive": round(dive["height"], 1),
        "band_top": round(band["high"], 1),
        "from 16 m/s": released,
    }


VARIANTS = [
    ({}, "rigid"),
    ({}, "free"),
    ({"hang_point": 0.5}, "free"),
    ({}, "at hang point"),
]


if __name__ == "__main__":
    args = sys.argv[1:]
    solver = {"dt": float(args[0]), "iterations": int(args[1])} if args else None
    for glider, kind in VARIANTS:
        print(json.dumps({"suspension": kind, **glider}), json.dumps(measure(glider, kind, solver)), flush=True)
