"""gpsaccel.kalman.consistency: z-scores with the stated sampling distributions, bounds, verdicts.

The Monte Carlo checks below use fixed seeds; each states its false-alarm rate.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from gpsaccel.kalman import consistency as c


def test_existing_names_still_work():
    for name in ("chi2_bounds", "nees", "nis", "normalized_squared", "fraction_inside",
                 "z_threshold", "Verdict", "verdict_from_z", "format_verdicts", "dof_of"):
        assert hasattr(c, name)


@pytest.mark.parametrize("dof", [1, 3, 30_000])
def test_z_from_chi2_is_the_exact_probability_transform(dof):
    q = np.array([1e-12, 1e-4, 0.025, 0.5, 0.975, 1 - 1e-4])
    x = stats.chi2.ppf(q, dof)
    np.testing.assert_allclose(c.z_from_chi2(x, dof), stats.norm.ppf(q), rtol=1e-7, atol=1e-8)
    far_up = stats.chi2.isf(1e-200, dof)  # beyond 1 − q in double precision
    assert c.z_from_chi2(far_up, dof) == pytest.approx(stats.norm.isf(1e-200), rel=1e-6)


@pytest.mark.parametrize("dof", [1, 3, 30, 453, 30_000])
def test_scipy_special_gives_scipy_stats_numbers_bit_for_bit(dof):
    # the module calls scipy.special directly (scipy.stats costs 1 CPU s to import): the same
    # numbers as scipy.stats' chi2 and norm, to the last bit, below, inside and beyond the support
    rng = np.random.default_rng(0)
    x = np.concatenate([[-1.0, 0.0, 1e-300, np.inf, np.nan],
                        rng.exponential(dof, 500), rng.exponential(50 * dof, 50)])
    k = np.full(x.shape, float(dof))
    with np.errstate(divide="ignore", invalid="ignore"):
        old = np.where(x > stats.chi2.median(k), stats.norm.isf(stats.chi2.sf(x, k)),
                       stats.norm.ppf(stats.chi2.cdf(x, k)))
        c2 = 2.0 / (9.0 * k)
        old = np.where(np.isinf(old) & (x > 0), (np.cbrt(x / k) - 1.0 + c2) / np.sqrt(c2), old)
    np.testing.assert_array_equal(c.z_from_chi2(x, dof), old)
    for alpha in (0.01, 0.05):
        assert c.z_threshold(alpha, dof) == float(stats.norm.isf(alpha / (2 * dof)))
        assert c.chi2_bounds(3, dof, alpha) == (float(stats.chi2.ppf(alpha / 2, 3 * dof) / dof),
                                                float(stats.chi2.ppf(1 - alpha / 2, 3 * dof) / dof))


def test_z_from_chi2_stays_finite_and_monotone_where_the_tail_underflows():
    x = np.array([3e4, 4e4, 1e5, 1e6]) * 1.0
    z = c.z_from_chi2(x, 30_000)
    assert np.all(np.isfinite(z)) and np.all(np.diff(z) > 0) and z[1] > 37
    assert c.z_from_chi2(0.0, 3) == -np.inf


@pytest.mark.parametrize("dof, n_runs, alpha", [(3, 10_000, 0.05), (2, 50, 0.01), (1, 1, 0.1)])
def test_ensemble_z_and_the_course_bounds_are_one_test(dof, n_runs, alpha):
    r1, r2 = c.chi2_bounds(dof, n_runs, alpha)
    z = c.z_ensemble_normalized_squared(np.array([r1, r2]), dof, n_runs)
    np.testing.assert_allclose(z, [-stats.norm.isf(alpha / 2), stats.norm.isf(alpha / 2)],
                               rtol=1e-9)


def test_sample_variance_z_is_standard_normal_for_gaussian_samples():
    # 4,000 sample variances of N = 5 draws (far from the normal approximation): KS test of the
    # z-scores against N(0, 1); false-alarm rate 0.1% (fixed seed).
    rng = np.random.default_rng(2024)
    sigma2 = 2.5
    s2 = rng.normal(0, np.sqrt(sigma2), (4000, 5)).var(axis=1, ddof=1)
    z = c.z_sample_variance(s2, sigma2, 5)
    assert stats.kstest(z, "norm").pvalue > 1e-3


def test_sample_covariance_standard_error_matches_its_closed_form_and_a_simulation():
    C = np.array([[4.0, 1.2], [1.2, 1.0]])
    se = c.sample_covariance_se(C, 101)
    np.testing.assert_allclose(se, np.sqrt((C**2 + np.outer(np.diag(C), np.diag(C))) / 100))
    # 20,000 sample covariances of N = 101: the spread of each element agrees with se within
    # 5% (its own sampling error is about 0.5%, so this cannot fail by chance).
    rng = np.random.default_rng(7)
    x = rng.multivariate_normal([0, 0], C, size=(20_000, 101))
    xc = x - x.mean(axis=1, keepdims=True)
    Ch = np.einsum("rna,rnb->rab", xc, xc) / 100
    np.testing.assert_allclose(Ch.std(axis=0), se, rtol=0.05)


def test_z_sample_covariance_diagonal_exact_and_nan_without_spread():
    C = np.diag([1.0, 0.0])
    z = c.z_sample_covariance(np.diag([1.0, 0.0]), C, 10)
    assert z[0, 0] == pytest.approx(stats.norm.ppf(stats.chi2.cdf(9.0, 9)))
    assert np.isnan(z[1, 1]) and np.isnan(z[0, 1])


def test_cross_moment_standard_errors():
    assert c.cross_moment_se(4.0, 9.0, 100) == pytest.approx(np.sqrt(36 / 100))
    assert c.cross_moment_se(4.0, 9.0, 100, centered=True) == pytest.approx(np.sqrt(99 * 36) / 100)
    # Simulated: (1/N) Σ (a − ā) b over 20,000 ensembles of N = 30; spread within 5% of the SE.
    rng = np.random.default_rng(3)
    a = rng.normal(0, 2, (20_000, 30))
    b = rng.normal(0, 3, (20_000, 30))
    m = ((a - a.mean(axis=1, keepdims=True)) * b).mean(axis=1)
    assert m.std() == pytest.approx(c.cross_moment_se(4.0, 9.0, 30, centered=True), rel=0.05)


def test_z_sample_mean():
    np.testing.assert_allclose(c.z_sample_mean(np.array([0.1, -0.2]), np.array([1.0, 4.0]), 100),
                               [1.0, -1.0])
    assert np.isnan(c.z_sample_mean(0.0, 0.0, 10))


def test_verdicts_skip_nan_and_fail_on_infinite_z():
    z = np.array([0.5, np.nan, -2.0])
    v = c.verdict_from_z("x", z, lambda i: f"at {i[0]}", alpha=0.05)
    assert v.n_tests == 2 and v.max_abs_z == 2.0 and v.where == "at 2" and v.passed
    assert v.threshold == pytest.approx(stats.norm.isf(0.05 / 4))
    bad = c.verdict_from_z("y", np.array([0.1, np.inf]), lambda i: "", alpha=0.05)
    assert not bad.passed
    with pytest.raises(ValueError, match="NaN"):
        c.verdict_from_z("z", np.array([np.nan]), lambda i: "")


def test_consistency_report():
    ok = c.verdict_from_z("ok", np.array([0.1]), lambda i: "", alpha=0.005)
    bad = c.verdict_from_z("bad", np.array([9.0]), lambda i: "t = 1 s", alpha=0.005)
    report = c.ConsistencyReport("title", (ok, bad), 0.01)
    assert not report.passed and report.failed == [bad] and report["ok"] is ok
    text = str(report)
    assert "FAIL" in text and "bad" in text and "0.01" in text
    with pytest.raises(KeyError):
        report["missing"]
    assert c.ConsistencyReport("t", (ok,), 0.01).passed


def test_off_diagonal_sample_covariance_z_is_exact_for_tiny_ensembles():
    # 5,000 sample covariances of N = 4 correlated Gaussian vectors (ρ = 0.8): every element's
    # z-score is N(0, 1) (KS test, false-alarm rate 0.1% per element, fixed seed).
    rng = np.random.default_rng(11)
    C = np.array([[2.0, 0.8 * np.sqrt(2 * 0.5), 0.1], [0.8 * np.sqrt(2 * 0.5), 0.5, 0.0],
                  [0.1, 0.0, 1.0]])
    x = rng.multivariate_normal([1.0, -2.0, 0.5], C, size=(5000, 4))
    xc = x - x.mean(axis=1, keepdims=True)
    C_hat = np.einsum("rna,rnb->rab", xc, xc) / 3
    z = c.z_sample_covariance(C_hat, C, 4)
    for a in range(3):
        for b in range(3):
            assert stats.kstest(z[:, a, b], "norm").pvalue > 1e-3, (a, b)


def test_cross_products_z_is_exact_whatever_the_other_factor():
    # a ~ N(0, 4) independent of a skewed, non-centred b; N = 3.  KS test, false-alarm 0.1%.
    rng = np.random.default_rng(12)
    a = rng.normal(0, 2, (20_000, 3))
    b = rng.exponential(1.0, (20_000, 3)) + 3.0
    z = c.z_cross_products((a * b).sum(axis=1), 4.0, (b * b).sum(axis=1))
    assert stats.kstest(z, "norm").pvalue > 1e-3
    assert np.isnan(c.z_cross_products(1.0, 0.0, 2.0))


def _one_at_a_time(v, C):
    """The per-vector loop normalized_squared had before its stacked solve (what the lessons'
    tagged NIS fractions were printed from): one LU solve and one dot per vector."""
    out = np.empty(v.shape[:-1])
    flat_v, flat_C, flat_out = v.reshape(-1, v.shape[-1]), C.reshape(-1, *C.shape[-2:]), out.reshape(-1)
    for i, (vi, Ci) in enumerate(zip(flat_v, flat_C, strict=True)):
        m = np.isfinite(vi)
        flat_out[i] = 0.0 if not m.any() else float(vi[m] @ np.linalg.solve(Ci[np.ix_(m, m)], vi[m]))
    return out


def _spd(rng, shape, n):
    A = rng.normal(size=(*shape, n, n))
    return A @ np.swapaxes(A, -1, -2) + 0.1 * np.eye(n)


@pytest.mark.parametrize(("shape", "n", "p_nan"), [
    ((200,), 5, 0.3),        # many patterns, some vectors empty
    ((4, 30), 3, 0.5),       # two leading axes
    ((60,), 1, 0.4),         # scalars: measured or not
    ((40,), 70, 0.05),       # more components than an integer key holds: np.unique's path
    ((), 4, 0.5),            # one vector
])
def test_nan_input_is_the_per_vector_solve_bit_for_bit(shape, n, p_nan):
    rng = np.random.default_rng(n)
    v = rng.normal(size=(*shape, n)) * 10.0 ** rng.integers(-3, 4, size=(*shape, n))
    v[rng.random(v.shape) < p_nan] = np.nan
    v.reshape(-1, n)[0] = np.nan                      # at least one empty vector and one NaN
    C = _spd(rng, shape, n)
    got = c.normalized_squared(v, C)
    assert got.shape == shape
    assert np.array_equal(got, _one_at_a_time(v, C))
    empty = ~np.isfinite(v).any(axis=-1)
    assert (got[empty] == 0.0).all() and (got[~empty] > 0.0).all()
    assert np.array_equal(c.nis(v, C), got)


def test_all_nan_input_is_zero_with_zero_dof():
    v = np.full((3, 2), np.nan)
    assert np.array_equal(c.normalized_squared(v, np.broadcast_to(np.eye(2), (3, 2, 2))), np.zeros(3))
    assert np.array_equal(c.dof_of(v), np.zeros(3))


def test_one_nan_anywhere_sends_the_finite_vectors_through_lu_as_before():
    # the lessons' numbers came from the LU loop for the finite vectors of any input with a NaN
    # too; the Cholesky path (all finite) may differ in the last bit, the NaN path may not
    rng = np.random.default_rng(3)
    v, C = rng.normal(size=(500, 5)), _spd(rng, (500,), 5)
    v[0, 2] = np.nan
    assert np.array_equal(c.normalized_squared(v, C), _one_at_a_time(v, C))
