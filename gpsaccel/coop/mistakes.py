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

from types import SimpleNamespace

import numpy as np

from gpsaccel.coop.filters import FilterResult, Ingredients, euler_nominal, run_batch
from gpsaccel.coop.model import ANGLE_STATES, CoopModel, wrap_angle
from gpsaccel.kalman import entries
from gpsaccel.kalman.linear_messages import MESSAGES as LINEAR_MESSAGES
from gpsaccel.kalman.mistakes import Mistake, apply

KINDS = ("ekf", "lkf")

__all__ = ["KINDS", "Ingredients", "Mistake", "catalogue", "codes", "euler_nominal",
           "heading_range", "ingredients", "run", "wrapped_difference"]


_WRAP_HINT = ("The bearings jump by 2π where they cross ±π; the residual y − h(x̄) must be "
              "wrapped to [−π, π) (e.g. np.mod(r + π, 2π) − π) for rows 1 and 3 (the two "
              "bearings), or the update drags the estimate by 2π/σ.")

#: The coop wording, one table: code.part -> the catalogue entry's message (``{dt}``: the model's
#: ΔT); ``homework.<code>`` -> the homework's findings (:mod:`gpsaccel.assignments.coop`).
MESSAGES: dict[str, str] = {
    "no-angle-wrap.residual": "The bearing residuals are not wrapped. " + _WRAP_HINT,
    "no-angle-wrap.both": "Neither your predicted bearings h(x̄) = atan2(Δη, Δξ) − θ nor the "
                          "residual y − h(x̄) are wrapped. " + _WRAP_HINT,
    "no-state-wrap": "Your heading estimates θg, θa leave [−π, π): in 100 s the UGV turns about "
                     "11 times and the UAV twice. The filter's arithmetic does not care (sin, "
                     "cos and the wrapped residual are periodic) but every error, NEES and plot "
                     "against the truth does: wrap x̂'s headings after each update and "
                     "prediction.",
    "dt-linearization.A": "Your covariance is propagated with F = A, the continuous-time "
                          "Jacobian; the DT transition is F = I + ΔT·A (ΔT = {dt:g} s).",
    "dt-linearization.dtA": "Your covariance is propagated with F = ΔT·A: the identity is "
                            "missing, F = I + ΔT·A.",
    "process-noise.omitted": "Your prediction leaves out Q: M = F P Fᵀ + Q. Without it the filter "
                             "becomes overconfident and stops listening to the measurements.",
    "process-noise.dt": "Your prediction adds ΔT·Q (ΔT = {dt:g} s); Q given to ekf/lkf is "
                        "already the covariance per DT step: M = F P Fᵀ + Q.",
    "std-as-variance": "Your update uses the standard deviations √R where R (variances) belongs: "
                       "S = H M Hᵀ + R with R as given.",
    "measurement-late": "Your update at t_(k+1) uses y_k, the previous row: the loop "
                               "updates before it predicts (or indexes y one row early). Predict "
                               "from t_k to t_(k+1), then update with y_(k+1) (row 0 of y is "
                               "NaN: nothing to update at t = 0).",
    "epoch-shift.output": "Every output row holds the estimate of the row before (x̂ at t_k "
                          "stored in row k+1): store x̂_(k+1) and P_(k+1) in row k+1, and x̂_0, "
                          "P_0 in row 0.",
    "p-not-symmetric": "Your update P = (I − KH) M is right in exact arithmetic but loses "
                       "symmetry to rounding; the Joseph form (I − KH) M (I − KH)ᵀ + K R Kᵀ "
                       "keeps P symmetric and positive definite.",
    "euler-propagation": "Your mean is propagated with one Euler step x + ΔT·f(x, u) per sample "
                         "(ΔT = {dt:g} s; for an LKF, an Euler nominal trajectory). That is an "
                         "approximation of the nonlinear motion with an error of order ΔT² per "
                         "step; the reference integrates the motion exactly (closed form, or "
                         "scipy.integrate.solve_ivp over each ΔT — either passes).",
    "jacobian-point.F-prior": "Your F = I + ΔT·A is evaluated at the predicted state x̄_(k+1); it "
                              "linearizes the step from x̂_k, so A(x̂_k, u).",
    "jacobian-point.H-posterior": "Your H = C is evaluated at x̂_k, the previous estimate; the "
                                  "measurement at t_(k+1) is predicted from x̄_(k+1), so "
                                  "H = C(x̄_(k+1)).",
    "jacobian-point.nominal": "Your F and H are evaluated on the nominal trajectory x* (an LKF's "
                              "Jacobians) while the mean follows the estimate; an EKF linearizes "
                              "about its own estimate: F = I + ΔT·A(x̂_k), H = C(x̄_(k+1)).",
    "jacobian-point.relinearized": "Your LKF evaluates F and H at its own estimate x̂ (and "
                                   "propagates x̂ itself): that is an EKF, as report 002's "
                                   "\"LKF\" is. The LKF linearizes once, about the nominal "
                                   "trajectory x* of the noiseless model: F_k = I + ΔT·A(x*_k), "
                                   "H_k = C(x*_k), and filters the perturbation δx = x − x*.",
    "returns-a-priori": "Your filter returns x̄ and M, the estimate before the update, instead "
                        "of x̂ and P.",
    "residual-covariance.none": "Your gain leaves R out of the residual covariance: K = M Hᵀ "
                                "(H M Hᵀ)⁻¹, where S = H M Hᵀ + R (the measurement's own noise is "
                                "part of the residual).",
    "residual-covariance.sqrt": "Your gain's residual covariance adds the standard deviations √R "
                                "where the variances belong (S = H M Hᵀ + R), while your P is "
                                "updated with R.",
    "joseph-sign.minus": "Your covariance update is Joseph's form with a minus: (I − K H) M "
                         "(I − K H)ᵀ − K R Kᵀ. The measurement's noise adds uncertainty: "
                         "+ K R Kᵀ.",
    "joseph-sign.plus": "Your covariance update writes I + K H where Joseph's form has I − K H: "
                        "P = (I − K H) M (I − K H)ᵀ + K R Kᵀ.",
    "prior-scale": "Your P0 is {factor:g} × the P0 of the problem: every variance of the prior "
                   "is off by a power of ten.",
    "jacobian-sign.ugv": "Your A = ∂f/∂x has the UGV's heading column with the wrong signs: "
                      "∂ξg/∂θg = −v sin θg and ∂ηg/∂θg = +v cos θg.",
    "jacobian-sign.uav": "Your A = ∂f/∂x has the UAV's heading column with the wrong signs: "
                      "∂ξa/∂θa = −v sin θa and ∂ηa/∂θa = +v cos θa.",
    "jacobian-sign.both": "Your A = ∂f/∂x has both heading columns with the wrong signs: "
                       "∂ξ/∂θ = −v sin θ and ∂η/∂θ = +v cos θ for each vehicle.",
    "jacobian-blocks": "Your C = ∂h/∂x has the UGV's and the UAV's position columns swapped in the "
                  "bearing and range rows (Δξ = ξa − ξg taken the other way round): ∂γag/∂ξg = "
                  "Δη/ρ², ∂ρ/∂ξg = −Δξ/ρ, and the UAV's columns the opposite.",
    "mean-not-propagated.ekf": "Your EKF's mean is not propagated: x̄_(k+1) = x̂_k while the "
                               "covariance is; the prediction is x̄_(k+1) = φ_ΔT(x̂_k, u).",
    "mean-not-propagated.lkf": "Your LKF's perturbation is not propagated: δx̄_(k+1) = δx̂_k "
                               "while the covariance is; δx̄_(k+1) = F_k δx̂_k.",
    "mean-not-propagated.nominal": "Your LKF's nominal trajectory is never propagated (x* = x0 at "
                                   "every step): the LKF linearizes about the noiseless "
                                   "trajectory x*_(k+1) = φ_ΔT(x*_k, u) from x0.",
    "returns-a-priori.hint": "Store x̂ and P after the update at each step.",
    # ------------------------------------- the homework's findings (assignments/coop.py)
    "homework.not-defined": "{where} is not defined yet (or still `...`).",
    "homework.return-value.dt": "dt_linearization must return three matrices (F, G, H); it returned a "
                                "{type}.",
    "homework.uses-own-jacobian": "{where} is {form} with your own jacobian_{base}: right here "
                                  "(question 1 grades jacobian_{base}).",
    "homework.zero-order-hold": "Your G is the exact zero-order hold ∫₀^ΔT e^{{Aτ}} dτ B = (ΔT·I + "
                                "ΔT²·A/2) B. It is a better discretization, but the question asks for "
                                "the course's Euler form: one Euler step of the perturbation.",
    "homework.ok.dt": "F = I + ΔT·A, G = ΔT·B and H = C at every state checked.",
    "homework.return-value.ekf": "ekf must return a pair (x_hat, P); it returned a {type}.",
    "homework.matches-reference": "x̂ and P match the course EKF on {where} to {tol:g} σ (largest "
                                  "distances {dx:.2g} σ, {dP:.2g} σσ).",
    "homework.ekf-mismatch": "Your EKF differs from the course EKF from {where} on: x̂ by up to "
                             "{dx:.3g} σ, P by up to {dP:.3g} σσ, and matches none of the typical "
                             "mistakes ({codes}). {row0}Check each step against the question: "
                             "the prediction (the exact step for x̄, the DT transition at the "
                             "previous estimate for M) and the update (the measurement Jacobian "
                             "at the prediction x̄, only the rows of y that are not NaN).",
    "homework.ekf-mismatch.row0": "Row 0 must be (x0, P0): nothing is measured at t = 0. ",
}

