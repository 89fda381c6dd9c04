"""Report 004's ship model: matrices, schedules, the multirate driver on it, bad input."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel.calibration.model import CalibrationModel
from gpsaccel.kalman.gain_sequence import apply_gains
from gpsaccel.kalman.multirate import run_multirate
from gpsaccel.ship.model import GPS_ROWS, REPORT_VARIANCES, ShipModel
from gpsaccel.ship.plan import nominal_plan
from gpsaccel.ship.simulation import simulate_ship
from gpsaccel.ship.zeroed_gain import run_zeroed_gain

IMU_ROWS = [c for c in range(9) if c not in GPS_ROWS]


def test_matrices_are_the_reports(model):
    Ts, (bx, by, bpsi) = 0.1, (0.4462, 0.0784, 1.3)
    Phi = model.Phi
    assert Phi.shape == (9, 9)
    np.testing.assert_array_equal(Phi[0], [1, Ts, Ts**2 / 2, 0, 0, 0, 0, 0, 0])
    np.testing.assert_array_equal(Phi[2], [0, -bx, 0, 0, 0, 0, 0, 0, 0])   # garbled row 3
    np.testing.assert_array_equal(Phi[5], [0, 0, 0, 0, -by, 0, 0, 0, 0])
    np.testing.assert_array_equal(Phi[6], [0, 0, 0, 0, 0, 0, 1, Ts, Ts**2 / 2])  # garbled row 7
    np.testing.assert_array_equal(Phi[8], [0, 0, 0, 0, 0, 0, 0, -bpsi, 0])
    off_block = Phi.copy()
    for i in (0, 3, 6):
        off_block[i:i + 3, i:i + 3] = 0
    assert not off_block.any()
    np.testing.assert_array_equal(model.V, np.diag(REPORT_VARIANCES))
    np.testing.assert_array_equal(model.H, np.eye(9))
    assert model.inertia == pytest.approx(12 * (0.25**2 + 1.05**2) / 12)
    # Q = Γ W Γᵀ with the random force where the input acts: rank 3, only acceleration rows
    assert np.linalg.matrix_rank(model.Q) == 3
    np.testing.assert_allclose(np.diag(model.Q)[[2, 5, 8]],
                               [0.25 / 144, 0.25 / 144, 0.0025 / model.inertia**2])
    np.testing.assert_array_equal(model.Gamma, model.B)


def test_kalman_filter_mapping(model):
    kf = model.kalman_filter()
    for ours, theirs in ((model.Phi, kf.F), (model.B, kf.B), (model.Q, kf.Q), (model.H, kf.H),
                         (model.V, kf.R), (model.M0, kf.P)):
        np.testing.assert_array_equal(ours, theirs)
    np.testing.assert_array_equal(kf.x[:, 0], model.x0)


def test_schedules(model):
    mono, multi = model.schedule(multirate=False), model.schedule(multirate=True)
    np.testing.assert_array_equal(mono.steps, np.arange(1, 1000))
    assert mono.mask.all()
    np.testing.assert_array_equal(multi.steps, np.arange(1, 1000))
    assert multi.mask[:, IMU_ROWS].all()
    gps_steps = multi.steps[multi.mask[:, 0]]
    np.testing.assert_array_equal(gps_steps, np.arange(10, 1000, 10))
    np.testing.assert_array_equal(multi.mask[:, 0], multi.mask[:, 3])
    slow = model.replace(gps_rate_hz=0.5, imu_rate_hz=5.0).schedule()
    np.testing.assert_array_equal(slow.steps, np.arange(2, 1000, 2))
    assert slow.mask[:, IMU_ROWS].all()
    np.testing.assert_array_equal(slow.steps[slow.mask[:, 0]], np.arange(20, 1000, 20))


@pytest.mark.parametrize("method", ["filterpy", "information"])
def test_driver_against_a_hand_computed_update_on_the_reduced_H(model, method):
    run = simulate_ship(model, np.random.default_rng(3))
    sched = model.schedule(multirate=True)
    z = run.measurements(sched)
    res = run_multirate(model, z, method=method, schedule=sched, u=run.u)
    Phi, Q, H, V, B = model.Phi, model.Q, model.H, model.V, model.B
    # first prediction, by hand: x̄1 = Φ x0 + B u0, M1 = Φ M0 Φᵀ + Q
    np.testing.assert_allclose(res.x_bar[0], Phi @ model.x0 + B @ run.u[0], rtol=1e-12)
    np.testing.assert_allclose(res.M[0], Phi @ model.M0 @ Phi.T + Q, rtol=1e-12)
    for i, rows in ((4, IMU_ROWS), (9, list(range(9)))):  # k = 5 (no GPS), k = 10 (GPS)
        assert list(np.flatnonzero(sched.mask[i])) == rows
        xb, M = res.x_bar[i], res.M[i]
        Hr, Vr = H[rows], V[np.ix_(rows, rows)]
        Kr = M @ Hr.T @ np.linalg.inv(Hr @ M @ Hr.T + Vr)
        x_hat = xb + Kr @ (z[i, rows] - Hr @ xb)
        P = (np.eye(9) - Kr @ Hr) @ M
        np.testing.assert_allclose(res.x_hat[i], x_hat, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(res.P[i], P, rtol=1e-8, atol=1e-14)
        np.testing.assert_allclose(res.K[i][:, rows], Kr, rtol=1e-8, atol=1e-14)
        missing = [c for c in range(9) if c not in rows]
        assert not res.K[i][:, missing].any()
    # ... and the hand gain on the reduced H is not the report's zeroed full gain
    i = 4
    K_full = res.M[i] @ np.linalg.inv(res.M[i] + V)
    assert np.abs(K_full[:, IMU_ROWS] - res.K[i][:, IMU_ROWS]).max() > 1e-6


@pytest.mark.parametrize("method", ["filterpy", "information"])
def test_known_input_equals_filtering_the_deviation_from_the_plan(model, method):
    """Superposition: with u, x̂ = x_plan + δx̂, δx̂ from z − H x_plan with no input."""
    run = simulate_ship(model, np.random.default_rng(4))
    sched = model.schedule(multirate=True)
    z = run.measurements(sched)
    with_u = run_multirate(model, z, method=method, schedule=sched, u=run.u)
    plan = nominal_plan(model)[: model.n_samples]
    # x0 of the model is the plan's start, so the deviation filter starts from 0
    dev = run_multirate(_ZeroMean(model), z - plan[sched.steps], method=method, schedule=sched)
    np.testing.assert_allclose(with_u.x_hat, plan[sched.steps] + dev.x_hat, atol=1e-9)
    np.testing.assert_allclose(with_u.P, dev.P, rtol=1e-12, atol=1e-16)


class _ZeroMean:
    """The ship model with x0 = 0 and no input: the filter of deviations from the plan."""

    def __init__(self, model):
        self._m = model
        self.x0 = np.zeros(9)

    def __getattr__(self, name):
        return getattr(self._m, name)

    def kalman_filter(self):
        kf = self._m.kalman_filter()
        kf.x = np.zeros((9, 1))
        kf.B = None
        return kf

    B = None




@pytest.mark.parametrize("kwargs, match", [
    ({"gps_rate_hz": 3.0}, "gps_rate_hz"),
    ({"imu_rate_hz": 20.0}, "imu_rate_hz"),
    ({"V": np.diag([1.0] * 8 + [-1.0])}, "V must be positive definite"),
    ({"M0_ship": np.ones((9, 9))}, "M0_ship must be positive definite"),
    ({"W": np.eye(2)}, "W must be a 3 x 3"),
    ({"beta": (0.4, 0.1)}, "beta"),
    ({"dt": 0.0}, "dt"),
    ({"wind_drift": -1.0}, "wind_drift"),
])
def test_bad_model_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        ShipModel(**kwargs)


def test_bad_run_input(model):
    run = simulate_ship(model, np.random.default_rng(0))
    sched = model.schedule()
    z = run.measurements(sched)
    with pytest.raises(ValueError, match="available"):
        model.schedule_from_mask(np.ones((999, 9), dtype=bool))
    with pytest.raises(ValueError, match="u must have shape"):
        run_multirate(model, z, schedule=sched, u=run.u[:-1])
    with pytest.raises(ValueError, match="B"):
        cal = CalibrationModel()
        run_multirate(cal, np.zeros((cal.n_gps, 2)), u=np.zeros((cal.n_steps, 1)))
    with pytest.raises(ValueError, match="covariance"):
        run_zeroed_gain(model, z, schedule=sched, u=run.u, covariance="short")
    with pytest.raises(ValueError, match="schedule must cover"):
        run.measurements(model.replace(n_samples=500).schedule())
    with pytest.raises(ValueError, match="wind_force"):
        simulate_ship(model, np.random.default_rng(0), wind_force=(1.0, 2.0, 3.0))
    res = run_multirate(model, z, schedule=sched, u=run.u)
    z_bad = z.copy()
    z_bad[4, 1] = np.nan  # an IMU row the gain uses
    with pytest.raises(ValueError, match="z is NaN where the gain"):
        apply_gains(model.Phi, model.H, model.x0, sched, res.K, z_bad[None], B=model.B, u=run.u)
