r"""The plan of the Monte Carlo: everything that does not depend on the draws, computed once.

Why the ensemble can be filtered as arrays
------------------------------------------
The gains and covariances of this problem do not depend on the data.  So the covariance recursion
runs once, per GPS epoch (the fast steps between fixes only predict):

    M_0 = M0;   S_i = H M_i Hᵀ + V;   K_i = M_i Hᵀ S_i⁻¹;
    P_i = (I − K_i H) M_i (I − K_i H)ᵀ + K_i V K_iᵀ          (Joseph form, as filterpy)
    M_{i+1} = Φ_N P_i Φ_Nᵀ + Q_N,   Φ_N = Φ^N,   Q_N = Σ_{k=0}^{N−1} Φ^k Γ W Γᵀ Φ^kᵀ

with N = ``gps_every`` (40) accelerometer steps per GPS interval, and the means of all the
realizations of a block go through the same K_i at once (:mod:`.reduction`)::

    r_i = z_i − H x̄_i,   x̂_i = x̄_i + K_i r_i,   x̄_{i+1} = Φ_N x̂_i.

These are the filterpy filter's own equations; its 40 predictions per interval compose to Φ_N and
Q_N up to rounding.  The tests run filterpy (:func:`gpsaccel.run_multirate`) once per realization
on the measurements the engine draws and find the same statistics to 1e-10.

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
:attr:`~.statistics.MonteCarloResult.predicted_mean_error`; the engine shows it and the verdict
flags it.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.calibration.model import CalibrationModel
from gpsaccel.calibration.simulation import TRUTHS, truth_mean
from gpsaccel.kalman.epochs import gain_recursion
from gpsaccel.kalman.update import CovarianceGuard, epoch_transition

#: Residual products kept by default: Σ r(t_i) r(t_{i−k})ᵀ for every epoch and k = 0 .. 50 (10 s at
#: 5 Hz: the pairs the three reports print are lags 1, 10 and 50).
DEFAULT_MAX_LAG = 50


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
    noise u_i (:mod:`.streams` gives its closed form), by the same recursion as N filter
    predictions: Q ← Φ Q Φᵀ + ΓWΓᵀ.
    """
    return epoch_transition(model.Phi, model.Q, model.gps_every)


def plan(model: CalibrationModel, truth: str = "error-model", max_lag: int = DEFAULT_MAX_LAG,
         residual_pairs: Iterable[tuple[int, int]] = (),
         full_residual_matrix: bool = False) -> EnsemblePlan:
    """The gains, covariances, noise factors and truth offset of ``model`` (see module docstring),
    and which residual products to accumulate (see :func:`~.engine.monte_carlo`).

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

