r"""The Monte Carlo validation of the calibration filter, as the reports ran it, but as arrays.

Reports 000, 001 and 003 check their filter on an ensemble of N realizations (10,000; 5,000):

* the ensemble-mean error ``e_ave(t_i) = (1/N) Σ_l e^l(t_i)`` (should be ≈ 0), with
  ``e^l = x^l − x̂^l``;
* the sample error variance ``P_ave(t_i) = 1/(N − 1) Σ_l (e^l − e_ave)(e^l − e_ave)ᵀ`` (should be
  ≈ the filter's P(t_i));
* orthogonality ``(1/N) Σ_l (e^l − e_ave) x̂^lᵀ`` (should be ≈ 0);
* independence of the residuals ``(1/N) Σ_l r^l(t_i) r^l(t_m)ᵀ`` (≈ 0 for t_m ≠ t_i).

:func:`monte_carlo` computes exactly these statistics (and the ensemble NEES and NIS) and
:meth:`MonteCarloResult.consistency` says how far each is from theory in units of its own sampling
error (:mod:`gpsaccel.kalman.consistency`), with pass/fail at a stated family-wise false-alarm rate.

Why it is fast: the ensemble is filtered as arrays
-----------------------------------------------------
The gains and covariances of this problem do not depend on the data.  So the covariance recursion
runs once, per GPS epoch (the fast steps between fixes only predict):

    M_0 = M0;   S_i = H M_i Hᵀ + V;   K_i = M_i Hᵀ S_i⁻¹;
    P_i = (I − K_i H) M_i (I − K_i H)ᵀ + K_i V K_iᵀ          (Joseph form, as filterpy)
    M_{i+1} = Φ_N P_i Φ_Nᵀ + Q_N,   Φ_N = Φ^N,   Q_N = Σ_{k=0}^{N−1} Φ^k Γ W Γᵀ Φ^kᵀ

with N = ``gps_every`` (40) accelerometer steps per GPS interval, and the means of all the
realizations of a block go through the same K_i at once::

    r_i = z_i − H x̄_i,   x̂_i = x̄_i + K_i r_i,   x̄_{i+1} = Φ_N x̂_i.

These are the filterpy filter's own equations; its 40 predictions per interval compose to Φ_N and
Q_N up to rounding.  The tests run filterpy (:func:`gpsaccel.run_multirate`) once per realization
on the measurements this module draws and find the same statistics to 1e-10.

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

The kinematic truth (reports 001/003)
-------------------------------------
With ``truth="kinematic"`` the true p, v are the closed forms of a(t) = A sin ωt while the
accelerometer is integrated by Euler's rule.  By linearity the true error state is the error-model
state *plus a deterministic path* that does not depend on the draw at all::

    x_kin(t_i) = x_em(t_i) + d(t_i),   d = [p_cf − p_Euler, v_cf − v_Euler, 0](t_i)

where p_cf, v_cf are the closed forms from p0 = v0 = 0 and p_Euler, v_Euler the Euler integrals of
the samples a(t_j) from 0 (:func:`gpsaccel.calibration.simulation.truth_mean`).  d is what the
Euler error model leaves out (the
accelerometer samples a(t_j), the velocity integrates a over the interval).  The filter is linear,
so the ensemble-mean error is then not zero but the filter's error on d alone,
:attr:`MonteCarloResult.predicted_mean_error`; the engine shows it and the verdict flags it.

Random draws, reproducible and mergeable
----------------------------------------
Run number l uses column ``l mod BLOCK_RUNS`` of the block ``b = l // BLOCK_RUNS``, whose
standard normals come from ``numpy.random.default_rng(SeedSequence(seed, spawn_key=(b,)))`` — the
b-th child of ``SeedSequence(seed)`` — drawn as one (605, BLOCK_RUNS) array in C order (row k:
normal k of every run; the layout the array filter reads without a transpose), whole for runs up
to ≈ 400 s, streamed a few epochs at a time beyond (the same numbers: numpy's Generator draws an
array whole or in consecutive pieces alike).  Run l is therefore the same realization whatever
``n_runs``, ``chunk_size``, executor or number of workers.  Each chunk returns its sums (count,
means, centred co-moments, the residual products Σ r_i r_{i−k}ᵀ up to ``max_lag`` and any pairs
asked for, Σ NEES, Σ NIS) and chunks merge in order (Chan et al.'s pairwise update), so memory
does not grow with ``n_runs``, only linearly with the duration, and the statistics
depend on the chunking only through floating-point rounding (≪ 1e-12 relative).  These draws are
*not* those of :func:`gpsaccel.simulate` (a different random stream, and no per-step noise): use
:func:`realizations` to get the engine's measurements and truths.
"""

from __future__ import annotations

import sys
from collections import deque
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel._blas import single_threaded_blas
from gpsaccel.calibration.model import STATE_NAMES, STATE_UNITS, CalibrationModel
from gpsaccel.calibration.simulation import TRUTHS, truth_mean
from gpsaccel.executors import resolve_executor
from gpsaccel.kalman.consistency import (
    ConsistencyReport,
    chi2_bounds,
    cross_moment_se,
    fraction_inside,
    sample_covariance_se,
    verdict_from_z,
    z_cross_products,
    z_ensemble_normalized_squared,
    z_sample_covariance,
    z_sample_mean,
)
from gpsaccel.kalman.epochs import gain_recursion
from gpsaccel.kalman.update import CovarianceGuard, epoch_transition

#: Runs per random block: one ``SeedSequence`` child each, and the largest array pass.
BLOCK_RUNS = 1000
#: Residual products kept by default: Σ r(t_i) r(t_{i−k})ᵀ for every epoch and k = 0 .. 50 (10 s at
#: 5 Hz: the pairs the three reports print are lags 1, 10 and 50).
DEFAULT_MAX_LAG = 50
#: A block's standard normals are drawn as one array when it takes at most this many bytes (runs
#: up to ≈ 400 s on the defaults); longer runs stream them, a few epochs at a time (same numbers).
WHOLE_DRAW_BYTES = 64 * 2**20
#: Epochs per streamed slab of normals.
STREAM_EPOCHS = 64


