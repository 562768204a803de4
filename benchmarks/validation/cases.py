"""The validation cases: warpsim against analytic solutions and published measurements.

Each case returns one or more rows (:class:`~benchmarks.validation.common.Row`): what is compared, the expected
value and its source, the measured value, the band that passes, and whether a miss is a known limit of the
paper's model (said plainly, never tuned away). All runs use Warp's ``cpu`` device unless told otherwise. The
cases live by object in the modules beside this one; :data:`CASES` names them for ``-k``.
"""

from __future__ import annotations

from collections.abc import Callable

from . import atmosphere_rows, turbulence_rows, unsteady, vortex_rows
from .basics import catenary, free_fall, pendulum, plate_drag
from .common import Row
from .convergence_rows import convergence_figures, flag_convergence
from .flag_rows import flag, flag_sheet
from .glider_rows import HALF, flying_glider, hang_glider
from .kite_rows import kite_angle, kite_flight_rows, kite_line
from .parachute_rows import FINE as PARACHUTE_FINE
from .parachute_rows import parachute

CASES: dict[str, Callable[[], list[Row]]] = {
    "free-fall": free_fall,
    "pendulum": pendulum,
    "catenary": catenary,
    "plate": plate_drag,
    "parachute": lambda: (
        parachute()
        + parachute(label="mass splitting", overrides={"solver": {"mass_splitting": True}})
        + parachute(label="dt halved, iterations doubled", overrides=PARACHUTE_FINE)
        + parachute("scenes/parachute_ringslot.toml")
        + parachute("scenes/parachute_ringslot.toml", "dt halved, iterations doubled", PARACHUTE_FINE)
    ),
    "kite": lambda: kite_line(False) + kite_line(True),
    "flag": flag,
    "flag-sheet": flag_sheet,
    "hang-glider": hang_glider,
    "flying-glider": flying_glider,
    "flying-glider-intermediate": lambda: flying_glider("scenes/hang_glider_intermediate.toml", "intermediate"),
    "flying-glider-lattice": lambda: flying_glider("scenes/hang_glider_lattice.toml", "lattice glider", HALF),
    "kite-angle": kite_angle,
    "kite-flight": kite_flight_rows,
    "convergence-glide": lambda: convergence_figures(["glider glide ratio", "glider trim speed"], beyond=True),
    "convergence-figures": lambda: convergence_figures(
        [
            "glider turn rate, bank held at 20°",
            "glider phugoid period",
            "kite line angle at the anchor",
            "parachute descent",
            "paper's flag flapping frequency (resolution 5)",
            "paper's flag flapping amplitude (resolution 5)",
        ],
        beyond=True,
    ),
    "convergence-flag": flag_convergence,
    "vortex": lambda: vortex_rows.vortex_rows() + vortex_rows.object_rows(),
    "atmosphere": atmosphere_rows.rows,
    "turbulence": turbulence_rows.field_rows,
    "unsteady": unsteady.wagner_rows,
}
