"""Bending stiffness (warpsim.physics.kernels.bending): hinges against their second difference, checked against the
energy they stand for, against Euler-Bernoulli's cantilever, and refused past their explicit step limit."""

from __future__ import annotations

import contextlib
import io

import numpy as np
import pytest
import warp as wp

import warpsim as ws
from warpsim.cli.main import main
from warpsim.objects.flag import add_plate_hinges
from warpsim.physics.config import AirConfig
from warpsim.physics.kernels.bending import bending_force

G = 9.81


def _strip(columns: int, rows: int, length: float, width: float, mu: float, bending: float, clamp: int = 1):
    """A plate ``length`` x ``width`` [m] of ``mu`` [kg/m^2] and bending stiffness ``bending`` [N m], as a grid of
    ``columns`` x ``rows`` particles lying flat (x along its length, y across), its first ``clamp`` columns
    nailed."""
    b = ws.ModelBuilder()
    b.set_terrain(ws.Heightfield.flat(height=-100.0))
    du, dv = length / (columns - 1), width / (rows - 1)
    ids, _, _ = b.add_grid(
        origin=(0.0, 0.0, 0.0),
        axis_u=(du, 0.0, 0.0),
        axis_v=(0.0, dv, 0.0),
        count_u=columns,
        count_v=rows,
        mass=mu * length * width,
        by_area=True,
    )
    for j in range(rows):
        for i in range(clamp):
            b.add_nail(int(ids[j, i]))
    add_plate_hinges(b, ids, du, dv, bending)
    return b.finalize("cpu"), ids


def test_the_force_is_the_gradient_of_the_plate_energy():
    """Each hinge stores k |x_a - 2 x_m + x_b|^2 / 2; the kernel's force is minus its gradient, at any shape."""
    m, _ = _strip(6, 4, 1.0, 0.6, 0.2, 0.3, clamp=0)
    rng = np.random.default_rng(3)
    q = m.particle_q0 + rng.normal(scale=0.05, size=m.particle_q0.shape)
    hinges, k = m.hinge_particles_np, m.hinge_stiffness.numpy().astype(np.float64)
    weights = m.hinge_weights_np.astype(np.float64)

    def energy(x):
        bend = np.einsum("hj,hjd->hd", weights, x[hinges])
        return 0.5 * float(np.sum(k * np.sum(bend * bend, axis=1)))

    state = m.state()
    state.particle_q.assign(q)
    zero = wp.zeros(m.particle_count, dtype=wp.vec3, device=m.device)
    out = wp.zeros_like(zero)
    bending_force(m, state, zero, out)
    force = out.numpy().astype(np.float64)
    step = 1e-6
    gradient = np.zeros_like(q)
    for i in range(q.shape[0]):
        for d in range(3):
            up, down = q.copy(), q.copy()
            up[i, d] += step
            down[i, d] -= step
            gradient[i, d] = (energy(up) - energy(down)) / (2.0 * step)
    assert np.abs(force + gradient).max() < 1e-4 * np.abs(gradient).max()
    # a straight strip, however turned and moved, and a flat plate feel nothing
    turn = np.array([[0.6, -0.8, 0.0], [0.8, 0.6, 0.0], [0.0, 0.0, 1.0]]) @ np.array(
        [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]
    )
    state.particle_q.assign(m.particle_q0 @ turn.T + np.array([1e3, -2e3, 50.0]))
    bending_force(m, state, zero, out)
    assert np.abs(out.numpy()).max() < 1e-6 * np.abs(force).max()


def test_a_bend_and_a_saddle_cost_what_a_plate_does():
    """A plate of Poisson's ratio 0 stores B/2 (w_xx^2 + w_yy^2 + 2 w_xy^2) per area: bent into w = a x^2 / 2
    (curvature a) it stores B a^2 A / 2, twisted into the saddle w = a x y it stores B a^2 A. The hinges and twists
    of a 1 m x 0.6 m grid hold both: the bend to the first order of its edges' half strips, the saddle exactly."""
    bending, a = 0.3, 0.02
    m, _ = _strip(11, 7, 1.0, 0.6, 0.2, bending, clamp=0)
    q0 = m.particle_q0
    hinges, k, weights = m.hinge_particles_np, m.hinge_stiffness.numpy().astype(np.float64), m.hinge_weights_np

    def energy(w):
        x = q0.copy()
        x[:, 2] += w(q0[:, 0], q0[:, 1])
        bend = np.einsum("hj,hjd->hd", weights.astype(np.float64), x[hinges])
        return 0.5 * float(np.sum(k * np.sum(bend * bend, axis=1)))

    area = 1.0 * 0.6
    assert energy(lambda x, y: a * x * y) == pytest.approx(bending * a**2 * area, rel=1e-6)
    # the bend: each row's hinges stand for its 8 inner segments' curvature over 9 of its 10 (the two end halves
    # carry none), so 0.9 of the whole
    assert energy(lambda x, y: 0.5 * a * x**2) == pytest.approx(0.9 * 0.5 * bending * a**2 * area, rel=1e-6)


