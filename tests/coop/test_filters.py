"""LKF, EKF, UKF for cooperative localization (report 002): agreement, consistency, the log."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel.coop import filters as nl
from gpsaccel.coop import model as coop
from gpsaccel.coop.model import CoopModel
from gpsaccel.coop.montecarlo import (
    consistency_test,
    repeated_sets,
    repeated_sets_by_q,
    set_seeds,
    truth_runs,
    tune_q,
)
from gpsaccel.kalman import consistency


def _oracle():
    """tests/coop/filterpy_oracle.py: filterpy's own filters, the oracle (not a package)."""
    import importlib.util
    from pathlib import Path

    spec = importlib.util.spec_from_file_location(
        "filterpy_oracle", Path(__file__).with_name("filterpy_oracle.py"))
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


filterpy_oracle = _oracle()

MODEL = CoopModel()


@pytest.fixture(scope="module")
def truth3():
    return MODEL.simulate(np.random.default_rng(42), n_runs=3)


@pytest.mark.parametrize("method", nl.METHODS)
def test_vectorised_filter_equals_filterpy(method, truth3):
    # the one filter (inverse-based gain, as filterpy) against filterpy's own objects: 1e-10
    # (measured 3e-14 relative: a vectorised matmul sums in another order than filterpy's dot).
    # filterpy's UKF takes 3 s a run: it checks run 0 over the whole 100 s here; every run of a
    # batch against it alone is test_runs_missing_different_components_are_updated_in_groups
    batch = nl.run_batch(method, MODEL, truth3.y)
    for i in range(1 if method == "ukf" else truth3.n_runs):
        one = filterpy_oracle.RUNNERS[method](MODEL, truth3.y[i])
        np.testing.assert_allclose(coop.state_residual(batch.x_hat[i], one.x_hat), 0,
                                   atol=1e-10)
        np.testing.assert_allclose(batch.P[i], one.P, atol=1e-10)
        np.testing.assert_allclose(batch.r[i], one.r, atol=1e-10)
        np.testing.assert_allclose(batch.S[i], one.S, atol=1e-10)


@pytest.mark.parametrize("method", nl.METHODS)
def test_nis_is_the_per_vector_solve_bit_for_bit(method, truth3):
    # FilterResult.nis is consistency.nis, which solves one stack per pattern of measured
    # components; the lessons' tagged NIS fractions were printed from a loop of one solve per
    # (run, step), so equal, not close, on a filter's own residual log (row 0 NaN, S in full).
    # The first 30 s (300 steps of each of the three runs; a step's equality is its own): the
    # whole 100 s cost 2 s of the loop of solves below
    model = CoopModel(duration=30.0)
    clean = truth3.y[:, :model.n_steps + 1]
    y = clean.copy()
    y[np.random.default_rng(5).random(y.shape) < 0.1] = np.nan   # mixed patterns, some rows empty
    y[1, 7] = np.nan
    for log in (clean, y):
        res = nl.run_batch(method, model, log)
        slow = np.zeros(res.r.shape[:-1])
        for i, j in np.ndindex(*slow.shape):
            r, m = res.r[i, j], np.isfinite(res.r[i, j])
            if m.any():
                slow[i, j] = r[m] @ np.linalg.solve(res.S[i, j][np.ix_(m, m)], r[m])
        assert np.array_equal(res.nis(), slow)
        assert np.array_equal(res.nis(), consistency.nis(res.r, res.S))
        assert slow[1, 7] == 0.0 or log is clean


@pytest.fixture(scope="module")
def truths():
    # 5 independent 50-run sets; seed 44 is not the tuning seed (2024)
    return [truth_runs(MODEL, 50, s) for s in set_seeds(44, 5)]


@pytest.fixture(scope="module")
def ekf_both(truths):
    # the five sets with the tuned Q and with Qtrue in three filter calls, not ten: each set's
    # numbers are its own call's, bit for bit (tests/coop/test_montecarlo.py), and a call's
    # per-step cost is shared
    return repeated_sets_by_q(MODEL, "ekf", {"tuned": None, "qtrue": MODEL.Qtrue}, truths=truths)


@pytest.fixture(scope="module")
def ekf_sets(ekf_both):
    return ekf_both["tuned"]


def test_tuned_ekf_passes_nees_and_nis_over_five_sets(ekf_sets):
    # For a consistent filter each fraction is ~0.95 (alpha = 0.05); NEES is correlated in time,
    # so one 50-run set scatters by several points.  The issue's acceptance: mean over 5 sets
    # >= 0.88 (NEES) and >= 0.90 (NIS).  The seeds are fixed: the test is deterministic.
    nees = np.mean([r.nees_fraction for r in ekf_sets])
    nis = np.mean([r.nis_fraction for r in ekf_sets])
    assert nees >= 0.88, nees
    assert nis >= 0.90, nis
    assert ekf_sets[0].nees_bounds == consistency.chi2_bounds(6, 50, 0.05)


def test_ekf_with_qtrue_is_overconfident_along_track(ekf_both):
    # same truth runs, Q = Qtrue: the predicted mean ignores E[cos(θ+δ)] = cos θ·e^(−σ²/2), so the
    # average NEES sits above n = 6 (the tuned Q, which inflates the position terms, fixes it)
    plain = ekf_both["qtrue"]
    assert len(plain) == 5 and np.array_equal(plain[0].Q, MODEL.Qtrue)
    mean_nees = np.mean([r.nees_mean.mean() for r in plain])
    assert mean_nees > 6.4, mean_nees
    assert np.mean([r.nees_fraction for r in plain]) < 0.85


