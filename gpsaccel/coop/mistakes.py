r"""Known mistakes in a student's cooperative-localization EKF and LKF, as runnable filters.

Every EKF or LKF a student writes for report 002 — right or wrong — is one choice of a few
ingredients (:class:`Ingredients`) in the same loop, for k = 0..K−1, j = k + 1::

    EKF  x̄_j = wrap(φ_ΔT(x̂_k, u0))          M_j = F P_k Fᵀ + Q,    F = I + ΔT·A(x̂_k, u0)
         H = C(x̄_j),  r = wrap(y_j − h(x̄_j)),  S = H M Hᵀ + R,  K = M Hᵀ S⁻¹
         x̂_j = wrap(x̄_j + K r),  P_j = (I − KH) M (I − KH)ᵀ + K R Kᵀ
    LKF  the same about the nominal x*: δx̄_j = F_k δx̂_k with F_k = I + ΔT·A(x*_k),
         H = C(x*_j), r = wrap(y_j − h(x*_j) − H δx̄_j), x̂ = wrap(x* + δx̂)

and a mistake changes one ingredient: ``no-angle-wrap`` leaves the bearing residual unwrapped,
``no-state-wrap`` the headings, ``dt-linearization`` uses F = A or F = ΔT·A, ``jacobian-point``
evaluates F at x̄_j or H at x̂_k (or both at the nominal; or an "LKF" linearizes about its own
estimate, i.e. is an EKF), ``process-noise`` drops Q or scales it by ΔT, ``std-as-variance``
takes R's standard deviations, ``epoch-shift`` updates with y_k at t_j (before the first
prediction) or returns every row one step late, ``p-not-symmetric`` uses the short form
P = (I − KH) M, ``euler-propagation`` one Euler step for the mean.  :func:`run` runs any set of
them on N logs at once (vectorised over runs, the same order of operations as
:func:`gpsaccel.coop.filters.run_batch`, so with no mistake it reproduces the reference EKF and
LKF to rounding).

The catalogue is system knowledge; the checker that matches a student's output against it is in
:mod:`gpsaccel.check`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from gpsaccel.coop.model import (
    ANGLE_STATES,
    N_MEAS,
    N_STATES,
    CoopModel,
    f,
    h,
    h_unwrapped,
    measurement_residual,
    propagate,
    state_residual,
    wrap_angle,
    wrap_state,
)
from gpsaccel.kalman import epochs
from gpsaccel.kalman.update import gain, joseph_update

KINDS = ("ekf", "lkf")


@dataclass(frozen=True)
class Ingredients:
    """The choices a student makes in the loop of the module docstring (defaults: right).

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


@dataclass(frozen=True)
class Mistake(epochs.Mistake):
    """One entry of the catalogue, the core's entry (code, variant, message, the ingredients it
    changes: :class:`gpsaccel.kalman.epochs.Mistake`) and the filters it applies to."""

    kinds: tuple[str, ...] = KINDS
    informational: bool = False

    def __str__(self) -> str:
        return f"{self.code} ({self.variant})"


