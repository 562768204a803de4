"""How the flying hang glider handles (issue 34): the pilot's flights and the references they are held against.

The default glider's bands are validation rows (tests/test_validation.py); here the intermediate glider's, and the
closed forms the rows use (R.T. Jones's dive recovery, the coordinated turn).
"""

import functools
import math

import numpy as np
import pytest

from benchmarks.validation import cases, glider_rows
from benchmarks.validation.handling import FINE, dive_band, dive_flight, glide_flight, phugoid_flight
from benchmarks.validation.piloting import fly_piloted, scene_descriptor
from benchmarks.validation.pitch import (
    delta_pitch_lag,
    inertial_phugoid,
    jones_recovery_height,
    lag_ratio,
    lagged_period,
    lift_slope_flight,
    pitch_derivatives,
    pitch_inertia,
    point_mass_recovery,
)
from warpsim.physics.atmosphere import isa
from warpsim.physics.model import AIR_DENSITY, GRAVITY


def test_jones_dive_recovery_closed_form_and_point_mass():
    # Jones (1977): about 12 m at 5 kg/m^2 and C_L 1.0 in sea-level air; the drag-free point mass from rest levels
    # at 3 (m/S) / (rho C_L) whatever it starts at; drag (L/D 8) costs a few per cent more height
    assert jones_recovery_height(5.0, 1.0, 1.225) == pytest.approx(12.24, abs=0.01)
    assert point_mass_recovery(6.7, 0.73, 1e9) == pytest.approx(jones_recovery_height(6.7, 0.73), rel=2e-3)
    with_drag = point_mass_recovery(6.7, 0.73, 8.0)
    assert 1.02 < with_drag / jones_recovery_height(6.7, 0.73) < 1.10
    band = dive_band("hang-glider", 12.0, 8.5)
    launch = scene_descriptor("hang-glider")["hang_glider"]["altitude"]  # the standard atmosphere's air there
    assert band["wing_loading"] == pytest.approx(94.0 / 14.0) and band["density"] == pytest.approx(isa(launch)[2])
    assert band["low"] < band["jones_trim"] < band["high"]


def test_the_bar_slews_and_the_pilot_stops_the_flight():
    # a step of the controls moves the bar at 2 per second; stop ends the flight
    d = scene_descriptor("hang-glider", glider={"altitude": 100.0})
    history = fly_piloted(d, 5.0, lambda s: {"roll": 1.0}, stop=lambda s: s["t"] >= 1.0)
    rolls = np.array([f["roll"] for f in history])
    assert len(history) == 20 and rolls[0] == pytest.approx(0.1) and rolls[4] == pytest.approx(0.5)
    assert rolls[-1] == 1.0 and np.all(np.diff(rolls) <= 0.1 + 1e-12)


@pytest.mark.slow
def test_intermediate_glider_handles_as_the_default_at_both_time_steps():
    """Issue 34, the intermediate glider (15 m^2, 30 + 80 kg): glide >= 8 at 9-13 m/s, 30 deg in 1.5-4 s, reversal
    3-4 s, 20-40 deg 20 s after centring, turn radii within 15 % of V^2 / (g tan bank), phugoid damping, stall,
    never tail first, at dt 0.005/55 and 0.005/110 (measured 2026-12-01: glide 8.11/8.02, 30 deg in 2.3 s, reversal
    3.7 s, 27.4/27.8 deg after centring); it misses what the default misses: the dive recovery hands off (39 m), the
    phugoid period, the roll-in's sideslip (52 deg) and the sideslip under half weight shift (31 deg), while pulled
    out with the bar held out it levels inside the band (23.7 / 23.2 m)."""
    rows = cases.CASES["flying-glider-intermediate"]()
    assert len(rows) == 15
    missing = {r.case.removeprefix("intermediate ") for r in rows if not r.ok}
    assert missing == set(glider_rows.FLYING_MISSES), [r for r in rows if not r.ok]
    turn40 = next(r for r in rows if r.case.endswith("~40°"))
    assert math.isfinite(float(turn40.measured.split()[0]))


