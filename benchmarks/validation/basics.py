"""The solver's own cases: free fall, a pendulum, a hanging chain and a falling plate, against closed forms
and a NumPy reference.
"""

from __future__ import annotations

import math

import numpy as np

from warpsim.physics.config import AirConfig
from warpsim.physics.kernels.aero import AeroModel
from warpsim.physics.model import AIR_DENSITY, GRAVITY
from warpsim.physics.terrain import Heightfield

from .common import Row, _Bench, _rel, complete_elliptic_k


def free_fall() -> list[Row]:
    """A particle dropped from rest at z = 0 over ground 1 km below. With ``x_prev = x`` at the start, Verlet
    gives ``z_n = -g dt² n(n+1)/2`` exactly (it is exact for constant acceleration, the start sets the offset)."""

    def build(b):
        b.set_terrain(Heightfield.flat(height=-1000.0))
        b.add_particle((0.0, 0.0, 0.0), 1.0)

    bench = _Bench(build)
    bench.state.set_velocity(np.zeros((1, 3)), bench.dt)
    n = 300
    bench.step(n)
    expected = -GRAVITY * bench.dt**2 * n * (n + 1) / 2
    z = float(bench.state.positions()[0, 2])
    err = abs(z - expected)
    t = n * bench.dt
    return [
        Row(
            "free fall",
            "height after 300 steps (3 s) of free fall from rest, dt 0.01 s",
            f"{expected:.4f} m",
            "Verlet from rest: -g dt² n(n+1)/2 (= -g t²/2 - g t dt/2; g = 9.80665 m/s²)",
            f"{z:.4f} m",
            "within 0.01 mm (float64 positions; the float32 a dt² rounds at 3e-8 relative)",
            err < 1e-5,
            note=f"error {1000 * err:.3f} mm; the continuous -g t²/2 = {-0.5 * GRAVITY * t * t:.4f} m",
        )
    ]


def pendulum() -> list[Row]:
    """A 1 kg bob on a 1 m stick from a nail, released at 5° and at 60°, dt 0.01 s: its first period against
    the exact period ``4 sqrt(L/g) K(sin(theta0/2))``, and the swing left after 10 periods."""
    rows = []
    length, dt = 1.0, 0.01
    for degrees in (5.0, 60.0):
        theta = math.radians(degrees)

        def build(b, theta=theta):
            pivot = b.add_particle((0.0, 0.0, 2.0), 1.0)  # near z = 1 m, where float32 resolves 1e-7 m
            b.add_nail(pivot)
            bob = b.add_particle((length * math.sin(theta), 0.0, 2.0 - length * math.cos(theta)), 1.0)
            b.add_stick(pivot, bob)

        bench = _Bench(build, dt=dt)
        bench.state.set_velocity(np.zeros((2, 3)), dt)
        n = int(round(22.0 / dt))
        x = np.empty(n)
        for k in range(n):
            bench.step()
            x[k] = bench.state.particle_q.numpy()[1][0]
        t = (np.arange(n) + 1) * dt
        idx = np.flatnonzero((x[:-1] > 0) & (x[1:] <= 0))  # downward zero crossings, once per period
        crossings = t[idx] + (t[idx + 1] - t[idx]) * x[idx] / (x[idx] - x[idx + 1])
        period = float(crossings[1] - crossings[0])
        exact = 4.0 * math.sqrt(length / GRAVITY) * complete_elliptic_k(math.sin(theta / 2.0))
        first = slice(int(crossings[0] / dt), int(crossings[1] / dt))  # the swing lost over the first period
        theta1 = math.asin(min(1.0, float(np.max(np.abs(x[first]))) / length))
        at_mean = 4.0 * math.sqrt(length / GRAVITY) * complete_elliptic_k(math.sin((theta + theta1) / 4.0))
        last = slice(int(crossings[9] / dt), int(crossings[10] / dt))
        swing = float(np.max(np.abs(x[last]))) / (length * math.sin(theta))
        rows.append(
            Row(
                f"pendulum {degrees:g}°",
                f"first period of a 1 m pendulum released at {degrees:g}°, dt 0.01 s, 55 iterations",
                f"{exact:.4f} s",
                "exact period 4√(L/g)·K(sin θ0/2) (complete elliptic integral)",
                f"{period:.4f} s",
                "within 1 %",
                abs(_rel(period, exact)) < 0.01,
                model_limit=degrees > 10.0,  # a large swing loses enough in one period to shorten it
                note=f"{100 * _rel(period, exact):+.2f} %; the swing shrinks from {degrees:g}° to "
                f"{math.degrees(theta1):.1f}° in that period (next row) and a smaller swing is quicker: the exact "
                f"period at the mean swing is {at_mean:.4f} s ({100 * _rel(period, at_mean):+.2f} %)",
            )
        )
        rows.append(
            Row(
                f"pendulum {degrees:g}° energy",
                "swing (horizontal amplitude) left after 10 periods",
                "100 %",
                "a frictionless pendulum keeps its energy",
                f"{100 * swing:.0f} %",
                "above 95 %",
                swing > 0.95,
                model_limit=True,
                note="the paper's method damps: projecting positions onto the constraint removes the velocity "
                "along the stick that Verlet's step put there, every step; smaller dt damps less",
            )
        )
    return rows


