"""The Monte Carlo engine: filterpy's statistics, exact noise, reproducible streaming, verdicts.

Statistical assertions use fixed seeds (never flaky) and say their false-alarm rate: the verdict
table is built so that a consistent filter fails some row with probability at most its alpha.
"""

from __future__ import annotations

import concurrent.futures as cf

import numpy as np
import pytest

from gpsaccel import monte_carlo
from gpsaccel.calibration.model import CalibrationModel
from gpsaccel.calibration.montecarlo import BLOCK_RUNS, gps_interval_noise, plan, realizations
from gpsaccel.calibration.montecarlo.reduction import _run_block
from gpsaccel.calibration.montecarlo.streams import _standard_normals
from gpsaccel.calibration.simulation import simulate, truth_mean
from gpsaccel.figures.runs import ensemble
from gpsaccel.kalman.consistency import nees, nis, z_sample_mean, z_threshold
from gpsaccel.kalman.multirate import run_multirate

MODEL = CalibrationModel()
FIELDS = ("e_ave", "P_ave", "P", "orthogonality", "residual_lags", "residual_mean",
          "nees", "nis")


def assert_close(actual, desired, rel):
    """Agreement to ``rel`` of the largest element of ``desired`` (exact zeros stay exact)."""
    desired = np.asarray(desired)
    np.testing.assert_allclose(actual, desired, rtol=rel, atol=rel * np.nanmax(np.abs(desired)))


def assert_same_result(a, b, rel):
    assert a.n_runs == b.n_runs
    for name in FIELDS:
        assert_close(getattr(a, name), getattr(b, name), rel)


# ------------------------------------------------------------------ the reports' experiment
@pytest.mark.parametrize("truth", ["error-model", "kinematic"])
def test_statistics_equal_filterpy_run_once_per_realization(truth):
    """Run filterpy (run_multirate) on each realization the engine draws; same statistics."""
    n = 16
    draws = realizations(MODEL, 0, n, seed=3, truth=truth)
    e, xh, r, nees_l, nis_l = [], [], [], [], []
    for l in range(n):
        res = run_multirate(MODEL, draws.z[l], method="filterpy")
        err = draws.x_gps[l] - res.x_hat
        e.append(err)
        xh.append(res.x_hat)
        r.append(res.r)
        nees_l.append(nees(err, res.P))
        nis_l.append(nis(res.r, res.S))
        assert_close(draws.x_hat[l], res.x_hat, 1e-10)  # and run by run
    e, xh, r = np.array(e), np.array(xh), np.array(r)
    e_ave = e.mean(axis=0)
    ec = e - e_ave
    mc = monte_carlo(MODEL, n, seed=3, truth=truth, progress=False, full_residual_matrix=True)
    assert_close(mc.e_ave, e_ave, 1e-10)
    assert_close(mc.P_ave, np.einsum("lia,lib->iab", ec, ec) / (n - 1), 1e-10)
    assert_close(mc.P, res.P, 1e-10)
    assert_close(mc.S, res.S, 1e-10)
    assert_close(mc.orthogonality, np.einsum("lia,lib->iab", ec, xh) / n, 1e-10)
    rr = np.einsum("lia,lmb->imab", r, r) / n
    assert_close(mc.residual_correlation, rr, 1e-10)
    # the default keeps the lags up to max_lag and the pairs asked for: the same numbers
    band = monte_carlo(MODEL, n, seed=3, truth=truth, progress=False, max_lag=7,
                       residual_pairs=[(3, 140), (150, 0), (20, 25)])
    assert band.residual_full is None and band.residual_pairs == ((140, 3), (150, 0))
    for i, m in [(0, 0), (150, 143), (143, 150), (7, 0), (140, 3), (3, 140), (150, 0), (20, 25)]:
        assert_close(band.residual_product(i, m), rr[i, m], 1e-10)
    for k in range(8):
        assert_close(band.residual_lags[k:, k], rr[np.arange(k, 151), np.arange(151 - k)], 1e-10)
        assert np.isnan(band.residual_lags[:k, k]).all()
    with pytest.raises(ValueError, match="max_lag = 7 and the pair was not requested"):
        band.residual_product(100, 50)
    with pytest.raises(ValueError, match="full_residual_matrix=True"):
        _ = band.residual_correlation
    assert_close(mc.nees, np.mean(nees_l, axis=0), 1e-10)
    assert_close(mc.nis, np.mean(nis_l, axis=0), 1e-10)


