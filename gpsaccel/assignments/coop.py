r"""The coop homework's checks: the Jacobians, the DT linearization, an EKF.

Report 002's cooperative localization (:mod:`gpsaccel.coop.model`): ẋ = f(x, u), y = h(x).

Jacobians (question 1): the student's ``jacobian_A(x, u)``, ``jacobian_B(x, u)``,
``jacobian_C(x)`` are checked by the checker's :func:`gpsaccel.check.jacobians` (analytic
Jacobians, element by element, at the nominal trajectory, random states, headings and bearings at
±π, vehicles 1 cm apart; codes ``jacobian-A``, ``jacobian-B``, ``jacobian-C``).

DT linearization (question 2), the course's Euler form F = I + ΔT·A, G = ΔT·B, H = C, checked by
:func:`gpsaccel.check.dt_model`; a matrix built right from the student's *own* (wrong) Jacobian
passes (the Jacobian's mistake is question 1's), an exact zero-order-hold G is named.

EKF (question 3).  The student's ``ekf(y, x0, P0, Q, R) -> (x_hat, P)`` against the package's EKF
(:func:`gpsaccel.coop.filters.run_ekf`): predict with the exact step φ_ΔT (``model.step``) and
M = F P Fᵀ + Q with F = I + ΔT·A(x̂), update with the rows of y that are not NaN, H = C(x̄), the
bearing residuals wrapped.  Distances are in units of the reference σ = √diag P_ref; both must be
within 1e-6.  A failing filter is matched against the typical mistakes (:func:`ekf_mistakes`):
entries of the coop catalogue (:func:`gpsaccel.coop.mistakes.catalogue`), run by the package's
one EKF with that entry's ingredients, so no second reference filter lives here.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np

from gpsaccel import registry
from gpsaccel.assignments._answers import array, assert_report, call
from gpsaccel.check.findings import mistake_finding
from gpsaccel.check.report import Report
from gpsaccel.coop.mistakes import MESSAGES as COOP_MESSAGES
from gpsaccel.coop.model import (
    CoopModel,
    state_residual,
)

__all__ = ["assert_report", "dt_linearization", "ekf", "jacobians"]

#: The homework's wording: the ``homework.*`` entries of the coop's one table
#: (:data:`gpsaccel.coop.mistakes.MESSAGES`), code (or code.part) -> template.
TEXT = {k.removeprefix("homework."): v for k, v in COOP_MESSAGES.items()
        if k.startswith("homework.")}

#: Distance (units of the reference σ) within which the EKF's x̂ and P count as equal.
EKF_TOL = 1e-6

def ekf_mistakes() -> tuple:
    """The EKF mistakes the homework recognises, in the order tried: the entries of the coop
    catalogue (:func:`gpsaccel.coop.mistakes.catalogue`) marked ``homework``."""
    from gpsaccel.coop.mistakes import catalogue

    return tuple(m for m in catalogue(kind="ekf") if m.homework)


# ------------------------------------------------------------------ Jacobians, DT model
def states(seed: int = 0, n_random: int = 20) -> tuple[np.ndarray, np.ndarray]:
    """(X (n, 6), U (n, 4)): the states and inputs :func:`gpsaccel.check.jacobians` uses."""
    from gpsaccel.check.jacobians import check_states, state_inputs

    model = CoopModel()
    X, _ = check_states(model, n_random, seed)
    return X, state_inputs(model, len(X), seed)


def jacobians(jacobian_A: object, jacobian_B: object, jacobian_C: object, seed: int = 0,
              n_random: int = 20) -> Report:
    """Question 1: the student's A(x, u), B(x, u), C(x), checked by
    :func:`gpsaccel.check.jacobians` (analytic, element by element); never raises."""
    from gpsaccel.check.jacobians import jacobians as check_jacobians  # the function itself

    given = {"A": jacobian_A, "B": jacobian_B, "C": jacobian_C}
    missing = [k for k, v in given.items() if v is None or v is Ellipsis]
    defined: dict[str, Any] = {k: v for k, v in given.items() if k not in missing}
    report = check_jacobians(**defined, n_random=n_random, seed=seed) if defined else \
        Report("Jacobians A, B, C")
    report.subject = "question 1: Jacobians A, B, C"
    for k in missing:
        report.add("not-defined", text=TEXT["not-defined"], where=f"jacobian_{k}", part=k)
    report.sort()
    return report


#: What each DT matrix is made of (course's Euler form) and the Jacobian it uses.
DT_FORMS = {"F": ("A", "F = I + ΔT·A"), "G": ("B", "G = ΔT·B"), "H": ("C", "H = C")}


def _close(a: np.ndarray, b: np.ndarray, rtol: float = 1e-6) -> bool:
    """Every element within rtol of its own size plus rtol times the matrix's largest."""
    scale = np.abs(b).max(axis=(-2, -1), keepdims=True)
    return bool(np.all(np.abs(a - b) <= rtol * (np.abs(b) + scale)))


