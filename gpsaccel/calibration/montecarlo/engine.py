r"""The Monte Carlo engine: :func:`monte_carlo` splits the runs into chunks, hands them to an
executor and merges their sums in order.

A chunk is whole random blocks (:mod:`.streams`), filtered and reduced to sums by
:mod:`.reduction` in the worker (:func:`_chunk_sums`, the one function an executor runs); at most
2 × workers chunks are in flight, and their sums merge in chunk order, so the result does not
depend on the executor or the number of workers, and memory not on ``n_runs``.
"""

from __future__ import annotations

import collections
import sys
from collections.abc import Iterable, Iterator

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel._blas import single_threaded_blas
from gpsaccel._interrupt import latched_sigint
from gpsaccel.calibration.model import CalibrationModel
from gpsaccel.calibration.montecarlo.planning import DEFAULT_MAX_LAG, EnsemblePlan, plan
from gpsaccel.calibration.montecarlo.reduction import EnsembleSums, _run_block
from gpsaccel.calibration.montecarlo.statistics import MonteCarloResult
from gpsaccel.calibration.montecarlo.streams import BLOCK_RUNS, _block_normals
from gpsaccel.calibration.simulation import TRUTHS
from gpsaccel.executors import resolve_executor


def _chunks(n_runs: int, chunk_size: int) -> Iterator[tuple[int, int]]:
    for lo in range(0, n_runs, chunk_size):
        yield lo, min(n_runs, lo + chunk_size)


def _progress_bar(progress: bool, total: int, desc: str):
    """tqdm.auto's bar: in a Jupyter kernel with ipywidgets the notebook bar (a lesson's long
    cell shows progress), elsewhere the terminal bar on stderr when it is a terminal, and nothing
    on a pipe, a log or under pytest (``disable=None``: tqdm's own "not a tty" rule, which its
    notebook bar does not apply)."""
    from tqdm.auto import tqdm

    quiet = not progress or sys.stderr is None
    return tqdm(total=total, desc=desc, unit="run", disable=True if quiet else None, leave=False)


def monte_carlo(model: CalibrationModel, n_runs: int, seed: int = 0, truth: str = "error-model",
                chunk_size: int | None = None, executor: object = None,
                progress: bool = True, max_lag: int = DEFAULT_MAX_LAG,
                residual_pairs: Iterable[tuple[int, int]] = (),
                full_residual_matrix: bool = False) -> MonteCarloResult:
    """The reports' Monte Carlo validation of the calibration filter, as arrays, streamed.

    Parameters
    ----------
    model : the :class:`~gpsaccel.calibration.model.CalibrationModel`.
    n_runs : ensemble size N (≥ 2).
    seed : non-negative integer; run l is the same realization for every n_runs, chunk_size and
        executor (:mod:`.streams`; the stream differs from :func:`gpsaccel.simulate`'s).
    truth : ``"error-model"`` (report 000) or ``"kinematic"`` (reports 001/003), as in
        :func:`gpsaccel.simulate`.
    chunk_size : runs per task submitted to the executor (default :data:`BLOCK_RUNS`), rounded
        up to a whole number of random blocks (:data:`BLOCK_RUNS` runs): a block's normals are
        drawn together, so a task of part of a block would pay for drawing all of it (chunks of
        1 draw the block once per run).  Results do not depend on it beyond rounding.
        At most 2 × workers tasks are in flight.
    executor : None (in this process), any :class:`concurrent.futures.Executor` (a process pool,
        ``dask.distributed.Client(...).get_executor()``), a ``dask.distributed.Client`` (left
        open), or a specification understood by
        :func:`gpsaccel.executors.resolve_executor` (``"processes"``, ``"dask-local"``,
        ``"tcp://host:port"``), which is then opened and closed here.
    progress : show a tqdm bar (in a Jupyter kernel, or when stderr is a terminal).
    max_lag : residual products Σ r(t_i) r(t_{i−k})ᵀ are kept for every epoch i and every lag
        k = 0 .. max_lag (default :data:`DEFAULT_MAX_LAG` = 50, i.e. 10 s at 5 Hz; clipped to
        n_gps − 1); the whiteness verdict tests all of them.
    residual_pairs : further epoch pairs (i, m) whose product to keep, at any lag.
    full_residual_matrix : keep every pair, the (2 n_gps)² matrix of the engine before 0.2
        (:attr:`MonteCarloResult.residual_correlation`): memory quadratic in the duration, 32 n²
        bytes per task and per result (0.7 MB at 30 s, 10 GB at 3,600 s).

    Memory (n = n_gps epochs, L = max_lag, B = BLOCK_RUNS, 8-byte floats).  What grows with the
    duration is the per-epoch sums: 4(L + 1) floats of residual products and ≈ 100 of moments
    per epoch, held at most two or three times over (a block's sums, the running total, the
    result), and the plan and model (≈ 150 per epoch); a block in flight adds its working arrays,
    8 B (4L + 40) bytes, and its draws, D = 8 (4n + 1) B bytes when that is at most
    WHOLE_DRAW_BYTES (n ≲ 2,000, drawn whole), else 16 · STREAM_EPOCHS · B · 2 (streamed).
    Measured peak (tracemalloc, in-process) ≤ 8 n (10 L + 300) bytes + 3 MB: linear in the
    duration, flat in ``n_runs``; ≈ 80 MB for an hour at 5 Hz (n = 18,001, L = 50).  With
    ``full_residual_matrix`` add 32 n² bytes ×3 (sums, running total, result; 10 GB each for
    an hour).  Each worker of a pool holds its own block.  Measured side by side with the engine
    that kept every pair: ``benchmarks/montecarlo_memory.py``.

    Returns a :class:`MonteCarloResult`; ``result.consistency()`` gives the verdicts.
    """
    if not isinstance(model, CalibrationModel):
        raise ValueError(f"model must be a CalibrationModel, got {type(model).__name__}")
    n_runs = _v.integer("n_runs", n_runs, minimum=2)
    seed = _v.integer("seed", seed, minimum=0)
    truth = _v.choice("truth", truth, TRUTHS)
    chunk_size = BLOCK_RUNS if chunk_size is None else _v.integer("chunk_size", chunk_size,
                                                                  minimum=1)
    chunk_size = whole_blocks(chunk_size)
    pl = plan(model, truth, max_lag, residual_pairs, full_residual_matrix)
    resolved = resolve_executor(executor)  # ValueError naming ``executor`` for anything else
    with resolved as ex:
        window = 1 if resolved.max_workers == 1 else 2 * max(2, resolved.max_workers or 2)
        sums = _run_ordered(ex, pl, seed, n_runs, chunk_size, window,
                            _progress_bar(progress, n_runs, f"monte carlo ({truth})"))
    return _result(model, pl, sums, seed)


