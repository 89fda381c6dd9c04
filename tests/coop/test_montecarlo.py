"""NEES/NIS truth-model tests and the Q tuning of report 002 (coop.montecarlo)."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel.coop.model import CoopModel
from gpsaccel.coop.montecarlo import consistency_test, repeated_sets, set_seeds, tune_q
from gpsaccel.kalman.consistency import chi2_bounds

MODEL = CoopModel()


@pytest.fixture(scope="module")
def ekf_run():
    return consistency_test(MODEL, "ekf", n_runs=20, seed=1, keep=True)


def test_averages_are_the_runs_nees_and_nis(ekf_run):
    res, truth = ekf_run.result, ekf_run.truth
    np.testing.assert_allclose(ekf_run.nees_mean, res.nees(truth.x)[:, 1:].mean(axis=0),
                               rtol=1e-12)
    np.testing.assert_allclose(ekf_run.nis_mean, res.nis()[:, 1:].mean(axis=0), rtol=1e-12)
    assert ekf_run.nees_bounds == chi2_bounds(6, 20, 0.05)
    assert ekf_run.nis_bounds == chi2_bounds(5, 20, 0.05)
    inside = np.mean((ekf_run.nees_mean >= ekf_run.nees_bounds[0])
                     & (ekf_run.nees_mean <= ekf_run.nees_bounds[1]))
    assert ekf_run.nees_fraction == pytest.approx(inside)


def test_the_tuned_ekf_passes_and_the_lkf_fails(ekf_run):
    # fixed seed; the tuned EKF's NIS fraction over 5 sets of 50 was 0.93-0.96 (README)
    assert ekf_run.nis_fraction > 0.85
    lkf = consistency_test(MODEL, "lkf", n_runs=20, seed=1)
    assert lkf.nees_fraction < 0.2  # the nominal is hundreds of metres from the truth


def test_sets_are_independent_and_reproducible():
    a, b = set_seeds(7, 2)
    assert a.entropy == b.entropy and a.spawn_key != b.spawn_key
    runs1 = repeated_sets(MODEL, "ekf", n_sets=2, n_runs=5, seed=7)
    runs2 = repeated_sets(MODEL, "ekf", n_sets=2, n_runs=5, seed=7)
    np.testing.assert_array_equal(runs1[1].nees_mean, runs2[1].nees_mean)
    assert not np.array_equal(runs1[0].nees_mean, runs1[1].nees_mean)


def test_tune_q_scores_every_candidate_and_prefers_the_least_inflation():
    res = tune_q(MODEL, "ekf", grid=((1.0, 4.0), (1.0, 2.0), (1.0,)), n_runs=10, seed=3)
    assert res.scales == [(1.0, 1.0, 1.0), (1.0, 2.0, 1.0), (4.0, 1.0, 1.0), (4.0, 2.0, 1.0)]
    good = res.score >= res.score.max() - res.tol
    chosen = res.scales.index(res.best)
    assert good[chosen]
    assert res.inflation[chosen] == res.inflation[good].min()
    assert "* = chosen" in res.table()


def test_bad_arguments_name_themselves():
    with pytest.raises(ValueError, match="method must be one of"):
        consistency_test(MODEL, "pf", n_runs=2)
    with pytest.raises(ValueError, match="alpha must be a probability"):
        consistency_test(MODEL, "ekf", n_runs=2, alpha=1.5)
    with pytest.raises(ValueError, match="grid must hold 3 lists"):
        tune_q(MODEL, "ekf", grid=((1.0,), (1.0,)))


def test_sets_and_candidates_filtered_together_equal_each_alone():
    # repeated_sets / tune_q stack their sets (one Q per run) into one filter call: every
    # number is that of the set's own call, bit for bit
    from gpsaccel.coop import montecarlo as mc
    from gpsaccel.coop.filters import scaled_q
    from gpsaccel.coop.model import CoopModel

    model = CoopModel(duration=5.0)
    truths = [mc.truth_runs(model, 4, s) for s in mc.set_seeds(3, 2)]
    Qs = [model.Qtrue, scaled_q(model.Qtrue, 2.0, 1.5, 1.0)]
    together = mc._tests(model, "ekf", [(Q, tr) for Q in Qs for tr in truths], 0.05)
    alone = [mc.consistency_test(model, "ekf", Q, truth=tr) for Q in Qs for tr in truths]
    for a, b in zip(together, alone, strict=True):
        np.testing.assert_array_equal(a.nees_mean, b.nees_mean)
        np.testing.assert_array_equal(a.nis_mean, b.nis_mean)


def test_several_qs_on_the_same_sets_are_each_qs_repeated_sets():
    # lesson 11 filters its three sets with the EKF's Qtrue and its tuned Q in one pass
    import concurrent.futures as cf

    from gpsaccel.coop.montecarlo import repeated_sets_by_q, repeated_truths

    model = CoopModel(duration=5.0)
    truths = repeated_truths(model, n_sets=3, n_runs=3, seed=11)
    with cf.ThreadPoolExecutor(2) as pool:
        both = repeated_sets_by_q(model, "ekf", {"qtrue": model.Qtrue, "tuned": None},
                                  truths=truths, executor=pool)
    assert list(both) == ["qtrue", "tuned"]
    for label, Q in (("qtrue", model.Qtrue), ("tuned", None)):
        alone = repeated_sets(model, "ekf", Q, truths=truths)
        assert len(both[label]) == 3
        for a, b in zip(both[label], alone, strict=True):
            assert np.array_equal(a.nees_mean, b.nees_mean) and np.array_equal(a.Q, b.Q)
            assert np.array_equal(a.nis_mean, b.nis_mean)
    with pytest.raises(ValueError, match="method"):
        repeated_sets_by_q(model, "lkf", {"q": None}, truths=truths)
    with pytest.raises(ValueError, match="truths"):
        repeated_sets_by_q(model, "ekf", {"q": None}, truths=[])


def test_sets_given_as_truths_are_the_sets_repeated_sets_simulates():
    # lesson 11 simulates its sets once and filters them three ways: the same numbers, bit for bit
    from gpsaccel.coop.montecarlo import repeated_truths

    truths = repeated_truths(MODEL, n_sets=2, n_runs=4, seed=11)
    given = repeated_sets(MODEL, "ekf", truths=truths)
    drawn = repeated_sets(MODEL, "ekf", n_sets=2, n_runs=4, seed=11)
    for a, b in zip(given, drawn, strict=True):
        assert np.array_equal(a.nees_mean, b.nees_mean) and np.array_equal(a.nis_mean, b.nis_mean)
    with pytest.raises(ValueError, match="truths"):
        repeated_sets(MODEL, "ekf", truths=[])


def test_tune_q_keeps_each_candidates_tests_as_a_run_of_that_q_alone():
    # lesson 11 reads the Q = Qtrue candidate's NEES from tune_q instead of filtering it again
    from gpsaccel.coop.filters import scaled_q
    from gpsaccel.coop.montecarlo import truth_runs

    model = CoopModel(duration=5.0)
    res = tune_q(model, "ekf", grid=((1.0, 2.0), (1.0,), (1.0,)), n_runs=4, n_sets=2, seed=3)
    for sc in res.scales:
        tests = res.candidate(sc)
        assert len(tests) == 2
        for tr_seed, got in zip(set_seeds(3, 2), tests, strict=True):
            alone = consistency_test(model, "ekf", scaled_q(model.Qtrue, *sc),
                                     truth=truth_runs(model, 4, tr_seed))
            assert np.array_equal(got.nees_mean, alone.nees_mean)
            assert np.array_equal(got.nis_mean, alone.nis_mean)
    assert res.candidate((2, 1, 1))[0].nees_fraction == pytest.approx(
        np.mean([t.nees_fraction for t in res.candidate((2.0, 1.0, 1.0))[:1]]))
    with pytest.raises(ValueError, match="not in list"):
        res.candidate((3.0, 1.0, 1.0))


def test_consistency_of_a_result_already_run_is_that_of_running_it():
    from gpsaccel.coop.filters import run_batch
    from gpsaccel.coop.montecarlo import truth_runs

    model = CoopModel(duration=5.0)
    truth = truth_runs(model, 4, 9)
    ran = consistency_test(model, "ekf", truth=truth, keep=True)
    read = consistency_test(model, "ekf", truth=truth, keep=True,
                            result=run_batch("ekf", model, truth.y))
    assert np.array_equal(ran.nees_mean, read.nees_mean)
    assert np.array_equal(ran.nis_mean, read.nis_mean)
    assert (ran.nees_bounds, ran.nis_bounds) == (read.nees_bounds, read.nis_bounds)
    assert read.result is not None and read.truth is truth and np.isnan(read.runtime_s)
    with pytest.raises(ValueError, match="result must be the EKF's"):
        consistency_test(model, "ekf", truth=truth, result=run_batch("lkf", model, truth.y))
    with pytest.raises(ValueError, match="result must be the EKF's"):
        consistency_test(model, "ekf", truth=truth, result=run_batch("ekf", model, truth.y[:2]))