def _at_states(report: Report, fn: object, X: np.ndarray, U: np.ndarray, what: str,
               shape: tuple[int, int], needs_u: bool = True) -> np.ndarray | None:
    out = []
    for x, u in zip(X, U, strict=True):
        value = call(report, what, fn, *((x.copy(), u.copy()) if needs_u else (x.copy(),)))
        arr = None if value is None else array(report, what, value, shape)
        if arr is None:
            return None
        out.append(arr)
    return np.stack(out)


def _student_matrices(report: Report, func: object, X: np.ndarray, U: np.ndarray,
                      dt: float) -> dict[str, np.ndarray] | None:
    """The student's F, G, H stacked over the states (None once a call or a shape fails)."""
    got: dict[str, list[np.ndarray]] = {"F": [], "G": [], "H": []}
    for x, u in zip(X, U, strict=True):
        out = call(report, "dt_linearization(x, u, dt)", func, x.copy(), u.copy(), dt)
        if out is None:
            return None
        if not isinstance(out, (tuple, list)) or len(out) != 3:
            report.add("return-value", text=TEXT["return-value.dt"], where="dt_linearization",
                       observed={"type": type(out).__name__})
            return None
        for name, v, shape in zip("FGH", out, ((6, 6), (6, 4), (5, 6)), strict=True):
            arr = array(report, name, v, shape)
            if arr is None:
                return None
            got[name].append(arr)
    return {k: np.stack(v) for k, v in got.items()}


def _explained(report: Report, name: str, base: str, form: str, mat: np.ndarray,
               X: np.ndarray, U: np.ndarray, fn: object, model: CoopModel) -> bool:
    """A matrix that fails against the right Jacobian but is the course's form of the student's
    own Jacobian (a note), or G the exact zero-order hold (named); True when reported."""
    from gpsaccel.coop.model import jacobian_A as true_A
    from gpsaccel.coop.model import jacobian_B as true_B

    dt, eye = model.dt, np.eye(6)
    own = None
    if fn is not None and fn is not Ellipsis:
        quiet = Report("own")
        own = _at_states(quiet, fn, X, U, f"jacobian_{base}", mat.shape[1:] if
                         base != "A" else (6, 6), needs_u=base != "C")
    if own is not None:
        want = eye + dt * own if name == "F" else dt * own if name == "G" else own
        if _close(mat, want):
            report.add("uses-own-jacobian", severity="note", text=TEXT["uses-own-jacobian"],
                       where=name, observed={"form": form, "base": base})
            return True
    if name == "G":
        A_ = np.stack([true_A(x, u) for x, u in zip(X, U, strict=True)])
        B_ = np.stack([true_B(x, u, model.L) for x, u in zip(X, U, strict=True)])
        zoh = (dt * eye + dt**2 / 2 * A_) @ B_  # A² = 0: ∫₀^ΔT e^{Aτ} dτ = ΔT I + ΔT²A/2
        if _close(mat, zoh):
            report.add("zero-order-hold", text=TEXT["zero-order-hold"], where="G", part="G")
            return True
    return False


def dt_linearization(func: object, seed: int = 0, n_random: int = 5,
                     jacobian_A: object = None, jacobian_B: object = None,
                     jacobian_C: object = None) -> Report:
    """Question 2: ``func(x, u, dt) -> (F, G, H)`` at the states of
    :func:`gpsaccel.check.dt_model` (ΔT of the course model).

    Each matrix is checked by :func:`gpsaccel.check.dt_model` against the right Jacobians; one
    that fails there but equals the course's form *built from the student's own* Jacobian
    (jacobian_A, jacobian_B, jacobian_C, when given) passes: a wrong element of B costs
    question 1, not question 2 too.  An exact zero-order-hold G = ∫₀^ΔT e^{Aτ} dτ B is named as
    such (the question asks for the Euler form).  Each matrix's findings are its part (F, G, H:
    partial credit); a call that fails or returns the wrong shapes concerns the whole question.
    """
    from gpsaccel.check import dt_model

    model = CoopModel()
    dt = model.dt
    X, U = states(seed, n_random)
    report = Report("question 2: DT linearization F, G, H")
    mats = _student_matrices(report, func, X, U, dt)
    if mats is None:
        return report
    index = {(x.tobytes(), u.tobytes()): i for i, (x, u) in enumerate(zip(X, U, strict=True))}
    own_fns = {"A": jacobian_A, "B": jacobian_B, "C": jacobian_C}
    for name, (base, form) in DT_FORMS.items():
        def at(x, u=None, _m=mats[name]):
            key = (np.asarray(x, float).tobytes(),
                   (U[0] if u is None else np.asarray(u, float)).tobytes())
            if key not in index:  # C(x) is called without u: find the state alone
                key = next(k for k in index if k[0] == key[0])
            return _m[index[key]]
        one: dict[str, Any] = {name: at}
        sub = dt_model(**one, n_random=n_random, seed=seed)
        if sub.passed or _explained(report, name, base, form, mats[name], X, U, own_fns[base],
                                    model):
            continue
        report.findings.extend(sub.tag(name).findings)  # this matrix's part
    if report.passed:
        report.add("ok", severity="note", text=TEXT["ok.dt"])
    report.sort()
    return report