def test_gps_interval_noise_is_the_exact_sum_of_the_200_hz_noise():
    """Q_N = W [[Δt⁴ N(4N²−1)/12, Δt³ N²/2], [Δt³ N²/2, N Δt²]], Φ_N = Φ^N."""
    dt, N, W = MODEL.dt, MODEL.gps_every, MODEL.W[0, 0]
    Phi_N, Q_N = gps_interval_noise(MODEL)
    np.testing.assert_allclose(Phi_N, np.linalg.matrix_power(MODEL.Phi, N), rtol=1e-14)
    want = W * np.array([[dt**4 * N * (4 * N**2 - 1) / 12, dt**3 * N**2 / 2, 0],
                         [dt**3 * N**2 / 2, N * dt**2, 0], [0, 0, 0]])
    np.testing.assert_allclose(Q_N, want, rtol=1e-12, atol=0)


def test_kinematic_offset_is_the_closed_form_truth_minus_the_error_model_truth():
    """simulate() with the same generator state under both truths differs by exactly d(t_i)."""
    a = simulate(MODEL, np.random.default_rng(11), truth="kinematic")
    b = simulate(MODEL, np.random.default_rng(11), truth="error-model")
    d = truth_mean(MODEL, "kinematic")
    np.testing.assert_allclose(a.x_gps - b.x_gps, d, rtol=0, atol=1e-9)
    assert np.abs(d[:, 1]).max() > 0.02  # Euler's velocity misses up to A·Δt/2 = 0.025 m/s
    assert not truth_mean(MODEL, "error-model").any()


def test_predicted_mean_error_is_filterpy_on_the_noise_free_kinematic_measurement():
    d = truth_mean(MODEL, "kinematic")
    res = run_multirate(MODEL, d[:, :2])  # z = H d: no noise at all
    mc = monte_carlo(MODEL, 2, truth="kinematic", progress=False)
    assert_close(mc.predicted_mean_error, d - res.x_hat, 1e-10)


# ------------------------------------------------------------------ what it must show
def test_error_model_10000_runs_every_statistic_within_its_sampling_error():
    # False-alarm rate of this assertion for a consistent filter: 1% (family-wise, whole table).
    mc = ensemble(10_000, 0, "error-model")
    report = mc.consistency(alpha=0.01)
    assert report.passed, str(report)
    assert len(report.verdicts) == 11
    # Report 000 printed max(P_ave − P) = −0.013 for element (1,1): about one standard error at
    # t = 0, where P₁₁ = 1/(1/100 + 1/1) m² and SE = P₁₁ √(2/(N − 1)) = 0.0140 m².
    se0 = mc.P_ave_se[0, 0, 0]
    assert se0 == pytest.approx(1 / 1.01 * np.sqrt(2 / 9999), rel=1e-9)
    assert round(se0, 3) == 0.014
    assert abs(-0.013) / se0 < 1.0
    k = report["P_ave−P[δp,δp]"].threshold
    assert abs(mc.P_ave[0, 0, 0] - mc.P[0, 0, 0]) < k * se0
    # Report 000's residual pair r(30 s) r(29.8 s)ᵀ is one element of residual_correlation.
    assert mc.t[-1] == pytest.approx(30.0) and mc.t[-2] == pytest.approx(29.8)
    z = mc.residual_product(-1, -2) / mc.residual_product_se(-1, -2)
    assert np.abs(z).max() < report["residual whiteness"].threshold


