"""The hand-written information-form filter (kalman.information) against the covariance form."""

from __future__ import annotations

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter

from gpsaccel.kalman.information import InformationFilter
from gpsaccel.kalman.update import gain, joseph_update

RNG = np.random.default_rng(3)
Phi = np.array([[1.0, 0.1, -0.005], [0.0, 1.0, -0.1], [0.0, 0.0, 1.0]])
Q = np.diag([1e-6, 1e-4, 0.0])
H = np.eye(2, 3)
V = np.diag([1.0, 0.0016])
M0 = np.diag([100.0, 1.0, 0.01])


def test_one_update_is_the_covariance_forms_update():
    f = InformationFilter(Phi, Q, H, V, np.zeros(3), M0)
    z = np.array([0.3, -0.02])
    f.update(z)
    K, _ = gain(M0, H, V)
    np.testing.assert_allclose(f.P, joseph_update(M0, K, H, V), rtol=1e-12)
    np.testing.assert_allclose(f.K, K, rtol=1e-12)
    np.testing.assert_allclose(f.x[:, 0], K @ z, rtol=1e-12)
    np.testing.assert_array_equal(f.P, f.P.T)  # symmetric to the last bit
    np.testing.assert_allclose(f.y[:, 0], z)
    np.testing.assert_array_equal(f.M, M0)


def test_matches_filterpy_step_by_step_with_a_known_input_and_partial_rows():
    B = np.array([[0.0], [0.1], [0.0]])
    f = InformationFilter(Phi, Q, H, V, np.zeros(3), M0, B=B)
    kf = KalmanFilter(dim_x=3, dim_z=2, dim_u=1)
    kf.F, kf.Q, kf.H, kf.R, kf.P, kf.B = Phi, Q, H, V.copy(), M0.copy(), B
    for k in range(30):
        u = np.array([[np.sin(k / 5)]])
        f.predict(u=u)
        kf.predict(u=u)
        np.testing.assert_allclose(f.P, kf.P, rtol=1e-10)
        z = RNG.standard_normal(2)
        rows = [0] if k % 3 else [0, 1]
        f.update(z[rows], R=V[np.ix_(rows, rows)], H=H[rows])
        kf.update(z[rows].reshape(-1, 1), R=V[np.ix_(rows, rows)], H=H[rows])
        np.testing.assert_allclose(f.x, kf.x, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(f.P, kf.P, rtol=1e-9, atol=1e-15)
    assert f.x_hat is f.x


def test_input_without_B_is_refused():
    f = InformationFilter(Phi, Q, H, V, np.zeros(3), M0)
    with pytest.raises(ValueError, match="u was given but the filter has no control-input"):
        f.predict(u=np.ones((1, 1)))