def test_billow_shift_twists_the_low_half_up_and_is_off_in_the_paper_design():
    from warpsim.objects.hang_glider import billow_rest_lengths
    from warpsim.run.simulation import Simulation
    from warpsim.scene.descriptor import defaults, merge

    sim = Simulation(scene_descriptor("hang-glider"))
    rec = sim.model.objects[0]
    built = sim.model.stick_rest.numpy()[rec.billow_sticks]
    np.testing.assert_allclose(billow_rest_lengths(rec, 0.0), built, rtol=1e-6)
    # the struts' particles in the build frame, raised for roll +1 (pilot right): the right half (side -1) rises
    pilot_right = billow_rest_lengths(rec, 1.0) - built
    assert np.abs(pilot_right).max() > 0.01
    # mirror images: roll -1 changes the left half's ties as roll +1 the right half's
    left_half = billow_rest_lengths(rec, -1.0) - built
    assert sorted(np.round(left_half[rec.billow_side == 1], 9)) == pytest.approx(
        sorted(np.round(pilot_right[rec.billow_side == -1], 9)), abs=1e-4
    )
    sim.step(100)
    sim.set_controls(roll=1.0)
    sim.step(50)
    q = sim.state.positions()
    nose, tail = q[rec.nose], q[rec.keel[-1]]
    left = q[rec.tips[0]] - q[rec.tips[1]]
    up = np.cross(nose - tail, left)
    up /= np.linalg.norm(up)
    side = rec.billow_side
    points = np.unique(rec.billow_particles)
    height = {s: np.mean([(q[p] - tail) @ up for p in points if np.sign((q[p] - tail) @ left) == s]) for s in (1, -1)}
    assert height[-1] > height[1] + 0.02, height  # the right (low) half's trailing edge is raised
    assert side.min() == -1 and side.max() == 1
    paper = Simulation(merge("t", defaults("hang-glider"), {"hang_glider": {"design": "paper"}})).model.objects[0]
    assert paper.billow_shift == 0.0


def test_lagged_point_mass_levels_at_3_plus_2c_wing_loadings():
    # a wing whose C_L falls a k (dgamma/dt) / V while its path turns: without drag cos(gamma) = rho C_L z /
    # ((1.5 + c) 2 m/S), level at (3 + 2c) (m/S) / (rho C_L); c = 0 is Jones's
    for c in (0.0, 0.3, 0.86):
        closed = (3.0 + 2.0 * c) * 6.7 / (AIR_DENSITY * 0.73)
        assert point_mass_recovery(6.7, 0.73, 1e9, lag=c) == pytest.approx(closed, rel=2e-3)
    assert point_mass_recovery(6.7, 0.73, 8.0, lag=0.5) > point_mass_recovery(6.7, 0.73, 8.0)
    assert lag_ratio(2.0, 3.7, 6.7, 1.3) == pytest.approx(1.3 * 3.7 * 2.0 / 13.4)


def test_lagged_phugoid_period_is_sqrt_1_plus_c_lanchester():
    # small oscillation of the drag-free lagged point mass about level flight at 12 m/s (RK4), period from the
    # speed's upward crossings of trim
    v0, c = 12.0, 0.8
    k = GRAVITY / v0**2

    def rate(y):
        v, gamma = y
        return np.array([-GRAVITY * math.sin(gamma), (k * v * v - GRAVITY * math.cos(gamma)) / ((1.0 + c) * v)])

    y, h, t, ups = np.array([v0 * 1.01, 0.0]), 1e-3, 0.0, []
    while len(ups) < 3:
        k1 = rate(y)
        k2 = rate(y + 0.5 * h * k1)
        k3 = rate(y + 0.5 * h * k2)
        k4 = rate(y + h * k3)
        new = y + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        if y[0] < v0 <= new[0]:
            ups.append(t + h * (v0 - y[0]) / (new[0] - y[0]))
        y, t = new, t + h
    assert (ups[2] - ups[0]) / 2.0 == pytest.approx(lagged_period(v0, c), rel=2e-3)
    assert lagged_period(v0) == pytest.approx(math.pi * math.sqrt(2.0) * v0 / GRAVITY)


def test_strip_theory_pitch_lag_of_a_delta_wing():
    # the delta 10 m x 2.8 m: quarter chord x = -0.7 - 0.42 y, chord 2.8 - 0.56 y, strip weights ~ (5 - y), so
    # var(y) = 25/18: radius of gyration of the lift 0.42 sqrt(25/18); k SM = r^2 with the angle of attack taken
    # where the lift acts, r^2 - cov(x, c)/2 at Pistolesi's three-quarter chord
    var_y = 25.0 / 18.0
    r2, cov = 0.42**2 * var_y, 0.42 * 0.56 * var_y
    assert delta_pitch_lag(10.0, 2.8)["radius"] == pytest.approx(math.sqrt(r2), rel=1e-4)
    for sm in (0.1, 0.3, 0.8):
        assert delta_pitch_lag(10.0, 2.8, sm, sample_at=0.25)["k"] * sm == pytest.approx(r2, rel=1e-3)
        assert delta_pitch_lag(10.0, 2.8, sm)["k"] * sm == pytest.approx(r2 - 0.5 * cov, rel=1e-3)
        # every piece of chord alone: the half-chord points' spread, 0.28^2 var(y), and the chord's, mean c^2 / 12
        # with mean c^2 = 2.8^2 / 2 over the strips' areas (16 pieces: c^2 / 12 (1 - 1/256))
        pieces = 0.28**2 * var_y + 2.8**2 / 2.0 / 12.0 * (1.0 - 1.0 / 256.0)
        assert delta_pitch_lag(10.0, 2.8, sm, sample_at=None)["k"] * sm == pytest.approx(pieces, rel=2e-3)
        # thin-aerofoil theory's quarter-chord pitch damping, C_m = -pi q c / (8 V), adds mean c^2 / 16 over the
        # strips' lift (weights ~ c: mean c^2 = 2.8^2 / 2) to k SM
        moment = delta_pitch_lag(10.0, 2.8, sm, quarter_chord_moment=True)["k"] * sm
        assert moment == pytest.approx(r2 - 0.5 * cov + 2.8**2 / 2.0 / 16.0, rel=1e-3)