def catenary() -> list[Row]:
    """A 12 m rope of 41 particles hung between two nails 10 m apart: its sag against the catenary of the same
    length, ``L = 2a sinh(S/2a)``, ``sag = a (cosh(S/2a) - 1)``."""
    span, length, count = 10.0, 12.0, 41

    def build(b):
        ids, _ = b.add_rope((-span / 2, 0.0, 50.0), (span / 2, 0.0, 50.0), count, 1.2)
        b.stick_rest[-(count - 1) :] = [length / (count - 1)] * (count - 1)
        b.add_nail(int(ids[0]))
        b.add_nail(int(ids[-1]))

    bench = _Bench(build, dt=0.01, damping=0.02)
    bench.step(3000)  # 30 s: the swinging dies out under the damping
    q = bench.state.positions()
    sag = 50.0 - float(q[:, 2].min())
    lo, hi = 0.1, 100.0  # solve L = 2a sinh(S/2a) for a by bisection
    for _ in range(200):
        a = 0.5 * (lo + hi)
        lo, hi = (a, hi) if 2 * a * math.sinh(span / (2 * a)) > length else (lo, a)
    expected = a * (math.cosh(span / (2 * a)) - 1.0)
    stretch = float(bench.model.stick_stretch(q).max())
    x = q[:, 0]
    shape = np.abs((50.0 - q[:, 2]) - (a * (math.cosh(span / (2 * a)) - np.cosh(x / a)))).max()
    return [
        Row(
            "hanging rope",
            "sag of a 12 m rope (40 links) hung between nails 10 m apart, after 30 s with damping",
            f"{expected:.4f} m",
            "catenary of the same length: L = 2a sinh(S/2a), sag = a(cosh(S/2a) - 1)",
            f"{sag:.4f} m",
            "within 1 %",
            abs(_rel(sag, expected)) < 0.01,
            note=f"{100 * _rel(sag, expected):+.2f} %; largest height error along the rope {1000 * shape:.1f} mm; "
            f"worst stick stretch {100 * stretch:.3f} %",
        )
    ]


def _falling_plate(model_name: str) -> tuple[float, float, float]:
    """Terminal speed [m/s] of a horizontal plate falling flat: one equilateral triangle of 1 m² (3 particles,
    3 sticks: always flat, and by symmetry it stays level), 0.1 kg; and the mass [kg] and area [m²] used."""
    mass, area = 0.1, 1.0
    side = math.sqrt(4.0 * area / math.sqrt(3.0))

    def build(b):
        radius = side / math.sqrt(3.0)  # of the circle through the corners
        angles = (0.0, 2.0 * math.pi / 3.0, 4.0 * math.pi / 3.0)
        ids = [b.add_particle((radius * math.cos(a), radius * math.sin(a), 100.0), mass / 3.0) for a in angles]
        for i in range(3):
            b.add_stick(ids[i], ids[(i + 1) % 3])
        b.add_triangle(*ids)

    air = AirConfig(model=AeroModel[model_name.upper()], density=AIR_DENSITY)  # the closed form's constant air
    bench = _Bench(build, dt=0.01, air=air)
    bench.step(500)  # 5 s: many time constants v_t / g
    before = bench.state.positions()[:, 2].mean()
    bench.step(100)
    speed = (before - bench.state.positions()[:, 2].mean()) / (100 * bench.dt)
    q = bench.state.positions()
    real_area = 0.5 * float(np.linalg.norm(np.cross(q[1] - q[0], q[2] - q[0])))
    return float(speed), mass, real_area


def plate_drag() -> list[Row]:
    """A flat plate falling face-on reaches the speed where its model drag equals its weight."""
    rows, speeds = [], {}
    for name, c_model in (("paper", 2.0), ("plate", 1.0 / (0.222 + 0.283))):
        speed, mass, area = speeds[name] = _falling_plate(name)
        law = math.sqrt(2.0 * mass * GRAVITY / (AIR_DENSITY * area * c_model))
        rows.append(
            Row(
                f"plate drag ({name})",
                f"terminal speed of a flat 1 m², 0.1 kg triangle falling face-on, aero = {name}",
                f"{law:.4f} m/s",
                f"the model's own law at 90°: C_N = {c_model:.3f} on ½ρv²A (warpsim.physics.kernels.aero)",
                f"{speed:.4f} m/s",
                "within 1 %",
                abs(_rel(speed, law)) < 0.01,
                note=f"{100 * _rel(speed, law):+.2f} %",
            )
        )
    speed, mass, area = speeds["paper"]
    real = math.sqrt(2.0 * mass * GRAVITY / (AIR_DENSITY * area * 1.17))
    rows.append(
        Row(
            "plate vs real plate",
            "the same falling plate against a real square plate",
            f"{real:.3f} m/s",
            "square flat plate normal to the flow: C_D = 1.17 (Hoerner, Fluid-Dynamic Drag, 1965, ch. 3)",
            f"{speed:.3f} m/s",
            "within 10 %",
            abs(_rel(speed, real)) < 0.10,
            model_limit=True,
            note=f"{100 * _rel(speed, real):+.1f} %: both models give a face-on plate C ≈ 2, the drag of a 2-D "
            "(infinitely wide) plate; round a square plate's edges the air escapes sideways, and its C_D is 1.17",
        )
    )
    return rows