def test_ukf_with_its_tuned_q_passes_nees_and_nis():
    runs = repeated_sets(MODEL, "ukf", n_sets=2, n_runs=50, seed=45)
    assert np.mean([r.nees_fraction for r in runs]) >= 0.88
    assert np.mean([r.nis_fraction for r in runs]) >= 0.90


def test_lkf_cannot_be_consistent_over_100_s():
    run = consistency_test(MODEL, "lkf", n_runs=30, seed=46, keep=True)
    xn = MODEL.nominal()
    drift = np.hypot(*(run.truth.x[:, -1, 3:5] - xn[-1, 3:5]).T)
    assert np.median(drift) > 100.0  # the truth wanders hundreds of metres from the nominal
    assert run.nees_fraction < 0.5
    assert run.nees_mean[-100:].mean() > 10 * run.nees_bounds[1]


def test_tuning_prefers_an_inflated_position_q_for_the_ekf():
    grid = ((1.0, 2.0), (1.0, 2.0), (1.0,))
    res = tune_q(MODEL, "ekf", grid=grid, n_runs=50, seed=2024)
    assert len(res.scales) == 4
    assert res.best != (1.0, 1.0, 1.0)
    i = res.scales.index((1.0, 1.0, 1.0))
    assert res.nees_fraction[i] < res.nees_fraction[res.scales.index(res.best)]


def test_filters_on_the_course_log_keep_every_innovation_finite():
    y = MODEL.log()
    for method in nl.METHODS:
        res = nl.run_filter(method, MODEL, y)
        assert np.isnan(res.r[0]).all()  # t = 0 is not measured: no update
        assert np.isfinite(res.r[1:]).all(), method
        assert np.isfinite(res.x_hat).all() and np.isfinite(res.P).all()
        np.testing.assert_array_equal(res.x_hat[0], MODEL.x0)
    ekf = nl.run_ekf(MODEL, y)
    assert 3.0 < ekf.nis()[1:].mean() < 7.0


def test_missing_components_are_left_out_of_the_update(truth3):
    y = truth3.y[0].copy()
    y[10] = np.nan  # a whole row: no update at all
    y[20, [1, 3]] = np.nan  # range and GPS easting missing
    for method in nl.METHODS:
        res = nl.run_filter(method, MODEL, y)
        assert np.isfinite(res.x_hat).all()
        np.testing.assert_array_equal(res.x_hat[10], res.x_bar[10])
        np.testing.assert_array_equal(res.P[10], res.M[10])
        assert np.isnan(res.r[20, [1, 3]]).all()
        assert np.isfinite(res.r[20, [0, 2, 4]]).all()
        assert consistency.dof_of(res.r[20]) == 3
    # the EKF's partial update is the update with the reduced H and R, by hand
    res = nl.run_ekf(MODEL, y)
    m = np.isfinite(y[20])
    xb, M = res.x_bar[20], res.M[20]
    H = MODEL.C(xb)[m]
    R = MODEL.Rtrue[np.ix_(m, m)]
    K = M @ H.T @ np.linalg.inv(H @ M @ H.T + R)
    r = coop.measurement_residual(y[20], coop.h(xb))[m]
    np.testing.assert_allclose(res.x_hat[20], coop.wrap_state(xb + K @ r), atol=1e-12)


#: The first 2 s (20 steps) of MODEL: enough for the groups below, and a UKF run of filterpy's
#: in a tenth of a second instead of 3 s.
SHORT = CoopModel(duration=2.0)


@pytest.mark.parametrize("method", nl.METHODS)
def test_runs_missing_different_components_are_updated_in_groups(method, truth3):
    # run 1 misses the range at step 5 and everything at step 7, run 2 the GPS at step 9: the one
    # vectorised filter gives each run what filterpy gives it alone (1e-10, as above), over the
    # first 20 steps of the three runs (the groups are at steps 5-9)
    y = truth3.y[:, :SHORT.n_steps + 1].copy()
    y[1, 5, 1] = np.nan
    y[1, 7] = np.nan
    y[2, 9, 3:] = np.nan
    batch = nl.run_batch(method, SHORT, y)
    for i in range(3):
        one = filterpy_oracle.RUNNERS[method](SHORT, y[i])
        np.testing.assert_allclose(coop.state_residual(batch.x_hat[i], one.x_hat), 0, atol=1e-10)
        np.testing.assert_allclose(batch.P[i], one.P, atol=1e-10)
        np.testing.assert_allclose(batch.r[i], one.r, atol=1e-10)
        np.testing.assert_allclose(batch.S[i], one.S, atol=1e-10)


@pytest.mark.parametrize("call, name", [
    (lambda y: nl.run_ekf(MODEL, y[:-1]), "y"),
    (lambda y: nl.run_ekf(MODEL, y.T), "y"),
    (lambda y: nl.run_ukf(MODEL, y, Q=np.diag([1, 1, 1, 1, 1, -1.0])), "Q"),
    (lambda y: nl.run_lkf(MODEL, y, R=np.eye(4)), "R"),
    (lambda y: nl.run_ekf(MODEL, y, P0=np.zeros((6, 6))), "P0"),
    (lambda y: nl.run_filter("pf", MODEL, y), "method"),
    (lambda y: nl.run_batch("ekf", MODEL, y), "y"),
    (lambda y: nl.scaled_q(MODEL.Qtrue, 0.0), "scale"),
])
def test_bad_input_names_the_argument(call, name, truth3):
    with pytest.raises(ValueError, match=name):
        call(truth3.y[0])
