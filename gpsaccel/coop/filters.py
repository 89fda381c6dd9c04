r"""Nonlinear filters for cooperative localization (report 002): LKF, EKF, UKF on filterpy.

All three run on a model with f, h and their Jacobians (:class:`gpsaccel.coop.model.CoopModel`)
over a measurement log y (K+1, 5) whose row k is taken at t_k = k·ΔT (row 0 is NaN in the course's
log: no update at t = 0).  Each step k → k+1 predicts, then updates with y_{k+1}.  A NaN component
means "not measured": it is left out of the update (its row of H and row/column of R dropped) and of
the NIS; an all-NaN row skips the update (x̂ = x̄, P = M).

Linearized KF (LKF, the assignment's perturbation form about the nominal x*_k from solve_ivp)::

    δx̄_{k+1} = F_k δx̂_k  (+ G_k δu_k, δu = 0),    M_{k+1} = F_k P_k F_kᵀ + Q,   F_k = I + ΔT·A(x*_k, u*)
    H = C(x*_{k+1}),   r = wrap(y_{k+1} − h(x*_{k+1}) − H δx̄_{k+1}),   S = H M Hᵀ + R
    K = M Hᵀ S⁻¹,      δx̂ = δx̄ + K r,   P = (I − KH) M (I − KH)ᵀ + K R Kᵀ,   x̂ = wrap(x* + δx̂)

The LKF's P and K do not depend on the data.  The report's "LKF" re-linearized about the estimate
(an EKF); this one does not, which is why it fails once the truth wanders from x* (lesson 10).

Extended KF (EKF, filterpy's ``ExtendedKalmanFilter`` with the state prediction overridden)::

    x̄ = wrap(φ_ΔT(x̂, u)),   M = F P Fᵀ + Q,   F = I + ΔT·A(x̂, u)
    H = C(x̄),   r = wrap(y − h(x̄)),   S = H M Hᵀ + R,   x̂ = wrap(x̄ + K r),   P Joseph form

Unscented KF (UKF, filterpy's ``UnscentedKalmanFilter`` with ``MerweScaledSigmaPoints``, α = 1,
β = 2, κ = 0: 13 points at ±√6·σ, W0 = 0 for the mean): angles enter through ``residual_x``,
``residual_z`` (wrapped differences) and the mean functions (:func:`angle_mean`, a weighted mean of
differences from the first sigma point, which is exact for linear quantities and wrap-safe).

``run_lkf`` / ``run_ekf`` / ``run_ukf`` run one log through filterpy objects.  For Monte Carlo,
:func:`run_batch` runs the same equations vectorised over runs with numpy (a test checks it against
the filterpy objects to 1e-10); use it when the truth has no partly-missing rows.

Process noise: ``Q`` defaults to the tuned :data:`TUNED_Q` of each filter (how each was found is
documented there); ``R`` defaults to Rtrue; x̂_0 = x0 and P_0 = P0 of the model.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from filterpy.kalman import (
    ExtendedKalmanFilter,
    KalmanFilter,
    MerweScaledSigmaPoints,
    UnscentedKalmanFilter,
)

from gpsaccel import _validation as _v
from gpsaccel.coop.model import (
    ANGLE_MEASUREMENTS,
    ANGLE_STATES,
    N_MEAS,
    N_STATES,
    CoopModel,
    h,
    measurement_residual,
    propagate,
    state_residual,
    wrap_angle,
    wrap_measurement,
    wrap_state,
)
from gpsaccel.kalman import consistency
from gpsaccel.kalman.update import cross_gain, gain, joseph_update

METHODS = ("lkf", "ekf", "ukf")

#: The tuned DT process-noise covariance Q of each filter, as multipliers of Qtrue's
#: (UGV position, UAV position, heading) terms (Qtrue = diag(1e-3, 1e-3, 1e-2, 1e-3, 1e-3, 1e-2)).
#: Found by :func:`gpsaccel.coop.montecarlo.tune_q`: 2 sets of N = 50 truth runs (seed 2024),
#: α = 0.05, score min(NEES fraction, NIS fraction) inside the χ² bounds, the candidate closest to
#: Qtrue within 0.02 of the top score.  Measured (fractions NEES / NIS on those 2 sets):
#:
#: * EKF, grid UGV (1, 2, 3, 4, 6, 8) x UAV (1, 1.5, 2, 3) x heading (0.7, 1, 1.4): top (8, 1, 1)
#:   0.954 / 0.958; chosen (4, 2, 1) 0.935 / 0.958; Qtrue itself 0.64 / 0.96.  The EKF's predicted
#:   mean ignores E[cos(θ + δ)] = cos θ·e^(−σ²/2); inflating the position terms covers that.
#: * UKF, grid (1, 1.5, 2, 3, 4)² x (0.5, 1, 2): top (1, 2, 1) 0.943 / 0.958; Qtrue 0.928 / 0.958
#:   is within the tolerance, so the UKF needs no inflation.
#: * LKF, powers of ten (1 … 1e4)² x (1, 10, 100) as the report did: nothing passes (top score
#:   0.037); chosen (1, 100, 1) 0.020 / 0.049.  The truth wanders hundreds of metres from the
#:   nominal, so no Q makes the LKF consistent over 100 s (lesson 10).
TUNED_SCALES = {
    "lkf": (1.0, 100.0, 1.0),
    "ekf": (4.0, 2.0, 1.0),
    "ukf": (1.0, 1.0, 1.0),
}

#: UKF sigma-point parameters (Merwe's α, β, κ).
UKF_ALPHA, UKF_BETA, UKF_KAPPA = 1.0, 2.0, 0.0


def scaled_q(Qtrue: np.ndarray, ugv_pos: float = 1.0, uav_pos: float = 1.0,
             heading: float = 1.0) -> np.ndarray:
    """Qtrue with its UGV position (ξg, ηg), UAV position (ξa, ηa) and heading terms scaled."""
    s = np.array([ugv_pos, ugv_pos, heading, uav_pos, uav_pos, heading], dtype=float)
    if not (np.isfinite(s).all() and (s > 0).all()):
        raise ValueError(f"Q scale factors must be finite and > 0, got {tuple(s[[0, 3, 2]])}")
    r = np.sqrt(s)
    return np.asarray(Qtrue) * np.outer(r, r)


def tuned_q(method: str, model: CoopModel | None = None) -> np.ndarray:
    """The documented default Q of ``method`` ('lkf', 'ekf', 'ukf') for ``model``'s Qtrue."""
    method = _v.choice("method", method, METHODS)
    model = CoopModel() if model is None else model
    return scaled_q(model.Qtrue, *TUNED_SCALES[method])