# ------------------------------------------------------------------------------ the plan
@dataclass(frozen=True, eq=False)
class EnsemblePlan:
    """Everything a worker needs to filter a block: data-independent, small, picklable.

    Shapes with n = n_gps epochs: K (n, 3, 2), P and M (n, 3, 3), S (n, 2, 2); Phi_N, Q_N (3, 3);
    L0 (3, 3) Cholesky factor of M0; LQ (3, 3) of Q_N (its third row and column are zero);
    LV (2, 2) of V; offset (n, 3) the deterministic part of the truth (zero for the error model);
    X (n, 3, 3) the covariance of the true error state; Xhat (n, 3, 3) the covariance of x̂;
    P_inv, S_inv (n, 3, 3), (n, 2, 2): inverses of P and S (for Σ NEES = tr(P⁻¹ Σ e eᵀ));
    mean_e, mean_xprior, mean_xhat (n, 3) and mean_r (n, 2): the expected error, prior, estimate
    and residual (the filter run on the offset alone; zero for the error model).
    What is accumulated of the residual products: max_lag (lags 0 .. max_lag of every epoch, at
    most n − 1), pairs ((i, m) with i − m > max_lag, sorted) and full (the whole (2n)² matrix).
    """

    truth: str
    n_gps: int
    t: np.ndarray
    H: np.ndarray
    Phi_N: np.ndarray
    Q_N: np.ndarray
    L0: np.ndarray
    LQ: np.ndarray
    LV: np.ndarray
    M: np.ndarray
    K: np.ndarray
    P: np.ndarray
    S: np.ndarray
    P_inv: np.ndarray
    S_inv: np.ndarray
    X: np.ndarray
    Xhat: np.ndarray
    offset: np.ndarray
    x0: np.ndarray
    mean_e: np.ndarray
    mean_xprior: np.ndarray
    mean_xhat: np.ndarray
    mean_r: np.ndarray
    max_lag: int = DEFAULT_MAX_LAG
    pairs: tuple[tuple[int, int], ...] = ()
    full: bool = False

    @property
    def n_normals(self) -> int:
        """Standard normals per realization: x_0 (3), u_i (2 per interval), η_i (2 per epoch)."""
        return 3 + 2 * (self.n_gps - 1) + 2 * self.n_gps


def gps_interval_noise(model: CalibrationModel) -> tuple[np.ndarray, np.ndarray]:
    """(Φ_N, Q_N): one GPS interval of N = gps_every accelerometer steps, composed exactly.

    Φ_N = Φ^N and Q_N = Σ_{k=0}^{N−1} Φ^k Γ W Γᵀ Φ^kᵀ, the covariance of the summed accelerometer
    noise u_i (see the module docstring for its closed form), by the same recursion as N filter
    predictions: Q ← Φ Q Φᵀ + ΓWΓᵀ.
    """
    return epoch_transition(model.Phi, model.Q, model.gps_every)


def plan(model: CalibrationModel, truth: str = "error-model", max_lag: int = DEFAULT_MAX_LAG,
         residual_pairs: Iterable[tuple[int, int]] = (),
         full_residual_matrix: bool = False) -> EnsemblePlan:
    """The gains, covariances, noise factors and truth offset of ``model`` (see module docstring),
    and which residual products to accumulate (see :func:`monte_carlo`).

    Besides the filter's M, K, P, S it propagates the covariance X of the true error state
    (X_0 = M0, X_{i+1} = Φ_N X_i Φ_Nᵀ + Q_N) and the covariance of the estimate,
    Cov x̂_i = Cov x̄_i + K_i S_i K_iᵀ with Cov x̄_0 = 0, Cov x̄_{i+1} = Φ_N Cov x̂_i Φ_Nᵀ (the
    residual r_i is uncorrelated with x̄_i); for a consistent filter Cov x̂ = X − P.  Built from
    products, not from the difference X − P, so it is exactly zero where x̂ cannot vary (the bias
    estimate at t = 0).
    """
    if not isinstance(model, CalibrationModel):
        raise ValueError(f"model must be a CalibrationModel, got {type(model).__name__}")
    truth = _v.choice("truth", truth, TRUTHS)
    n = model.n_gps
    max_lag = min(_v.integer("max_lag", max_lag, minimum=0), n - 1)
    pairs = _residual_pairs(residual_pairs, n, max_lag)
    if not isinstance(full_residual_matrix, bool):
        raise ValueError(f"full_residual_matrix must be True or False, got {full_residual_matrix!r}")
    H, V = model.H, model.V
    Phi_N, Q_N = gps_interval_noise(model)
    # K = M Hᵀ S⁻¹ with S⁻¹ as filterpy forms it; P unsymmetrised (the Joseph form's own)
    K, M, P, S = gain_recursion(Phi_N, Q_N, H, V, model.M0, n, inverse=True, symmetrise=False)
    X = np.empty((n, 3, 3))
    Xhat = np.empty((n, 3, 3))
    Xi, Cbar = model.M0.copy(), np.zeros((3, 3))
    for i in range(n):
        if i > 0:
            Xi = Phi_N @ X[i - 1] @ Phi_N.T + Q_N
            Cbar = Phi_N @ Xhat[i - 1] @ Phi_N.T
        X[i] = Xi
        Xhat[i] = Cbar + K[i] @ S[i] @ K[i].T
    guard = CovarianceGuard(
        "monte_carlo", "The ensemble engine runs the covariance (Joseph) form; its statistics "
        "are measured against this P. Check the filter with run_multirate(..., "
        "method=\"information\") on this model (README: which form when).")
    guard.check_stack(model.t_gps, M=M, P=P)
    guard.warn(stacklevel=4)
    LQ = np.zeros((3, 3))
    LQ[:2, :2] = np.linalg.cholesky(Q_N[:2, :2])  # Q_N has no bias part: Γ's third entry is 0
    # Expected values: E x_i = d_i (the offset; x_0 and the noise have zero mean), and the filter,
    # being linear, maps it like data: E r_i = H d_i − H E x̄_i, E x̂_i = E x̄_i + K_i E r_i.
    if not np.array_equal(H, np.eye(2, 3)):
        raise ValueError("model.H must be [I 0] (GPS measures δp and δv) for the ensemble engine")
    offset = truth_mean(model, truth)
    x0 = np.asarray(model.x0, dtype=float)
    mean_xprior = np.empty((n, 3))
    mean_xhat = np.empty((n, 3))
    mean_r = np.empty((n, 2))
    for i in range(n):
        mean_xprior[i] = x0 if i == 0 else Phi_N @ mean_xhat[i - 1]
        mean_r[i] = H @ offset[i] - H @ mean_xprior[i]
        mean_xhat[i] = mean_xprior[i] + K[i] @ mean_r[i]
    return EnsemblePlan(truth, n, model.t_gps, H, Phi_N, Q_N, np.linalg.cholesky(model.M0), LQ,
                        np.linalg.cholesky(V), M, K, P, S, np.linalg.inv(P), np.linalg.inv(S), X,
                        Xhat, offset, x0, offset - mean_xhat, mean_xprior, mean_xhat, mean_r,
                        max_lag, pairs, full_residual_matrix)