def test_kinematic_truth_is_flagged_many_standard_errors_off():
    mc = ensemble(10_000, 0, "kinematic")
    report = mc.consistency(alpha=0.01)
    assert not report.passed
    for name in ("e_ave[δv]", "e_ave[b]"):
        assert not report[name].passed
        assert report[name].max_abs_z > 50, str(report)
    assert not report["NEES (χ²(3N)/N)"].passed
    # The offset is deterministic, so everything centred on the ensemble mean is unchanged ...
    for name in ("P_ave−P[δp,δp]", "P_ave−P[δv,δv]", "P_ave−P[b,b]", "P_ave−P off-diagonal",
                 "orthogonality"):
        assert report[name].passed
    # ... and the mean error is the filter's error on that offset, up to sampling error
    # (false-alarm rate 1% over the 453 z-scores, Bonferroni).
    z = z_sample_mean(mc.e_ave - mc.predicted_mean_error, mc.sigma**2, mc.n_runs)
    assert np.abs(z).max() < z_threshold(0.01, z.size)


# ------------------------------------------------------------------ streaming and executors
def test_run_l_is_the_same_realization_whatever_the_range():
    a = realizations(MODEL, 0, BLOCK_RUNS + 5, seed=7)
    b = realizations(MODEL, BLOCK_RUNS - 3, BLOCK_RUNS + 2, seed=7)
    np.testing.assert_array_equal(a.z[BLOCK_RUNS - 3:BLOCK_RUNS + 2], b.z)
    np.testing.assert_array_equal(a.x_gps[BLOCK_RUNS - 3:BLOCK_RUNS + 2], b.x_gps)
    c = realizations(MODEL, 0, 5, seed=8)
    assert not np.allclose(a.z[:5], c.z)


def test_merged_sums_equal_the_sums_of_the_whole():
    pl = plan(MODEL, "kinematic")
    xi = _standard_normals(5, pl.n_normals, 0, 300)
    whole, arrays = _run_block(pl, xi, keep=True)
    parts = [_run_block(pl, xi[:, lo:hi])[0] for lo, hi in ((0, 7), (7, 180), (180, 300))]
    merged = parts[0].merge(parts[1]).merge(parts[2])
    assert merged.n == whole.n == 300
    for name in ("mean_e", "mean_xhat", "mean_r", "C_ee", "C_ex", "rr_band", "nees", "nis"):
        assert_close(getattr(merged, name), getattr(whole, name), 1e-12)
    # and the shifted on-the-fly sums equal the textbook formulas on the kept arrays
    e = arrays["x"] - arrays["x_hat"]
    ec = e - e.mean(axis=2, keepdims=True)
    xc = arrays["x_hat"] - arrays["x_hat"].mean(axis=2, keepdims=True)
    assert_close(whole.C_ee, np.einsum("iam,ibm->iab", ec, ec), 1e-12)
    assert_close(whole.C_ex, np.einsum("iam,ibm->iab", ec, xc), 1e-12)
    assert_close(whole.mean_e, e.mean(axis=2), 1e-12)


def test_results_do_not_depend_on_chunk_size_executor_or_workers():
    n = 2 * BLOCK_RUNS + 317
    ref = monte_carlo(MODEL, n, seed=1, truth="kinematic", progress=False)
    assert_same_result(monte_carlo(MODEL, n, seed=1, truth="kinematic", chunk_size=437,
                                   progress=False), ref, 1e-12)
    assert_same_result(monte_carlo(MODEL, n, seed=1, truth="kinematic", chunk_size=n,
                                   progress=False), ref, 1e-12)
    with cf.ThreadPoolExecutor(max_workers=3) as pool:
        assert_same_result(monte_carlo(MODEL, n, seed=1, truth="kinematic", executor=pool,
                                       progress=False), ref, 1e-12)
    with cf.ProcessPoolExecutor(max_workers=2) as pool:
        assert_same_result(monte_carlo(MODEL, n, seed=1, truth="kinematic", executor=pool,
                                       chunk_size=700, progress=False), ref, 1e-12)
    tiny = monte_carlo(MODEL, 5, seed=1, truth="kinematic", chunk_size=1, progress=False)
    assert_same_result(tiny, monte_carlo(MODEL, 5, seed=1, truth="kinematic", progress=False),
                       1e-12)


