r"""The UKF's half of the coop filter: sigma points, angle-safe means, its predict and update.

:mod:`gpsaccel.coop.filters` runs one loop with two kinds of step: a linearised one (EKF, LKF)
and this one, which replaces the linearisation point by sigma points.  Merwe's points with α = 1,
β = 2, κ = 0: 13 points at ±√6·σ, W0 = 0 for the mean.  Angles are averaged through wrapped
differences (:func:`angle_mean`), and the points are redrawn after the prediction, as filterpy's
``UnscentedKalmanFilter`` does (the tests check the two to 1e-10).  K = Pxz S⁻¹ with S⁻¹ formed by
inversion, filterpy's order of operations.
"""

from __future__ import annotations

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.coop.model import (
    ANGLE_MEASUREMENTS,
    ANGLE_STATES,
    N_STATES,
    CoopModel,
    angle_index,
    h,
    measurement_residual,
    propagate,
    state_residual,
    wrap_angle,
    wrap_state_inplace,
)
from gpsaccel.kalman.update import cross_gain

#: UKF sigma-point parameters (Merwe's α, β, κ).
UKF_ALPHA, UKF_BETA, UKF_KAPPA = 1.0, 2.0, 0.0


def angle_mean(points: np.ndarray, weights: np.ndarray, angles: tuple[int, ...]) -> np.ndarray:
    """Weighted mean of points (..., m, d) with wrap-safe angle components ``angles``.

    mean = p₀ + Σ wᵢ·wrap(pᵢ − p₀) on the angles (Σ wᵢ = 1), plain Σ wᵢ pᵢ elsewhere; then wrapped.
    """
    points = np.asarray(points, dtype=float)
    ref = points[..., :1, :]
    d = points - ref
    idx = angle_index(angles)
    d[..., idx] = wrap_angle(d[..., idx])
    mean = ref[..., 0, :] + np.einsum("...md,m->...d", d, weights)
    mean[..., idx] = wrap_angle(mean[..., idx])
    return mean


def ukf_points(alpha: float = UKF_ALPHA, beta: float = UKF_BETA, kappa: float = UKF_KAPPA):
    """filterpy's Merwe sigma points for the 6 states, sigma points built with wrapped angles.

    0 < α ≤ 1 (the spread of the points; α = 0 divides by zero in the weights, a negative α
    mirrors them), β ≥ 0 (prior knowledge of the distribution, 2 for a Gaussian) and n + κ > 0
    (otherwise the points' covariance n + λ = α²(n + κ) is not positive), all finite.
    """
    from filterpy.kalman import MerweScaledSigmaPoints

    alpha = _v.finite_float("alpha", alpha)
    if not 0.0 < alpha <= 1.0:
        raise ValueError(f"alpha must be in (0, 1] (the sigma points' spread), got {alpha!r}")
    beta = _v.finite_float("beta", beta)
    if beta < 0.0:
        raise ValueError(f"beta must be >= 0 (2 for a Gaussian prior), got {beta!r}")
    kappa = _v.finite_float("kappa", kappa)
    if N_STATES + kappa <= 0.0:
        raise ValueError(f"kappa must be > -{N_STATES} (n + kappa > 0 for n = {N_STATES} states), "
                         f"got {kappa!r}")
    return MerweScaledSigmaPoints(N_STATES, alpha=alpha, beta=beta, kappa=kappa,
                                  subtract=state_residual)


def _tr(a: np.ndarray) -> np.ndarray:
    return np.swapaxes(a, -1, -2)


def _sigma_points(x, P, lam):
    """Merwe sigma points (N, 2n+1, n) as filterpy builds them (rows of the upper Cholesky).

    Written into one array, wrapped in place (a concatenation of two wrapped copies cost a tenth
    of the UKF).  Its memory layout is the one that concatenation had, each run's (2n+1, n)
    block column-major: the einsums downstream sum in an order that follows the layout, and
    this keeps their numbers bit for bit."""
    n = N_STATES
    U = _tr(np.linalg.cholesky((lam + n) * P))  # upper factor: U[k] = row k
    pts = np.empty((x.shape[0], n, 2 * n + 1)).transpose(0, 2, 1)
    pts[:, 0] = x                                 # the mean as it is (not wrapped again)
    np.add(x[:, None, :], U, out=pts[:, 1:n + 1])
    np.subtract(x[:, None, :], U, out=pts[:, n + 1:])
    wrap_state_inplace(pts[:, 1:])
    return pts


class Unscented:
    """The UKF's predict and update (sigma points instead of a linearisation point).

    The same interface as the linearised step of :mod:`gpsaccel.coop.filters` (``start``,
    ``estimate``, ``predict``, ``update``), so the one loop there runs either.
    """

    def __init__(self, model: CoopModel, alpha: float, beta: float, kappa: float) -> None:
        pts = ukf_points(alpha, beta, kappa)
        self.model, self.Wm, self.Wc = model, pts.Wm, pts.Wc
        self.lam = alpha**2 * (N_STATES + kappa) - N_STATES

    def start(self, x0: np.ndarray) -> np.ndarray:
        return x0

    def estimate(self, j: int, s: np.ndarray) -> np.ndarray:
        return s

    def predict(self, k: int, x: np.ndarray, P: np.ndarray, Q: np.ndarray):
        m = self.model
        sig = wrap_state_inplace(propagate(_sigma_points(x, P, self.lam), m.u0, m.dt, m.L))
        x = angle_mean(sig, self.Wm, ANGLE_STATES)
        d = state_residual(sig, x[:, None, :])
        return x, np.einsum("m,nmi,nmj->nij", self.Wc, d, d) + Q

    def update(self, j: int, x: np.ndarray, M: np.ndarray, y: np.ndarray, m: np.ndarray,
               R: np.ndarray, runs=slice(None)):
        Wc = self.Wc
        sig = _sigma_points(x, M, self.lam)
        zs = h(sig)
        zp = angle_mean(zs, self.Wm, ANGLE_MEASUREMENTS)   # componentwise: a subset is a subset
        dz = measurement_residual(zs, zp[:, None, :])
        r = measurement_residual(y, zp)
        if not m.all():
            dz, r, R = dz[..., m], r[:, m], R[np.ix_(m, m)]
        S = np.einsum("m,nmi,nmj->nij", Wc, dz, dz) + R
        dx = state_residual(sig, x[:, None, :])
        Pxz = np.einsum("m,nmi,nmj->nij", Wc, dx, dz)
        K = cross_gain(Pxz, S, inverse=True)           # K = Pxz S⁻¹, as filterpy
        x = wrap_state_inplace(x + np.einsum("nij,nj->ni", K, r))
        return x, M - K @ S @ _tr(K), r, S