#: The catalogue: (message key, title, the ingredients it changes, options of the entry).
_ENTRIES: tuple[tuple[str, str, tuple[tuple, ...], dict], ...] = (
    ("no-angle-wrap.residual", "residual y − h(x̄) not wrapped",
     (("wrap_residual", "difference"),), {"homework": True}),
    ("no-angle-wrap.both", "h and the residual not wrapped", (("wrap_residual", "none"),), {}),
    ("no-state-wrap", "headings not wrapped", (("wrap_state", False),), {}),
    ("dt-linearization.A", "F = A", (("F_form", "A"),), {}),
    ("dt-linearization.dtA", "F = ΔT·A", (("F_form", "dtA"),), {}),
    ("process-noise.omitted", "Q omitted", (("q_scale", 0.0),), {}),
    ("process-noise.dt", "Q scaled by ΔT", (("q_scale", "dt"),), {}),
    ("std-as-variance", "R replaced by √R", (("r_sqrt", True),), {}),
    ("measurement-late", "update with y_k before the prediction",
     (("shift", "measurement"),), {}),
    ("epoch-shift.output", "outputs one row late", (("shift", "output"),), {}),
    ("p-not-symmetric", "P = (I − KH) M", (("joseph", False),), {"informational": True}),
    ("euler-propagation", "one Euler step per sample", (("propagation", "euler"),),
     {"homework": True}),
    ("jacobian-point.F-prior", "F at the prior x̄_(k+1)", (("F_point", "prior"),),
     {"kinds": ("ekf",)}),
    ("jacobian-point.H-posterior", "H at the previous posterior x̂_k", (("H_point", "posterior"),),
     {"kinds": ("ekf",), "homework": True}),
    ("jacobian-point.nominal", "F and H at the nominal",
     (("F_point", "nominal"), ("H_point", "nominal")), {"kinds": ("ekf",)}),
    ("jacobian-point.relinearized", "LKF linearized about the estimate", (("relinearize", True),),
     {"kinds": ("lkf",)}),
    ("returns-a-priori", "x̄ and M returned", (("output", "prior"),),
     {"kinds": ("ekf",), "checker": False, "homework": True}),
    ("jacobian-sign.both", "both heading columns of A, signs flipped", (("heading_sign", "both"),),
     {}),
    ("jacobian-sign.ugv", "the UGV's heading column of A, signs flipped", (("heading_sign", "ugv"),),
     {}),
    ("jacobian-sign.uav", "the UAV's heading column of A, signs flipped", (("heading_sign", "uav"),),
     {}),
    ("jacobian-blocks", "C's UGV and UAV position columns swapped", (("C_swapped", True),), {}),
    ("mean-not-propagated.ekf", "x̄ = x̂", (("mean_propagated", False),), {"kinds": ("ekf",)}),
    ("mean-not-propagated.lkf", "δx̄ = δx̂", (("mean_propagated", False),), {"kinds": ("lkf",)}),
    ("mean-not-propagated.nominal", "x* = x0 at every step", (("nominal_frozen", True),),
     {"kinds": ("lkf",)}),
)


