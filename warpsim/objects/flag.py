"""The flag: a rectangular sheet nailed along a pole, in two designs (``flag.design``): ``sheet``, a stiff woven
sheet whose flapping converges as the mesh is refined, and ``paper``, the cloth of the paper's Verlet/Euler
comparison (slide 15)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..physics.atmosphere import air_density
from ..physics.builder import ModelBuilder, check_memory
from ..physics.config import AIR_DENSITY, NON_NEGATIVE, POSITIVE, STANDARD_AIR, Bounds, Checked, choice, number
from ..physics.lattice import trailing_edges
from ..physics.model import Model, ObjectRecord
from ..physics.shapes import edge_halves
from ..physics.terrain import Heightfield
from .figures import FigureView, Measure

SHEET_ITERATIONS = 7
"""Iterations per particle along the flag at which the validation's sheet flag is converged in its iterations (twice
as many flap the same at resolutions 9, 17 and 33; benchmarks/validation/flag_rows.py SHEET_FLAG)."""


@dataclass(kw_only=True)
class FlagConfig(Checked):
    """Parameters of the flag.

    Attributes:
        design: ``sheet`` (the default: a bending stiffness of 0.1 N m, a card's or a thin plastic sheet's, and a
            woven cloth in its plane, stiff along its threads and soft in shear, masses by area, at resolution 17
            with elastic sticks whose iterations converge: its flapping is the flag's, the same at resolutions 17 and
            33 and with the threads made 64 times softer, and in the band measured for flags; docs/flag.md) or
            ``paper`` (the paper's cloth: rigid sticks, no bending, even masses, resolution 5, whose flapping is its
            mesh's and its time step's). In a scene or with ``--set`` it is a preset (:data:`PRESETS`): it sets
            the keys below but ``width``, ``height``, ``mass_per_area``, ``pole_height`` and ``position``, and
            ``solver.mass_splitting``, ``solver.dt``, ``solver.iterations`` and ``air.density`` (the paper's constant
            air, or 0: the standard atmosphere), and then the scene's own keys apply.
            The builder itself reads only the individual keys: ``FlagConfig(design="paper")`` alone is still the
            sheet (the keys' defaults are the sheet's); the paper's keys are ``PRESETS["paper"]["flag"]``.
        width: length of the flag away from the pole, along +x [m].
        height: height of the flag along the pole [m].
        resolution: particles along the width; along the height as many as keep cells near square. The sheet's
            17 flaps within 0.1 % of 33 and 2 % faster than 9 (its spacing, 0.125 m, is finer than the bending
            length ``(B / (rho U^2))^(1/3)``, 0.17 m in 4 m/s). The paper design's 5 is coarse on purpose: even with
            the paper's 55 Jacobi iterations at dt = 1/100 s it keeps every rigid stick within 1% of its rest length;
            finer paper cloth stretches more (see README).
        mass_per_area: fabric areal density [kg/m^2] (flag nylon ~0.1-0.2).
        mass_lumping: how the cloth's mass is shared among its particles. ``"area"`` (the sheet's) gives each
            particle the cloth it stands for (a quarter of every cell it touches), as a real cloth's. ``"even"``
            (the paper's) gives every particle the same, so that the grid's edges carry twice the cloth their area
            holds and its corners four times, a heavier border the coarser the mesh (a sheet flag with every stick
            alike flapped within 9 % of itself at resolutions 9, 17 and 33 by area, 10 % with even masses;
            docs/flag.md).
        bending_stiffness: the cloth's bending stiffness ``B`` [N m] (per metre of width: ``E t^3 / 12`` for a
            sheet of Young's modulus ``E`` and thickness ``t``; Poisson's ratio 0), as hinges along the grid's rows
            and columns and a twist in every cell (:func:`add_plate_hinges`, :mod:`warpsim.physics.kernels.bending`).
            0 (the paper's) is a cloth that folds freely; its flapping is then set by the mesh (docs/flag.md).
            A flag's fabric has ~1e-5 to 1e-3, which sets waves of centimetres, finer than these meshes; a stiffer
            sheet (0.1, the sheet's: a card or a thin plastic sheet) sets its waves at the flag's length, and its
            flapping converges as the mesh is refined (with a woven cloth, whatever its threads' stiffness:
            ``shear_compliance``). Explicit: dt must stay under
            ``Model.bending_dt`` (a scene past it is refused).
        cloth_compliance: stretch [m/N] per newton of tension of each of the cloth's sticks (XPBD; needs
            ``solver.mass_splitting``). A square grid's sticks, with both diagonals in every cell, give the cloth an
            in-plane stiffness of about ``1.5 / cloth_compliance`` [N/m] under a pull one way (``2 /`` held
            sideways) at any resolution. The sheet's 1.5625e-5 makes its threads 64,000 N/m. 0 is the paper's rigid
            sticks, which the iterations only approach: finer cloth then stretches more and answers to the iteration
            count.
        shear_compliance: stretch [m/N] per newton of each cell's two diagonal sticks, which alone resist the cloth's
            shear along its threads (the rows and columns, ``cloth_compliance``): a shear stiffness ``G t`` of
            ``1 / shear_compliance`` [N/m] on square cells (``2 a b / (a^2 + b^2)`` of it on cells ``a`` by ``b``;
            on the bias the threads hold it: ``1 / (2 cloth_compliance)``). The sheet's 1e-2 is 100 N/m in shear
            (its diagonals stretch up to ~5 % as the cloth shears: the run's worst stick). 0 gives the diagonals
            ``cloth_compliance`` too: every stick alike, a cloth stiff in shear. A woven fabric is stiff along its
            threads and shears under small forces (its threads turn at their crossings): with diagonals of 100 N/m
            the sheet flag flaps within 3.5 % whatever its threads' stiffness (1,000 to 64,000 N/m), where the grid
            of like sticks flaps slower the stiffer it is made (its crossed cells are over-constrained, and the
            trend is what their locking would do; docs/flag.md).
        pole_height: height of the flag's top edge above the terrain at the pole's foot [m].
        position: (x, y) of the pole [m].
        lattice: the cloth is a lifting surface of the vortex law too (its free edge, downstream of the pole, the
            trailing edge; no profile drag and no stall): under ``air.model = "vortex"`` its air is the lattice's
            (with ``air.wake = "shed"``, a wake shed over time), otherwise the per-triangle law's as before. An
            experiment, not validated: the flag's flapping on the lattice depends on its mesh (docs/validation.md,
            "The flag on the lattice").
    """

    width: float = number(2.0, POSITIVE)
    height: float = number(1.2, POSITIVE)
    design: str = choice("sheet", ("sheet", "paper"))
    resolution: int = number(17, Bounds(2, 4096))
    mass_per_area: float = number(0.15, POSITIVE)
    mass_lumping: str = choice("area", ("even", "area"))
    bending_stiffness: float = number(0.1, NON_NEGATIVE)
    cloth_compliance: float = number(1.5625e-5, NON_NEGATIVE)
    shear_compliance: float = number(1e-2, NON_NEGATIVE)
    pole_height: float = number(5.0, POSITIVE)
    position: tuple[float, float] = (0.0, 0.0)
    lattice: bool = False


_DESIGN_KEYS = ("resolution", "mass_lumping", "bending_stiffness", "cloth_compliance", "shear_compliance")
PRESETS = {
    # 1.25 ms steps (the bending's explicit limit at resolution 17 is 2.3 ms) and 7 iterations per particle along
    # the flag (119): within 1 % of dt/4 with 4 times the iterations, the same with twice the iterations
    # (benchmarks/validation: the 'flag flapping' and 'sheet flag' rows); elastic sticks converge only with mass
    # splitting
    "sheet": {
        "flag": {k: getattr(FlagConfig(), k) for k in _DESIGN_KEYS},
        "air": {"density": STANDARD_AIR},
        "solver": {"mass_splitting": True, "dt": 0.00125, "iterations": SHEET_ITERATIONS * FlagConfig().resolution},
    },
    # 1.25 ms steps and 110 iterations: the flapping's frequency and amplitude within 4 % of their limit as dt -> 0
    # and the iterations grow (1.94 Hz, ±0.28 m; at the paper's 10 ms and 55: 1.67 Hz, ±0.41 m)
    "paper": {
        "flag": {
            "resolution": 5,
            "mass_lumping": "even",
            "bending_stiffness": 0.0,
            "cloth_compliance": 0.0,
            "shear_compliance": 0.0,
        },
        "air": {"density": AIR_DENSITY},  # the paper's constant air (slide 14)
        "solver": {"mass_splitting": False, "dt": 0.00125, "iterations": 110},
    },
}
"""``flag.design`` presets: ``{design: {section: {key: value}}}`` (see :class:`FlagConfig`)."""

MAX_PARTICLES = 2048 * 2048  # a larger flag takes minutes to build and gigabytes to hold


def add_plate_hinges(builder: ModelBuilder, ids: np.ndarray, du: float, dv: float, bending: float) -> None:
    """Give a grid of particles ``ids`` (``[rows, columns]``, spacing ``du`` [m] along a row, ``dv`` [m] along a
    column) a plate's bending stiffness ``bending`` [N m] with Poisson's ratio 0, whose energy per area is
    ``B/2 (w_xx^2 + w_yy^2 + 2 w_xy^2)``: a hinge on every three particles in a row or a column, of stiffness
    ``B w / h^3`` with ``h`` its spacing and ``w`` the width of the strip it stands for (half a spacing on the grid's
    edges), and a twist on every cell, of stiffness ``2 B / (du dv)``."""
    rows, columns = ids.shape
    for j, width in enumerate(dv * edge_halves(rows)):
        for i in range(1, columns - 1):
            builder.add_hinge(ids[j, i - 1], ids[j, i], ids[j, i + 1], bending * width / du**3)
    for i, width in enumerate(du * edge_halves(columns)):
        for j in range(1, rows - 1):
            builder.add_hinge(ids[j - 1, i], ids[j, i], ids[j + 1, i], bending * width / dv**3)
    for j in range(rows - 1):
        for i in range(columns - 1):
            builder.add_twist(ids[j, i], ids[j, i + 1], ids[j + 1, i], ids[j + 1, i + 1], 2.0 * bending / (du * dv))


def build_flag(builder: ModelBuilder, cfg: FlagConfig, terrain: Heightfield) -> ObjectRecord:
    """Add a flag on a pole standing on ``terrain`` at ``cfg.position``; the pole-side column is nailed."""
    if cfg.resolution < 2:
        raise ValueError(f"flag resolution must be at least 2, got {cfg.resolution}")
    count_u = int(cfg.resolution)
    rows = cfg.height / cfg.width * (count_u - 1)
    if not rows * count_u <= MAX_PARTICLES:
        raise ValueError(
            f"a {cfg.width:g} m x {cfg.height:g} m flag at resolution {count_u} would have about {rows * count_u:.3g} "
            f"particles (rows keep the cells square), more than {MAX_PARTICLES:,}: lower the resolution or the "
            "height-to-width ratio"
        )
    count_v = max(2, int(round(rows)) + 1)
    check_memory(count_u * count_v, f"a flag of {count_u} x {count_v}")
    x0, y0 = cfg.position
    top = float(terrain.height(x0, y0)) + cfg.pole_height
    p0 = builder.particle_count
    ids, sticks, tris = builder.add_grid(
        origin=(x0, y0, top - cfg.height),
        axis_u=(cfg.width / (count_u - 1), 0.0, 0.0),
        axis_v=(0.0, 0.0, cfg.height / (count_v - 1)),
        count_u=count_u,
        count_v=count_v,
        mass=cfg.mass_per_area * cfg.width * cfg.height,
        by_area=cfg.mass_lumping == "area",
    )
    for j in range(count_v):
        builder.add_nail(int(ids[j, 0]))
    if cfg.cloth_compliance > 0.0:
        builder.set_compliance(sticks, cfg.cloth_compliance)
    if cfg.shear_compliance > 0.0:
        # each cell's diagonals: their two ends on different rows and different columns
        row, column = np.divmod(np.asarray([builder.stick_particles[s] for s in sticks]) - p0, count_u)
        diagonals = sticks[(row[:, 0] != row[:, 1]) & (column[:, 0] != column[:, 1])]
        builder.set_compliance(diagonals, cfg.shear_compliance)
    if cfg.bending_stiffness > 0.0:
        add_plate_hinges(builder, ids, cfg.width / (count_u - 1), cfg.height / (count_v - 1), cfg.bending_stiffness)
    if cfg.lattice:  # a lifting surface for the vortex law, its free edge (downstream of the pole) the trailing edge
        points = np.asarray(builder.particle_q, dtype=np.float64)
        tri_idx = np.asarray(builder.tri_indices, dtype=np.int64)[tris]
        builder.set_triangle_sail(tris, (0.0, 0.0, 0.0, np.radians(60.0)))  # potential flow: no profile drag, no stall
        builder.add_lifting_surface(tris, trailing_edges(points, tri_idx, (1.0, 0.0, 0.0)))
    particles = np.arange(p0, builder.particle_count)
    return builder.add_object(
        ObjectRecord(
            name="flag",
            kind="flag",
            particles=particles,
            parts={"cloth": particles, "pole": ids[:, 0].copy()},
            tri_parts={"cloth": tris},
            stick_groups={"cloth": sticks},
        )
    )


# ---------------------------------------------------------------------------------------------- figures
FLAG_FIGURES = {
    "flap": (
        "m",
        "sideways offset of the flag's top trailing corner from the plane of its pole and the wind; its window "
        "frequency is the flapping frequency (the mesh's without a bending stiffness its mesh resolves, the elastic "
        "cloth's with one: the run's note says which, flag_caveat)",
    ),
}


def flag_figures(model: Model, record: ObjectRecord) -> Measure:
    """The flag's :data:`FLAG_FIGURES` of a frame. The flag is a grid whose rows run from the pole outwards, the
    top row last (:func:`~warpsim.objects.flag.build_flag`): its last particle is the top trailing corner, the
    pole's last the top of the pole."""
    corner, pole_top = int(record.parts["cloth"][-1]), int(record.parts["pole"][-1])

    def measure(view: FigureView) -> dict[str, float]:
        across = np.array([-view.wind[1], view.wind[0], 0.0], dtype=np.float64)  # horizontal, left of the wind
        speed = np.linalg.norm(across)
        across = across / speed if speed > 1e-6 else np.array([0.0, 1.0, 0.0])  # no wind: across the flag as built
        return {"flap": float((view.positions[corner] - view.positions[pole_top]) @ across)}

    return measure


def flag_hud(f: dict[str, float]) -> str:
    """The flag's heads-up text: its trailing corner's sideways offset."""
    return f"flap {f['flap']:+5.2f} m"


def flag_caveat(flag, settings) -> str:
    """What the flag's flapping figures are not (the mesh's, the iterations'), and which cloth's they are.

    Without a bending stiffness they are the mesh's: the paper's air law is local and its cloth folds freely, so
    nothing but the mesh picks a wavelength (converged in the time step, resolution 5 flaps at f L/U 0.96 and
    resolution 9 at 1.36; docs/flag.md, "The flag at fine resolution"). With one, the validation's sheet flag
    (B 0.1 N m, a woven cloth, masses by area) flaps within 0.1 % at resolutions 17 and 33 and 2 % slower at 9:
    its figures are the flag's on a mesh finer than resolution 17 and than the bending length
    ``(B / (rho U^2))^(1/3)``, with elastic sticks and at least :data:`SHEET_ITERATIONS` iterations per particle
    along it (the rigid sticks' iterations never converge on a fine mesh, and the flapping follows their count).
    Even then they are the cloth's in its plane: a woven cloth (``flag.shear_compliance``, stiff threads and a soft
    shear, as the validation's sheet flag) flaps the same whatever its threads' stiffness, one of like sticks flaps
    slower the stiffer it is made (its crossed cells lock; less so on a finer mesh), so that a paper sheet's
    in-plane stiffness is beyond these meshes (the validation's rows 'sheet flag frequency, thread stiffness' and
    'every stick alike').
    The Euler mass-spring comparison's flapping is not validated."""
    solver = settings.solver  # flag: its FlagConfig; settings: the scene's (solver, wind, air) of its world
    resolution, bending = int(flag.resolution), float(flag.bending_stiffness)
    where = "(docs/flag.md, 'The flag at fine resolution')"
    if bending <= 0.0:
        return (
            f"note: the flap's frequency and size are those of this mesh (resolution {resolution}), not a real "
            f"flag's: the local air law and the bending-free cloth pick no wavelength, so a finer mesh flaps "
            f'otherwise; the default flag (flag.design = "sheet") converges {where}'
        )
    if solver.method != "verlet":
        return f"note: the Euler mass-spring comparison's flapping is not validated {where}"
    if float(flag.cloth_compliance) <= 0.0 or not solver.mass_splitting:
        return (
            "note: with rigid sticks (flag.cloth_compliance = 0) the flapping follows the iteration count on a fine "
            "mesh; set flag.cloth_compliance (e.g. 1e-3) and solver.mass_splitting = true for one that converges "
            f"{where}"
        )
    speed = float(np.linalg.norm(settings.wind.velocity))
    spacing = float(flag.width) / (resolution - 1)
    density = air_density(settings.air, 0.0)  # a flag flies near the ground
    length = (bending / (density * max(speed, 1e-3) ** 2)) ** (1.0 / 3.0)
    if resolution < 17 or spacing > length:
        finest = max(17, int(np.ceil(float(flag.width) / length)) + 1)
        alike = ", 8 % with every stick alike" if float(flag.shear_compliance) <= 0.0 else ""
        return (
            f"note: at resolution {resolution} (spacing {spacing:.2g} m against a bending length of {length:.2g} m) "
            f"the flapping is still the mesh's in part (the validation's sheet flag flaps 2 % slower at resolution 9 "
            f"than at 33{alike}); resolution {finest} or more should converge {where}"
        )
    if int(solver.iterations) < SHEET_ITERATIONS * resolution:
        return (
            f"note: {solver.iterations} iterations, fewer than the {SHEET_ITERATIONS} per particle along the flag "
            f"({SHEET_ITERATIONS * resolution}) at which the validation's sheet flag flaps as with twice as many "
            f"{where}"
        )
    if float(flag.shear_compliance) > 0.0:
        return (
            f"note: the flapping is this flag's, a woven cloth ({1.0 / float(flag.shear_compliance):,.0f} N/m in "
            "shear) with a card's bending, converged in its mesh, step, iterations and threads (the validation's, at "
            "100 N/m); the worst stick stretch is its diagonals as the cloth shears, as meant. A fabric's waves are "
            f"finer than this mesh, and a sheet stiff in shear (paper) locks on it {where}"
        )
    stiffness = 1.5 / float(flag.cloth_compliance)
    return (
        f"note: the flapping is this cloth's, every stick alike, about {stiffness:,.0f} N/m in its plane (1.5 / "
        "flag.cloth_compliance: a pull stretches the diagonals too): a "
        "stiffer one flaps slower (16 times stiffer: 15 % at resolution 17, 11 % at 33; its crossed cells lock), "
        "and a paper sheet, a hundred times stiffer or more, is out of reach here; a woven cloth "
        f"(flag.shear_compliance, the default flag's) does not depend on its threads' stiffness {where}"
    )
