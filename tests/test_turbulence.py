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


@pytest.mark.slow
def test_the_field_is_von_karmans_where_the_grid_holds_it():
    """The rows of docs/validation.md, sampled as the kernels sample (trilinearly, between the nodes): variance per
    component, integral length scale and every band of the one-point spectrum within 10 %, the two-point correlations
    along and across the wind within 0.05 of von Kármán's."""
    rows = field_rows()
    assert len(rows) == 7
    for row in rows:
        assert row.ok, (row.case, row.measured)
    for name in "uvw":  # the eddies the grid cannot hold are missing, never more than the model has
        assert float(next(r for r in rows if r.case == f"turbulence variance {name}").measured) <= 1.0
    field = turbulence.field(24.5)
    assert field.velocity.nbytes == 320 * 160 * 160 * 3 * 4  # the memory the docs state: 98 MB


def test_one_field_has_the_models_variance_whatever_its_seed():
    """Random phases with each mode's own energy: a field's variance is the model's, not a draw of it (with random
    amplitudes a periodic box's few large eddies spread it ±10 % from one seed to the next); ``u``'s is exact."""
    small = (64, 32, 32)
    fields = [turbulence.synthesise(24.5, seed, small).velocity.astype(np.float64) for seed in (0, 1, 2)]
    variance = np.array([f.var(axis=(0, 1, 2)) for f in fields])
    np.testing.assert_allclose(variance[:, 0], variance[0, 0], rtol=1e-5)
    np.testing.assert_allclose(variance[:, 1:], variance[:1, 1:].repeat(3, axis=0), rtol=0.05)
    assert not np.allclose(fields[0], fields[1])
    spectra = np.fft.fftn(fields[0], axes=(0, 1, 2))  # divergence-free: k . v(k) = 0 for every mode
    k = np.meshgrid(*[np.fft.fftfreq(n) for n in small], indexing="ij")
    div = sum(k[c] * spectra[..., c] for c in range(3))
    assert np.sum(np.abs(div) ** 2) < 1e-10 * sum(np.sum(np.abs(k[c] * spectra[..., c]) ** 2) for c in range(3))


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
