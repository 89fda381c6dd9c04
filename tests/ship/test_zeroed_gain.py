"""Report 004's zeroed-gain update, a hook of the multirate driver."""

from __future__ import annotations

import numpy as np

from gpsaccel.kalman.update import joseph_update as joseph
from gpsaccel.ship.model import GPS_ROWS
from gpsaccel.ship.simulation import simulate_ship
from gpsaccel.ship.zeroed_gain import run_zeroed_gain


def test_zeroed_gain_applies_the_full_gain_with_gps_columns_zeroed(model):
    run = simulate_ship(model, np.random.default_rng(6))
    sched = model.schedule(multirate=True)
    res = run_zeroed_gain(model, run.measurements(sched), schedule=sched, u=run.u)
    for i in (4, 9):
        M = res.M[i]
        K_full = M @ np.linalg.inv(M + model.V)
        np.testing.assert_allclose(res.K_full[i], K_full, rtol=1e-9, atol=1e-14)
        expected = K_full.copy()
        expected[:, list(GPS_ROWS)] *= sched.mask[i, list(GPS_ROWS)]
        np.testing.assert_allclose(res.K[i], expected, rtol=1e-9, atol=1e-14)
        np.testing.assert_allclose(res.P[i], joseph(M, res.K[i], model.H, model.V), rtol=1e-12)
    np.testing.assert_array_equal(res.P, res.P_actual)


def test_report_covariance_gain_is_the_reports_C_Ht_S_inverse(model):
    """With the report's (I − K H) M the carried covariance C is not symmetric, so neither is
    S = H C Hᵀ + V, and K = C Hᵀ S⁻¹ (the report's ``Rpred*An'/(...)``) differs from
    C Hᵀ S⁻ᵀ.  The gain must be the former (the driver once computed the latter)."""
    run = simulate_ship(model, np.random.default_rng(6))
    sched = model.schedule(multirate=True)
    res = run_zeroed_gain(model, run.measurements(sched), schedule=sched, u=run.u,
                          covariance="report")
    H, V = model.H, model.V
    worst_asym, worst_gap = 0.0, 0.0
    for i in range(sched.n_epochs):
        C = res.M[i]
        S_inv = np.linalg.inv(H @ C @ H.T + V)
        np.testing.assert_allclose(res.K_full[i], C @ H.T @ S_inv, rtol=1e-9, atol=1e-13)
        worst_asym = max(worst_asym, np.abs(C - C.T).max() / np.abs(C).max())
        gap = np.abs(C @ H.T @ S_inv.T - C @ H.T @ S_inv).max() / np.abs(C @ H.T @ S_inv).max()
        worst_gap = max(worst_gap, gap)
    # the test can tell the two forms apart: the carried C is visibly non-symmetric (4e-4
    # measured) and the transposed inverse would move the gain by 0.7 % of its size
    assert worst_asym > 1e-5
    assert worst_gap > 1e-3


def test_joseph_variant_carries_a_symmetric_covariance(model):
    run = simulate_ship(model, np.random.default_rng(7))
    sched = model.schedule(multirate=True)
    res = run_zeroed_gain(model, run.measurements(sched), schedule=sched, u=run.u)
    scale = np.abs(res.P).max(axis=(1, 2))
    assert (np.abs(res.P - np.swapaxes(res.P, 1, 2)).max(axis=(1, 2)) / scale).max() < 1e-14