def test_inertial_phugoid_closed_forms():
    # without inertia: Lanchester's phugoid with the lag (period sqrt(1 + c) his, damping sqrt(1 + c) / (sqrt(2) L/D));
    # a little inertia: the damping falls by tau omega / (2 (1 + c)), omega = sqrt(2) g / (V sqrt(1 + c))
    for c in (0.0, 0.3, 0.86):
        still = inertial_phugoid(12.0, 1e9, c)
        assert still["period"] == pytest.approx(lagged_period(12.0, c), rel=1e-6) and abs(still["zeta"]) < 1e-6
        assert inertial_phugoid(12.0, 8.5, c)["zeta"] == pytest.approx(math.sqrt(1.0 + c) / (math.sqrt(2.0) * 8.5))
        small = inertial_phugoid(12.0, 1e9, c, 0.3, 0.01)
        omega = math.sqrt(2.0) * GRAVITY / (12.0 * math.sqrt(1.0 + c))
        assert small["zeta"] == pytest.approx(-small["tau"] * omega / (2.0 * (1.0 + c)), rel=0.01)
    # the glider's figures (I/m 0.59 m^2, SM 0.29 m, 12 m/s, L/D 8.5): c 0.86 keeps it damped, Pistolesi's 0.1 not
    assert inertial_phugoid(12.0, 8.5, 0.86, 0.29, 0.59)["zeta"] > 0.06
    assert abs(inertial_phugoid(12.0, 8.5, 0.1, 0.29, 0.59)["zeta"]) < 0.01


@functools.cache
def _pitch_figures(fine: bool) -> dict:
    solver = FINE if fine else None
    glide, phugoid = glide_flight("hang-glider", solver), phugoid_flight("hang-glider", solver)
    slope = lift_slope_flight("hang-glider", solver)
    ratio = phugoid["period"] / phugoid["lanchester"]
    band = dive_band(
        "hang-glider",
        glide["speed"],
        glide["glide"],
        lift_slope=slope["slope"],
        static_margin=slope["static_margin"],
        period_ratio=ratio,
    )
    tunnel = pitch_derivatives("hang-glider", solver)
    dive = dive_flight("hang-glider", solver)["height"]
    bar_out = dive_flight("hang-glider", solver, bar=-1.0)["height"]
    inertia = pitch_inertia("hang-glider", solver)["inertia_per_mass"]
    return {
        "dive": dive,
        "bar_out": bar_out,
        "ratio": ratio,
        "band": band,
        "tunnel": tunnel,
        "glide": glide,
        "phugoid": phugoid,
        "inertia": inertia,
        **slope,
    }


@pytest.mark.parametrize("fine", [False, True], ids=["dt0.01", "dt0.005"])
@pytest.mark.slow
def test_glider_dive_and_phugoid_misses_are_one_pitch_damping_lag(fine):
    """The glider's phugoid period gives its lag c = (T / T_L)^2 - 1 (measured 0.86 / 0.78); the point mass with that
    lag predicts the dive recovery (35.5 / 32.3 m against 37.4 / 35.3 m measured). A rigid tailless delta at the
    glider's measured static margin (0.29 / 0.27 m; lift slope 3.70 / 3.61 per rad) has c 0.10-0.31 by strip theory
    (24.5-27.5 m, +5 to +14 %): the glider's pitch damping is 3-8 times too strong for its stiffness."""
    f = _pitch_figures(fine)
    b = f["band"]
    assert 3.3 < f["slope"] < 4.2 and 0.2 < f["static_margin"] < 0.35
    assert f["dive"] == pytest.approx(b["predicted"], rel=0.12)
    assert b["rigid_lag"] < b["panel_lag"] < 0.4 < b["lag"]
    assert b["high"] < b["rigid"] < b["panel"] < f["dive"]


