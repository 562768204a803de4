"""The round parachutes' cases: descent and swing against Knacke's canopy table."""

from __future__ import annotations

import math

from warpsim.physics.atmosphere import scene_density
from warpsim.physics.model import GRAVITY
from warpsim.run.simulation import Simulation
from warpsim.scene import descriptor

from .common import Row

KNACKE = (
    "Knacke, Parachute Recovery Systems Design Manual, NWC TP 6575 (1991), Table 5-1: flat circular canopy C_D0 "
    "0.75-0.80 on the nominal (cloth) area, oscillation ±10-40°; ringslot C_D0 0.56-0.65, oscillation 0 to ±5°"
)
FINE = {"solver": {"dt": descriptor.defaults("parachute")["solver"]["dt"] / 2.0, "iterations": 110}}
"""The canopies' step halved with twice the iterations: their rows' convergence check."""

CANOPY_BANDS = {"flat": ((0.75, 0.80), (10.0, 40.0)), "ringslot": ((0.56, 0.65), (0.0, 5.0))}
"""Knacke's Table 5-1 per canopy: (C_D0 range, swing amplitude range [deg])."""


def parachute(scene: str = "scenes/parachute.toml", label: str = "", overrides: dict | None = None) -> list[Row]:
    """The round parachute of ``scene`` (hoop on, whole-canopy air force, gusty breeze) flown 60 s: its rate of
    descent and its swing over 10-60 s, measured from the particles, against Knacke's table for its canopy."""
    from warpsim.objects.parachute import descent_and_swing

    d = descriptor.merge("validation", descriptor.resolve(scene)[0], overrides or {})
    kind = d["parachute"]["canopy"]
    sim = Simulation(d)
    record = sim.model.objects[0]
    nominal = float(sim.model.canopy_nominal_area[0])
    weight = sim.model.particle_free_mass[record.particles].sum() * GRAVITY
    descent, swing, swing_rms = descent_and_swing(sim, 60.0)
    # the air's density at the mean altitude of the 10-60 s window
    rho = scene_density(d["air"], sim.state.positions()[record.particles, 2].mean() + 25.0 * descent)
    (c_low, c_high), (s_low, s_high) = CANOPY_BANDS[kind]
    fast, slow = (math.sqrt(2 * weight / (rho * nominal * c)) for c in (c_low, c_high))
    c_d0 = 2 * weight / (rho * nominal * descent**2)
    solver = d["solver"]
    settings = f"dt {solver['dt']:g} s, {solver['iterations']} iterations" + (
        ", mass splitting" if solver["mass_splitting"] else ""
    )
    tag = f"parachute {kind}" + (f" ({label})" if label else "")
    return [
        Row(
            f"{tag} descent",
            f"mean rate of descent 10-60 s, {weight / GRAVITY:.0f} kg under {nominal:.1f} m² of {kind} canopy, "
            f"gusty 3 m/s breeze ({settings})",
            f"{slow:.2f}-{fast:.2f} m/s",
            KNACKE,
            f"{descent:.2f} m/s",
            "within that range",
            slow <= descent <= fast,
            note=f"C_D0 = {c_d0:.3f} from the measured rate; the canopy's tangential coefficient C_T(0) is set so "
            "that the swinging flat canopy's rate gives Knacke's C_D0 (a rate measured on swinging canopies)",
        ),
        Row(
            f"{tag} swing",
            f"largest angle of the person-to-canopy line from the vertical, 10-60 s ({settings})",
            f"{'±' if s_low else '0 to ±'}{s_low:g}-{s_high:g}°" if s_low else f"under ±{s_high:g}°",
            KNACKE,
            f"±{swing:.1f}° (rms {swing_rms:.1f}°)",
            f"{s_low:g}-{s_high:g}°",
            s_low <= swing <= s_high,
        ),
    ]