@pytest.mark.slow
def test_a_cantilever_sags_as_euler_bernoulli_says():
    """A 1 m plate of 0.15 kg/m^2 and B = 5 N m, clamped (its first two columns nailed: zero slope halfway between
    them) and loaded by its weight alone, sags at its tip q L^4 / (8 B) (Euler-Bernoulli; q = mu g the load per
    area) with L the length beyond the clamp, L0 - h/2: measured -0.63 % and -0.24 % at 11 and 21 columns (the exact
    solution of the discrete beam, K u = f, is -0.55 % and -0.13 %). Against the whole length L0 the error halves as
    the spacing does (first order): -19 % and -9.9 %."""
    length, bending, mu = 1.0, 5.0, 0.15
    sag, off = {}, {}
    for columns in (11, 21):
        m, ids = _strip(columns, 3, length, 0.2, mu, bending, clamp=2)
        dt = 0.5 * m.bending_dt
        # damping: a velocity decay of ~20 /s, settled well within the run
        solver = ws.SolverVerlet(m, air=AirConfig(scale=0.0), damping=20.0 * dt, iterations=200)
        state, control = m.state(), m.control()
        for _ in range(int(round(0.8 / dt))):
            solver.step(state, control, dt)
        sag[columns] = -float(state.positions()[ids[:, -1], 2].mean())
        h = length / (columns - 1)
        clamped = mu * G * (length - 0.5 * h) ** 4 / (8.0 * bending)
        off[columns] = 1.0 - sag[columns] / (mu * G * length**4 / (8.0 * bending))
        assert sag[columns] == pytest.approx(clamped, rel=0.01 if columns == 11 else 0.004), (columns, sag)
    assert 0.0 < off[21] < 0.1 and 1.6 < off[11] / off[21] < 2.4, off


def test_no_bending_stiffness_is_the_papers_cloth():
    from warpsim.scene import descriptor

    paper = descriptor.merge("t", descriptor.resolve("flag")[0], {"flag": {"design": "paper"}})
    sim = ws.Simulation(paper)
    assert sim.model.hinge_count == 0 and sim.solver.particle_force is sim.solver.particle_air
    stiff = ws.Simulation(descriptor.merge("t", paper, {"flag": {"bending_stiffness": 0.1}}))
    # 5 particles from the pole out, 3 up it: a hinge per three in a row (3 rows x 3), per three in a column (5 x 1),
    # a twist per cell (4 x 2)
    assert stiff.model.hinge_count == 3 * 3 + 5 * 1 + 4 * 2


def test_mass_lumping_by_area_gives_each_particle_its_own_cloth():
    """flag.mass_lumping = "area": every particle the cloth of the quarter cells it touches (interior h^2, edges
    half, corners a quarter), the whole cloth's mass kept; "even", the paper's, the same for all (edges twice their
    area's)."""
    from warpsim.scene import descriptor

    def masses(lumping):
        d = descriptor.merge("t", descriptor.resolve("flag")[0], {"flag": {"resolution": 9, "mass_lumping": lumping}})
        m = ws.Simulation(d).model
        ids = np.asarray(m.objects[0].particles)
        return m.particle_free_mass[ids], m.particle_q0[ids], d["flag"]

    even, q, flag = masses("even")
    area, _, _ = masses("area")
    cloth = flag["mass_per_area"] * flag["width"] * flag["height"]  # 0.36 kg
    h = (
        flag["width"] / 8
    )  # 0.25 m: resolution 9 along 2 m, 1.2 m in 4.8 -> 5 cells (6 rows) of 0.24 m (cells kept near square)
    x, z = q[:, 0] - q[:, 0].min(), q[:, 2] - q[:, 2].min()
    rim = (np.isclose(x, 0) | np.isclose(x, x.max())).astype(int) + (np.isclose(z, 0) | np.isclose(z, z.max()))
    free = x > 1e-6  # the pole's particles are nailed: no free mass
    assert np.all(even[free] == pytest.approx(cloth / len(q)))
    dv = flag["height"] / 5
    for edges, share in ((0, 1.0), (1, 0.5), (2, 0.25)):
        pick = free & (rim == edges)
        assert pick.any() and np.allclose(area[pick], flag["mass_per_area"] * h * dv * share), (edges, area[pick])
    pole_share = flag["mass_per_area"] * h * dv * (0.5 * 4 + 0.25 * 2)  # four edge and two corner particles held
    assert area.sum() + pole_share == pytest.approx(cloth)
    with pytest.raises(ValueError, match="flag.mass_lumping = 'nodes' is not one of even, area"):
        descriptor.merge("t", descriptor.resolve("flag")[0], {"flag": {"mass_lumping": "nodes"}})