def whole_blocks(chunk_size: int) -> int:
    """``chunk_size`` rounded up to a multiple of :data:`BLOCK_RUNS` (see :func:`monte_carlo`)."""
    return -(-chunk_size // BLOCK_RUNS) * BLOCK_RUNS


def _run_ordered(ex, pl: EnsemblePlan, seed: int, n_runs: int, chunk_size: int, window: int,
                 bar) -> EnsembleSums:
    """Submit chunks with at most ``window`` in flight; merge results in chunk order.  Ctrl-C
    stops it where it lands, and at the latest at the next chunk (:mod:`gpsaccel._interrupt`:
    an interrupt dropped inside a finaliser would otherwise let every chunk run)."""
    # collections.deque, not a name of this module: Sphinx 9.2's autodoc (Python >= 3.12) loads
    # an imported class as a member and fails on deque's signature (sphinx-doc/sphinx#14576)
    pending: collections.deque = collections.deque()
    chunks = _chunks(n_runs, chunk_size)
    acc = None
    try:
        with latched_sigint(raise_now=True) as interrupted:
            for lo, hi in chunks:
                interrupted.check()
                pending.append(ex.submit(_chunk_sums, pl, seed, lo, hi))
                while len(pending) >= window:
                    acc = _take(pending.popleft(), acc, bar)
                    interrupted.check()
            while pending:
                acc = _take(pending.popleft(), acc, bar)
                interrupted.check()
    finally:
        for f in pending:
            f.cancel()
        bar.close()
    assert acc is not None  # n_runs ≥ 1: one chunk at least
    return acc


def _take(future, acc: EnsembleSums | None, bar) -> EnsembleSums:
    part = future.result()
    bar.update(part.n)
    return part if acc is None else acc.merge(part, in_place=True)


def _result(model: CalibrationModel, pl: EnsemblePlan, s: EnsembleSums,
            seed: int) -> MonteCarloResult:
    N, n = s.n, pl.n_gps
    lags = s.rr_band  # divided in place: one copy of the band, not two, at the peak
    lags /= N
    lags[np.arange(n)[:, None] < np.arange(pl.max_lag + 1)[None, :]] = np.nan  # i − k < 0
    full = None
    if s.rr_full is not None:
        full = np.ascontiguousarray((s.rr_full / N).reshape(n, 2, n, 2).transpose(0, 2, 1, 3))
    return MonteCarloResult(
        n_runs=N, seed=seed, truth=pl.truth, t=pl.t.copy(), e_ave=s.mean_e,
        P_ave=s.C_ee / (N - 1), P=pl.P.copy(), orthogonality=s.C_ex / N,
        residual_lags=lags, residual_pairs=pl.pairs, residual_pair_products=s.rr_pairs / N,
        residual_full=full, residual_mean=s.mean_r, S=pl.S.copy(),
        nees=s.nees / N, nis=s.nis / N, estimate_covariance=pl.Xhat.copy(),
        estimate_sample_covariance=s.C_xx / (N - 1),
        predicted_mean_error=pl.mean_e.copy(), model=model)


def _chunk_sums(pl: EnsemblePlan, seed: int, start: int, stop: int) -> EnsembleSums:
    """Sums of runs ``start:stop``, one random block (≤ BLOCK_RUNS runs) at a time, merged in order.

    Module-level and picklable: this is what an executor runs.  BLAS runs single-threaded meanwhile
    (:mod:`gpsaccel._blas`): the products are small, and the executor's workers are the parallelism.
    """
    acc = None
    lo = start
    with single_threaded_blas():
        while lo < stop:
            hi = min(stop, (lo // BLOCK_RUNS + 1) * BLOCK_RUNS)
            part = _run_block(pl, _block_normals(seed, pl.n_gps, lo, hi))[0]
            acc = part if acc is None else acc.merge(part, in_place=True)
            lo = hi
    assert acc is not None  # start < stop: one block at least
    return acc

