r"""Filter a whole ensemble of measurement records with a gain sequence computed once.

For a linear-Gaussian model the gains K_k, and the covariances M_k and P_k, do not depend on the
measured values: only on Φ, Q, H, V, M0 and which components arrive when (the schedule).  So a
Monte Carlo of R runs does not need R filters: run the filter once (any z with the right NaN
pattern) to get K_k, then move every run's estimate with the same recursion, as arrays::

    x̄_{k+1} = Φ x̂_k + B u_k            (every fast step; (R, n) at once)
    x̂_k     = x̄_k + K_k (z_k − H x̄_k)  (at each epoch; missing components have zero gain columns)

This reproduces the estimates of :func:`gpsaccel.kalman.multirate.run_multirate` and of
:func:`gpsaccel.ship.zeroed_gain.run_zeroed_gain` run by run (tests check agreement to 1e-9).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.kalman.schedule import Schedule
from gpsaccel.kalman.update import step_schedule


@dataclass(frozen=True, eq=False)
class EnsembleEstimates:
    """x_bar, x_hat : (R, n_epochs, n) a priori and a posteriori means of every run."""

    x_bar: np.ndarray
    x_hat: np.ndarray


def apply_gains(Phi: np.ndarray, H: np.ndarray, x0: np.ndarray, schedule: Schedule,
                K: np.ndarray, z: np.ndarray, B: np.ndarray | None = None,
                u: np.ndarray | None = None) -> EnsembleEstimates:
    """Run the fixed-gain recursion of the module docstring over an ensemble.

    Parameters
    ----------
    Phi : (n, n) transition.  H : (p, n) measurement matrix.  x0 : (n,) a priori mean at step 0.
    schedule : the epochs (``schedule.steps``) at which the gains apply.
    K : (n_epochs, n, p) gains, zero columns for components not measured.
    z : (R, n_epochs, p) measurements; NaN where not measured (its gain column must be zero).
    B, u : known input, (n, m) and (n_steps, m), or both None.
    """
    Phi = np.asarray(Phi, dtype=float)
    H = np.asarray(H, dtype=float)
    p, n = H.shape
    x0 = _v.finite_array("x0", x0, (n,))
    K = _v.finite_array("K", K, (schedule.n_epochs, n, p))
    z = _v.finite_array("z", z, (None, schedule.n_epochs, p), allow_nan=True)
    if (B is None) != (u is None):
        raise ValueError("B and u must be given together (or neither)")
    if u is not None:
        B = np.asarray(B, dtype=float)
        u = _v.finite_array("u", u, (schedule.n_steps, B.shape[1]))
    missing = ~np.isfinite(z)
    gain_used = np.abs(K).max(axis=1) > 0  # (n_epochs, p): columns the gain uses
    if np.any(missing & gain_used[None]):
        raise ValueError("z is NaN where the gain K uses that component")
    z = np.where(missing, 0.0, z)

    R = z.shape[0]
    x = np.broadcast_to(x0, (R, n)).copy()
    x_bar = np.empty((R, schedule.n_epochs, n))
    x_hat = np.empty((R, schedule.n_epochs, n))

    def predict(k: int) -> None:
        nonlocal x
        x = x @ Phi.T
        if u is not None:
            x += B @ u[k]

    def update(i: int) -> None:
        nonlocal x
        x_bar[:, i] = x
        r = z[:, i] - x @ H.T
        r[missing[:, i]] = 0.0
        x = x + r @ K[i].T
        x_hat[:, i] = x

    step_schedule(schedule, predict, update)
    return EnsembleEstimates(x_bar, x_hat)
