r"""Nonlinear filters for cooperative localization (report 002): LKF, EKF, UKF, written once.

All three run on a model with f, h and their Jacobians (:class:`gpsaccel.coop.model.CoopModel`)
over measurement logs y (N, K+1, 5) at once (a leading run axis: a Monte Carlo set is one call),
row k taken at t_k = k·ΔT (row 0 is NaN in the course's log: no update at t = 0).  Each step
k → k+1 predicts, then updates with y_{k+1}.  A NaN component means "not measured": it is left out
of the update (its row of H and row/column of R dropped) and of the NIS; an all-NaN row skips the
update (x̂ = x̄, P = M).  Runs whose rows miss different components are updated in groups.

One loop (:func:`run_batch`) on Stone Soup's pattern (``predictor/kalman.py``,
``updater/kalman.py``): a predictor and an updater, and one hook, *where the filter is
linearised*.  :class:`_Linearised` is the EKF and the LKF:

    EKF (about the estimate)   x̄ = wrap(φ_ΔT(x̂, u)),  M = F P Fᵀ + Q,  F = I + ΔT·A(x̂, u)
                               H = C(x̄),  r = wrap(y − h(x̄)),  S = H M Hᵀ + R,  K = M Hᵀ S⁻¹
                               x̂ = wrap(x̄ + K r),  P = (I − KH) M (I − KH)ᵀ + K R Kᵀ
    LKF (about the nominal x*) the perturbation δx = x − x*:  δx̄ = F_k δx̂,  F_k = I + ΔT·A(x*_k),
                               H = C(x*_j),  r = wrap(y − h(x*_j) − H δx̄),  x̂ = wrap(x* + δx̂)

The LKF's P and K do not depend on the data (one covariance sequence serves every run); the
report's "LKF" re-linearized about the estimate (an EKF), which is why it fails once the truth
wanders from x* (lesson 10).  :class:`~gpsaccel.coop.unscented.Unscented` is the UKF's step
(sigma points instead of a linearisation point; :mod:`gpsaccel.coop.unscented`).  Everything else
(the loop, NaN rows, outputs) they share.

Where the rest lives: what a run returns, with its NEES and NIS, is
:class:`~gpsaccel.coop.result.FilterResult` (:mod:`gpsaccel.coop.result`); the UKF's sigma points,
:func:`~gpsaccel.coop.unscented.angle_mean` and its parameters are :mod:`gpsaccel.coop.unscented`.
``FilterResult`` and ``UKF_ALPHA``, ``UKF_BETA``, ``UKF_KAPPA`` are importable from here too,
where callers have always found them.

A student's filter, right or wrong, is this loop with other :class:`Ingredients` (the catalogue
of :mod:`gpsaccel.coop.mistakes` is a list of such changes).  S⁻¹ is formed by inversion and
K = (M Hᵀ) S⁻¹, filterpy's order of operations: the tests check every filter against filterpy's
``KalmanFilter``, ``ExtendedKalmanFilter`` and ``UnscentedKalmanFilter`` to 1e-10.
``run_lkf`` / ``run_ekf`` / ``run_ukf`` are the same loop on one log.

Process noise: ``Q`` defaults to the tuned :data:`TUNED_SCALES` of each filter (how each was
found is documented there); ``R`` defaults to Rtrue; x̂_0 = x0 and P_0 = P0 of the model.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.coop.model import (
    N_MEAS,
    N_STATES,
    CoopModel,
    f,
    h,
    h_unwrapped,
    measurement_residual,
    propagate,
    state_residual,
    wrap_state,
    wrap_state_inplace,
)
from gpsaccel.coop.result import FilterResult
from gpsaccel.coop.unscented import UKF_ALPHA, UKF_BETA, UKF_KAPPA, Unscented
from gpsaccel.kalman.update import covariance_update, gain, joseph_update

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


# --------------------------------------------------------------------------- the ingredients
@dataclass(frozen=True)
class Ingredients:
    """The choices made in the loop of the module docstring (the defaults are the right ones).

    A student's EKF or LKF is one choice of these; each catalogued mistake changes one or two
    (:mod:`gpsaccel.coop.mistakes`).

    wrap_residual : "yes"; "difference" leaves y − h(x̄) unwrapped; "none" also leaves h's bearing
        unwrapped (atan2(Δη, Δξ) − θ as computed).
    wrap_state : wrap the headings of x̄ and x̂ to [−π, π).
    F_form : "I+dtA", "A" or "dtA".
    F_point : where the EKF evaluates A: "posterior" x̂_k (right), "prior" x̄_j, "nominal" x*_k.
    H_point : where the EKF evaluates C: "prior" x̄_j (right), "posterior" x̂_k, "nominal" x*_j.
    q_scale : Q is multiplied by this (1; 0 drops it; ΔT).
    r_sqrt : R replaced by its elementwise square root (standard deviations as variances).
    shift : "none"; "measurement" updates at t_j with y_k (the update before the prediction);
        "output" returns row j = the estimate of row j − 1 (row 0 twice).
    joseph : the Joseph update (True) or P = (I − KH) M (False).
    propagation : "exact" (closed form, or any ODE solver at its default tolerances) or "euler"
        (one Euler step x + ΔT·f(x, u) per sample; for the LKF, an Euler nominal).
    relinearize : an "LKF" that linearizes about its own estimate, not the nominal: an EKF.
    output : "posterior" returns x̂, P; "prior" returns x̄, M (the estimate before the update).

    and the slips every system shares (:mod:`gpsaccel.kalman.entries`, under the same names):

    V_gain : the R of the gain's S (its covariance update keeps R): zeros, or √R.
    form : None, or a covariance update of :data:`gpsaccel.kalman.update.COVARIANCE_FORMS`
        ("minus", "plus": Joseph's form with a sign wrong), over ``joseph``'s.
    M0 : the P0 the filter starts from (None: the model's).
    heading_sign : A's heading column (∂ξ/∂θ, ∂η/∂θ) with its signs flipped, for "ugv", "uav"
        or "both" vehicles; C_swapped : C's bearing and range rows with the UGV and UAV position
        blocks swapped (Δ taken the other way round).
    mean_propagated : False keeps the mean where it was (the EKF's x̄ = x̂; the LKF's δx̄ = δx̂);
        nominal_frozen : an LKF about x* = x0 at every step (a nominal never propagated).
    """

    wrap_residual: str = "yes"
    wrap_state: bool = True
    F_form: str = "I+dtA"
    F_point: str = "posterior"
    H_point: str = "prior"
    q_scale: float = 1.0
    r_sqrt: bool = False
    shift: str = "none"
    joseph: bool = True
    propagation: str = "exact"
    relinearize: bool = False
    output: str = "posterior"
    V_gain: np.ndarray | None = None
    form: str | None = None
    M0: np.ndarray | None = None
    heading_sign: str | None = None
    C_swapped: bool = False
    mean_propagated: bool = True
    nominal_frozen: bool = False


RIGHT = Ingredients()

#: The entries of A each vehicle's heading column holds (∂ξ/∂θ, ∂η/∂θ): the UGV's, the UAV's.
HEADING_COLUMNS = {"ugv": ((0, 1), 2), "uav": ((3, 4), 5)}


# --------------------------------------------------------------------------- helpers
def _tr(a: np.ndarray) -> np.ndarray:
    return np.swapaxes(a, -1, -2)


def _add_gain(x: np.ndarray, K: np.ndarray, r: np.ndarray) -> np.ndarray:
    """x + K r for runs x (N, n), r (N, p); K (n, p) shared or (N, n, p) per run."""
    if K.ndim == 2:
        return x + r @ K.T
    return x + np.einsum("nij,nj->ni", K, r)


def _check(model: CoopModel, y: object, Q: Any, R: object, x0: object, P0: object,
           method: str, batch: bool = False):
    if not isinstance(model, CoopModel):
        raise ValueError(f"model must be a CoopModel, got {type(model).__name__}")
    shape = (None, model.n_steps + 1, N_MEAS) if batch else (model.n_steps + 1, N_MEAS)
    y = _v.finite_array("y", y, shape, allow_nan=True)
    if batch and Q is not None and np.ndim(Q) == 3:  # one Q per run (a tuning grid at once)
        Q = np.asarray(Q, dtype=float)
        if Q.shape != (y.shape[0], N_STATES, N_STATES):
            raise ValueError(f"Q must be (6, 6) or one (6, 6) per run ({y.shape[0]}, 6, 6), "
                             f"got {Q.shape}")
        for q in np.unique(Q, axis=0):
            _v.spd_matrix("Q", q, N_STATES)
    else:
        Q = tuned_q(method, model) if Q is None else _v.spd_matrix("Q", Q, N_STATES)
    R = model.Rtrue if R is None else _v.spd_matrix("R", R, N_MEAS)
    x0 = model.x0 if x0 is None else _v.finite_array("x0", x0, (N_STATES,))
    P0 = model.P0 if P0 is None else _v.spd_matrix("P0", P0, N_STATES)
    return y, Q, R, x0, P0


def euler_nominal(model: CoopModel) -> np.ndarray:
    """The nominal trajectory (K+1, 6) by Euler steps from x0 (headings wrapped)."""
    x = np.empty((model.n_steps + 1, N_STATES))
    x[0] = model.x0
    for k in range(model.n_steps):
        x[k + 1] = wrap_state(x[k] + model.dt * f(x[k], model.u0, model.L))
    return x


# --------------------------------------------------------------------------- predictor/updater
class _Linearised:
    """The EKF and the LKF: predict and update of a filter linearised at a point (the hook).

    The EKF linearises about its own estimate (F at x̂_k, H at x̄_j, the mean through the exact
    step); the LKF about the nominal x*, carrying the perturbation δx = x − x* as its state.
    """

    def __init__(self, model: CoopModel, g: Ingredients, kind: str,
                 nominal: np.ndarray | None) -> None:
        self.model, self.g, self.lkf = model, g, kind == "lkf"
        if nominal is None and (self.lkf or "nominal" in (g.F_point, g.H_point)):
            nominal = euler_nominal(model) if g.propagation == "euler" else model.nominal()
        if g.nominal_frozen:  # a nominal never propagated: x* = x0 at every step
            nominal = np.broadcast_to(model.x0, (model.n_steps + 1, N_STATES)).copy()
        self.xn: np.ndarray = np.empty((0, N_STATES)) if nominal is None else nominal
        self.I = np.eye(N_STATES)
        if self.lkf:  # linearised once, about x*: F_k, H_k, h(x*_k) for every step
            xn = np.asarray(nominal)
            self.Fs, self.Hs = self.F_of(model.A(xn)), self.C_of(model.C(xn))
            self.yn, self.yn_raw = h(xn), h_unwrapped(xn)

    def C_of(self, C: np.ndarray) -> np.ndarray:
        """C as the filter writes it (``C_swapped``: the two position blocks of rows 0-2)."""
        if self.g.C_swapped:
            C = C.copy()
            C[..., :3, [0, 1, 3, 4]] = C[..., :3, [3, 4, 0, 1]]
        return C

    def F_of(self, A: np.ndarray) -> np.ndarray:
        if self.g.heading_sign:  # a sign slip in the heading column(s) of A
            A = A.copy()
            for who in ("ugv", "uav") if self.g.heading_sign == "both" else (self.g.heading_sign,):
                rows, col = HEADING_COLUMNS[who]
                A[..., rows, col] = -A[..., rows, col]
        if self.g.F_form == "I+dtA":
            return self.I + self.model.dt * A
        return A if self.g.F_form == "A" else self.model.dt * A

    def wrap(self, x: np.ndarray) -> np.ndarray:
        # x is always the filter's own new array (a step, an update): wrapped where it is
        return wrap_state_inplace(x) if self.g.wrap_state else np.array(x, dtype=float)

    def start(self, x0: np.ndarray) -> np.ndarray:
        """The filter's state at step 0: x̂_0 (EKF) or δx̂_0 = x̂_0 − x*_0 (LKF)."""
        return state_residual(x0, self.xn[0]) if self.lkf else x0

    def estimate(self, j: int, s: np.ndarray) -> np.ndarray:
        """The state estimate x at step j from the filter's state s."""
        return self.wrap(self.xn[j] + s) if self.lkf else s

    def predict(self, k: int, s: np.ndarray, P: np.ndarray, Q: np.ndarray):
        """(s̄, M) at step k + 1 from (s, P) at step k."""
        if self.lkf:
            F = self.Fs[k]
            return (s @ F.T if self.g.mean_propagated else s.copy()), F @ P @ _tr(F) + Q
        g, model = self.g, self.model
        self.x_prev = s
        if g.F_point == "posterior":
            F = self.F_of(model.A(s))
        if not g.mean_propagated:
            x = self.wrap(s.copy())
        elif g.propagation == "euler":
            x = self.wrap(s + model.dt * f(s, model.u0, model.L))
        else:
            x = self.wrap(propagate(s, model.u0, model.dt, model.L))
        if g.F_point == "prior":
            F = self.F_of(model.A(x))
        elif g.F_point == "nominal":
            F = self.F_of(model.A(self.xn[k]))
        return x, F @ P @ _tr(F) + Q

    def _observe(self, j: int, s: np.ndarray, runs
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """(H, ŷ wrapped, ŷ as computed) at step j for the runs ``runs`` of the filter's state."""
        if self.lkf:
            H = self.Hs[j]
            d = s @ H.T
            return H, self.yn[j] + d, self.yn_raw[j] + d
        point = self.g.H_point
        xH = s if point == "prior" else self.x_prev[runs] if point == "posterior" else self.xn[j]
        return (self.C_of(self.model.C(xH)), h(s),
                (h_unwrapped(s) if self.g.wrap_residual == "none" else None))

    def update(self, j: int, s: np.ndarray, M: np.ndarray, y: np.ndarray, m: np.ndarray,
               R: np.ndarray, runs=slice(None)):
        """(ŝ, P, r, S) from (s̄, M) and the measured components ``m`` of y (N, 5)."""
        g = self.g
        H, yhat, yraw = self._observe(j, s, runs)
        if g.wrap_residual == "yes":
            r = measurement_residual(y, yhat)
        else:
            assert yraw is not None or g.wrap_residual == "difference"
            r = y - (yhat if g.wrap_residual == "difference" else yraw)
        if not m.all():
            H, r, R = H[..., m, :], r[:, m], R[np.ix_(m, m)]
        Rg = R if g.V_gain is None else np.asarray(g.V_gain)[np.ix_(m, m)]
        K, S = gain(M, H, Rg, inverse=True)             # K = M Hᵀ S⁻¹, as filterpy
        if self.lkf:
            s = _add_gain(s, K, r)
        else:
            s = self.wrap(_add_gain(s, K, r))
        if g.form is not None:
            P = covariance_update(M, K, H, R, g.form)
        else:
            P = joseph_update(M, K, H, R) if g.joseph else (self.I - K @ H) @ M
        return s, P, r, S


# --------------------------------------------------------------------------- the one loop
def _groups(finite: np.ndarray):
    """[(runs, measured components)] of one row: runs (a slice or indices) sharing a pattern."""
    first = finite[0]
    if (finite == first).all():
        return [(slice(None), first)] if first.any() else []
    pats, inv = np.unique(finite, axis=0, return_inverse=True)
    return [(np.flatnonzero(inv.ravel() == i), p) for i, p in enumerate(pats) if p.any()]


def _full_S(flt, j: int, s: np.ndarray, M: np.ndarray, R: np.ndarray, runs) -> np.ndarray:
    """S of all five components (a partly measured row reports it whole, as filterpy's EKF)."""
    H = flt._observe(j, s, runs)[0]
    return H @ M @ _tr(H) + R


def _store_update(out, j, runs, m, r, S, full_S) -> None:
    if isinstance(runs, slice) and m.all():
        out["r"][:, j], out["S"][:, j] = r, S
        return
    n = r.shape[0]
    rr = np.full((n, N_MEAS), np.nan)
    rr[:, m] = r
    out["r"][runs, j] = rr
    if full_S is None:  # the UKF reports S on the measured components only
        full_S = np.full((n, N_MEAS, N_MEAS), np.nan)
        full_S[:, m[:, None] & m[None, :]] = S.reshape(n, -1)
    out["S"][runs, j] = full_S


def run_batch(method: str, model: CoopModel, y: np.ndarray, Q: np.ndarray | None = None,
              R: np.ndarray | None = None, x0: np.ndarray | None = None,
              P0: np.ndarray | None = None, nominal: np.ndarray | None = None,
              ingredients: Ingredients = RIGHT, alpha: float = UKF_ALPHA,
              beta: float = UKF_BETA, kappa: float = UKF_KAPPA,
              steps: int | None = None) -> FilterResult:
    """Filter ``method`` ('lkf', 'ekf', 'ukf') on N logs y (N, K+1, 5) at once (module docstring).

    ``Q`` (6, 6), or (N, 6, 6) one per run (a tuning grid in one call: for the EKF and UKF each
    run's arithmetic is that of its own call, bit for bit; the LKF shares one covariance and one
    matrix product across its runs when Q is shared, so there a run's last bits can depend on
    the runs beside it and on whether Q was given per run).  ``ingredients`` makes it a
    student's filter (EKF and LKF; :mod:`gpsaccel.coop.mistakes`); ``alpha``, ``beta``,
    ``kappa`` are the UKF's sigma-point parameters (:func:`ukf_points`).  ``steps``: only the
    first ``steps`` rows, the same numbers as those rows of the whole run (each row depends only
    on the rows before it; the checker bounds a catalogue filter's distance to a student's from
    its first rows).
    """
    method = _v.choice("method", method, METHODS)
    if np.ndim(y) == 3 and np.shape(y)[0] == 0:
        raise ValueError("y holds no run (shape (0, ...)): run_batch needs at least one log")
    y, Q, R, x0, P0 = _check(model, y, Q, R, x0, P0, method, batch=True)
    if steps is not None:
        y = y[:, :_v.integer("steps", steps, minimum=1)]
    g = ingredients
    Q = Q * g.q_scale if g.q_scale != 1.0 else Q
    R = np.sqrt(R) if g.r_sqrt else R
    P0 = P0 if g.M0 is None else np.asarray(g.M0, dtype=float)
    if method == "ukf":
        flt: _Linearised | Unscented = Unscented(model, alpha, beta, kappa)
    else:
        if nominal is not None:
            nominal = model._trajectory("nominal", nominal)
        flt = _Linearised(model, g, "ekf" if g.relinearize else method, nominal)
    out = _loop(flt, model, y, Q, R, x0, P0, g, shared_P=method == "lkf" and not g.relinearize)
    if g.output == "prior":
        out["x_hat"], out["P"] = out["x_bar"].copy(), out["M"].copy()
    if g.shift == "output":
        for key in ("x_hat", "P"):
            out[key][:, 1:] = out[key][:, :-1].copy()
    return FilterResult(method, model.t[:y.shape[1]], **out)


def _loop(flt, model, y, Q, R, x0, P0, g, shared_P: bool) -> dict[str, np.ndarray]:
    """Predict, then update with the measured components, at every step: the only loop."""
    N, K1 = y.shape[0], y.shape[1]
    out = {"x_bar": np.empty((N, K1, 6)), "M": np.empty((N, K1, 6, 6)),
           "x_hat": np.empty((N, K1, 6)), "P": np.empty((N, K1, 6, 6)),
           "r": np.full((N, K1, 5), np.nan), "S": np.full((N, K1, 5, 5), np.nan)}
    x = np.broadcast_to(x0, (N, 6)).copy()
    # the LKF's covariance does not depend on the data: one sequence for all runs
    P = P0.copy() if shared_P else np.broadcast_to(P0, (N, 6, 6)).copy()
    out["x_bar"][:, 0] = out["x_hat"][:, 0] = x
    out["M"][:, 0] = out["P"][:, 0] = P
    finite = np.isfinite(y)
    rows = [_groups(finite[:, i]) for i in range(K1)]
    s = flt.start(x)
    for k in range(K1 - 1):
        j = k + 1
        s, P = flt.predict(k, s, P, Q)
        out["x_bar"][:, j], out["M"][:, j] = flt.estimate(j, s), P
        row = k if g.shift == "measurement" else j
        groups = rows[row]
        if len(groups) > 1 or groups and not isinstance(groups[0][0], slice):
            s = s.copy()
            P = np.broadcast_to(P, (N, 6, 6)).copy()   # different rows: different covariances
        for runs, m in groups:
            full = isinstance(runs, slice)
            M = P if full else P[runs]
            sg, Pg, r, S = flt.update(j, s if full else s[runs], M, y[runs, row], m, R, runs)
            full_S = None
            if not m.all() and isinstance(flt, _Linearised):
                full_S = _full_S(flt, j, s if full else s[runs], M, R, runs)
            if full:
                s, P = sg, Pg
            else:
                s[runs], P[runs] = sg, Pg
            _store_update(out, j, runs, m, r, S, full_S)
        out["x_hat"][:, j], out["P"][:, j] = flt.estimate(j, s), P
    return out


def _one(method: str, model: CoopModel, y: np.ndarray, Q, R, x0, P0, **kwargs) -> FilterResult:
    """``run_batch`` on the one log y (K+1, 5), the run axis dropped."""
    if not isinstance(model, CoopModel):
        raise ValueError(f"model must be a CoopModel, got {type(model).__name__}")
    y = _v.finite_array("y", y, (model.n_steps + 1, N_MEAS), allow_nan=True)
    res = run_batch(method, model, y[None], Q, R, x0, P0, **kwargs)
    return FilterResult(method, res.t, *(getattr(res, k)[0] for k in
                                         ("x_bar", "M", "x_hat", "P", "r", "S")))


def run_lkf(model: CoopModel, y: np.ndarray, Q: np.ndarray | None = None,
            R: np.ndarray | None = None, x0: np.ndarray | None = None,
            P0: np.ndarray | None = None, nominal: np.ndarray | None = None,
            ingredients: Ingredients = RIGHT) -> FilterResult:
    """The linearized KF about the nominal on one log (``nominal`` (K+1, 6) defaults to
    :meth:`CoopModel.nominal`; x̂_0 = x0 means δx̂_0 = x0 − x*_0)."""
    return _one("lkf", model, y, Q, R, x0, P0, nominal=nominal, ingredients=ingredients)


def run_ekf(model: CoopModel, y: np.ndarray, Q: np.ndarray | None = None,
            R: np.ndarray | None = None, x0: np.ndarray | None = None,
            P0: np.ndarray | None = None, ingredients: Ingredients = RIGHT) -> FilterResult:
    """The extended KF (Jacobians at the estimate, recomputed every step) on one log
    (``ingredients``: a student's EKF, :mod:`gpsaccel.coop.mistakes`)."""
    return _one("ekf", model, y, Q, R, x0, P0, ingredients=ingredients)


def run_ukf(model: CoopModel, y: np.ndarray, Q: np.ndarray | None = None,
            R: np.ndarray | None = None, x0: np.ndarray | None = None,
            P0: np.ndarray | None = None, alpha: float = UKF_ALPHA, beta: float = UKF_BETA,
            kappa: float = UKF_KAPPA) -> FilterResult:
    """The unscented KF (angle-aware means and residuals) on one log."""
    return _one("ukf", model, y, Q, R, x0, P0, alpha=alpha, beta=beta, kappa=kappa)


RUNNERS: dict[str, Callable[..., FilterResult]] = {"lkf": run_lkf, "ekf": run_ekf,
                                                    "ukf": run_ukf}


def run_filter(method: str, model: CoopModel, y: np.ndarray, Q: np.ndarray | None = None,
               **kwargs) -> FilterResult:
    """``run_lkf`` / ``run_ekf`` / ``run_ukf`` by name."""
    return RUNNERS[_v.choice("method", method, METHODS)](model, y, Q, **kwargs)