# ------------------------------------------------------------------------------------ EKF
@lru_cache(maxsize=8)
def _reference(y_bytes: bytes, shape: tuple[int, ...], variant: tuple[str, str] | None,
               x0: bytes, P0: bytes, Q: bytes, R: bytes) -> tuple[np.ndarray, np.ndarray]:
    from gpsaccel.coop.filters import run_ekf
    from gpsaccel.coop.mistakes import ingredients

    def arr(b, s):
        return np.frombuffer(b, dtype=float).reshape(s)
    mistakes = () if variant is None else tuple(m for m in ekf_mistakes()
                                                if (m.code, m.variant) == variant)
    res = run_ekf(CoopModel(), arr(y_bytes, shape), arr(Q, (6, 6)), arr(R, (5, 5)),
                  arr(x0, (6,)), arr(P0, (6, 6)), ingredients=ingredients(mistakes))
    return res.x_hat, res.P


def _ref(y, x0, P0, Q, R, variant=None):
    c = [np.ascontiguousarray(a, dtype=float) for a in (y, x0, P0, Q, R)]
    return _reference(c[0].tobytes(), c[0].shape, variant, *(a.tobytes() for a in c[1:]))


def _distances(x, P, x_ref, P_ref) -> tuple[float, float, int]:
    sd = np.sqrt(np.diagonal(P_ref, axis1=1, axis2=2))
    dx = np.abs(state_residual(x, x_ref)) / sd
    dP = np.abs(P - P_ref) / (sd[:, :, None] * sd[:, None, :])
    bad = (dx > EKF_TOL).any(axis=1) | (dP > EKF_TOL).any(axis=(1, 2))
    first = int(np.argmax(bad)) if bad.any() else -1
    return float(dx.max()), float(dP.max()), first


def ekf(func: object, y: np.ndarray, x0: np.ndarray | None = None, P0: np.ndarray | None = None,
        Q: np.ndarray | None = None, R: np.ndarray | None = None, label: str = "the course log"
        ) -> Report:
    """Check the student's ``ekf(y, x0, P0, Q, R) -> (x_hat, P)`` on the log ``y`` (K+1, 5)."""
    model = CoopModel()
    x0 = model.x0 if x0 is None else np.asarray(x0, dtype=float)
    P0 = model.P0 if P0 is None else np.asarray(P0, dtype=float)
    Q = model.Qtrue if Q is None else np.asarray(Q, dtype=float)
    R = model.Rtrue if R is None else np.asarray(R, dtype=float)
    n = model.n_steps + 1
    report = Report(f"question 3: EKF on {label}")
    out = call(report, "ekf(y, x0, P0, Q, R)", func, y.copy(), x0.copy(), P0.copy(), Q.copy(),
               R.copy())
    if out is None:
        report.sort()
        return report
    if not isinstance(out, (tuple, list)) or len(out) != 2:
        report.add("return-value", text=TEXT["return-value.ekf"], where="ekf",
                   observed={"type": type(out).__name__})
        return report
    x = array(report, "x_hat", out[0], (n, 6))
    P = array(report, "P", out[1], (n, 6, 6))
    if x is None or P is None:
        return report
    x_ref, P_ref = _ref(y, x0, P0, Q, R)
    dx, dP, first = _distances(x, P, x_ref, P_ref)
    report.details.update({"dx_sigma": dx, "dP_sigma2": dP})
    if first < 0:
        report.add("matches-reference", severity="note", text=TEXT["matches-reference"],
                   where=label, observed={"tol": EKF_TOL, "dx": dx, "dP": dP})
        return report
    for m in ekf_mistakes():
        xm, Pm = _ref(y, x0, P0, Q, R, (m.code, m.variant))
        if _distances(x, P, xm, Pm)[2] < 0:
            # the student reads the code's wording and what their EKF does (the entry's variant);
            # the entry's message, which states the right step, is the instructor's
            mistake_finding(report, m, where=label)
            return report
    t = model.t
    report.add("ekf-mismatch", text=TEXT["ekf-mismatch"], where=f"t = {t[first]:g} s (step {first})",
               observed={
                   "dx": dx, "dP": dP, "codes": ", ".join(m.code for m in ekf_mistakes()),
                   "row0": TEXT["ekf-mismatch.row0"]
                   if first == 0 else ""})
    return report


# the homework, for `gpsaccel assignment` / `gpsaccel grade` (its master: assignments/coop/)
registry.add_assignment(
    "coop", __name__, system="coop", problem="coop",
    title="Cooperative localization: Jacobians, the DT model, an EKF (report 002)")
