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

Each entry is the core's one entry type (:class:`gpsaccel.kalman.mistakes.Mistake`: code, title,
message, hint, the ingredients it changes, ``kinds`` the filters it applies to, ``homework`` for
the four the homework's EKF question names).  The catalogue is system knowledge; the checker that
matches a student's output against it is in :mod:`gpsaccel.check`, the homework in
:mod:`gpsaccel.assignments.coop`.
"""

from __future__ import annotations

import numpy as np

from gpsaccel.coop.filters import FilterResult, Ingredients, euler_nominal, run_batch
from gpsaccel.coop.model import ANGLE_STATES, CoopModel, wrap_angle
from gpsaccel.kalman.mistakes import Mistake, apply

KINDS = ("ekf", "lkf")

__all__ = ["KINDS", "Ingredients", "Mistake", "catalogue", "codes", "euler_nominal",
           "heading_range", "ingredients", "run", "wrapped_difference"]


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
                (("wrap_residual", "difference"),), homework=True),
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
                f"over each ΔT — either passes).", (("propagation", "euler"),), homework=True),
    ]
    out += [
        Mistake("jacobian-point", "F at the prior x̄_(k+1)",
                "Your F = I + ΔT·A is evaluated at the predicted state x̄_(k+1); it linearizes the "
                "step from x̂_k, so A(x̂_k, u).", (("F_point", "prior"),), kinds=("ekf",)),
        Mistake("jacobian-point", "H at the previous posterior x̂_k",
                "Your H = C is evaluated at x̂_k, the previous estimate; the measurement at "
                "t_(k+1) is predicted from x̄_(k+1), so H = C(x̄_(k+1)).",
                (("H_point", "posterior"),), kinds=("ekf",), homework=True),
        Mistake("jacobian-point", "F and H at the nominal",
                "Your F and H are evaluated on the nominal trajectory x* (an LKF's Jacobians) "
                "while the mean follows the estimate; an EKF linearizes about its own estimate: "
                "F = I + ΔT·A(x̂_k), H = C(x̄_(k+1)).",
                (("F_point", "nominal"), ("H_point", "nominal")), kinds=("ekf",)),
        Mistake("jacobian-point", "LKF linearized about the estimate",
                "Your LKF evaluates F and H at its own estimate x̂ (and propagates x̂ itself): "
                "that is an EKF, as report 002's \"LKF\" is. The LKF linearizes once, about the "
                "nominal trajectory x* of the noiseless model: F_k = I + ΔT·A(x*_k), "
                "H_k = C(x*_k), and filters the perturbation δx = x − x*.",
                (("relinearize", True),), kinds=("lkf",)),
        Mistake("returns-a-priori", "x̄ and M returned",
                "Your filter returns x̄ and M, the estimate before the update, instead of x̂ "
                "and P.", (("output", "prior"),), kinds=("ekf",), hint="Store x̂ and P after the "
                "update at each step.", checker=False, homework=True),
    ]
    return tuple(m for m in out if m.applies(kind))


def codes(kind: str = "ekf") -> tuple[str, ...]:
    """The checker's codes for ``kind``, in order."""
    return tuple(dict.fromkeys(m.code for m in catalogue(kind=kind) if m.checker))


def ingredients(mistakes: tuple[Mistake, ...] = ()) -> Ingredients:
    """The ingredients of a filter making ``mistakes`` (none: the right one)."""
    return apply(Ingredients(), mistakes)


def run(model: CoopModel, y: np.ndarray, Q: np.ndarray, R: np.ndarray, kind: str = "ekf",
        mistakes: tuple[Mistake, ...] = (), nominal: np.ndarray | None = None,
        x0: np.ndarray | None = None, P0: np.ndarray | None = None) -> FilterResult:
    """The ``kind`` filter that makes ``mistakes`` on logs y (N, K+1, 5): the one filter of
    :func:`gpsaccel.coop.filters.run_batch` with the mistakes' ingredients."""
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    return run_batch(kind, model, y, Q, R, x0, P0, nominal, ingredients(mistakes))


def heading_range(x_hat: np.ndarray) -> float:
    """The largest |heading| (rad) in x̂ (..., 6): > π means the headings were not wrapped."""
    return float(np.abs(np.asarray(x_hat)[..., list(ANGLE_STATES)]).max())


def wrapped_difference(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a − b for states, the heading differences wrapped (so 2π apart counts as equal)."""
    d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    d[..., list(ANGLE_STATES)] = wrap_angle(d[..., list(ANGLE_STATES)])
    return d
