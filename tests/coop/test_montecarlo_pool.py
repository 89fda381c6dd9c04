"""coop.montecarlo on a process pool gives the serial numbers, bit for bit (lesson 11 relies on it).

Serially the sets' runs are stacked into one filter call with one Q per run; on a pool each set is
a call of its own with one Q: the equality below is that a run's numbers depend on nothing else
in its call, and that the truth sets depend only on their seeds.
"""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel.coop.model import CoopModel
from gpsaccel.coop.montecarlo import repeated_sets, repeated_truths, tune_q
from gpsaccel.executors import resolve_executor

MODEL = CoopModel(duration=5.0)


@pytest.fixture(scope="module")
def pool():
    with resolve_executor("processes", max_workers=2) as ex:
        yield ex


def _same_runs(a, b):
    assert len(a) == len(b)
    for r, s in zip(a, b, strict=True):
        assert r.nees_mean.tobytes() == s.nees_mean.tobytes()
        assert r.nis_mean.tobytes() == s.nis_mean.tobytes()
        assert np.array_equal(r.Q, s.Q) and r.n_runs == s.n_runs


@pytest.mark.parametrize("method", ["ekf", "ukf"])
def test_repeated_sets_on_a_pool_equal_serial(pool, method):
    serial = repeated_sets(MODEL, method, MODEL.Qtrue, n_sets=3, n_runs=4, seed=11)
    pooled = repeated_sets(MODEL, method, MODEL.Qtrue, n_sets=3, n_runs=4, seed=11, executor=pool)
    _same_runs(serial, pooled)
    # and against sets given as truths, filtered with a tuned Q (a second filter on the same sets)
    truths = repeated_truths(MODEL, n_sets=3, n_runs=4, seed=11, executor=pool)
    _same_runs(repeated_sets(MODEL, method, truths=truths),
               repeated_sets(MODEL, method, truths=truths, executor=pool))


def test_repeated_truths_on_a_pool_equal_serial(pool):
    serial = repeated_truths(MODEL, n_sets=3, n_runs=4, seed=5)
    pooled = repeated_truths(MODEL, n_sets=3, n_runs=4, seed=5, executor=pool)
    for a, b in zip(serial, pooled, strict=True):
        assert a.x.tobytes() == b.x.tobytes() and a.y.tobytes() == b.y.tobytes()


def test_tune_q_on_a_pool_equals_serial(pool):
    grid = ((1.0, 2.0), (1.0, 3.0), (1.0,))
    serial = tune_q(MODEL, "ekf", grid=grid, n_runs=4, n_sets=2, seed=3)
    pooled = tune_q(MODEL, "ekf", grid=grid, n_runs=4, n_sets=2, seed=3, executor=pool)
    assert serial.scales == pooled.scales
    assert serial.nees_fraction.tobytes() == pooled.nees_fraction.tobytes()
    assert serial.nis_fraction.tobytes() == pooled.nis_fraction.tobytes()
    assert serial.best == pooled.best