def _droop(shear_compliance: float) -> float:
    """The default flag at resolution 9, its threads stiff (6.25e-5 m/N) and its diagonals ``shear_compliance``
    [m/N], hung in still air: the trailing edge's mean drop [m] below where it was built, 1-5 s after its release."""
    from benchmarks.validation.flag_rows import flag_samples
    from warpsim.scene import descriptor

    d = descriptor.merge(
        "t",
        descriptor.resolve("flag")[0],
        {
            "flag": {
                "resolution": 9,
                "mass_lumping": "area",
                "bending_stiffness": 0.1,  # holds the cloth in its plane
                "cloth_compliance": 6.25e-5,
                "shear_compliance": shear_compliance,
            },
            "wind": {"velocity": [0.0, 0.0, 0.0]},
            "solver": {"mass_splitting": True, "iterations": 252, "dt": 0.00125},
        },
    )
    sim = ws.Simulation(d)
    q0 = sim.state.positions()
    cloth = np.asarray(sim.model.objects[0].particles)
    edge = cloth[np.isclose(q0[cloth, 0], q0[cloth, 0].max())]
    return float(np.mean([np.mean(q0[edge, 2] - p[edge, 2]) for _, p in flag_samples(sim, 5.0, after=1.0)]))


@pytest.mark.slow
def test_shear_compliance_is_the_woven_cloths_shear_stiffness():
    """flag.shear_compliance gives each cell's two diagonals their own compliance, so that the cloth's shear
    stiffness is G t = 1 / shear_compliance [N/m] whatever its threads' (each diagonal of stiffness k stretches
    h gamma / sqrt 2 under a shear gamma: k h^2 gamma^2 / 2 per cell of area h^2). Hung from its pole in still air, the
    flag's weight W shears it in its plane as a deep cantilever of length L and depth H: its free edge drops
    W L / (2 kappa G t H) (Timoshenko's shear deflection: kappa 1 for inextensible threads, toward 5/6 as the
    threads' own stretch and the free edges relax the shear across the depth; the in-plane bending adds 8 G t / E t
    of it, 5 % here), measured from the particles (they swing about it undamped: the mean over 1-5 s; 1.05 and 1.03
    times W L / (2 G t H), where a static solve of the same grid of springs gives 1.04 and 1.02), and twice as far at
    twice the compliance."""
    from warpsim.scene import descriptor

    weight = 0.15 * 2.0 * 1.2 * 9.80665  # the flag's cloth [N]: 0.15 kg/m^2 on 2 m x 1.2 m
    drops = {c: _droop(c) for c in (1e-2, 2e-2)}
    for compliance, drop in drops.items():
        expected = weight * 2.0 / (2.0 * 1.2 / compliance)  # 2.9 cm at G t = 100 N/m
        assert expected <= drop <= 1.2 * expected, (compliance, drop, expected)
    assert drops[2e-2] / drops[1e-2] == pytest.approx(2.0, rel=0.1)
    with pytest.raises(ValueError, match="flag.shear_compliance = -1"):
        descriptor.merge("t", descriptor.resolve("flag")[0], {"flag": {"shear_compliance": -1}})


def test_a_step_past_the_bending_limit_is_refused_in_one_line():
    text, errors = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(text), contextlib.redirect_stderr(errors):
        code = main(
            ["run", "flag", "--seconds", "1", "--set", "flag.bending_stiffness=50", "--set", "flag.resolution=17"]
        )
    assert code == 2, (text.getvalue(), errors.getvalue())
    line = errors.getvalue().strip()
    assert "\n" not in line and "too long for the cloth's bending stiffness" in line and "dt <=" in line, line


