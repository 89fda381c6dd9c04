"""The shared pieces: gain, Joseph update, epoch transition, the stepping loop (kalman.update)."""

from __future__ import annotations

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter

from gpsaccel.kalman.schedule import Schedule
from gpsaccel.kalman.update import (
    cross_gain,
    epoch_transition,
    gain,
    joseph_update,
    step_schedule,
)

RNG = np.random.default_rng(11)


def _spd(n: int) -> np.ndarray:
    A = RNG.standard_normal((n, n))
    return A @ A.T + n * np.eye(n)


def test_gain_is_M_Ht_S_inverse_even_for_a_non_symmetric_M():
    M, V, H = _spd(4), _spd(2), RNG.standard_normal((2, 4))
    M[0, 1] += 0.3  # not symmetric
    K, S = gain(M, H, V)
    np.testing.assert_allclose(S, H @ M @ H.T + V, rtol=1e-14)
    np.testing.assert_allclose(K, M @ H.T @ np.linalg.inv(S), rtol=1e-12)
    assert np.abs(K - M @ H.T @ np.linalg.inv(S).T).max() > 1e-3  # the other form is different


def test_the_inverse_form_is_filterpy_s_gain():
    """inverse=True (the vectorised Monte Carlo filters): K = (M Hᵀ)·inv(S), filterpy's form."""
    rng = np.random.default_rng(3)
    for n, p in ((3, 2), (6, 5), (2, 1)):
        A, B = rng.standard_normal((n, n)), rng.standard_normal((p, p))
        M, V, H = A @ A.T + n * np.eye(n), B @ B.T + np.eye(p), rng.standard_normal((p, n))
        kf = KalmanFilter(dim_x=n, dim_z=p)
        kf.P, kf.H, kf.R, kf.x = M.copy(), H, V, np.zeros((n, 1))
        kf.update(np.zeros((p, 1)))
        K, S = gain(M, H, V, inverse=True)
        assert np.array_equal(K, M @ H.T @ np.linalg.inv(H @ M @ H.T + V))
        np.testing.assert_allclose(K, kf.K, rtol=1e-12)
        np.testing.assert_allclose(S, kf.S, rtol=1e-14)
        np.testing.assert_allclose(K, gain(M, H, V)[0], rtol=1e-12)  # the solve: K to rounding
        C = M @ H.T                                                    # cross_gain: K = C S⁻¹
        np.testing.assert_allclose(cross_gain(C, S), K, rtol=1e-12)
        assert np.array_equal(cross_gain(C, S, inverse=True), K)


def test_joseph_equals_the_short_form_for_the_optimal_gain_and_is_exact_for_any_gain():
    M, V, H = _spd(3), _spd(2), RNG.standard_normal((2, 3))
    K, S = gain(M, H, V)
    np.testing.assert_allclose(joseph_update(M, K, H, V), (np.eye(3) - K @ H) @ M, rtol=1e-11,
                               atol=1e-13)
    # any other gain: the covariance of x − x̄ − K(H(x − x̄) + v) is the Joseph form
    K2 = K + 0.1 * RNG.standard_normal(K.shape)
    A = np.hstack([np.eye(3) - K2 @ H, -K2])
    joint = np.block([[M, np.zeros((3, 2))], [np.zeros((2, 3)), V]])
    np.testing.assert_allclose(joseph_update(M, K2, H, V), A @ joint @ A.T, rtol=1e-12)


def test_gain_and_joseph_broadcast_over_a_stack():
    Ms = np.stack([_spd(3) for _ in range(5)])
    H, V = RNG.standard_normal((2, 3)), _spd(2)
    K, S = gain(Ms, H, V)
    P = joseph_update(Ms, K, H, V)
    for c in range(5):
        Kc, Sc = gain(Ms[c], H, V)
        np.testing.assert_allclose(K[c], Kc, rtol=1e-13)
        np.testing.assert_allclose(P[c], joseph_update(Ms[c], Kc, H, V), rtol=1e-13)


def test_epoch_transition_is_n_predictions_composed():
    Phi = np.array([[1.0, 0.1], [0.0, 0.95]])
    Q = np.diag([1e-3, 2e-2])
    F, Qn = epoch_transition(Phi, Q, 7)
    np.testing.assert_allclose(F, np.linalg.matrix_power(Phi, 7), rtol=1e-14)
    expected = sum(np.linalg.matrix_power(Phi, j) @ Q @ np.linalg.matrix_power(Phi, j).T
                   for j in range(7))
    np.testing.assert_allclose(Qn, expected, rtol=1e-13)
    F0, Q0 = epoch_transition(Phi, Q, 0)
    np.testing.assert_array_equal(F0, np.eye(2))
    assert not Q0.any()
    with pytest.raises(ValueError, match="steps"):
        epoch_transition(Phi, Q, -1)


def test_step_schedule_predicts_every_step_and_updates_at_each_epoch_in_order():
    sched = Schedule.from_periods(10, [4, 4])  # epochs at steps 0, 4, 8
    calls: list[tuple[str, int]] = []
    step_schedule(sched, lambda k: calls.append(("predict", k)),
                  lambda i: calls.append(("update", i)), lambda k: calls.append(("at", k)))
    assert calls == [("at", 0), ("update", 0),
                     ("predict", 0), ("at", 1), ("predict", 1), ("at", 2), ("predict", 2),
                     ("at", 3), ("predict", 3), ("at", 4), ("update", 1),
                     ("predict", 4), ("at", 5), ("predict", 5), ("at", 6), ("predict", 6),
                     ("at", 7), ("predict", 7), ("at", 8), ("update", 2),
                     ("predict", 8), ("at", 9), ("predict", 9), ("at", 10)]