def _residual_pairs(pairs: Iterable[tuple[int, int]], n: int,
                    max_lag: int) -> tuple[tuple[int, int], ...]:
    """Requested epoch pairs as sorted (later, earlier) with a lag beyond max_lag (the others are
    in the lag band anyway); ValueError naming ``residual_pairs`` for anything else."""
    try:
        given = [tuple(p) for p in pairs]
    except TypeError:
        raise ValueError("residual_pairs must be a sequence of (i, m) epoch-index pairs") from None
    out = set()
    for p in given:
        if len(p) != 2:
            raise ValueError(f"residual_pairs: each pair must be (i, m), got {p!r}")
        i, m = (_v.integer("residual_pairs index", q, minimum=0) for q in p)
        if max(i, m) >= n:
            raise ValueError(f"residual_pairs: epoch indices must be < n_gps = {n}, got {p!r}")
        i, m = max(i, m), min(i, m)
        if i - m > max_lag:
            out.add((i, m))
    return tuple(sorted(out))


# ------------------------------------------------------------------------------ draws and filter
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


def _run_block(pl: EnsemblePlan, xi: np.ndarray | _ArrayNormals,
               keep: bool = False) -> tuple[EnsembleSums, dict[str, np.ndarray] | None]:
    """Truth, measurements, filter and sums for each column of standard normals xi (n_normals, m).

    Everything is linear, so every quantity is its expected value (``pl.mean_*``, the filter run
    on the deterministic offset; zero for the error model) plus a zero-mean part driven by the
    noise.  ``xi`` is the (n_normals, m) array of standard normals or a streamed source of them.
    The loop runs the zero-mean part only — x̃_i = Φ_N x̃_{i−1} + u_{i−1},
    r̃_i = x̃_i[:2] + η_i − x̄̃_i[:2], x̂̃_i = x̄̃_i + K_i r̃_i, ẽ_i = x̃_i − x̂̃_i — with every
    quantity a (component, run) array, so that each step is one small matrix times m columns.
    Per epoch it accumulates G_i = Σ w wᵀ of w = [ẽ; x̂̃; 1] (which holds Σ ẽ ẽᵀ, Σ ẽ x̂̃ᵀ and
    the sums Σ ẽ, Σ x̂̃), and the residual products Σ r̃_i r̃_{i−k}ᵀ for k = 0 .. max_lag from a
    ring of the last max_lag + 1 residuals (each written twice, at q and q + max_lag + 1 with
    q = −i mod (max_lag + 1), so that r̃_i, r̃_{i−1}, ... r̃_{i−k} are one contiguous slice), the
    requested pairs, and with ``full`` every residual.  The expected values go back in afterwards,
    exactly: with r = r̃ + ρ, Σ r rᵀ = Σ r̃ r̃ᵀ + ρ (Σ r̃)ᵀ + (Σ r̃) ρᵀ + m ρ ρᵀ, and likewise
    Σ e eᵀ for NEES = tr(P⁻¹ e eᵀ) and NIS = tr(S⁻¹ r rᵀ).  The co-moments are centred on the
    expected values, so no precision is lost to a large mean.

    With ``keep`` it also returns the full arrays (epoch, component, run): x (true error state),
    z, x_bar, x_hat, r.
    """
    normals = xi if isinstance(xi, _ArrayNormals) else _ArrayNormals(xi, pl.n_gps)
    m, n, L = normals.m, pl.n_gps, pl.max_lag
    Phi_N, K = pl.Phi_N, pl.K
    LQ, LV = pl.LQ[:2, :2], pl.LV
    w = np.empty((7, m))  # [ẽ; x̂̃; 1]
    w[6] = 1.0
    xhat = w[3:6]
    G = np.empty((n, 7, 7))
    Kr = np.empty((3, m))
    ring = np.empty((2 * (L + 1), 2, m))  # r̃_i at q and q + L + 1, q = −i mod (L + 1)
    band = np.zeros((n, L + 1, 2, 2))  # Σ r̃_i r̃_{i−k}ᵀ
    s_r = np.empty((n, 2))  # Σ r̃_i
    earlier: dict[int, np.ndarray] = {mm: np.empty(0) for _, mm in pl.pairs}  # r̃_m kept for
    # the requested pairs (each filled at its epoch m, before the later epoch i reads it)
    later: dict[int, list[int]] = {}
    for j, (i, _) in enumerate(pl.pairs):
        later.setdefault(i, []).append(j)
    pair_sums = np.zeros((len(pl.pairs), 2, 2))
    r_all = np.empty((2 * n, m)) if pl.full else None  # stacked r̃: r̃_0[p], r̃_0[v], r̃_1[p], ...
    ubuf, ebuf = np.empty((2, m)), np.empty((2, m))
    x = pl.L0 @ normals.x0  # x̃_0 ~ N(0, M0)
    xbar = np.zeros((3, m))  # x̄_0 = x0 is deterministic
    if keep:
        kept = {k: np.empty((n, d, m)) for k, d in
                (("x", 3), ("z", 2), ("x_bar", 3), ("x_hat", 3), ("r", 2))}
    for i, un, en in normals.epochs():
        # u_{i−1} = L_Q ξ and η_i = L_V ξ (both factors lower triangular 2x2)
        for out, Lf, xn in ((ubuf, LQ, un), (ebuf, LV, en)):
            if xn is None:
                continue
            np.multiply(Lf[0, 0], xn[0], out=out[0])
            np.multiply(Lf[1, 0], xn[0], out=out[1])
            out[1] += Lf[1, 1] * xn[1]
        if i > 0:
            x = Phi_N @ x
            x[:2] += ubuf  # x̃_i = Φ_N x̃_{i−1} + u_{i−1}
            xbar = Phi_N @ xhat  # x̄̃_i = Φ_N x̂̃_{i−1}
        q = (-i) % (L + 1)
        r = ring[q]
        np.add(x[:2], ebuf, out=r)
        r -= xbar[:2]  # r̃_i = H x̃_i + η_i − H x̄̃_i
        ring[q + L + 1] = r
        k = min(i, L)
        window = ring[q:q + k + 1].reshape(2 * (k + 1), m)  # r̃_i, r̃_{i−1}, ..., r̃_{i−k}
        band[i, :k + 1] = (r @ window.T).reshape(2, k + 1, 2).transpose(1, 0, 2)
        s_r[i] = r.sum(axis=1)
        for j in later.get(i, ()):
            pair_sums[j] = r @ earlier[pl.pairs[j][1]].T
        if i in earlier:
            earlier[i] = r.copy()
        if r_all is not None:
            r_all[2 * i:2 * i + 2] = r
        np.matmul(K[i], r, out=Kr)
        np.add(xbar, Kr, out=xhat)  # x̂̃_i = x̄̃_i + K_i r̃_i
        np.subtract(x, xhat, out=w[:3])  # ẽ_i
        np.matmul(w, w.T, out=G[i])
        if keep:
            kept["x"][i], kept["x_bar"][i], kept["x_hat"][i] = x, xbar, xhat
            kept["z"][i], kept["r"][i] = x[:2] + ebuf, r
    # -- the sums, expected values put back
    sw = G[:, 6, :6]  # Σ w (n, 6)
    de, dx = sw[:, :3] / m, sw[:, 3:] / m  # block means of ẽ and x̂̃
    C = G[:, :6, :6] - m * (sw[:, :, None] / m) * (sw[:, None, :] / m)
    mu = pl.mean_e
    see = G[:, :3, :3] + mu[:, :, None] * sw[:, None, :3] + sw[:, :3, None] * mu[:, None, :] \
        + m * mu[:, :, None] * mu[:, None, :]  # Σ e eᵀ
    rho = pl.mean_r  # (n, 2): Σ r_i r_mᵀ = Σ r̃_i r̃_mᵀ + ρ_i (Σ r̃_m)ᵀ + (Σ r̃_i) ρ_mᵀ + m ρ_i ρ_mᵀ
    rr_full = None
    if r_all is not None:
        rr_full = r_all @ r_all.T
    if rho.any():
        def shift(i, mm):
            return (rho[i][..., :, None] * s_r[mm][..., None, :]
                    + s_r[i][..., :, None] * rho[mm][..., None, :]
                    + m * rho[i][..., :, None] * rho[mm][..., None, :])
        ii = np.arange(n)[:, None]
        mm = ii - np.arange(L + 1)[None, :]
        band += np.where((mm >= 0)[..., None, None], shift(ii, np.maximum(mm, 0)), 0.0)
        if pl.pairs:
            pi, pm = np.array(pl.pairs).T
            pair_sums += shift(pi, pm)
        if rr_full is not None:
            rv, sv = rho.reshape(-1), s_r.reshape(-1)
            rr_full += np.outer(rv, sv)
            rr_full += np.outer(sv, rv)
            rr_full += m * np.outer(rv, rv)
    rr_diag = band[:, 0]  # Σ r_i r_iᵀ
    sums = EnsembleSums(
        n=m, mean_e=mu + de, mean_xhat=pl.mean_xhat + dx,
        mean_r=pl.mean_r + s_r / m,
        C_ee=C[:, :3, :3], C_ex=C[:, :3, 3:], C_xx=C[:, 3:, 3:], rr_band=band,
        rr_pairs=pair_sums, rr_full=rr_full,
        nees=np.einsum("iab,iba->i", pl.P_inv, see),
        nis=np.einsum("iab,iba->i", pl.S_inv, rr_diag))
    if not keep:
        return sums, None
    kept["x"] += pl.offset[:, :, None]
    kept["z"] += pl.offset[:, :2, None]
    kept["x_bar"] += pl.mean_xprior[:, :, None]
    kept["x_hat"] += pl.mean_xhat[:, :, None]
    kept["r"] += pl.mean_r[:, :, None]
    return sums, kept


