r"""The pieces every linear filter of the package shares: one gain, one Joseph update, one epoch
transition and one loop over a schedule.

Gain and Joseph update (course notation: a priori M, measurement matrix H, noise V)::

    S = H M Hᵀ + V                         residual covariance
    K = M Hᵀ S⁻¹                           gain (the optimal one for this M)
    P = (I − K H) M (I − K H)ᵀ + K V Kᵀ    a posteriori covariance of the estimate x̂ = x̄ + K r

The Joseph form holds for *any* gain K, optimal or not, and keeps P symmetric and positive
semidefinite in floating point; filterpy's ``KalmanFilter.update`` uses it too.  Every function
here broadcasts over leading axes, so a stack of candidate filters is updated at once.

Epoch transition.  n fast steps with (Φ, Q) between two updates compose into one step::

    Φ_n = Φⁿ,     Q_n = Σ_{j<n} Φʲ Q Φʲᵀ

(the calibration problem's 40 accelerometer steps between GPS fixes are one step with Φ⁴⁰, Q₄₀).

The stepping loop.  A multirate filter walks the fast grid k = 0..n_steps, predicting every step
and updating at the epochs of a :class:`~gpsaccel.kalman.schedule.Schedule`.
:func:`step_schedule` is that loop, once, with hooks: what a prediction does, what an update does
(the optimal update with the rows that arrived, or a system's own variant such as report 004's
zeroed gain), and what to record at every fast step.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.kalman.schedule import Schedule


def _T(a: np.ndarray) -> np.ndarray:
    """Transpose of the last two axes."""
    return np.swapaxes(a, -1, -2)


def gain(M: np.ndarray, H: np.ndarray, V: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(K, S): the gain K = M Hᵀ S⁻¹ and the residual covariance S = H M Hᵀ + V.

    M (..., n, n), H (..., p, n), V (..., p, p).  K is computed as Kᵀ = S⁻ᵀ (M Hᵀ)ᵀ by a linear
    solve, which is M Hᵀ S⁻¹ whether or not M (and so S) is symmetric: a filter that carries the
    report's non-symmetric (I − K H) M gets exactly the gain its own equations define.
    """
    S = H @ M @ _T(H) + V
    K = _T(np.linalg.solve(_T(S), H @ _T(M)))
    return K, S


def joseph_update(M: np.ndarray, K: np.ndarray, H: np.ndarray, V: np.ndarray) -> np.ndarray:
    """(I − K H) M (I − K H)ᵀ + K V Kᵀ: the a posteriori covariance of any gain K (..., n, n)."""
    A = np.eye(M.shape[-1]) - K @ H
    return A @ M @ _T(A) + K @ V @ _T(K)


def epoch_transition(Phi: np.ndarray, Q: np.ndarray, steps: int) -> tuple[np.ndarray, np.ndarray]:
    """(Φⁿ, Σ_{j<n} Φʲ Q Φʲᵀ): mean transition and process noise of n = ``steps`` fast steps.

    Computed by the same recursion as n predictions, Q_n ← Φ Q_n Φᵀ + Q, so it agrees with a
    filter that predicts step by step to the last bit that recursion keeps.
    """
    steps = _v.integer("steps", steps, minimum=0)
    F = np.eye(Phi.shape[0])
    Qe = np.zeros_like(Q, dtype=float)
    for _ in range(steps):
        F = Phi @ F
        Qe = Phi @ Qe @ Phi.T + Q
    return F, Qe


def step_schedule(schedule: Schedule, predict: Callable[[int], None],
                  update: Callable[[int], None],
                  on_step: Callable[[int], None] | None = None) -> None:
    """Walk the fast grid of ``schedule``: the one loop of every multirate filter here.

    ``predict(k)`` moves the filter from fast step k to k + 1; ``update(i)`` runs the update of
    epoch i (at fast step ``schedule.steps[i]``, after the predictions that reach it);
    ``on_step(k)``, if given, is called when step k has been reached (k = 0 first, and at an
    epoch before its update), for whatever a caller records on the fast grid.  After the last
    epoch the filter keeps predicting to the end of the grid.
    """
    step = 0
    if on_step is not None:
        on_step(0)
    for i, epoch_step in enumerate(schedule.steps):
        while step < epoch_step:
            predict(step)
            step += 1
            if on_step is not None:
                on_step(step)
        update(i)
    while step < schedule.n_steps:
        predict(step)
        step += 1
        if on_step is not None:
            on_step(step)