@dataclass
class FilterResult:
    """What a filter run produced; arrays may carry a leading run axis (N, ...) from run_batch.

    t : (K+1,) s.  x_bar, x_hat : (..., K+1, 6) x̄ and x̂ (angles wrapped); M, P :
    (..., K+1, 6, 6) M and P.  r : (..., K+1, 5) residual r = y − ŷ (NaN where not measured, row 0
    NaN); S : (..., K+1, 5, 5) its covariance.  Row 0 holds the initial x̂_0, P_0.
    """

    method: str
    t: np.ndarray
    x_bar: np.ndarray
    M: np.ndarray
    x_hat: np.ndarray
    P: np.ndarray
    r: np.ndarray
    S: np.ndarray

    @property
    def sigma(self) -> np.ndarray:
        """Posterior standard deviations √diag(P) (..., K+1, 6)."""
        return np.sqrt(np.diagonal(self.P, axis1=-2, axis2=-1))

    def errors(self, x_true: np.ndarray) -> np.ndarray:
        """Estimation errors x − x̂ (headings wrapped), same leading shape as x_hat."""
        return state_residual(x_true, self.x_hat)

    def nees(self, x_true: np.ndarray) -> np.ndarray:
        """NEES eᵀ P⁻¹ e at every step (..., K+1)."""
        return consistency.nees(self.errors(x_true), self.P)

    def nis(self) -> np.ndarray:
        """NIS rᵀ S⁻¹ r at every step (..., K+1); 0 with 0 dof where nothing was measured."""
        return consistency.nis(self.r, self.S)


