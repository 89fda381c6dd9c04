"""filterpy's own filters on one coop log: the oracle the package's one vectorised filter is
checked against (the package's filters before they were written once; filterpy's KalmanFilter,
ExtendedKalmanFilter and UnscentedKalmanFilter do the arithmetic)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter, KalmanFilter, UnscentedKalmanFilter

from gpsaccel.coop.filters import _check
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
    wrap_measurement,
    wrap_state,
)
from gpsaccel.coop.result import FilterResult
from gpsaccel.coop.unscented import UKF_ALPHA, UKF_BETA, UKF_KAPPA, angle_mean, ukf_points


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