def catalogue(model: CoopModel | None = None, kind: str = "ekf") -> tuple[Mistake, ...]:
    """Every mistake that applies to ``kind`` ("ekf" or "lkf"), with ``model``'s numbers."""
    model = CoopModel() if model is None else model
    dt = model.dt
    wrap_hint = ("The bearings jump by 2π where they cross ±π; the residual y − h(x̄) must be "
                 "wrapped to [−π, π) (e.g. np.mod(r + π, 2π) − π) for rows 1 and 3 (the two "
                 "bearings), or the update drags the estimate by 2π/σ.")
    out = [
        Mistake("no-angle-wrap", "residual y − h(x̄) not wrapped",
                "The bearing residuals are not wrapped. " + wrap_hint,
                (("wrap_residual", "difference"),)),
        Mistake("no-angle-wrap", "h and the residual not wrapped",
                "Neither your predicted bearings h(x̄) = atan2(Δη, Δξ) − θ nor the residual "
                "y − h(x̄) are wrapped. " + wrap_hint, (("wrap_residual", "none"),)),
        Mistake("no-state-wrap", "headings not wrapped",
                "Your heading estimates θg, θa leave [−π, π): in 100 s the UGV turns about 11 "
                "times and the UAV twice. "
                "The filter's arithmetic does not care (sin, cos and the wrapped residual are "
                "periodic) but every error, NEES and plot against the truth does: wrap x̂'s "
                "headings after each update and prediction.", (("wrap_state", False),)),
        Mistake("dt-linearization", "F = A",
                f"Your covariance is propagated with F = A, the continuous-time Jacobian; the DT "
                f"transition is F = I + ΔT·A (ΔT = {dt:g} s).", (("F_form", "A"),)),
        Mistake("dt-linearization", "F = ΔT·A",
                "Your covariance is propagated with F = ΔT·A: the identity is missing, "
                "F = I + ΔT·A.", (("F_form", "dtA"),)),
        Mistake("process-noise", "Q omitted",
                "Your prediction leaves out Q: M = F P Fᵀ + Q. Without it the filter becomes "
                "overconfident and stops listening to the measurements.", (("q_scale", 0.0),)),
        Mistake("process-noise", "Q scaled by ΔT",
                f"Your prediction adds ΔT·Q (ΔT = {dt:g} s); Q given to ekf/lkf is already the "
                f"covariance per DT step: M = F P Fᵀ + Q.", (("q_scale", dt),)),
        Mistake("std-as-variance", "R replaced by √R",
                "Your update uses the standard deviations √R where R (variances) belongs: "
                "S = H M Hᵀ + R with R as given.", (("r_sqrt", True),)),
        Mistake("epoch-shift", "update with y_k before the prediction",
                "Your update at t_(k+1) uses y_k, the previous row: the loop updates before it "
                "predicts (or indexes y one row early). Predict from t_k to t_(k+1), then update "
                "with y_(k+1) (row 0 of y is NaN: nothing to update at t = 0).",
                (("shift", "measurement"),)),
        Mistake("epoch-shift", "outputs one row late",
                "Every output row holds the estimate of the row before (x̂ at t_k stored in "
                "row k+1): store x̂_(k+1) and P_(k+1) in row k+1, and x̂_0, P_0 in row 0.",
                (("shift", "output"),)),
        Mistake("p-not-symmetric", "P = (I − KH) M",
                "Your update P = (I − KH) M is right in exact arithmetic but loses symmetry to "
                "rounding; the Joseph form (I − KH) M (I − KH)ᵀ + K R Kᵀ keeps P symmetric "
                "and positive definite.", (("joseph", False),), informational=True),
        Mistake("euler-propagation", "one Euler step per sample",
                f"Your mean is propagated with one Euler step x + ΔT·f(x, u) per sample (ΔT = "
                f"{dt:g} s; for an LKF, an Euler nominal trajectory). That is an approximation "
                f"of the nonlinear motion with an error of order ΔT² per step; the reference "
                f"integrates the motion exactly (closed form, or scipy.integrate.solve_ivp "
                f"over each ΔT — either passes).", (("propagation", "euler"),)),
    ]
    out += [
        Mistake("jacobian-point", "F at the prior x̄_(k+1)",
                "Your F = I + ΔT·A is evaluated at the predicted state x̄_(k+1); it linearizes the "
                "step from x̂_k, so A(x̂_k, u).", (("F_point", "prior"),), ("ekf",)),
        Mistake("jacobian-point", "H at the previous posterior x̂_k",
                "Your H = C is evaluated at x̂_k, the previous estimate; the measurement at "
                "t_(k+1) is predicted from x̄_(k+1), so H = C(x̄_(k+1)).",
                (("H_point", "posterior"),), ("ekf",)),
        Mistake("jacobian-point", "F and H at the nominal",
                "Your F and H are evaluated on the nominal trajectory x* (an LKF's Jacobians) "
                "while the mean follows the estimate; an EKF linearizes about its own estimate: "
                "F = I + ΔT·A(x̂_k), H = C(x̄_(k+1)).",
                (("F_point", "nominal"), ("H_point", "nominal")), ("ekf",)),
        Mistake("jacobian-point", "LKF linearized about the estimate",
                "Your LKF evaluates F and H at its own estimate x̂ (and propagates x̂ itself): "
                "that is an EKF, as report 002's \"LKF\" is. The LKF linearizes once, about the "
                "nominal trajectory x* of the noiseless model: F_k = I + ΔT·A(x*_k), "
                "H_k = C(x*_k), and filters the perturbation δx = x − x*.",
                (("relinearize", True),), ("lkf",)),
    ]
    return tuple(m for m in out if kind in m.kinds)


