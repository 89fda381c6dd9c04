"""The multirate driver, filterpy against the hand-written information form, and by-hand values."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel import CalibrationModel, run_multirate, simulate
from gpsaccel.calibration.compare import differences


@pytest.fixture(scope="module")
def model():
    return CalibrationModel()


@pytest.fixture(scope="module", params=["error-model", "kinematic"])
def both(model, request):
    run = simulate(model, np.random.default_rng(5), truth=request.param)
    return run, run_multirate(model, run.z), run_multirate(model, run.z, method="information")


def test_forms_agree_to_1e10(both):
    _, fp, info = both
    dx, dP = differences(fp.x_hat, fp.P, info.x_hat, info.P)
    assert dx < 1e-10 and dP < 1e-10
    dx, dM = differences(fp.x_bar, fp.M, info.x_bar, info.M)
    assert dx < 1e-10 and dM < 1e-10
    np.testing.assert_allclose(info.K, fp.K, rtol=1e-9, atol=1e-14)


def test_P_at_t0_by_hand(both):
    for res in both[1:]:
        np.testing.assert_allclose(res.P[0], np.diag([100 / 101, 0.0016 / 1.0016, 0.01]),
                                   rtol=1e-13, atol=1e-16)
        np.testing.assert_array_equal(res.M[0], np.diag([100.0, 1.0, 0.01]))


def test_P_at_30s_matches_the_reports_and_an_independent_gps_rate_recursion(model, both):
    """At the GPS rate the 40 steps are one step with Φ⁴⁰ and Q₄₀ = Σ Φᵏ Q Φᵏᵀ (k < 40)."""
    Phi40 = np.linalg.matrix_power(model.Phi, 40)
    Q40 = sum(np.linalg.matrix_power(model.Phi, k) @ model.Q @ np.linalg.matrix_power(model.Phi, k).T
              for k in range(40))
    H, V = model.H, model.V
    M = model.M0
    for _ in range(151):
        S = H @ M @ H.T + V
        K = M @ H.T @ np.linalg.inv(S)
        P = (np.eye(3) - K @ H) @ M
        M = Phi40 @ P @ Phi40.T + Q40
    for res in both[1:]:
        np.testing.assert_allclose(res.P[-1], P, rtol=1e-9, atol=1e-15)
        np.testing.assert_allclose(np.diag(res.P[-1]), [9.504e-3, 4.759e-5, 2.153e-7], rtol=5e-4)


def test_residuals_and_gains_are_consistent(both):
    run, fp, _ = both
    np.testing.assert_allclose(fp.r, run.z - fp.x_bar[:, :2], rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(fp.x_hat, fp.x_bar + np.einsum("kij,kj->ki", fp.K, fp.r),
                               rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(fp.S, fp.M[:, :2, :2] + np.diag([1.0, 0.0016]), rtol=1e-14)


def test_fast_grid_propagates_between_fixes(model, both):
    _, fp, _ = both
    assert fp.x_fast.shape == (6001, 3)
    np.testing.assert_array_equal(fp.x_fast[::40], fp.x_bar)
    np.testing.assert_array_equal(fp.M_fast[::40], fp.M)
    x = fp.x_hat[3]
    for _ in range(17):
        x = model.Phi @ x
    np.testing.assert_allclose(fp.x_fast[3 * 40 + 17], x, rtol=1e-13)


@pytest.mark.parametrize("method", ["filterpy", "information"])
def test_outage_propagates_only(model, method):
    run = simulate(model, np.random.default_rng(9))
    z = run.z.copy()
    z[50:75] = np.nan  # a 5-second outage
    res = run_multirate(model, z, method=method)
    np.testing.assert_array_equal(res.K[50:75], 0.0)
    np.testing.assert_array_equal(res.P[50:75], res.M[50:75])
    np.testing.assert_array_equal(res.x_hat[50:75], res.x_bar[50:75])
    assert np.isnan(res.r[50:75]).all() and not res.used[50:75].any()
    sd = res.sigma
    assert np.all(np.diff(sd[50:75, 0]) > 0)  # position uncertainty grows during the outage
    assert sd[75, 0] < sd[74, 0]              # and shrinks at the first fix after it
    nominal = run_multirate(model, run.z, method=method).sigma
    excess = sd / nominal  # 1 where the outage has been forgotten
    assert np.all(excess[74] > 1.4) and np.all(excess[-1] < 1.1)  # recovering, all three states


def test_partial_measurement_uses_the_remaining_rows(model):
    """Velocity only at one epoch: the update on the reduced H = [0 1 0], V = 0.0016, by hand."""
    run = simulate(model, np.random.default_rng(10))
    z = run.z.copy()
    z[20, 0] = np.nan
    res = run_multirate(model, z)
    info = run_multirate(model, z, method="information")
    M, xb = res.M[20], res.x_bar[20]
    h = np.array([[0.0, 1.0, 0.0]])
    s = (h @ M @ h.T)[0, 0] + 0.0016
    k = M @ h.T / s
    np.testing.assert_allclose(res.K[20][:, 1], k[:, 0], rtol=1e-12)
    np.testing.assert_array_equal(res.K[20][:, 0], 0.0)
    np.testing.assert_allclose(res.x_hat[20], xb + k[:, 0] * (z[20, 1] - xb[1]), rtol=1e-12)
    np.testing.assert_allclose(res.P[20], M - k @ h @ M, rtol=1e-10, atol=1e-15)
    dx, dP = differences(res.x_hat, res.P, info.x_hat, info.P)
    assert dx < 1e-10 and dP < 1e-10


def test_bad_input(model):
    z = simulate(model, np.random.default_rng(0)).z
    with pytest.raises(ValueError, match="method"):
        run_multirate(model, z, method="joseph")
    with pytest.raises(ValueError, match=r"z must have shape \(151 x 2\)"):
        run_multirate(model, z[:-1])
    with pytest.raises(ValueError, match=r"z must have shape"):
        run_multirate(model, z.T)
    bad = z.copy()
    bad[3, 1] = np.inf
    with pytest.raises(ValueError, match="z contains an infinite value"):
        run_multirate(model, bad)


def test_epoch_transition_composes_the_fast_steps(model):
    from gpsaccel.kalman.update import epoch_transition

    F, Qe = epoch_transition(model.Phi, model.Q, 40)
    powers = [np.linalg.matrix_power(model.Phi, k) for k in range(41)]
    np.testing.assert_allclose(F, powers[40], rtol=1e-15)
    np.testing.assert_allclose(Qe, sum(Pk @ model.Q @ Pk.T for Pk in powers[:40]), rtol=1e-12)
    dt = 0.2  # Φ(Δt)⁴⁰ = Φ(40Δt): the bias integrates exactly over the GPS interval
    np.testing.assert_allclose(F, [[1, dt, -dt**2 / 2], [0, 1, -dt], [0, 0, 1]], rtol=1e-13)
    with pytest.raises(ValueError, match="steps"):
        epoch_transition(model.Phi, model.Q, -1)