def catalogue(model: CoopModel | None = None, kind: str = "ekf") -> tuple[Mistake, ...]:
    """Every mistake that applies to ``kind`` ("ekf" or "lkf"), with ``model``'s numbers (its
    ΔT in the messages and in ``process-noise``'s ΔT·Q): the coop filter's own entries, then the
    ideas every system shares (:mod:`gpsaccel.kalman.entries`: V left out of S or √R there,
    Joseph's sign, a prior off by a power of ten) in the coop's words."""
    model = CoopModel() if model is None else model
    dt = model.dt
    out = []
    for key, title, changes, options in _ENTRIES:
        changes = tuple((f, dt if v == "dt" else v) for f, v in changes)
        out.append(Mistake(key.split(".")[0], title, MESSAGES[key].format(dt=dt), changes,
                           hint=MESSAGES.get(f"{key}.hint", ""), **options))
    return tuple(m for m in out + _shared(model) if m.applies(kind))


def _shared(model: CoopModel) -> list[Mistake]:
    """The shared entries on the coop's numbers: R as the filter's V, P0 as its M0."""

    def text(key: str, **fields: object) -> str:
        return {**LINEAR_MESSAGES, **MESSAGES}[key].format(**fields)

    numbers = SimpleNamespace(V=model.Rtrue, M0=model.P0)
    return (entries.residual_covariance(numbers, text, name="R")
            + entries.joseph_sign(numbers, text, name="R")
            + entries.prior_scale(numbers, text, name="P0"))


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