@dataclass(frozen=True, eq=False)
class Realizations:
    """The engine's realizations ``runs`` (global run indices), for checking it against filterpy.

    x_gps (m, n_gps, 3): the true error state at the GPS times; z (m, n_gps, 2) the measurement
    (m, m/s); x_bar, x_hat (m, n_gps, 3) and residuals (m, n_gps, 2) the engine's filter.
    """

    runs: np.ndarray
    t: np.ndarray
    x_gps: np.ndarray
    z: np.ndarray
    x_bar: np.ndarray
    x_hat: np.ndarray
    r: np.ndarray


def realizations(model: CalibrationModel, start: int, stop: int, seed: int = 0,
                 truth: str = "error-model") -> Realizations:
    """Runs ``start`` .. ``stop − 1`` of the ensemble ``monte_carlo(model, ..., seed, truth)`` uses.

    Feed ``z[l]`` to :func:`gpsaccel.run_multirate` to run filterpy on realization l; its
    ``x_gps[l] − x_hat`` is the error the engine accumulated for that run.
    """
    seed = _v.integer("seed", seed, minimum=0)
    start = _v.integer("start", start, minimum=0)
    stop = _v.integer("stop", stop, minimum=start + 1)
    pl = plan(model, truth)
    out = _run_block(pl, _standard_normals(seed, pl.n_normals, start, stop), keep=True)[1]
    assert out is not None  # keep=True keeps them
    runs_first = {k: np.ascontiguousarray(v.transpose(2, 0, 1)) for k, v in out.items()}
    return Realizations(np.arange(start, stop), pl.t, runs_first["x"], runs_first["z"],
                        runs_first["x_bar"], runs_first["x_hat"], runs_first["r"])