def test_dask_cluster_gives_the_same_result_by_address_client_and_executor():
    distributed = pytest.importorskip("distributed")
    n = BLOCK_RUNS + 250
    ref = monte_carlo(MODEL, n, seed=2, progress=False)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        # "tcp://host:port", as `gpsaccel montecarlo --dask tcp://...` passes it
        got = monte_carlo(MODEL, n, seed=2, executor=cluster.scheduler_address, chunk_size=500,
                          progress=False)
        assert_same_result(got, ref, 1e-12)
        with distributed.Client(cluster) as client:
            assert_same_result(monte_carlo(MODEL, n, seed=2, executor=client, progress=False),
                               ref, 1e-12)
            with client.get_executor() as ex:  # a concurrent.futures.Executor, unchanged
                assert_same_result(monte_carlo(MODEL, n, seed=2, executor=ex, chunk_size=300,
                                               progress=False), ref, 1e-12)
            assert client.status == "running"  # a client we passed in is left open


def test_no_progress_bar_when_not_a_terminal(capsys):
    monte_carlo(MODEL, 3, progress=True)
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err == ""


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize("kwargs, name", [
    ({"n_runs": 1}, "n_runs"),
    ({"n_runs": 10.0}, "n_runs"),
    ({"truth": "closed-form"}, "truth"),
    ({"executor": object()}, "executor"),
    ({"executor": "nonsense"}, "executor"),
    ({"chunk_size": 0}, "chunk_size"),
    ({"seed": -1}, "seed"),
])
def test_bad_input_raises_value_error_naming_the_argument(kwargs, name):
    args = {"n_runs": 10} | kwargs
    with pytest.raises(ValueError, match=name):
        monte_carlo(MODEL, progress=False, **args)


def test_bad_model():
    with pytest.raises(ValueError, match="model"):
        monte_carlo("report 000", 10)


def test_blas_thread_count_is_restored_after_overlapping_users():
    from gpsaccel._blas import blas_threads, single_threaded_blas

    before = blas_threads()
    with single_threaded_blas():
        assert all(n == 1 for n in blas_threads())
        with single_threaded_blas():  # a second, overlapping user (another executor thread)
            pass
        assert all(n == 1 for n in blas_threads())  # not restored while the first is inside
    assert blas_threads() == before
    with cf.ThreadPoolExecutor(max_workers=2) as pool:
        monte_carlo(MODEL, 2 * BLOCK_RUNS, executor=pool, progress=False)
    assert blas_threads() == before


def test_cli_montecarlo_prints_the_table_and_writes_the_figures(tmp_path, capsys):
    from gpsaccel.cli import main

    assert main(["montecarlo", "--runs", "300", "--truth", "kinematic", "--out", str(tmp_path),
                 "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "e_ave[δv]" in out and "residual whiteness" in out and "NEES" in out
    assert "r(30 s) r(29.8 s)ᵀ" in out
    names = sorted(p.name for p in tmp_path.glob("*.png"))
    assert names == [f"montecarlo-kinematic-{s}.png" for s in
                     ("ensemble-mean-error", "orthogonality", "pave-minus-p-grid", "pave-minus-p")]
    assert main(["montecarlo", "--runs", "1", "--out", str(tmp_path)]) == 2
    assert main(["montecarlo", "--dask", "nowhere", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "argument --runs" in err and "--dask" in err


def test_summary_prints_the_reports_numbers_with_their_standard_errors():
    mc = monte_carlo(MODEL, 200, seed=3, truth="kinematic", progress=False)
    text = mc.summary()
    d0 = mc.P_ave[0, 0, 0] - mc.P[0, 0, 0]
    assert f"{d0:+.4f} m² (standard error {mc.P_ave_se[0, 0, 0]:.4f} m²" in text
    assert "r(30 s) r(29.8 s)ᵀ" in text
    assert "δv: -0.014 m/s at t = 30 s" in text  # the Euler offset the filter carries
    assert "theory predicts" not in monte_carlo(MODEL, 20, seed=3, progress=False).summary()