# --------------------------------------------------------------------------- helpers
def angle_mean(points: np.ndarray, weights: np.ndarray, angles: tuple[int, ...]) -> np.ndarray:
    """Weighted mean of points (..., m, d) with wrap-safe angle components ``angles``.

    mean = p₀ + Σ wᵢ·wrap(pᵢ − p₀) on the angles (Σ wᵢ = 1), plain Σ wᵢ pᵢ elsewhere; then wrapped.
    """
    points = np.asarray(points, dtype=float)
    ref = points[..., :1, :]
    d = points - ref
    idx = list(angles)
    d[..., idx] = wrap_angle(d[..., idx])
    mean = ref[..., 0, :] + np.einsum("...md,m->...d", d, weights)
    mean[..., idx] = wrap_angle(mean[..., idx])
    return mean


def _subset_residual(mask: np.ndarray) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """measurement_residual restricted to the measured components ``mask``."""
    if mask.all():
        return measurement_residual

    def residual(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        full = np.zeros(N_MEAS)
        full[mask] = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
        return wrap_measurement(full)[mask]

    return residual


def _subset_angles(mask: np.ndarray) -> tuple[int, ...]:
    pos = np.cumsum(mask) - 1
    return tuple(int(pos[i]) for i in ANGLE_MEASUREMENTS if mask[i])


def _check(model: CoopModel, y: object, Q: object, R: object, x0: object, P0: object,
           method: str, batch: bool = False):
    if not isinstance(model, CoopModel):
        raise ValueError(f"model must be a CoopModel, got {type(model).__name__}")
    shape = (None, model.n_steps + 1, N_MEAS) if batch else (model.n_steps + 1, N_MEAS)
    y = _v.finite_array("y", y, shape, allow_nan=True)
    Q = tuned_q(method, model) if Q is None else _v.spd_matrix("Q", Q, N_STATES)
    R = model.Rtrue if R is None else _v.spd_matrix("R", R, N_MEAS)
    x0 = model.x0 if x0 is None else _v.finite_array("x0", x0, (N_STATES,))
    P0 = model.P0 if P0 is None else _v.spd_matrix("P0", P0, N_STATES)
    return y, Q, R, x0, P0


def _empty(model: CoopModel, lead: tuple[int, ...] = ()) -> dict[str, np.ndarray]:
    K1 = model.n_steps + 1
    return {"x_bar": np.empty(lead + (K1, 6)), "M": np.empty(lead + (K1, 6, 6)),
            "x_hat": np.empty(lead + (K1, 6)), "P": np.empty(lead + (K1, 6, 6)),
            "r": np.full(lead + (K1, 5), np.nan), "S": np.full(lead + (K1, 5, 5), np.nan)}


# --------------------------------------------------------------------------- single-run filters
def run_lkf(model: CoopModel, y: np.ndarray, Q: np.ndarray | None = None,
            R: np.ndarray | None = None, x0: np.ndarray | None = None,
            P0: np.ndarray | None = None, nominal: np.ndarray | None = None) -> FilterResult:
    """Linearized KF about the nominal (filterpy ``KalmanFilter`` on the perturbation δx).

    ``nominal`` (K+1, 6) defaults to :meth:`CoopModel.nominal`; x̂_0 = x0 means δx̂_0 = x0 − x*_0.
    """
    y, Q, R, x0, P0 = _check(model, y, Q, R, x0, P0, "lkf")
    xn = model.nominal() if nominal is None else model._trajectory("nominal", nominal)
    Fs, Hs, yn = model.F(xn), model.C(xn), h(xn)
    kf = KalmanFilter(dim_x=N_STATES, dim_z=N_MEAS)
    kf.x = state_residual(x0, xn[0])
    kf.P = P0.copy()
    kf.Q = Q
    out = _empty(model)
    out["x_bar"][0] = out["x_hat"][0] = wrap_state(xn[0] + kf.x)
    out["M"][0] = out["P"][0] = kf.P
    for k in range(model.n_steps):
        kf.F = Fs[k]
        kf.predict()
        j = k + 1
        out["x_bar"][j] = wrap_state(xn[j] + kf.x)
        out["M"][j] = kf.P
        m = np.isfinite(y[j])
        if m.any():
            H = Hs[j][m]
            r = measurement_residual(y[j], yn[j] + Hs[j] @ kf.x)[m]
            # filterpy forms z − H δx̄; hand it z = H δx̄ + r so its residual is the wrapped r
            kf.update(H @ kf.x + r, R=R[np.ix_(m, m)], H=H)
            out["r"][j, m] = kf.y
            out["S"][j] = Hs[j] @ kf.P_prior @ Hs[j].T + R
        out["x_hat"][j] = wrap_state(xn[j] + kf.x)
        out["P"][j] = kf.P
    return FilterResult("lkf", model.t, **out)


class _CoopEKF(ExtendedKalmanFilter):
    """filterpy's EKF with the state prediction replaced by the exact nonlinear step."""

    x: np.ndarray

    def __init__(self, model: CoopModel) -> None:
        super().__init__(dim_x=N_STATES, dim_z=N_MEAS)
        self.model = model

    def predict_x(self, u=0) -> None:
        self.x = self.model.step(self.x)


def run_ekf(model: CoopModel, y: np.ndarray, Q: np.ndarray | None = None,
            R: np.ndarray | None = None, x0: np.ndarray | None = None,
            P0: np.ndarray | None = None) -> FilterResult:
    """Extended KF (filterpy ``ExtendedKalmanFilter``, Jacobians recomputed every step)."""
    y, Q, R, x0, P0 = _check(model, y, Q, R, x0, P0, "ekf")
    ekf = _CoopEKF(model)
    ekf.x = x0.copy()
    ekf.P = P0.copy()
    ekf.Q = Q
    out = _empty(model)
    out["x_bar"][0] = out["x_hat"][0] = x0
    out["M"][0] = out["P"][0] = P0
    for k in range(model.n_steps):
        ekf.F = model.F(ekf.x)
        ekf.predict()
        j = k + 1
        out["x_bar"][j], out["M"][j] = ekf.x, ekf.P
        m = np.isfinite(y[j])
        if m.any():
            ekf.update(y[j][m], lambda x, m=m: model.C(x)[m], lambda x, m=m: h(x)[m],
                       R=R[np.ix_(m, m)], residual=_subset_residual(m))
            ekf.x = wrap_state(ekf.x)
            Hf = model.C(out["x_bar"][j])
            out["r"][j, m] = ekf.y
            out["S"][j] = Hf @ out["M"][j] @ Hf.T + R
        out["x_hat"][j], out["P"][j] = ekf.x, ekf.P
    return FilterResult("ekf", model.t, **out)


def ukf_points(alpha: float = UKF_ALPHA, beta: float = UKF_BETA,
               kappa: float = UKF_KAPPA) -> MerweScaledSigmaPoints:
    """filterpy's Merwe sigma points for the 6 states, sigma points built with wrapped angles.

    0 < α ≤ 1 (the spread of the points; α = 0 divides by zero in the weights, a negative α
    mirrors them), β ≥ 0 (prior knowledge of the distribution, 2 for a Gaussian) and n + κ > 0
    (otherwise the points' covariance n + λ = α²(n + κ) is not positive), all finite.
    """
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


def run_ukf(model: CoopModel, y: np.ndarray, Q: np.ndarray | None = None,
            R: np.ndarray | None = None, x0: np.ndarray | None = None,
            P0: np.ndarray | None = None, alpha: float = UKF_ALPHA, beta: float = UKF_BETA,
            kappa: float = UKF_KAPPA) -> FilterResult:
    """Unscented KF (filterpy ``UnscentedKalmanFilter``), angle-aware means and residuals."""
    y, Q, R, x0, P0 = _check(model, y, Q, R, x0, P0, "ukf")
    ukf = UnscentedKalmanFilter(
        dim_x=N_STATES, dim_z=N_MEAS, dt=model.dt, hx=h,
        fx=lambda x, dt: wrap_state(propagate(x, model.u0, dt, model.L)),
        points=ukf_points(alpha, beta, kappa),
        x_mean_fn=lambda s, w: angle_mean(s, w, ANGLE_STATES),
        z_mean_fn=lambda s, w: angle_mean(s, w, ANGLE_MEASUREMENTS),
        residual_x=state_residual, residual_z=measurement_residual)
    ukf.x = x0.copy()
    ukf.P = P0.copy()
    ukf.Q = Q
    ukf.R = R
    out = _empty(model)
    out["x_bar"][0] = out["x_hat"][0] = x0
    out["M"][0] = out["P"][0] = P0
    for k in range(model.n_steps):
        ukf.predict()
        j = k + 1
        out["x_bar"][j], out["M"][j] = ukf.x, ukf.P
        m = np.isfinite(y[j])
        if m.all():
            ukf.update(y[j])
        elif m.any():
            full = (ukf.residual_z, ukf.z_mean)
            ukf.residual_z = _subset_residual(m)
            ang = _subset_angles(m)
            ukf.z_mean = lambda s, w, ang=ang: angle_mean(s, w, ang)
            try:
                ukf.update(y[j][m], R=R[np.ix_(m, m)], hx=lambda x, m=m: h(x)[m])
            finally:
                ukf.residual_z, ukf.z_mean = full
        if m.any():
            ukf.x = wrap_state(ukf.x)
            out["r"][j, m] = ukf.y
            if m.all():
                out["S"][j] = ukf.S
            else:
                out["S"][j][np.ix_(m, m)] = ukf.S
        out["x_hat"][j], out["P"][j] = ukf.x, ukf.P
    return FilterResult("ukf", model.t, **out)


RUNNERS = {"lkf": run_lkf, "ekf": run_ekf, "ukf": run_ukf}


def run_filter(method: str, model: CoopModel, y: np.ndarray, Q: np.ndarray | None = None,
               **kwargs) -> FilterResult:
    """``run_lkf`` / ``run_ekf`` / ``run_ukf`` by name."""
    return RUNNERS[_v.choice("method", method, METHODS)](model, y, Q, **kwargs)


# --------------------------------------------------------------------------- vectorised over runs
def run_batch(method: str, model: CoopModel, y: np.ndarray, Q: np.ndarray | None = None,
              R: np.ndarray | None = None, x0: np.ndarray | None = None,
              P0: np.ndarray | None = None, nominal: np.ndarray | None = None) -> FilterResult:
    """The same filter as ``run_<method>`` on N logs y (N, K+1, 5) at once, vectorised with numpy.

    Same equations, same order of operations (Joseph update, S⁻¹ by inversion, the UKF's sigma
    points redrawn after the prediction as filterpy does).  A row of y must be wholly NaN or
    wholly finite across all runs (the Monte Carlo case); otherwise use the single-run filters.
    """
    method = _v.choice("method", method, METHODS)
    if np.ndim(y) == 3 and np.shape(y)[0] == 0:
        raise ValueError("y holds no run (shape (0, ...)): run_batch needs at least one log")
    y, Q, R, x0, P0 = _check(model, y, Q, R, x0, P0, method, batch=True)
    nan = np.isnan(y)
    rows = nan.all(axis=(0, 2))
    if (nan.any(axis=(0, 2)) != rows).any():
        raise ValueError("y: in run_batch a row (time step) must be all NaN or all finite over "
                         "every run; use run_ekf/run_lkf/run_ukf for partly missing rows")
    N = y.shape[0]
    out = _empty(model, (N,))
    x = np.broadcast_to(x0, (N, 6)).copy()
    P = np.broadcast_to(P0, (N, 6, 6)).copy()
    out["x_bar"][:, 0] = out["x_hat"][:, 0] = x
    out["M"][:, 0] = out["P"][:, 0] = P
    step = {"lkf": _batch_lkf, "ekf": _batch_ekf, "ukf": _batch_ukf}[method]
    step(model, y, rows, Q, R, x, P, out, nominal)
    return FilterResult(method, model.t, **out)


def _tr(a: np.ndarray) -> np.ndarray:
    return np.swapaxes(a, -1, -2)


def _batch_lkf(model, y, skip, Q, R, x, P, out, nominal):
    xn = model.nominal() if nominal is None else model._trajectory("nominal", nominal)
    Fs, Hs, yn = model.F(xn), model.C(xn), h(xn)
    dx = state_residual(x, xn[0])
    P = P[0]  # the LKF's covariance does not depend on the data: one sequence for all runs
    for k in range(model.n_steps):
        j = k + 1
        dx = dx @ Fs[k].T
        M = Fs[k] @ P @ Fs[k].T + Q
        out["x_bar"][:, j] = wrap_state(xn[j] + dx)
        out["M"][:, j] = M
        if skip[j]:
            P = M
        else:
            H = Hs[j]
            r = measurement_residual(y[:, j], yn[j] + dx @ H.T)
            K, S = gain(M, H, R, inverse=True)             # K = M Hᵀ S⁻¹, as filterpy
            dx = dx + r @ K.T
            P = joseph_update(M, K, H, R)
            out["r"][:, j] = r
            out["S"][:, j] = S
        out["x_hat"][:, j] = wrap_state(xn[j] + dx)
        out["P"][:, j] = P


def _batch_ekf(model, y, skip, Q, R, x, P, out, nominal):
    for k in range(model.n_steps):
        j = k + 1
        F = model.F(x)
        x = model.step(x)
        P = F @ P @ _tr(F) + Q
        out["x_bar"][:, j], out["M"][:, j] = x, P
        if not skip[j]:
            H = model.C(x)
            r = measurement_residual(y[:, j], h(x))
            K, S = gain(P, H, R, inverse=True)             # K = M Hᵀ S⁻¹, as filterpy
            x = wrap_state(x + np.einsum("nij,nj->ni", K, r))
            P = joseph_update(P, K, H, R)
            out["r"][:, j], out["S"][:, j] = r, S
        out["x_hat"][:, j], out["P"][:, j] = x, P


def _sigma_points(x, P, lam):
    """Merwe sigma points (N, 2n+1, n) as filterpy builds them (rows of the upper Cholesky)."""
    n = N_STATES
    U = _tr(np.linalg.cholesky((lam + n) * P))  # upper factor: U[k] = row k
    return np.concatenate([x[:, None, :], wrap_state(x[:, None, :] + U),
                           wrap_state(x[:, None, :] - U)], axis=1)


def _batch_ukf(model, y, skip, Q, R, x, P, out, nominal):
    pts = ukf_points()
    Wm, Wc = pts.Wm, pts.Wc
    lam = UKF_ALPHA**2 * (N_STATES + UKF_KAPPA) - N_STATES
    for k in range(model.n_steps):
        j = k + 1
        sig = wrap_state(propagate(_sigma_points(x, P, lam), model.u0, model.dt, model.L))
        x = angle_mean(sig, Wm, ANGLE_STATES)
        d = state_residual(sig, x[:, None, :])
        P = np.einsum("m,nmi,nmj->nij", Wc, d, d) + Q
        out["x_bar"][:, j], out["M"][:, j] = x, P
        if not skip[j]:
            sig = _sigma_points(x, P, lam)
            zs = h(sig)
            zp = angle_mean(zs, Wm, ANGLE_MEASUREMENTS)
            dz = measurement_residual(zs, zp[:, None, :])
            S = np.einsum("m,nmi,nmj->nij", Wc, dz, dz) + R
            dx = state_residual(sig, x[:, None, :])
            Pxz = np.einsum("m,nmi,nmj->nij", Wc, dx, dz)
            K = cross_gain(Pxz, S, inverse=True)           # K = Pxz S⁻¹, as filterpy
            r = measurement_residual(y[:, j], zp)
            x = wrap_state(x + np.einsum("nij,nj->ni", K, r))
            P = P - K @ S @ _tr(K)
            out["r"][:, j], out["S"][:, j] = r, S
        out["x_hat"][:, j], out["P"][:, j] = x, P
