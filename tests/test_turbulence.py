"""Frozen turbulence (warpsim.physics.turbulence): the field, what the kernels sample from it, one field for every
world, the flight it makes the same at any frame rate and after a resume, and bad settings in one line."""

import numpy as np
import pytest
import warp as wp

from benchmarks.validation.turbulence_rows import field_rows
from warpsim.cli import main
from warpsim.physics import turbulence
from warpsim.physics.kernels.aero import TurbulenceData, turbulence_at
from warpsim.run.simulation import Simulation
from warpsim.scene import descriptor

TURBULENT = {"wind": {"turbulence_intensity": 0.15}}


@wp.kernel
def _sample(turb: TurbulenceData, points: wp.array(dtype=wp.vec3d), out: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    out[i] = turbulence_at(turb, 0, points[i])


def _kite(overrides: dict | None = None, **kwargs) -> Simulation:
    d = descriptor.merge("test", descriptor.resolve("kite")[0], TURBULENT)
    return Simulation(descriptor.merge("test", d, overrides or {}), **kwargs)


def test_the_field_is_von_karmans_where_the_grid_holds_it():
    """The rows of docs/validation.md: integral length scale within 10 %, the across-wind correlation within 0.05,
    and the rest within what the grid's missing small eddies allow (measured: variance 0.84-0.91, spectrum bands
    0.85-1.03, along-wind correlation at L/4 0.76 against 0.70)."""
    rows = {row.case: row for row in field_rows()}
    assert rows["turbulence integral length scale"].ok and rows["turbulence correlation across the wind"].ok
    for name in "uvw":
        assert 0.8 <= float(rows[f"turbulence variance {name}"].measured) <= 1.0
    bands = [float(b) for b in rows["turbulence one-point spectrum"].measured.split(", ")]
    assert all(0.8 <= b <= 1.1 for b in bands)
    field = turbulence.field(24.5)
    assert field.velocity.nbytes == 192 * 96 * 96 * 3 * 4  # the memory the docs state: 21 MB


def test_the_kernels_sample_the_field_as_the_host_does():
    """``turbulence_at`` (trilinear, periodic, scaled by the world's sigma) against the host's own sampler, at points
    anywhere (negative, far beyond the box) and moved by the world's shift."""
    sim = _kite()
    turb = sim.control.turbulence
    field = turb.field
    rng = np.random.default_rng(3)
    points = rng.uniform(-3000.0, 3000.0, (200, 3))
    out = wp.zeros(len(points), dtype=wp.vec3)
    wp.launch(_sample, len(points), [turb.data, wp.array(points, dtype=wp.vec3d)], [out])
    shift = turb.data.shift.numpy()[0]
    sigma = float(turb.data.scale.numpy()[0])
    assert sigma == pytest.approx(0.15 * np.linalg.norm(descriptor.resolve("kite")[0]["wind"]["velocity"]), rel=1e-6)
    np.testing.assert_allclose(out.numpy(), sigma * field.sample(points + shift), rtol=1e-4, atol=1e-5 * sigma)


def test_every_world_shares_one_field_and_flies_its_own_part_of_it():
    sim = _kite({"worlds": {"count": 3, "wind": {"turbulence_seed": [0, 1, 1]}}})
    turb = sim.control.turbulence
    assert turb.data.velocity.shape == turbulence.GRID  # one field, whatever the worlds
    shift = turb.data.shift.numpy()
    assert not np.allclose(shift[0], shift[1]) and np.array_equal(shift[1], shift[2])
    sim.step(200)
    q = sim.state.positions().reshape(3, -1, 3)
    assert np.array_equal(q[1], q[2] - q[2][:1] + q[1][:1]) or np.allclose(q[1], q[2])  # same seed, same flight
    assert not np.allclose(q[0], q[1])


def test_turbulence_shakes_the_kite_and_resumes_bit_for_bit():
    """The kite wanders across the wind more in 15 % turbulence than in steady wind (its centre's sideways position
    over 4-10 s); a run checkpointed and restored flies on exactly as one run."""
    wander = {}
    for intensity in (0.0, 0.15):
        sim = _kite({"wind": {"turbulence_intensity": intensity}})
        record = sim.model.objects[0]
        ys = []

        def keep(frame, ys=ys, record=record):
            if frame.time >= 4.0:
                ys.append(frame.positions[record.particles, 1].mean())

        sim.run(10.0, on_frame=keep)
        wander[intensity] = np.std(ys)
    assert wander[0.15] > 2.0 * wander[0.0], wander
    a = _kite()
    a.run(0.5)
    saved = a.checkpoint()
    a.run(0.5)
    b = _kite()
    b.restore(saved)
    b.run(0.5)
    assert np.array_equal(a.state.positions(), b.state.positions())


@pytest.mark.parametrize(
    ("setting", "message"),
    [
        ("wind.turbulence_intensity=2", "wind.turbulence_intensity"),
        ("wind.turbulence_length=0.1", "wind.turbulence_length"),
    ],
)
def test_bad_turbulence_settings_are_one_line(setting, message, capsys):
    code = main(["run", "kite", "--seconds", "0.1", "--set", setting])
    err = capsys.readouterr().err
    assert code == 2 and message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1, err


def test_worlds_of_other_length_scales_are_refused_in_one_line(capsys):
    turbulent, lengths = "wind.turbulence_intensity=0.1", "wind.turbulence_length=20,30"
    code = main(["run", "kite", "--seconds", "0.1", "--set", turbulent, "--vary", lengths])
    err = capsys.readouterr().err
    assert code == 2 and "one wind.turbulence_length" in err and len(err.strip().splitlines()) == 1, err


def test_a_blow_up_goes_back_to_the_air_of_the_last_good_frame():
    """The turbulence moves every step: a bad frame undone puts the worlds back where they were in the field at the
    last good frame (it went back to where they were at the last change of the controls)."""
    sim = _kite()
    sim.run(3 * sim.steps_per_frame * sim.dt)
    good = sim.control.turbulence.data.shift.numpy().copy()
    record = sim.model.objects[0]

    def poison(index):
        q = sim.state.particle_q.numpy()
        q[record.particles[3]] = np.inf
        sim.state.particle_q.assign(q)

    with pytest.raises(Exception, match="non-finite"):
        sim.advance(before=poison)
    np.testing.assert_array_equal(sim.control.turbulence.data.shift.numpy(), good)
