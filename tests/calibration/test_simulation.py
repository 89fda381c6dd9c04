"""simulate(): both truths exactly as the reports build them."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel import CalibrationModel, simulate
from gpsaccel.calibration.simulation import euler_integrate, simulate_many


@pytest.fixture(scope="module")
def model():
    return CalibrationModel()


def test_error_model_truth_is_the_phi_gamma_recursion(model):
    """Report 000's Monte Carlo: X(:, j+1) = Φ X(:, j) + Γ w(j), from [p0 − p̄0, v0 − v̄0, b]."""
    run = simulate(model, np.random.default_rng(1), truth="error-model")
    x = np.array([run.p0 - model.p0_mean, run.v0 - model.v0_mean, run.b])
    np.testing.assert_array_equal(run.x[0], x)
    for j in range(model.n_steps):
        x = model.Phi @ x + model.Gamma[:, 0] * run.w[j]
        if j % 500 == 499:
            np.testing.assert_allclose(run.x[j + 1], x, rtol=1e-9, atol=1e-9)
    np.testing.assert_array_equal(run.x_gps, run.x[::40])
    np.testing.assert_array_equal(run.z, run.x_gps[:, :2] + run.eta)


def test_error_model_total_truth_is_euler_integrated_acceleration(model):
    run = simulate(model, np.random.default_rng(2), truth="error-model")
    p_E, v_E = euler_integrate(run.a, model.dt, run.p0, run.v0)
    np.testing.assert_allclose(run.p, p_E, rtol=1e-12, atol=1e-8)
    np.testing.assert_allclose(run.v, v_E, rtol=1e-12, atol=1e-9)


def test_kinematic_truth_is_closed_form_minus_euler(model):
    """Reports 001/003: closed-form truth minus the Euler-integrated accelerometer."""
    run = simulate(model, np.random.default_rng(3), truth="kinematic")
    t = model.t_imu
    w = 0.1
    np.testing.assert_allclose(run.v, run.v0 + 10 / w - 10 / w * np.cos(w * t), rtol=1e-14)
    np.testing.assert_allclose(run.p, run.p0 + (run.v0 + 10 / w) * t - 10 / w**2 * np.sin(w * t),
                               rtol=1e-14)
    v_c, p_c = [model.v0_mean], [model.p0_mean]
    for j in range(model.n_steps):  # the reports' loop, literally
        p_c.append(p_c[-1] + v_c[-1] * model.dt + run.a_c[j] * model.dt**2 / 2)
        v_c.append(v_c[-1] + run.a_c[j] * model.dt)
    np.testing.assert_allclose(run.v_c, v_c, rtol=1e-12)
    np.testing.assert_allclose(run.p_c, p_c, rtol=1e-12)
    np.testing.assert_allclose(run.x[:, 0], run.p - run.p_c, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(run.x[:, 2], run.b)
    np.testing.assert_allclose(run.z, np.column_stack([run.gps_p - run.p_c[::40],
                                                       run.gps_v - run.v_c[::40]]), atol=1e-9)
    np.testing.assert_allclose(run.a_c[:-1], run.a[:-1] + run.b + run.w, rtol=1e-15)


@pytest.mark.parametrize("omega", [0.1, 1e-300, 50.0], ids=["report", "tiny-omega", "fast"])
def test_a_batch_is_simulate_called_again_and_again_to_the_bit(omega):
    """``simulate_many`` computes the truth's draw-free parts once for the batch: its runs are
    those of ``simulate`` called once per run on the one generator, every array to the bit, and
    the closed-form truth is ``model.position`` / ``model.velocity`` at each run's (p0, v0)."""
    model = CalibrationModel(omega=omega)
    for truth in ("error-model", "kinematic"):
        rng = np.random.default_rng(4)
        one_by_one = [simulate(model, rng, truth) for _ in range(3)]
        batch = simulate_many(model, 3, seed=4, truth=truth)
        for a, b in zip(one_by_one, batch, strict=True):
            for name, value in vars(a).items():
                np.testing.assert_array_equal(getattr(b, name), value, strict=True, err_msg=name)
            assert not np.shares_memory(a.a, b.a)                 # each run its own arrays
        assert not np.shares_memory(batch[0].a, batch[1].a)
        if truth == "kinematic":
            run = batch[-1]
            np.testing.assert_array_equal(run.p, model.position(model.t_imu, run.p0, run.v0))
            np.testing.assert_array_equal(run.v, model.velocity(model.t_imu, run.v0))
    with pytest.raises(ValueError, match="model must be a CalibrationModel"):
        simulate_many(object(), 2)
    with pytest.raises(ValueError, match="truth"):
        simulate_many(model, 2, truth="closed-form")


def test_same_generator_state_same_draws_for_both_truths(model):
    a = simulate(model, np.random.default_rng(7), "error-model")
    b = simulate(model, np.random.default_rng(7), "kinematic")
    assert (a.p0, a.v0, a.b) == (b.p0, b.v0, b.b)
    np.testing.assert_array_equal(a.w, b.w)
    np.testing.assert_array_equal(a.eta, b.eta)
    c = simulate(model, np.random.default_rng(7), "error-model")
    np.testing.assert_array_equal(a.z, c.z)


def test_draws_have_the_model_statistics(model):
    """500 realizations: sample moments within 4.5 standard errors (false alarm ~1e-5 per check)."""
    runs = simulate_many(model, 500, seed=11)
    x0 = np.array([r.x[0] for r in runs])
    sd0 = np.sqrt(np.diag(model.M0))
    assert np.all(np.abs(x0.mean(axis=0)) < 4.5 * sd0 / np.sqrt(500))
    eta = np.concatenate([r.eta for r in runs])
    w = np.concatenate([r.w for r in runs])
    n_eta, n_w = len(eta), len(w)
    np.testing.assert_allclose(eta.var(axis=0), np.diag(model.V),
                               rtol=4.5 * np.sqrt(2 / n_eta))
    assert abs(w.var() / 0.0004 - 1) < 4.5 * np.sqrt(2 / n_w)


def test_bad_input(model):
    with pytest.raises(ValueError, match="truth"):
        simulate(model, np.random.default_rng(0), truth="closed-form")
    with pytest.raises(ValueError, match="rng must be a numpy.random.Generator"):
        simulate(model, 0)
    with pytest.raises(ValueError, match="model must be a CalibrationModel"):
        simulate(object(), np.random.default_rng(0))