def test_the_flags_note_says_what_its_flapping_is_not():
    """The run's note under the flap figure, per what the flag is built with (objects.flag.flag_caveat)."""
    from warpsim.objects.flag import SHEET_ITERATIONS, flag_caveat
    from warpsim.scene import descriptor
    from warpsim.scene.scene import Scene

    def caveat(d):
        scene = Scene(d)
        return flag_caveat(scene.object_config(), scene.settings)

    def note(iterations=None, method="verlet", mass_splitting=True, **flag):
        d = descriptor.merge("t", descriptor.resolve("flag")[0], {"flag": {"design": "paper", **flag}})
        d["solver"].update(method=method, mass_splitting=mass_splitting)
        d["solver"]["iterations"] = iterations or SHEET_ITERATIONS * d["flag"]["resolution"]
        return caveat(d)

    assert "those of this mesh (resolution 5)" in note()  # the paper's cloth
    default = caveat(descriptor.resolve("flag")[0])  # the default flag, the sheet: converged
    assert "this flag's, a woven cloth (100 N/m in shear) with a card's bending, converged" in default
    sheet = {"bending_stiffness": 0.1, "cloth_compliance": 1e-3}
    assert "rigid sticks" in note(bending_stiffness=0.1, resolution=17)
    assert "rigid sticks" in note(resolution=17, mass_splitting=False, **sheet)
    assert "Euler mass-spring" in note(resolution=17, method="euler", **sheet)
    # the bending length (0.1 / (1.294 * 4.03^2))^(1/3) = 0.17 m: resolution 9's 0.25 m spacing is coarser
    assert "at resolution 9 (spacing 0.25 m against a bending length of 0.17 m)" in note(resolution=9, **sheet)
    assert "33, 8 % with every stick alike)" in note(resolution=9, **sheet)
    assert "than at 33); resolution" in note(resolution=9, **sheet, shear_compliance=1e-2)  # woven: no like sticks
    for resolution in (17, 33):  # converged in the mesh and the iterations; like sticks lock as they stiffen
        said = note(resolution=resolution, **sheet)
        assert "this cloth's, every stick alike, about 1,500 N/m in its plane (1.5 / flag.cloth_compliance" in said
        said = note(resolution=resolution, **sheet, shear_compliance=1e-2)  # a woven cloth: the threads do not count
        assert "this flag's, a woven cloth (100 N/m in shear) with a card's bending, converged" in said, said
        assert "the worst stick stretch is its diagonals as the cloth shears" in said, said
    assert "119 iterations, fewer than the 7 per particle along the flag (231)" in note(
        resolution=33, iterations=119, **sheet
    )
    # a fabric's stiffness: centimetre waves, finer than resolution 33's 6 cm spacing
    assert "resolution 33 (spacing 0.062 m" in note(resolution=33, bending_stiffness=1e-4, cloth_compliance=1e-3)


@pytest.mark.slow
def test_the_sheet_flag_flaps_with_waves_running_to_its_tip():
    """The default flag (scenes/flag.toml, the sheet design) at resolution 9 (coarse, for speed; 17 and 33 flap 2 %
    faster in the validation): the corner flaps steadily at f L/U 0.433 (0.87 Hz in 4.03 m/s, 10-35 s), and the
    phase of the middle row's sideways motion lags along it: a wave running from the pole to the tip at c/U 1.12,
    lambda/L 2.57 (measured 2026-11-27 with the woven cloth; the validation's 'sheet flag' rows). Without the
    bending stiffness the same cloth flaps otherwise (resolution 9: 0.93 Hz, 17: 1.17 Hz, the picture's runs: the
    mesh's)."""
    from benchmarks.validation.flag_rows import flag_wave
    from warpsim.scene import descriptor

    sheet = descriptor.resolve("scenes/flag.toml")[0]
    overrides = {
        "flag": {
            key: sheet["flag"][key]
            for key in ("bending_stiffness", "cloth_compliance", "shear_compliance", "mass_lumping")
        },
        "solver": {"mass_splitting": True, "iterations": 126},
    }
    wave = flag_wave(9, 0.000625, overrides, seconds=35.0, after=10.0, design="sheet")
    assert 0.37 < wave["fL/U"] < 0.46, wave
    assert 0.8 < wave["c/U"] < 1.25 and 1.8 < wave["λ/L"] < 3.2, wave
    assert wave["rms"] > 0.2, wave  # a flap, not a ripple
