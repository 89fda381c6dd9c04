"""Parameter hygiene: arguments that used to fail deep inside (AttributeError, ZeroDivisionError,
a ComplexWarning, NaN with overflow warnings) or were silently accepted get a ValueError that
names them, or a warning that says what is wrong."""

from __future__ import annotations

import warnings

import mpmath
import numpy as np
import pytest

from gpsaccel import CalibrationModel, CoopModel, ShipModel, run_multirate, simulate
from gpsaccel.calibration.model import _one_minus_cos_over, _x_minus_sin_over_square
from gpsaccel.coop.filters import run_batch, run_ukf
from gpsaccel.kalman.multirate import MissingInputWarning
from gpsaccel.ship.simulation import simulate_ship

COOP = CoopModel()


@pytest.fixture(scope="module")
def coop_log():
    return COOP.simulate(np.random.default_rng(0), 1).y[0]


@pytest.mark.parametrize("kwargs, message", [
    ({"alpha": 0.0}, r"alpha must be in \(0, 1\]"),
    ({"alpha": -1.0}, r"alpha must be in \(0, 1\]"),
    ({"alpha": 1.5}, r"alpha must be in \(0, 1\]"),
    ({"beta": -0.5}, "beta must be >= 0"),
    ({"beta": float("nan")}, "beta must be finite"),
    ({"kappa": -6.0}, "kappa must be > -6"),
    ({"kappa": float("inf")}, "kappa must be finite"),
])
def test_ukf_sigma_point_parameters_are_validated(coop_log, kwargs, message):
    with pytest.raises(ValueError, match=message):
        run_ukf(COOP, coop_log, **kwargs)


def test_ukf_accepts_its_valid_range(coop_log):
    for kwargs in ({"alpha": 1e-3}, {"alpha": 1.0, "beta": 0.0, "kappa": -5.5}):
        assert np.isfinite(run_ukf(COOP, coop_log, **kwargs).x_hat).all()


def test_non_model_and_bad_schedule_are_value_errors():
    with pytest.raises(ValueError, match="model must be a linear-Gaussian model .* got str"):
        run_multirate("report 000", np.zeros((151, 2)))
    with pytest.raises(ValueError, match="schedule must be a gpsaccel.Schedule, got str|"
                                         "schedule must be a gpsaccel.Schedule"):
        run_multirate(CalibrationModel(), np.zeros((151, 2)), schedule="abc")


def test_coop_simulate_wants_a_generator():
    with pytest.raises(ValueError, match="rng must be a numpy.random.Generator.*got int"):
        COOP.simulate(0)


def test_complex_measurements_are_refused_not_cast():
    z = np.zeros((151, 2), dtype=complex)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no ComplexWarning on the way
        with pytest.raises(ValueError, match="z must be real"):
            run_multirate(CalibrationModel(), z)
        with pytest.raises(ValueError, match="z must be real"):
            run_multirate(CalibrationModel(), [[0.0, 1j]] * 151)
        with pytest.raises(ValueError, match="M0 must be real"):
            CalibrationModel(M0=np.eye(3) * (1 + 0j))


def test_run_batch_with_zero_runs_says_so():
    with pytest.raises(ValueError, match="y holds no run"):
        run_batch("ekf", COOP, np.zeros((0, COOP.n_steps + 1, 5)))


def test_ship_filtered_without_its_input_warns():
    """Without u the filter predicts with u = 0: the ship's RMSE grows many times over."""
    model = ShipModel()
    run = simulate_ship(model, np.random.default_rng(0))
    sched = model.schedule(multirate=True)
    z = run.measurements(sched)
    with warnings.catch_warnings():
        warnings.simplefilter("error", MissingInputWarning)
        good = run_multirate(model, z, schedule=sched, u=run.u)
    with pytest.warns(MissingInputWarning, match="ShipModel has a control input .* no u was given"):
        bad = run_multirate(model, z, schedule=sched)
    truth = run.x[sched.steps]
    rmse = [np.sqrt(np.mean((r.x_hat[:, :2] - truth[:, :2]) ** 2)) for r in (good, bad)]
    assert rmse[1] > 5 * rmse[0], rmse  # measured (seed 0): 0.31 m with u, 5.8 m without
    with warnings.catch_warnings():  # a model without B: nothing to warn about
        warnings.simplefilter("error", MissingInputWarning)
        run_multirate(CalibrationModel(), simulate(CalibrationModel(), np.random.default_rng(0)).z)


def test_tiny_omega_gives_the_constant_acceleration_limit():
    """ω = 1e-300 used to divide by zero (A/ω² overflows, ω² underflows); the stable closed form
    gives the limit a(t) = A ω t → v = v0 + A ω t²/2 ≈ v0, p ≈ p0 + v0 t."""
    model = CalibrationModel(omega=1e-300)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        run = simulate(model, np.random.default_rng(0), "kinematic")
    assert np.isfinite(run.p).all() and np.isfinite(run.x_gps).all()
    t = model.t_imu
    np.testing.assert_allclose(model.velocity(t, 3.0), 3.0, rtol=0, atol=0)
    np.testing.assert_allclose(model.position(t, 1.0, 3.0), 1.0 + 3.0 * t, rtol=1e-15)


def test_huge_amplitude_is_refused_at_construction():
    with pytest.raises(ValueError, match="accel_amplitude = 1e\\+308 .* beyond float64"):
        CalibrationModel(accel_amplitude=1e308)
    CalibrationModel(accel_amplitude=1e150)  # large but representable: accepted


@pytest.mark.parametrize("x", [1e-12, 1e-5, 0.0099, 0.0101, 0.5, 0.999, 1.001, 3.0, 29.9])
def test_stable_closed_form_pieces_against_50_digits(x):
    mpmath.mp.dps = 80
    X = mpmath.mpf(x)
    g = (X - mpmath.sin(X)) / X**2
    f = (1 - mpmath.cos(X)) / X
    assert abs(float((_x_minus_sin_over_square(np.array(x)) - g) / g)) < 4e-16
    assert abs(float((_one_minus_cos_over(np.array(x)) - f) / f)) < 4e-16


def test_reports_closed_form_unchanged_to_rounding():
    model = CalibrationModel()
    t = model.t_imu
    w, A = model.angular_frequency, model.accel_amplitude
    np.testing.assert_allclose(model.velocity(t, 100.0), 100 + A / w * (1 - np.cos(w * t)),
                               rtol=1e-14)
    np.testing.assert_allclose(model.position(t, 0.0, 100.0),
                               (100 + A / w) * t - A / w**2 * np.sin(w * t), rtol=1e-13, atol=1e-12)