# ------------------------------------------------------------------------------ mergeable sums
@dataclass(eq=False)
class EnsembleSums:
    """Sufficient statistics of a set of runs; two sets merge with :meth:`merge`.

    n : runs.  mean_e, mean_xhat (n_gps, 3) and mean_r (n_gps, 2): means.
    C_ee, C_ex, C_xx (n_gps, 3, 3): centred co-moments Σ (e − ē)(e − ē)ᵀ, Σ (e − ē)(x̂ − x̂̄)ᵀ,
    Σ (x̂ − x̂̄)(x̂ − x̂̄)ᵀ.
    rr_band (n_gps, max_lag + 1, 2, 2): Σ r_i r_{i−k}ᵀ (zero where i − k < 0).
    rr_pairs (len(pairs), 2, 2): Σ r_i r_mᵀ for the plan's requested pairs (i, m).
    rr_full (2 n_gps, 2 n_gps) or None: Σ r rᵀ over the stacked residuals [r_0; r_1; ...], only
    when the full matrix was asked for.
    nees, nis (n_gps,): Σ eᵀ P⁻¹ e and Σ rᵀ S⁻¹ r.
    """

    n: int
    mean_e: np.ndarray
    mean_xhat: np.ndarray
    mean_r: np.ndarray
    C_ee: np.ndarray
    C_ex: np.ndarray
    C_xx: np.ndarray
    rr_band: np.ndarray
    rr_pairs: np.ndarray
    rr_full: np.ndarray | None
    nees: np.ndarray
    nis: np.ndarray

    def merge(self, other: EnsembleSums, in_place: bool = False) -> EnsembleSums:
        """The sums of both sets (Chan, Golub & LeVeque's pairwise update of the co-moments).

        With ``in_place`` the residual products (the largest arrays, O(n_gps · max_lag)) are
        added into this object's arrays, which the result then shares: the engine's running
        total uses it, so that a merge holds two copies of them, not three.
        """
        n = self.n + other.n
        fa, fb = self.n / n, other.n / n
        de = other.mean_e - self.mean_e
        dx = other.mean_xhat - self.mean_xhat
        w = self.n * other.n / n
        rr_band, rr_pairs = ((np.add(a, b, out=a) if in_place else a + b)
                             for a, b in ((self.rr_band, other.rr_band),
                                          (self.rr_pairs, other.rr_pairs)))
        a, b = self.rr_full, other.rr_full
        rr_full = None if a is None or b is None else (np.add(a, b, out=a) if in_place else a + b)
        return EnsembleSums(
            n,
            self.mean_e + fb * de,
            self.mean_xhat + fb * dx,
            fa * self.mean_r + fb * other.mean_r,
            self.C_ee + other.C_ee + w * de[:, :, None] * de[:, None, :],
            self.C_ex + other.C_ex + w * de[:, :, None] * dx[:, None, :],
            self.C_xx + other.C_xx + w * dx[:, :, None] * dx[:, None, :],
            rr_band, rr_pairs, rr_full,
            self.nees + other.nees,
            self.nis + other.nis,
        )


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


