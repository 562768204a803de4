"""Validation rows of the standard atmosphere (:mod:`warpsim.physics.atmosphere`): the atmosphere itself against
ISO 2533's table, and a round canopy's rate of descent at altitude against the square-root law of its sea-level
descent, measured from the particles.

    python -m benchmarks.validation.atmosphere_rows      # prints the rows
"""

from __future__ import annotations

import math

from warpsim.objects.parachute import descent_and_swing
from warpsim.physics.atmosphere import isa
from warpsim.run.simulation import Simulation
from warpsim.scene import descriptor

from .common import Row
from .parachute_rows import FINE as PARACHUTE_FINE

ISO_2533 = (
    "ISO 2533:1975 Standard Atmosphere (= U.S. Standard Atmosphere 1976 below 32 km), table by geometric altitude: "
    "density at 0, 1, 3, 5, 11 and 20 km"
)
ISO_TABLE = {0.0: 1.2250, 1000.0: 1.1117, 3000.0: 0.90925, 5000.0: 0.73643, 11000.0: 0.36480, 20000.0: 0.088910}
"""Geometric altitude [m] -> tabulated density [kg/m^3]."""

SCALING = (
    "a canopy at terminal speed carries its weight with 0.5 rho v^2 C_D0 S_0, so v ~ rho^-1/2 "
    "(Knacke, Parachute Recovery Systems Design Manual, NWC TP 6575, 1991, ch. 5)"
)

ALTITUDES = (1000.0, 3000.0, 5000.0)
"""[m] where the canopy's descent is compared with its sea-level descent."""


def atmosphere_table() -> list[Row]:
    """The modelled density against ISO 2533's table (4 significant figures there): within 0.1 %."""
    rows = []
    for h, expected in ISO_TABLE.items():
        got = float(isa(h)[2])
        err = got / expected - 1.0
        rows.append(
            Row(
                f"ISA density at {h / 1000:g} km",
                "density of the standard atmosphere (warpsim.physics.atmosphere.isa)",
                f"{expected:.5g} kg/m³",
                ISO_2533,
                f"{got:.5g} kg/m³ ({100 * err:+.3f} %)",
                "within 0.1 %",
                abs(err) <= 1e-3,
            )
        )
    return rows


def canopy_descent(start: float, overrides: dict | None = None, seconds: float = 30.0) -> tuple[float, float]:
    """The ringslot canopy (steady, under ±5° of swing) released ``start`` [m] up in still air: its mean rate of
    descent [m/s] over 10 s to ``seconds`` [s] and the person's mean altitude [m] then, from the particles."""
    d = descriptor.merge(
        "validation",
        descriptor.resolve("scenes/parachute_ringslot.toml")[0],
        {
            "parachute": {"altitude": start},
            "wind": {"velocity": [0.0, 0.0, 0.0], "gust_intensity": 0.0},
            "air": {"density": 0.0},  # the standard atmosphere
        },
    )
    sim = Simulation(descriptor.merge("validation", d, overrides or {}))
    person = sim.model.objects[0].person
    descent, _, _ = descent_and_swing(sim, seconds)
    end = float(sim.state.positions()[person, 2])
    return descent, end + 0.5 * (seconds - 10.0) * descent


def canopy_at_altitude(label: str = "", overrides: dict | None = None) -> list[Row]:
    """The ringslot canopy's descent at 1, 3 and 5 km against ``v_0 sqrt(rho_0 / rho)`` from its descent near sea
    level (released at 350 m) and the modelled densities at the windows' mean altitudes; within 3 %."""
    v0, h0 = canopy_descent(350.0, overrides)
    rows = []
    tag = f" ({label})" if label else ""
    for h in ALTITUDES:
        v, mean = canopy_descent(h + 250.0, overrides)
        expected = v0 * math.sqrt(float(isa(h0)[2]) / float(isa(mean)[2]))
        err = v / expected - 1.0
        rows.append(
            Row(
                f"canopy descent at {h / 1000:g} km{tag}",
                f"ringslot canopy, still air, standard atmosphere: rate of descent 10-30 s about {mean:.0f} m up, "
                f"against {v0:.3f} m/s about {h0:.0f} m up",
                f"{expected:.3f} m/s",
                SCALING,
                f"{v:.3f} m/s ({100 * err:+.2f} %)",
                "within 3 %",
                abs(err) <= 0.03,
            )
        )
    return rows


def rows() -> list[Row]:
    """Every row of this module: the table, and the canopy at the defaults, with dt halved and iterations doubled,
    and 10 km out (position independence)."""
    return (
        atmosphere_table()
        + canopy_at_altitude()
        + canopy_at_altitude("dt halved, iterations doubled", PARACHUTE_FINE)
        + canopy_at_altitude("10 km out", {"parachute": {"position": [10000.0, 0.0]}})
    )


if __name__ == "__main__":
    for row in rows():
        print(f"{row.status:5s} {row.case}: {row.measured} vs {row.expected} [{row.band}]")
