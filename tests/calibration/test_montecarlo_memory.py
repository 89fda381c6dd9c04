"""The Monte Carlo engine's memory is linear in the duration, and its chunks cost what they do.

Memory is measured with tracemalloc (numpy reports its buffers to it), deterministic: no timing.
"""

from __future__ import annotations

import concurrent.futures as cf
import tracemalloc

import numpy as np
import pytest

import gpsaccel.calibration.montecarlo.streams as streams
from gpsaccel import monte_carlo
from gpsaccel.calibration.model import CalibrationModel
from gpsaccel.calibration.montecarlo import BLOCK_RUNS, plan, whole_blocks
from gpsaccel.calibration.montecarlo.reduction import _run_block
from gpsaccel.calibration.montecarlo.streams import (
    _block_normals,
    _standard_normals,
    _StreamedNormals,
)

MODEL = CalibrationModel()


@pytest.mark.parametrize("truth", ["error-model", "kinematic"])
def test_streamed_normals_give_the_same_numbers_as_the_whole_block(truth):
    """Streaming (long runs) draws exactly the normals of the whole-block draw, so every sum is
    bit-identical; here forced on the 30 s model with slabs that do not divide the epochs."""
    pl = plan(MODEL, truth, max_lag=9, residual_pairs=[(150, 3)], full_residual_matrix=True)
    lo, hi = BLOCK_RUNS + 17, BLOCK_RUNS + 130  # inside block 1
    whole, kept = _run_block(pl, _standard_normals(4, pl.n_normals, lo, hi), keep=True)
    old = streams.STREAM_EPOCHS
    try:
        streams.STREAM_EPOCHS = 13
        streamed, kept_s = _run_block(pl, _StreamedNormals(4, pl.n_gps, 1, 17, 130), keep=True)
    finally:
        streams.STREAM_EPOCHS = old
    for name in ("mean_e", "C_ee", "C_ex", "C_xx", "rr_band", "rr_pairs", "rr_full", "nees",
                 "nis"):
        np.testing.assert_array_equal(getattr(streamed, name), getattr(whole, name), err_msg=name)
    for name in kept:
        np.testing.assert_array_equal(kept_s[name], kept[name], err_msg=name)


def test_long_runs_stream_their_draws():
    long = CalibrationModel(duration=3600.0)
    assert isinstance(_block_normals(0, long.n_gps, 0, 5), _StreamedNormals)
    assert not isinstance(_block_normals(0, MODEL.n_gps, 0, 5), _StreamedNormals)


def _peak_mib(f) -> float:
    tracemalloc.start()
    try:
        f()
        return tracemalloc.get_traced_memory()[1] / 2**20
    finally:
        tracemalloc.stop()


def test_an_hour_at_5_hz_fits_in_tens_of_megabytes():
    """3,600 s is 18,001 GPS epochs: the full residual matrix alone would be 9.66 GiB (the old
    engine's MemoryError); the lag band, the sums and streamed draws take ≈ 60 MiB.

    Run for real: the peak is the largest of several phases' (a block in flight: ≈ 4 MiB fixed
    plus 2.6 kB per epoch; the merged sums: 3.3 kB per epoch, nothing fixed), and the steeper one
    overtakes near 6,000 epochs, so peaks of short runs extrapolated to the hour give 49 MiB where
    the hour takes 57-59 MiB: an extrapolation would prove nothing."""
    long = CalibrationModel(duration=3600.0)
    peak = _peak_mib(lambda: monte_carlo(long, 2, seed=0, progress=False))
    assert peak < 120, peak
    n = long.n_gps
    assert 8 * (2 * n) ** 2 / 2**30 > 9.6  # what the old engine asked for


def test_memory_grows_linearly_with_the_duration(monkeypatch):
    """Doubling the duration at most doubles the peak (a quadratic engine would quadruple it),
    at 60, 120 and 240 s on the code path of long runs (normals streamed, as from ≈ 400 s on)."""
    monkeypatch.setattr(streams, "WHOLE_DRAW_BYTES", 0)
    durations = (60.0, 120.0, 240.0)
    assert isinstance(_block_normals(0, CalibrationModel(duration=60.0).n_gps, 0, 5),
                      _StreamedNormals)
    # once untraced first, so one-time costs (lazy imports, caches) are in no peak
    monte_carlo(CalibrationModel(duration=durations[0]), 2, seed=0, progress=False)
    peaks = [_peak_mib(lambda d=d: monte_carlo(CalibrationModel(duration=d), 2, seed=0,
                                               progress=False))
             for d in durations]
    assert peaks[1] < 2.3 * peaks[0] and peaks[2] < 2.3 * peaks[1], peaks
    # and affine: the second doubling adds twice what the first added (not four times)
    assert peaks[2] - peaks[1] < 2.2 * (peaks[1] - peaks[0]), peaks


def test_full_matrix_is_opt_in_and_says_so():
    mc = monte_carlo(MODEL, 10, seed=0, progress=False)
    assert mc.residual_full is None and mc.max_lag == 50
    assert "lags ≤ 50" in str(mc.consistency())
    full = monte_carlo(MODEL, 10, seed=0, progress=False, full_residual_matrix=True)
    assert full.residual_correlation.shape == (151, 151, 2, 2)
    assert "every pair of epochs" in str(full.consistency())
    assert monte_carlo(MODEL, 10, seed=0, progress=False, max_lag=10_000).max_lag == 150


@pytest.mark.parametrize("kwargs, name", [
    ({"max_lag": -1}, "max_lag"),
    ({"max_lag": 2.5}, "max_lag"),
    ({"residual_pairs": [(1, 2, 3)]}, "residual_pairs"),
    ({"residual_pairs": [(0, 151)]}, "residual_pairs"),
    ({"residual_pairs": 5}, "residual_pairs"),
    ({"full_residual_matrix": "yes"}, "full_residual_matrix"),
])
def test_bad_residual_options_name_themselves(kwargs, name):
    with pytest.raises(ValueError, match=name):
        monte_carlo(MODEL, 10, progress=False, **kwargs)


class _Recording(cf.Executor):
    """Runs tasks in this thread and records the runs each one was given."""

    def __init__(self):
        self.tasks = []

    def submit(self, fn, /, *args, **kwargs):
        self.tasks.append(args[2:4])
        fut = cf.Future()
        fut.set_result(fn(*args, **kwargs))
        return fut


def test_chunks_are_whole_random_blocks():
    """A chunk that is part of a block would draw the whole block anyway: chunk_size is rounded up
    to whole blocks (chunk_size 1 for 10,000 runs drew 10,000 blocks: 70 s instead of 0.2 s)."""
    assert [whole_blocks(c) for c in (1, 999, 1000, 1001, 2500)] == [1000, 1000, 1000, 2000, 3000]
    ex = _Recording()
    small = monte_carlo(MODEL, 2 * BLOCK_RUNS + 5, seed=1, chunk_size=1, executor=ex,
                        progress=False)
    assert ex.tasks == [(0, 1000), (1000, 2000), (2000, 2005)]
    ref = monte_carlo(MODEL, 2 * BLOCK_RUNS + 5, seed=1, progress=False)
    np.testing.assert_allclose(small.P_ave, ref.P_ave, rtol=1e-12)
