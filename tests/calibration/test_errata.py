"""The reports' mistakes and the exact error statistics of a mismatched filter (calibration.errata)."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel.calibration import errata
from gpsaccel.calibration.mistakes import mutant, reference
from gpsaccel.calibration.montecarlo import monte_carlo
from gpsaccel.kalman.consistency import z_sample_mean, z_sample_variance, z_threshold


def test_optimal_filter_on_its_own_model_has_actual_covariance_P():
    m = errata.report_model("000")
    s = errata.error_statistics(m, reference(m), truth="error-model")
    scale = np.sqrt(np.einsum("kii,kjj->kij", s.P, s.P))
    assert np.abs(s.cov - s.P).max() / scale.max() < 1e-9
    assert np.abs((s.cov - s.P) / scale).max() < 1e-8
    assert np.all(s.mean == 0)


def test_kinematic_mean_agrees_with_the_monte_carlo_engines_prediction():
    # Two independent derivations: errata's joint recursion and montecarlo's filtered offset.
    m = errata.report_model("001")
    s = errata.error_statistics(m, reference(m), truth="kinematic")
    mc = monte_carlo(m, 2, seed=0, truth="kinematic", progress=False)
    np.testing.assert_allclose(s.mean, mc.predicted_mean_error, rtol=0, atol=1e-10)


def test_x0_total_state_leaves_the_closed_form_velocity_error_at_t0():
    s, _ = errata.x0_total_state().statistics()
    V22 = 0.04**2
    # first update: δv̂ = 100 + K22 (z − 100), K22 = 1/(1 + V22) -> mean error −100 V22/(1 + V22)
    assert s.mean[0, 1] == pytest.approx(-100 * V22 / (1 + V22), rel=1e-9)
    assert s.mean[0, 0] == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("make", [errata.x0_total_state, errata.phi13_sign, errata.m0_swapped,
                                  errata.w_written, errata.process_noise_on_gps_interval,
                                  errata.position_sigma_as_variance])
def test_no_mistaken_filter_beats_the_kalman_filter(make):
    # On the same truth the Kalman filter has the smallest mean-square error matrix of all linear
    # filters: E[e eᵀ]_mistaken − P_optimal is positive semidefinite at every time.
    er = make()
    assert er.truth_model is er.baseline_model and er.truth == "error-model"
    wrong, base = er.statistics()
    mse = wrong.cov + np.einsum("ki,kj->kij", wrong.mean, wrong.mean)
    gap = mse - base.cov
    for k in range(gap.shape[0]):
        scale = np.sqrt(np.outer(np.diag(base.cov[k]), np.diag(base.cov[k])))
        assert np.linalg.eigvalsh(gap[k] / scale).min() > -1e-8, f"t index {k}"


def test_gamma_sign_and_costless_slips():
    c = errata.cost(errata.bias_variance_as_sigma())
    np.testing.assert_allclose(c.rms_end, c.baseline_rms_end, rtol=2e-3)
    assert np.all(c.ratio_max <= 1 + 1e-9)  # only too cautious, never overconfident


def test_exact_statistics_match_a_monte_carlo_of_the_mistaken_filter():
    # 600 realizations of the closed-form truth through report 003's filter (Q on the GPS interval).
    # Family-wise false-alarm rate 0.002 over the 453 mean and 453 variance z-scores (Bonferroni),
    # fixed seed.
    er = errata.process_noise_on_gps_interval()
    n = 600
    exact = errata.error_statistics(er.truth_model, er.filt, "kinematic")
    e = errata.monte_carlo_errors(er.truth_model, er.filt, n, seed=7, truth="kinematic")
    var = np.diagonal(exact.cov, axis1=1, axis2=2)
    z_mean = z_sample_mean(e.mean(axis=0), var, n, expected=exact.mean)
    z_var = z_sample_variance(e.var(axis=0, ddof=1), var, n)
    bound = z_threshold(0.001, z_mean.size)
    assert np.nanmax(np.abs(z_mean)) < bound
    assert np.nanmax(np.abs(z_var)) < bound
    # the mistake is visible at this size: the claimed σ_v differs from the actual one
    assert exact.claimed_sigma[-1, 1] / exact.sigma[-1, 1] > 1.2


def test_error_statistics_refuses_mismatched_epochs_and_non_models():
    m = errata.report_model("000")
    with pytest.raises(ValueError, match="epochs"):
        errata.error_statistics(m.replace(duration=10.0), reference(m))
    with pytest.raises(ValueError, match="truth_model"):
        errata.error_statistics(object(), reference(m))
    with pytest.raises(ValueError, match="truth"):
        errata.error_statistics(m, mutant("phi-sign", m), truth="closed")


def test_cost_table_names_every_erratum():
    table = errata.cost_table()
    for make in errata.ALL_ERRATA:
        assert make().key in table
