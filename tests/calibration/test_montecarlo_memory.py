"""The Monte Carlo engine's memory is linear in the duration, and its chunks cost what they do.

Memory is measured with tracemalloc (numpy reports its buffers to it), deterministic: no timing.
"""

from __future__ import annotations

import concurrent.futures as cf
import tracemalloc

import numpy as np
import pytest

import gpsaccel.calibration.montecarlo.engine as engine
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


#: The engine's phases, each entered and left through one of these names of its module: the plan,
#: a chunk's blocks in flight, the result.  Between them, the merged sums are held.
PHASES = ("plan", "_chunk_sums", "_result")


def _phase_peaks(monkeypatch, model: CalibrationModel) -> list[int]:
    """The traced peak (bytes) of each phase of ``monte_carlo(model, 2)`` and of each stretch
    between phases, in the order they ran: everything held at the time counts, as in the peak."""
    peaks: list[int] = []

    def close() -> None:  # the stretch that ends here: its peak, then a fresh one
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.reset_peak()

    def timed(f):
        def wrapper(*args, **kwargs):
            close()
            try:
                return f(*args, **kwargs)
            finally:
                close()
        return wrapper

    def draws(seed, n_gps, lo, hi):  # a block's loop over its epochs is a phase of its own
        normals = _block_normals(seed, n_gps, lo, hi)
        loop = normals.epochs

        def epochs():
            close()
            yield from loop()
            close()
        normals.epochs = epochs
        return normals

    with monkeypatch.context() as mp:
        for name in PHASES:
            mp.setattr(engine, name, timed(getattr(engine, name)))
        mp.setattr(engine, "_block_normals", draws)
        tracemalloc.start()
        try:
            monte_carlo(model, 2, seed=0, progress=False)
            close()
        finally:
            tracemalloc.stop()
    return peaks


#: Three durations, equally spaced, whose epochs leave the hour's last slab of streamed draws
#: (n_gps ≡ 18,001 mod STREAM_EPOCHS: the last slab is still held when a block's sums are made).
DURATIONS = (144.0, 272.0, 400.0)


def test_an_hour_at_5_hz_fits_in_tens_of_megabytes(monkeypatch):
    """3,600 s is 18,001 GPS epochs: the full residual matrix alone would be 9.66 GiB (the old
    engine's MemoryError); the lag band, the sums and streamed draws take ≈ 57 MiB.

    Proved on short runs, phase by phase, on the code path of long runs (normals streamed, as from
    ≈ 400 s on): each phase's peak (the plan; a block's draws and set-up, its loop over the epochs,
    its sums; the result; the stretches between them) is measured at DURATIONS, shown affine in
    the number of epochs (equal steps add equal bytes, within 10 %: a quadratic phase would add
    1.6 times as much the second step) and extrapolated to the hour.  The whole peak's
    extrapolation would prove nothing: a steeper phase (a block's sums) overtakes the loop (≈ 4
    MiB fixed) near 6,000 epochs, 49 MiB extrapolated where the hour took 57 MiB; below ≈ 700
    epochs phases still cross their own fixed temporaries.  Checked once by running the hour
    (20+ CPU s, removed from the suite): 56.52 MiB measured, the block's sums; 56.52 predicted.
    """
    monkeypatch.setattr(streams, "WHOLE_DRAW_BYTES", 0)
    models = [CalibrationModel(duration=d) for d in DURATIONS]
    hour = CalibrationModel(duration=3600.0).n_gps
    n = [m.n_gps for m in models]
    assert n[2] - n[1] == n[1] - n[0]
    assert {k % streams.STREAM_EPOCHS for k in (*n, hour)} == {hour % streams.STREAM_EPOCHS}
    assert isinstance(_block_normals(0, n[0], 0, 5), _StreamedNormals)
    # once untraced first, so one-time costs (lazy imports, caches) are in no peak
    monte_carlo(models[0], 2, seed=0, progress=False)
    runs = [_phase_peaks(monkeypatch, m) for m in models]
    assert len({len(r) for r in runs}) == 1 and len(runs[0]) == 2 * len(PHASES) + 3, runs
    slack = 2**16  # bytes: a phase that does not grow may wobble by a few small objects
    predicted = []
    for a, b, c in zip(*runs, strict=True):
        assert abs((c - b) - (b - a)) <= 0.1 * abs(b - a) + slack, (a, b, c)  # affine
        predicted.append(c + (hour - n[2]) * max(c - b, b - a, 0) / (n[2] - n[1]))
    assert max(predicted) / 2**20 < 120, [p / 2**20 for p in predicted]
    assert max(predicted) > 4 * max(runs[2])  # the hour's peak is a growing phase's
    # the whole peak is affine too (a quadratic engine's would grow faster each step)
    peaks = [max(r) for r in runs]
    assert peaks[2] - peaks[1] < 1.1 * (peaks[1] - peaks[0]), peaks
    assert 8 * (2 * hour) ** 2 / 2**30 > 9.6  # what the old engine asked for


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
