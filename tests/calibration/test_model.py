"""CalibrationModel: report 000's numbers, the filterpy mapping, and bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gpsaccel import CalibrationModel


def test_defaults_are_report_000():
    m = CalibrationModel()
    dt = 0.005
    assert (m.dt, m.gps_every, m.duration) == (0.005, 40, 30.0)
    assert m.n_gps == 151 and m.n_steps == 6000
    np.testing.assert_array_equal(m.Phi, [[1, dt, -dt**2 / 2], [0, 1, -dt], [0, 0, 1]])
    np.testing.assert_array_equal(m.Gamma, -np.array([[dt**2 / 2], [dt], [0]]))
    np.testing.assert_array_equal(m.H, [[1, 0, 0], [0, 1, 0]])
    np.testing.assert_array_equal(m.V, np.diag([1.0, 0.0016]))
    np.testing.assert_array_equal(m.W, [[0.0004]])
    np.testing.assert_array_equal(m.M0, np.diag([100.0, 1.0, 0.01]))
    np.testing.assert_allclose(m.Q, 0.0004 * m.Gamma @ m.Gamma.T, rtol=0, atol=0)
    assert m.angular_frequency == 0.1
    assert m.t_gps[-1] == pytest.approx(30.0) and m.t_imu[-1] == pytest.approx(30.0)


def test_kalman_filter_mapping():
    m = CalibrationModel()
    kf = m.kalman_filter()
    np.testing.assert_array_equal(kf.F, m.Phi)
    np.testing.assert_array_equal(kf.Q, m.Gamma @ m.W @ m.Gamma.T)
    np.testing.assert_array_equal(kf.H, m.H)
    np.testing.assert_array_equal(kf.R, m.V)
    np.testing.assert_array_equal(kf.P, m.M0)
    np.testing.assert_array_equal(kf.x, np.zeros((3, 1)))
    kf.P[0, 0] = -1.0  # the filter owns copies: the model is not changed through it
    assert m.M0[0, 0] == 100.0


def test_frequency_conventions():
    f = 0.1 / (2 * math.pi)
    m = CalibrationModel(frequency_hz=f)
    assert m.angular_frequency == pytest.approx(0.1, rel=1e-15)
    t = np.linspace(0, 30, 7)
    np.testing.assert_allclose(m.acceleration(t), CalibrationModel().acceleration(t), rtol=1e-13)
    assert CalibrationModel(omega=2.0).angular_frequency == 2.0
    with pytest.raises(ValueError, match="omega and frequency_hz"):
        CalibrationModel(omega=0.1, frequency_hz=1.0)


def test_closed_form_truth_is_the_integral_of_a():
    m = CalibrationModel(accel_amplitude=3.0, omega=0.7)
    t = np.linspace(0, 30, 30001)
    v = m.velocity(t, v0=5.0)
    p = m.position(t, p0=-2.0, v0=5.0)
    np.testing.assert_allclose(np.gradient(v, t, edge_order=2), m.acceleration(t), atol=1e-5)
    np.testing.assert_allclose(np.gradient(p, t, edge_order=2), v, atol=1e-5)
    assert v[0] == 5.0 and p[0] == -2.0


def test_duration_multiple_with_floating_point_tolerance():
    # 30 % 0.2 is not 0 in floating point, yet 30 s is 150 GPS intervals of 0.2 s.
    assert 30.0 % 0.2 != 0.0
    assert CalibrationModel(duration=30.0).n_gps == 151
    assert CalibrationModel(dt=0.01, gps_every=20, duration=0.6).n_gps == 4


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"gps_every": 0}, "gps_every"),
        ({"gps_every": 40.0}, "gps_every must be an integer"),
        ({"gps_every": True}, "gps_every"),
        ({"dt": 0.0}, "dt"),
        ({"dt": -0.005}, "dt"),
        ({"dt": float("nan")}, "dt"),
        ({"duration": 30.1}, "duration"),
        ({"duration": 0.1}, "duration"),
        ({"V": [[1.0, 0.1], [0.0, 0.0016]]}, "V must be symmetric"),
        ({"V": np.diag([1.0, -0.0016])}, "V must be positive definite"),
        ({"V": np.eye(3)}, "V must be a 2 x 2"),
        ({"M0": np.diag([100.0, 1.0, 0.0])}, "M0 must be positive definite"),
        ({"M0": np.diag([100.0, np.nan, 0.01])}, "M0 contains NaN"),
        ({"W": -0.0004}, "W must be positive definite"),
        ({"W": float("inf")}, "W contains NaN or inf"),
        ({"omega": 0.0}, "omega"),
        ({"accel_amplitude": float("inf")}, "accel_amplitude"),
    ],
)
def test_bad_input_names_the_argument(kwargs, match):
    with pytest.raises(ValueError, match=match):
        CalibrationModel(**kwargs)


def test_replace_validates_again():
    m = CalibrationModel().replace(W=0.0016)
    assert m.W[0, 0] == 0.0016
    with pytest.raises(ValueError, match="gps_every"):
        CalibrationModel().replace(gps_every=-1)