def codes(kind: str = "ekf") -> tuple[str, ...]:
    """The catalogue's codes for ``kind``, in order."""
    return tuple(dict.fromkeys(m.code for m in catalogue(kind=kind)))


def ingredients(mistakes: tuple[Mistake, ...] = ()) -> Ingredients:
    """The ingredients of a filter making ``mistakes`` (none: the right one)."""
    g = Ingredients()
    for m in mistakes:
        g = replace(g, **dict(m.changes))
    return g


def _tr(a: np.ndarray) -> np.ndarray:
    return np.swapaxes(a, -1, -2)


def _residual(y: np.ndarray, yhat_wrapped: np.ndarray, yhat_raw: np.ndarray,
              g: Ingredients) -> np.ndarray:
    if g.wrap_residual == "yes":
        return measurement_residual(y, yhat_wrapped)
    if g.wrap_residual == "difference":
        return y - yhat_wrapped
    return y - yhat_raw


@dataclass
class Output:
    """What a (possibly mistaken) filter returns: x̂ (N, K+1, 6), P (N, K+1, 6, 6), and its
    residuals r (N, K+1, 5) and their covariances S (N, K+1, 5, 5) (row 0 NaN)."""

    x_hat: np.ndarray
    P: np.ndarray
    r: np.ndarray
    S: np.ndarray


