"""gpsaccel.executors: every specification gives a working executor and closes what it opened."""

from __future__ import annotations

import concurrent.futures as cf
import operator

import pytest

from gpsaccel.executors import InProcessExecutor, resolve_executor


def test_in_process_executor_runs_at_submit_and_stores_exceptions():
    ex = InProcessExecutor()
    calls = []
    f = ex.submit(calls.append, 1)
    assert calls == [1] and f.done() and f.result() is None
    bad = ex.submit(operator.truediv, 1, 0)
    with pytest.raises(ZeroDivisionError):
        bad.result()
    assert list(ex.map(operator.add, [1, 2], [10, 20])) == [11, 22]
    ex.shutdown()
    with pytest.raises(RuntimeError):
        ex.submit(int)


@pytest.mark.parametrize("spec", [None, "inprocess", "threads", "processes"])
def test_named_specs_compute_and_close(spec):
    resolved = resolve_executor(spec, max_workers=2)
    assert resolved.owned
    with resolved as ex:
        assert isinstance(ex, cf.Executor)
        assert [f.result() for f in [ex.submit(pow, 2, k) for k in range(4)]] == [1, 2, 4, 8]
    with pytest.raises(RuntimeError):  # shut down on leaving the block
        ex.submit(int)
    resolved.close()  # idempotent


def test_a_given_executor_is_used_and_left_open():
    with cf.ThreadPoolExecutor(max_workers=1) as pool:
        with resolve_executor(pool) as ex:
            assert ex is pool
        assert pool.submit(operator.add, 2, 3).result() == 5  # still open: its owner closes it


@pytest.mark.parametrize("spec", ["nonsense", 3, object(), "tcp:/missing-slash"])
def test_bad_specs_raise_value_error_naming_executor(spec):
    with pytest.raises(ValueError, match="executor"):
        resolve_executor(spec)


def test_bad_max_workers():
    with pytest.raises(ValueError, match="max_workers"):
        resolve_executor("threads", max_workers=0)


def test_dask_local_spec_starts_and_closes_a_cluster():
    pytest.importorskip("distributed")
    resolved = resolve_executor("dask-local", max_workers=1)
    with resolved as ex:
        assert isinstance(ex, cf.Executor)
        assert ex.submit(operator.mul, 6, 7).result() == 42
    assert "LocalCluster" in resolved.description
