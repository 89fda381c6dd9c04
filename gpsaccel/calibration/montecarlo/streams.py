r"""The Monte Carlo's random draws: exact per GPS interval, seeded per block, streamed when long.

The 200 Hz noise, represented exactly
-------------------------------------
The truth of the error model is x_{j+1} = Φ x_j + Γ w_j with w_j ~ N(0, W) at every
accelerometer step.  Over one GPS interval only the sum matters::

    x_{i+1} = Φ_N x_i + u_i,   u_i = Σ_{k=0}^{N−1} Φ^{N−1−k} Γ w_{iN+k} ~ N(0, Q_N).

With Φ^j Γ = −[Δt²(j + ½), Δt, 0]ᵀ, Q_N = W [[Δt⁴ N(4N² − 1)/12, Δt³ N²/2, 0],
[Δt³ N²/2, N Δt², 0], [0, 0, 0]]: a 2-D Gaussian per interval, drawn through its Cholesky factor.
A realization therefore costs 3 + 2(n_gps − 1) + 2 n_gps = 605 standard normals on the defaults
(x_0, u_i, GPS noise η_i), not the 6,000 accelerometer samples; the law of (x_i, z_i) at the GPS
epochs, which is all the filter and the statistics see, is exactly the same.

Random draws, reproducible
--------------------------
Run number l uses column ``l mod BLOCK_RUNS`` of the block ``b = l // BLOCK_RUNS``, whose
standard normals come from ``numpy.random.default_rng(SeedSequence(seed, spawn_key=(b,)))`` — the
b-th child of ``SeedSequence(seed)`` — drawn as one (605, BLOCK_RUNS) array in C order (row k:
normal k of every run; the layout the array filter reads without a transpose), whole for runs up
to ≈ 400 s, streamed a few epochs at a time beyond (the same numbers: numpy's Generator draws an
array whole or in consecutive pieces alike).  Run l is therefore the same realization whatever
``n_runs``, ``chunk_size``, executor or number of workers.  These draws are *not* those of
:func:`gpsaccel.simulate` (a different random stream, and no per-step noise): use
:func:`~.reduction.realizations` to get the engine's measurements and truths.

:data:`WHOLE_DRAW_BYTES` and :data:`STREAM_EPOCHS` are read from this module when a block is
drawn, so a test that sets them here (to force streaming on a short run) is obeyed.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

#: Runs per random block: one ``SeedSequence`` child each, and the largest array pass.
BLOCK_RUNS = 1000
#: A block's standard normals are drawn as one array when it takes at most this many bytes (runs
#: up to ≈ 400 s on the defaults); longer runs stream them, a few epochs at a time (same numbers).
WHOLE_DRAW_BYTES = 64 * 2**20
#: Epochs per streamed slab of normals.
STREAM_EPOCHS = 64


def _standard_normals(seed: int, n_normals: int, start: int, stop: int) -> np.ndarray:
    """(n_normals, stop − start) standard normals of runs ``start:stop``: column l is run l.

    Block b holds runs b·BLOCK_RUNS .. (b+1)·BLOCK_RUNS − 1; its normals are one
    (n_normals, BLOCK_RUNS) array drawn in C order from
    ``default_rng(SeedSequence(seed, spawn_key=(b,)))``, always whole, so a run's normals do not
    depend on which runs are asked for.
    """
    parts = []
    for b in range(start // BLOCK_RUNS, (stop - 1) // BLOCK_RUNS + 1):
        lo = max(start, b * BLOCK_RUNS) - b * BLOCK_RUNS
        hi = min(stop, (b + 1) * BLOCK_RUNS) - b * BLOCK_RUNS
        rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(b,)))
        parts.append(rng.standard_normal((n_normals, BLOCK_RUNS))[:, lo:hi])
    return parts[0] if len(parts) == 1 else np.concatenate(parts, axis=1)


class _ArrayNormals:
    """The normals of some runs as one (n_normals, m) array (see :func:`_standard_normals`), read
    epoch by epoch: x_0's three rows, then per epoch i the rows of u_{i−1} (i > 0) and of η_i."""

    def __init__(self, xi: np.ndarray, n_gps: int) -> None:
        self.xi, self.n, self.m = xi, n_gps, xi.shape[1]
        self.x0 = xi[:3]

    def epochs(self) -> Iterator[tuple[int, np.ndarray | None, np.ndarray]]:
        xi, nu = self.xi, 3 + 2 * (self.n - 1)
        for i in range(self.n):
            yield i, (xi[1 + 2 * i:3 + 2 * i] if i else None), xi[nu + 2 * i:nu + 2 * i + 2]


class _StreamedNormals(_ArrayNormals):
    """The same normals of runs ``lo:hi`` of block ``b``, drawn STREAM_EPOCHS epochs at a time.

    The block's stream is x_0 (3 rows), u_0 .. u_{n−2} (2 rows each), η_0 .. η_{n−1} (2 rows
    each), each row BLOCK_RUNS normals; numpy's Generator gives the same numbers whether an array
    is drawn whole or in consecutive pieces.  Two generators walk it in step: one from the start
    (x_0 and the u's), one from the first η, which it reaches by drawing the u rows once and
    discarding them (the price of streaming: the u's are drawn twice).  Memory: two slabs of
    2 · STREAM_EPOCHS rows, not the 4 n_gps rows of the whole block.
    """

    def __init__(self, seed: int, n_gps: int, b: int, lo: int, hi: int) -> None:
        self.n, self.m, self.cols = n_gps, hi - lo, slice(lo, hi)
        ss = np.random.SeedSequence(seed, spawn_key=(b,))
        self.gu = np.random.default_rng(ss)
        self.ge = np.random.default_rng(ss)
        self.x0 = self.gu.standard_normal((3, BLOCK_RUNS))[:, self.cols]
        self.ge.standard_normal((3, BLOCK_RUNS))
        left = n_gps - 1
        while left:
            k = min(left, STREAM_EPOCHS)
            self.ge.standard_normal((2 * k, BLOCK_RUNS))
            left -= k

    def epochs(self) -> Iterator[tuple[int, np.ndarray | None, np.ndarray]]:
        i = 0
        while i < self.n:
            k = min(self.n - i, STREAM_EPOCHS)
            ku = k - 1 if i == 0 else k  # there is no u before epoch 0
            U = self.gu.standard_normal((2 * ku, BLOCK_RUNS))[:, self.cols] if ku else None
            E = self.ge.standard_normal((2 * k, BLOCK_RUNS))[:, self.cols]
            for j in range(k):
                ju = j - 1 if i == 0 else j
                u = U[2 * ju:2 * ju + 2] if U is not None and i + j else None
                yield i + j, u, E[2 * j:2 * j + 2]
            i += k


def _block_normals(seed: int, n_gps: int, lo: int, hi: int) -> _ArrayNormals:
    """Normals of runs ``lo:hi`` (within one block): drawn whole if that is small, else streamed."""
    b = lo // BLOCK_RUNS
    n_normals = 3 + 2 * (n_gps - 1) + 2 * n_gps
    if 8 * n_normals * BLOCK_RUNS <= WHOLE_DRAW_BYTES:
        return _ArrayNormals(_standard_normals(seed, n_normals, lo, hi), n_gps)
    return _StreamedNormals(seed, n_gps, b, lo - b * BLOCK_RUNS, hi - b * BLOCK_RUNS)