@pytest.mark.parametrize("fine", [False, True], ids=["dt0.01", "dt0.005"])
def test_glider_pitch_lag_is_its_triangles_lifting_alone(fine):
    """The glider's air law in a wind tunnel of rigid velocity fields (pitch.pitch_derivatives, measured: static
    margin 0.28 / 0.27 m, damping M_q^/M_alpha 1.86 / 1.92 m, pitch-rate lift L_q^/L_alpha -0.12 / -0.17 m, k 1.98 /
    2.09 m): the static margin is the one flown (trim shift with the pilot), k is strip theory's with every piece
    of chord lifting alone (1.52 m at 0.286 m) plus the wing's airspeed falling as it swings back above the centre of
    gravity (about 2 C_L h / a = 0.35 m, h = 0.92 m), and its lag c matches the phugoid's within 20 %."""
    f = _pitch_figures(fine)
    t, b = f["tunnel"], f["band"]
    assert t["static_margin"] == pytest.approx(f["static_margin"], abs=0.03)
    assert t["slope"] == pytest.approx(f["slope"], rel=0.1)
    pieces = delta_pitch_lag(10.0, 2.8, t["static_margin"], sample_at=None)["k"]
    assert pieces < t["k"] < pieces + 2.0 * t["cl"] * 0.92 / t["slope"] + 0.2
    assert t["pitch_lift"] < 0.0 < t["damping"]
    lag = lag_ratio(t["k"], t["slope"], b["wing_loading"], b["density"])
    assert lag == pytest.approx(b["lag"], rel=0.2)


@pytest.mark.parametrize("fine", [False, True], ids=["dt0.01", "dt0.005"])
def test_glider_phugoid_damping_is_drag_less_pitch_inertia(fine):
    """The glider's phugoid damping (measured 0.071 / 0.064) is the third-order phugoid's
    (pitch.inertial_phugoid: 0.074 / 0.068) from its own figures: trim speed, glide ratio, the lag c from its period
    (0.86 / 0.78), the static margin flown (0.29 / 0.27 m) and the pitch inertia of its particles (I/m 0.589 / 0.583
    m^2). Drag with the lag alone would give 0.113 / 0.115: the pilot below and the wing above take a third of it, so a
    lag near thin-aerofoil theory's (c 0.1) would leave the phugoid undamped at this static margin."""
    f = _pitch_figures(fine)
    g, p = f["glide"], f["phugoid"]
    lag = f["ratio"] ** 2 - 1.0
    assert 0.5 < f["inertia"] < 0.7
    full = inertial_phugoid(g["speed"], g["glide"], lag, f["static_margin"], f["inertia"])
    assert p["zeta"] == pytest.approx(full["zeta"], rel=0.15)
    assert inertial_phugoid(g["speed"], g["glide"], lag)["zeta"] > 1.4 * p["zeta"]


@pytest.mark.parametrize("fine", [False, True], ids=["dt0.01", "dt0.005"])
def test_glider_pulled_out_with_the_bar_out_levels_within_jones_band(fine):
    """Jones's band is a wing held at its trim C_L or above through the pull-out; a pilot who pushes the bar full
    out from the release holds it there (measured 23.0 / 21.0 m against 15.6-23.1 / 15.6-21.7 m), where hands off
    it levels 14 m lower (the xfail below)."""
    f = _pitch_figures(fine)
    assert f["band"]["low"] <= f["bar_out"] <= f["band"]["high"]
    assert f["bar_out"] < f["dive"] - 5.0


@pytest.mark.xfail(strict=True, reason="issue 34: the glider's pitch damping lag (c ~0.8, see the test above)")
@pytest.mark.parametrize("fine", [False, True], ids=["dt0.01", "dt0.005"])
def test_glider_dive_recovery_and_phugoid_period_in_jones_and_lanchester_bands(fine):
    f = _pitch_figures(fine)
    assert f["band"]["low"] <= f["dive"] <= f["band"]["high"]
    assert abs(f["ratio"] - 1.0) <= 0.2


@pytest.mark.slow
def test_washout_experiment_reproduces_the_validation_and_shortens_the_phugoid():
    """benchmarks/validation/washout_experiment.py (issue 34, not in the model): with no imposed twist it flies the
    validation's own hands-off dive and phugoid (37.4 m, 7.40 s measured), so its table in docs/glider.md is
    comparable; a washout growing by 10 deg per unit of q/q0 shortens the phugoid (6.44 s) and the dive (29.3 m) and
    takes damping away (0.071 -> 0.043)."""
    from benchmarks.validation.washout_experiment import run

    plain, twisted = run(0.0), run(10.0)
    assert plain["dive"] == pytest.approx(_pitch_figures(False)["dive"], rel=1e-6)
    assert plain["period"] == pytest.approx(_pitch_figures(False)["phugoid"]["period"], rel=1e-6)
    assert twisted["period"] < 0.9 * plain["period"] and twisted["dive"] < 0.85 * plain["dive"]
    assert twisted["zeta"] < plain["zeta"]