# ------------------------------------------------------------------------------ the result
@dataclass(frozen=True, eq=False)
class MonteCarloResult:
    """The ensemble statistics of :func:`monte_carlo`.  Units: m, m/s, m/s² and their products;
    n below is the number of GPS epochs (151 on the defaults).

    Attributes
    ----------
    n_runs, seed, truth : what was run.
    t : (n,) GPS times (s).
    e_ave : (n, 3) ensemble-mean error (1/N) Σ e, e = x − x̂.
    P_ave : (n, 3, 3) sample error covariance with the N − 1 divisor (reports' Eq. 16).
    P : (n, 3, 3) the filter's a posteriori covariance.
    orthogonality : (n, 3, 3) (1/N) Σ (e − e_ave) x̂ᵀ (reports' Eq. 17).
    residual_lags : (n, L + 1, 2, 2) (1/N) Σ r(t_i) r(t_{i−k})ᵀ for k = 0 .. L = ``max_lag``
        (Eq. 18 for every pair up to that lag; NaN where i − k < 0).  Any product is read with
        :meth:`residual_product`: report 000's r(30 s) r(29.8 s)ᵀ is ``residual_product(150, 149)``.
    residual_pairs : the requested pairs (i, m), i > m, beyond ``max_lag``, and
        residual_pair_products : (len(residual_pairs), 2, 2) their (1/N) Σ r(t_i) r(t_m)ᵀ.
    residual_full : (n, n, 2, 2) every pair, only with ``full_residual_matrix=True`` (else None);
        also as :attr:`residual_correlation`.
    residual_mean : (n, 2) (1/N) Σ r.
    S : (n, 2, 2) the residual covariance H M Hᵀ + V.
    nees, nis : (n,) ensemble averages of eᵀ P⁻¹ e and rᵀ S⁻¹ r.
    estimate_covariance : (n, 3, 3) the theoretical covariance of x̂ (for orthogonality's error).
    estimate_sample_covariance : (n, 3, 3) the sample covariance of x̂ (N − 1 divisor).
    predicted_mean_error : (n, 3) the mean error theory predicts for this truth: zero for the
        error model, the filter's error on the deterministic path d for the kinematic truth.
    """

    n_runs: int
    seed: int
    truth: str
    t: np.ndarray
    e_ave: np.ndarray
    P_ave: np.ndarray
    P: np.ndarray
    orthogonality: np.ndarray
    residual_lags: np.ndarray
    residual_pairs: tuple[tuple[int, int], ...]
    residual_pair_products: np.ndarray
    residual_full: np.ndarray | None
    residual_mean: np.ndarray
    S: np.ndarray
    nees: np.ndarray
    nis: np.ndarray
    estimate_covariance: np.ndarray
    estimate_sample_covariance: np.ndarray
    predicted_mean_error: np.ndarray
    model: CalibrationModel = field(repr=False)

    @property
    def sigma(self) -> np.ndarray:
        """(n, 3) the filter's standard deviations √diag P."""
        return np.sqrt(np.diagonal(self.P, axis1=1, axis2=2))

    @property
    def e_ave_se(self) -> np.ndarray:
        """(n, 3) standard error of e_ave for a consistent filter, √(diag P / N)."""
        return self.sigma / np.sqrt(self.n_runs)

    @property
    def P_ave_se(self) -> np.ndarray:
        """(n, 3, 3) standard error of each element of P_ave, √((P_ab² + P_aa P_bb)/(N − 1)).

        At t = 0 for P_ave[δp, δp]: 0.990 · √(2/9999) = 0.014 m² on report 000's numbers.
        """
        return sample_covariance_se(self.P, self.n_runs)

    @property
    def orthogonality_se(self) -> np.ndarray:
        """(n, 3, 3) standard error of the orthogonality matrix, √((N − 1) P_aa Cov x̂_bb) / N."""
        d_e = np.diagonal(self.P, axis1=1, axis2=2)
        d_x = np.diagonal(self.estimate_covariance, axis1=1, axis2=2)
        return cross_moment_se(d_e[:, :, None], d_x[:, None, :], self.n_runs, centered=True)

    @property
    def max_lag(self) -> int:
        """The largest lag k of :attr:`residual_lags` (every product Σ r_i r_{i−k}ᵀ up to it)."""
        return self.residual_lags.shape[1] - 1

    @property
    def residual_correlation(self) -> np.ndarray:
        """(n, n, 2, 2) (1/N) Σ r(t_i) r(t_m)ᵀ for every pair: only kept on request, since it
        takes 32 n² bytes (10 GB for an hour at 5 Hz); ValueError otherwise."""
        if self.residual_full is None:
            raise ValueError(
                "residual_correlation: the full matrix of residual products was not kept; run "
                "monte_carlo(..., full_residual_matrix=True), or read single products with "
                f"residual_product(i, m) (lags up to max_lag = {self.max_lag}, plus "
                "residual_pairs=...)")
        return self.residual_full

    def residual_product(self, i: int, m: int) -> np.ndarray:
        """(2, 2) (1/N) Σ r(t_i) r(t_m)ᵀ, from the lag band, the requested pairs or the full
        matrix; ValueError saying how to keep it when none has it.  Negative indices count from
        the end, as in numpy."""
        n = self.t.size
        i, m = (_v.integer(name, v, minimum=-n) % n for name, v in (("i", i), ("m", m)))
        if max(i, m) >= n:
            raise ValueError(f"i and m must be epoch indices < {n}, got {(i, m)}")
        if self.residual_full is not None:
            return self.residual_full[i, m]
        if abs(i - m) <= self.max_lag:
            return self.residual_lags[i, i - m] if i >= m else self.residual_lags[m, m - i].T
        later, earlier = max(i, m), min(i, m)
        if (later, earlier) in self.residual_pairs:
            out = self.residual_pair_products[self.residual_pairs.index((later, earlier))]
            return out if i > m else out.T
        raise ValueError(
            f"residual_product({i}, {m}): lag {abs(i - m)} > max_lag = {self.max_lag} and the pair "
            f"was not requested; run monte_carlo(..., residual_pairs=[({i}, {m})]) or a larger "
            f"max_lag")

    def residual_product_se(self, i: int, m: int) -> np.ndarray:
        """(2, 2) standard error of :meth:`residual_product` (i ≠ m), √(S_i,aa S_m,bb / N) for
        independent residuals."""
        d = np.diagonal(self.S, axis1=1, axis2=2)
        return cross_moment_se(d[i][:, None], d[m][None, :], self.n_runs)

    def residual_correlation_se(self) -> np.ndarray:
        """(n, n, 2, 2) standard error of :attr:`residual_correlation` off the diagonal (i ≠ m),
        √(S_i,aa S_m,bb / N) for independent residuals (32 n² bytes; see
        :meth:`residual_product_se` for one pair)."""
        d = np.diagonal(self.S, axis1=1, axis2=2)
        return cross_moment_se(d[:, None, :, None], d[None, :, None, :], self.n_runs)

    def z_scores(self) -> dict[str, np.ndarray]:
        """z-scores of every statistic against theory for a consistent filter (NaN: no spread).

        Each is exactly N(0, 1) under theory, for any N (:mod:`gpsaccel.kalman.consistency`):

        ``e_ave`` (n, 3): e_ave / √(P_aa / N).
        ``P_ave`` (n, 3, 3): diagonal through χ²(N − 1); off the diagonal the regression form of
            :func:`~gpsaccel.kalman.consistency.z_sample_covariance` (element (a, b) conditions on b).
        ``orthogonality`` (n, 3, 3): N O_ab / √(P_aa Σ (x̂_b − x̂̄_b)²), exact because e is
            independent of x̂ (:func:`~gpsaccel.kalman.consistency.z_cross_products`).
        ``residual_lags`` (n, L + 1, 2, 2): for the pair (t_i, t_{i−k}), k ≥ 1,
            N R_ab / √(S_i,aa Σ r_{i−k},b²), exact because r_i is independent of r_{i−k}; NaN for
            k = 0 and where i − k < 0.  ``residual_pairs`` (len(residual_pairs), 2, 2): the same
            for the requested pairs.  ``residual_correlation`` (n, n, 2, 2), only when the full
            matrix was kept: every pair t_m < t_i, NaN for i ≤ m (each pair counts once).
        ``nees``, ``nis`` (n,): N·NEES ~ χ²(3N), N·NIS ~ χ²(2N).

        The standard errors (:attr:`e_ave_se`, :attr:`P_ave_se`, :attr:`orthogonality_se`,
        :meth:`residual_correlation_se`) are the unconditional ones, for plotting; the z-scores
        use the sample's own Σ b² where that makes them exact, so z is close to, not equal to,
        value / SE.
        """
        N, n = self.n_runs, self.t.size
        d_P = np.diagonal(self.P, axis1=1, axis2=2)
        d_X = np.diagonal(self.estimate_sample_covariance, axis1=1, axis2=2) * (N - 1)
        ortho = z_cross_products(N * self.orthogonality, d_P[:, :, None], d_X[:, None, :])
        d_S = np.diagonal(self.S, axis1=1, axis2=2)
        power = N * np.einsum("mbb->mb", self.residual_lags[:, 0])  # Σ_l r_m,b²
        L = self.max_lag
        later = np.arange(n)[:, None] - np.arange(L + 1)[None, :]  # epoch i − k
        lz = z_cross_products(N * np.nan_to_num(self.residual_lags), d_S[:, None, :, None],
                              power[np.maximum(later, 0)][:, :, None, :])
        lz[(later < 0) | (np.arange(L + 1)[None, :] == 0)] = np.nan
        pi = np.array([p[0] for p in self.residual_pairs], dtype=int)
        pm = np.array([p[1] for p in self.residual_pairs], dtype=int)
        pz = z_cross_products(N * self.residual_pair_products, d_S[pi][:, :, None],
                              power[pm][:, None, :])
        extra = {}
        if self.residual_full is not None:
            rz = z_cross_products(N * self.residual_full, d_S[:, None, :, None],
                                  power[None, :, None, :])
            rz[np.triu_indices(n)] = np.nan  # keep pairs t_m < t_i only
            extra["residual_correlation"] = rz
        return {
            "e_ave": z_sample_mean(self.e_ave, d_P, N),
            "P_ave": z_sample_covariance(self.P_ave, self.P, N),
            "orthogonality": ortho,
            "residual_lags": lz,
            "residual_pairs": pz,
            **extra,
            "nees": z_ensemble_normalized_squared(self.nees, 3, N),
            "nis": z_ensemble_normalized_squared(self.nis, 2, N),
        }

    def summary(self) -> str:
        """The numbers the reports printed, each with its standard error (what the CLI prints).

        P_ave − P for (δp, δp) at t = 0 (report 000 printed −0.013), the residual correlation
        r(t_end) r(t_end − T)ᵀ (report 000's pair), and, for a truth the error model does not
        describe exactly, the mean error theory predicts (:attr:`predicted_mean_error`) at its
        largest in standard errors of e_ave.
        """
        d0, se0 = self.P_ave[0, 0, 0] - self.P[0, 0, 0], self.P_ave_se[0, 0, 0]
        lines = [f"P_ave − P at t = 0 for (δp, δp): {d0:+.4f} m² (standard error {se0:.4f} m², "
                 f"z = {d0 / se0:+.2f}; report 000 printed −0.013)"]
        rc, rc_se = self.residual_product(-1, -2), self.residual_product_se(-1, -2)
        lines.append(f"residual correlation r({self.t[-1]:g} s) r({self.t[-2]:g} s)ᵀ (report "
                     f"000's pair) ± its standard error:")
        for a in range(2):
            lines.append("  [" + ",  ".join(f"{rc[a, b]:+.2e} ± {rc_se[a, b]:.1e}"
                                            for b in range(2)) + "]")
        if np.any(self.predicted_mean_error):
            lines.append("the mean error theory predicts for this truth (the filter's error on "
                         "the Euler integration error alone), at its largest, in standard "
                         "errors of e_ave:")
            ratio = np.abs(self.predicted_mean_error) / self.e_ave_se
            for k, (name, unit) in enumerate(zip(STATE_NAMES, STATE_UNITS, strict=True)):
                i = int(np.argmax(ratio[:, k]))
                lines.append(f"  {name:>2}: {self.predicted_mean_error[i, k]:+.3g} {unit} at "
                             f"t = {self.t[i]:g} s = {ratio[i, k]:.1f} SE (e_ave there "
                             f"{self.e_ave[i, k]:+.3g})")
        return "\n".join(lines)

    def consistency(self, alpha: float = 0.01) -> ConsistencyReport:
        """Verdicts on every statistic, family-wise false-alarm rate ``alpha`` for the table.

        Rows: e_ave per state; P_ave − P per diagonal element (exact χ²) and off the diagonal;
        orthogonality (9 elements); residual whiteness (4 elements for every pair of epochs up to
        ``max_lag`` apart and every requested pair; every pair t_m < t_i when the full matrix was
        kept);
        ensemble NEES (χ²(3N)) and NIS (χ²(2N)).  Each row reports its largest |z| over time with
        its location and value; it fails when that exceeds the Bonferroni bound of its own tests
        at ``alpha / rows``.
        """
        z = self.z_scores()
        t, N = self.t, self.n_runs
        rows = 11
        a = _v.probability("alpha", alpha) / rows
        se_e, se_P, se_o = self.e_ave_se, self.P_ave_se, self.orthogonality_se
        verdicts = []
        for k, (s, u) in enumerate(zip(STATE_NAMES, STATE_UNITS, strict=True)):
            def mean_at(i: tuple, k: int = k, u: str = u) -> str:
                return (f"t = {t[i[0]]:g} s: e_ave = {self.e_ave[i[0], k]:.3g} {u} (SE "
                        f"{se_e[i[0], k]:.2g}, predicted {self.predicted_mean_error[i[0], k]:.3g})")

            verdicts.append(verdict_from_z(f"e_ave[{s}]", z["e_ave"][:, k], mean_at, a))
        dP = self.P_ave - self.P
        for k, s in enumerate(STATE_NAMES):
            def variance_at(i: tuple, k: int = k) -> str:
                return (f"t = {t[i[0]]:g} s: P_ave − P = {dP[i[0], k, k]:.3g} "
                        f"(P {self.P[i[0], k, k]:.3g}, SE {se_P[i[0], k, k]:.2g})")

            verdicts.append(verdict_from_z(f"P_ave−P[{s},{s}]", z["P_ave"][:, k, k],
                                           variance_at, a))
        off = z["P_ave"].copy()
        idx = np.arange(3)
        off[:, idx, idx] = np.nan
        off[:, 1, 0] = off[:, 2, 0] = off[:, 2, 1] = np.nan  # symmetric: count each pair once
        verdicts.append(verdict_from_z(
            "P_ave−P off-diagonal", off,
            lambda i: f"t = {t[i[0]]:g} s, ({STATE_NAMES[i[1]]},{STATE_NAMES[i[2]]}): "
                      f"{dP[i]:.3g} (SE {se_P[i]:.2g})",
            a))
        verdicts.append(verdict_from_z(
            "orthogonality", z["orthogonality"],
            lambda i: f"t = {t[i[0]]:g} s, ({STATE_NAMES[i[1]]},{STATE_NAMES[i[2]]}): "
                      f"{self.orthogonality[i]:.3g} (SE {se_o[i]:.2g})",
            a))
        if self.residual_full is not None:
            rc = self.residual_full
            verdicts.append(verdict_from_z(
                "residual whiteness", z["residual_correlation"],
                lambda i: f"r({t[i[0]]:g} s)[{'pv'[i[2]]}] r({t[i[1]]:g} s)[{'pv'[i[3]]}]: "
                          f"{rc[i]:.3g}",
                a))
        else:  # the lag band and the requested pairs, as one family of tests
            band, pairs = z["residual_lags"], z["residual_pairs"]
            n_band = t.size * (self.max_lag + 1)

            def where(idx):
                j, a_, b_ = idx[0] // 4, idx[0] % 4 // 2, idx[0] % 2
                if j < n_band:
                    i, mm = j // (self.max_lag + 1), j // (self.max_lag + 1) - j % (self.max_lag + 1)
                else:
                    i, mm = self.residual_pairs[j - n_band]
                val = self.residual_product(i, mm)[a_, b_]
                return f"r({t[i]:g} s)[{'pv'[a_]}] r({t[mm]:g} s)[{'pv'[b_]}]: {val:.3g}"

            verdicts.append(verdict_from_z(
                "residual whiteness", np.concatenate([band.reshape(-1), pairs.reshape(-1)]), where, a))
        for name, key, dof in (("NEES", "nees", 3), ("NIS", "nis", 2)):
            vals = getattr(self, key)
            bounds = chi2_bounds(dof, N, 0.05)
            inside = fraction_inside(vals, bounds)

            def chi2_at(i: tuple, vals: np.ndarray = vals, bounds: tuple = bounds,
                        inside: float = inside) -> str:
                return (f"t = {t[i[0]]:g} s: {vals[i[0]]:.4g}; {inside:.0%} of epochs inside "
                        f"the 95% bounds [{bounds[0]:.4g}, {bounds[1]:.4g}]")

            verdicts.append(verdict_from_z(f"{name} (χ²({dof}N)/N)", z[key], chi2_at, a))
        assert len(verdicts) == rows
        title = (f"Monte Carlo consistency: {N} runs, truth {self.truth}, seed {self.seed}, "
                 f"{t.size} GPS epochs; residual whiteness over " +
                 ("every pair of epochs" if self.residual_full is not None else
                  f"lags ≤ {self.max_lag}" + (f" and {len(self.residual_pairs)} more pairs"
                                              if self.residual_pairs else "")))
        return ConsistencyReport(title, tuple(verdicts), float(alpha))


# ------------------------------------------------------------------------------ the engine
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
        executor (see the module docstring; the stream differs from :func:`gpsaccel.simulate`'s).
    truth : ``"error-model"`` (report 000) or ``"kinematic"`` (reports 001/003), as in
        :func:`gpsaccel.simulate`.
    chunk_size : runs per task submitted to the executor (default :data:`BLOCK_RUNS`), rounded
        up to a whole number of random blocks (:data:`BLOCK_RUNS` runs): a block's normals are
        drawn together, so a task of part of a block would pay for drawing all of it (10,000 runs
        in chunks of 1 took 70 s instead of 0.2 s).  Results do not depend on it beyond rounding.
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
    """Submit chunks with at most ``window`` in flight; merge results in chunk order."""
    pending: deque = deque()
    chunks = _chunks(n_runs, chunk_size)
    acc = None
    try:
        for lo, hi in chunks:
            pending.append(ex.submit(_chunk_sums, pl, seed, lo, hi))
            while len(pending) >= window:
                acc = _take(pending.popleft(), acc, bar)
        while pending:
            acc = _take(pending.popleft(), acc, bar)
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
