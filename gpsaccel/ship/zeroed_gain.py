r"""Report 004's multirate filter: compute the full gain, then zero the columns of missing sensors.

What the report does (its ``BD(:,1,n) = zeros; BD(:,4,n) = zeros``) at a step where some
components of z are not measured::

    K_full = M Hᵀ (H M Hᵀ + V)⁻¹                 the gain as if every component had arrived
    K      = K_full with the columns of the missing components set to 0
    x̂      = x̄ + K (z − H x̄)                    (missing components contribute nothing)

This is *not* the optimal update with the rows that did arrive.  The optimal one (the multirate
driver, :func:`gpsaccel.kalman.multirate.run_multirate`) uses only those rows r::

    K_r = M H_rᵀ (H_r M H_rᵀ + V_r)⁻¹

The two differ because (H M Hᵀ + V)⁻¹ couples the components: the columns of K_full that are kept
were computed on the assumption that the missing measurements would also correct the estimate, so
they under-weight what did arrive.  Any gain K gives the a posteriori error covariance of the
Joseph form, valid for every K (not only the optimal one)::

    P = (I − K H) M (I − K H)ᵀ + K V Kᵀ

whereas the short form ``P = (I − K H) M`` that the report uses holds only for the optimal gain;
with a zeroed gain it is not even symmetric, and it claims less uncertainty than the filter has.

Two covariances (``covariance=``)
---------------------------------
``"joseph"``: the filter carries the Joseph covariance of the gain it applies, and computes the
    next gains from it: a self-consistent suboptimal filter; its P is its true error covariance.
``"report"``: the filter carries ``(I − K H) M`` and computes the next gains from it, exactly as
    the report's loop.  Its true error covariance is then propagated alongside with the Joseph
    form of the same gains (``P_actual``), so its claim can be checked.

The report also applies, at the steps where the GPS arrives, the gain of its *monorate* filter
(``BD(:,:,n) = B(:,:,n)``), not the gain of the filter being run; ``full_epoch_gains`` reproduces
that (pass the monorate run's gains).  The known input enters the prediction as in the driver:
x̄_{k+1} = Φ x̂_k + B u_k, M_{k+1} = Φ P_k Φᵀ + Q.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.kalman.multirate import LinearGaussianModel, MultirateResult, check_inputs
from gpsaccel.kalman.schedule import Schedule

COVARIANCES = ("joseph", "report")


@dataclass(frozen=True, eq=False)
class ZeroedGainResult(MultirateResult):
    """A :class:`~gpsaccel.kalman.multirate.MultirateResult` plus what the zeroed gain needs.

    P : the covariance the filter carries and reports (Joseph or the report's (I − K H) M).
    P_actual : (n_epochs, n, n) the true a posteriori error covariance of the gains applied
        (Joseph form; equal to P when ``covariance="joseph"``).
    M_actual : the matching true a priori covariance.
    K_full : (n_epochs, n, p) the full gain before its columns were zeroed.
    covariance : ``"joseph"`` or ``"report"``.
    """

    P_actual: np.ndarray
    M_actual: np.ndarray
    K_full: np.ndarray
    covariance: str


def joseph(M: np.ndarray, K: np.ndarray, H: np.ndarray, V: np.ndarray) -> np.ndarray:
    """(I − K H) M (I − K H)ᵀ + K V Kᵀ: the a posteriori covariance of any gain K."""
    A = np.eye(M.shape[0]) - K @ H
    return A @ M @ A.T + K @ V @ K.T


def run_zeroed_gain(model: LinearGaussianModel, z: np.ndarray, schedule: Schedule | None = None,
                    covariance: str = "joseph", u: np.ndarray | None = None,
                    full_epoch_gains: np.ndarray | None = None) -> ZeroedGainResult:
    """Filter ``z`` (n_epochs, p) on ``schedule`` with the report's zeroed-column gain.

    Same inputs as :func:`~gpsaccel.kalman.multirate.run_multirate` (a NaN or a component the
    schedule does not deliver is missing; its gain column is zeroed).  ``full_epoch_gains``
    (n_epochs, n, p), if given, is applied instead of the filter's own gain at every epoch where
    all p components arrive (the report's reuse of its monorate gain).
    """
    covariance = _v.choice("covariance", covariance, COVARIANCES)
    inputs = check_inputs(model, z, schedule, u)
    schedule, H, V, z, B, u = (inputs.schedule, inputs.H, inputs.V, inputs.z, inputs.B, inputs.u)
    Phi, Q = np.asarray(model.Phi, dtype=float), np.asarray(model.Q, dtype=float)
    p, n = H.shape
    if full_epoch_gains is not None:
        full_epoch_gains = _v.finite_array("full_epoch_gains", full_epoch_gains,
                                           (schedule.n_epochs, n, p))

    n_epochs, n_fast = schedule.n_epochs, schedule.n_steps + 1
    x_bar, x_hat = np.empty((n_epochs, n)), np.empty((n_epochs, n))
    M, P = np.empty((n_epochs, n, n)), np.empty((n_epochs, n, n))
    M_act, P_act = np.empty((n_epochs, n, n)), np.empty((n_epochs, n, n))
    K, K_full = np.zeros((n_epochs, n, p)), np.zeros((n_epochs, n, p))
    residuals = np.full((n_epochs, p), np.nan)
    S = np.empty((n_epochs, p, p))
    used = schedule.mask & np.isfinite(z)
    x_fast, M_fast = np.empty((n_fast, n)), np.empty((n_fast, n, n))

    x = np.asarray(model.x0, dtype=float).copy()
    C = np.asarray(model.M0, dtype=float).copy()
    C_act = C.copy()  # the true covariance of this filter's error

    def predict(k: int) -> None:
        nonlocal x, C, C_act
        x = Phi @ x + (B @ u[k] if u is not None else 0.0)
        C = Phi @ C @ Phi.T + Q
        C_act = Phi @ C_act @ Phi.T + Q

    step = 0
    x_fast[0], M_fast[0] = x, C
    for i, epoch_step in enumerate(schedule.steps):
        while step < epoch_step:
            predict(step)
            step += 1
            x_fast[step], M_fast[step] = x, C
        x_bar[i], M[i], M_act[i] = x, C, C_act
        S[i] = H @ C @ H.T + V
        K_full[i] = np.linalg.solve(S[i], H @ C.T).T  # M Hᵀ S⁻¹, S symmetric
        rows = np.flatnonzero(used[i])
        if full_epoch_gains is not None and rows.size == p:
            K[i] = full_epoch_gains[i]
        else:
            K[i][:, rows] = K_full[i][:, rows]
        r = np.zeros(p)
        r[rows] = z[i, rows] - H[rows] @ x
        residuals[i, rows] = r[rows]
        x = x + K[i] @ r
        if covariance == "joseph":
            C = joseph(C, K[i], H, V)
        else:
            C = (np.eye(n) - K[i] @ H) @ C  # the report's short form, not symmetrised
        C_act = joseph(C_act, K[i], H, V)
        x_hat[i], P[i], P_act[i] = x, C, C_act
    while step < schedule.n_steps:
        predict(step)
        step += 1
        x_fast[step], M_fast[step] = x, C

    t = np.arange(n_fast) * model.dt
    return ZeroedGainResult(f"zeroed-gain ({covariance})", t, t[schedule.steps], schedule.steps,
                            x_bar, M, x_hat, P, K, residuals, S, used, x_fast, M_fast,
                            P_act, M_act, K_full, covariance)