def run(model: CoopModel, y: np.ndarray, Q: np.ndarray, R: np.ndarray, kind: str = "ekf",
        mistakes: tuple[Mistake, ...] = (), nominal: np.ndarray | None = None,
        x0: np.ndarray | None = None, P0: np.ndarray | None = None) -> Output:
    """Run the ``kind`` filter that makes ``mistakes`` on logs y (N, K+1, 5) with Q and R.

    Rows of y must be wholly NaN or wholly finite over all runs (the checker's simulated logs and
    the course log are).  x̂_0 = x0, P_0 = P0 of the model unless given.
    """
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    g = ingredients(mistakes)
    if kind == "lkf" and g.relinearize:
        kind = "ekf"
    y = np.asarray(y, dtype=float)
    N, K1 = y.shape[0], y.shape[1]
    skip = np.isnan(y).all(axis=(0, 2))
    Q = np.asarray(Q, dtype=float) * g.q_scale
    R = np.sqrt(np.asarray(R, dtype=float)) if g.r_sqrt else np.asarray(R, dtype=float)
    x0 = model.x0 if x0 is None else np.asarray(x0, dtype=float)
    P0 = model.P0 if P0 is None else np.asarray(P0, dtype=float)
    if nominal is None and (kind == "lkf" or "nominal" in (g.F_point, g.H_point)):
        nominal = euler_nominal(model) if g.propagation == "euler" else model.nominal()
    xn: np.ndarray = np.empty((0, N_STATES)) if nominal is None else nominal  # EKF: unused
    wrap_x = wrap_state if g.wrap_state else (lambda v: np.array(v, dtype=float))
    I = np.eye(N_STATES)

    def F_of(A: np.ndarray) -> np.ndarray:
        return {"I+dtA": I + model.dt * A, "A": A, "dtA": model.dt * A}[g.F_form]

    def update_cov(M, K, H):
        return joseph_update(M, K, H, R) if g.joseph else (I - K @ H) @ M

    x_hat = np.empty((N, K1, N_STATES))
    P_out = np.empty((N, K1, N_STATES, N_STATES))
    r_out = np.full((N, K1, N_MEAS), np.nan)
    S_out = np.full((N, K1, N_MEAS, N_MEAS), np.nan)
    x = np.broadcast_to(x0, (N, N_STATES)).copy()
    P = np.broadcast_to(P0, (N, N_STATES, N_STATES)).copy()
    x_hat[:, 0], P_out[:, 0] = x, P
    if kind == "lkf":
        dx = state_residual(x, xn[0])
        Fs, Hs, yn_w = F_of(model.A(xn)), model.C(xn), h(xn)
        yn_raw = h_unwrapped(xn)
    for k in range(K1 - 1):
        j = k + 1
        m_row = k if g.shift == "measurement" else j
        if kind == "ekf":
            if g.F_point == "posterior":
                F = F_of(model.A(x))
            x_prev = x
            x = wrap_x(_propagate(model, x, g.propagation))
            if g.F_point == "prior":
                F = F_of(model.A(x))
            elif g.F_point == "nominal":
                F = F_of(model.A(xn[k]))
            P = F @ P @ _tr(F) + Q
            if not skip[m_row]:
                xH = {"prior": x, "posterior": x_prev, "nominal": None}[g.H_point]
                H = model.C(xn[j]) if xH is None else model.C(xH)
                r = _residual(y[:, m_row], h(x), h_unwrapped(x), g)
                K, S = gain(P, H, R)                    # K = P Hᵀ (H P Hᵀ + R)⁻¹
                x = wrap_x(x + np.einsum("nij,nj->ni", K, r))
                P = update_cov(P, K, H)
                r_out[:, j], S_out[:, j] = r, S
        else:
            dx = dx @ Fs[k].T
            P = Fs[k] @ P @ _tr(Fs[k]) + Q
            if not skip[m_row]:
                H = Hs[j]
                r = _residual(y[:, m_row], yn_w[j] + dx @ H.T, yn_raw[j] + dx @ H.T, g)
                K, S = gain(P, H, R)                    # K = P Hᵀ (H P Hᵀ + R)⁻¹
                dx = dx + np.einsum("nij,nj->ni", K, r)
                P = update_cov(P, K, H)
                r_out[:, j], S_out[:, j] = r, S
            x = wrap_x(xn[j] + dx)
        x_hat[:, j], P_out[:, j] = x, P
    if g.shift == "output":
        x_hat[:, 1:], P_out[:, 1:] = x_hat[:, :-1].copy(), P_out[:, :-1].copy()
    return Output(x_hat, P_out, r_out, S_out)


def _propagate(model: CoopModel, x: np.ndarray, how: str = "exact") -> np.ndarray:
    if how == "euler":
        return x + model.dt * f(x, model.u0, model.L)
    return propagate(x, model.u0, model.dt, model.L)


def euler_nominal(model: CoopModel) -> np.ndarray:
    """The nominal trajectory (K+1, 6) by Euler steps from x0 (headings wrapped)."""
    x = np.empty((model.n_steps + 1, N_STATES))
    x[0] = model.x0
    for k in range(model.n_steps):
        x[k + 1] = wrap_state(x[k] + model.dt * f(x[k], model.u0, model.L))
    return x


def heading_range(x_hat: np.ndarray) -> float:
    """The largest |heading| (rad) in x̂ (..., 6): > π means the headings were not wrapped."""
    return float(np.abs(np.asarray(x_hat)[..., list(ANGLE_STATES)]).max())


def wrapped_difference(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a − b for states, the heading differences wrapped (so 2π apart counts as equal)."""
    d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    d[..., list(ANGLE_STATES)] = wrap_angle(d[..., list(ANGLE_STATES)])
    return d
