r"""The coop homework's checks: Jacobians and DT linearization by finite differences, an EKF.

Report 002's cooperative localization (:mod:`gpsaccel.coop.model`): ẋ = f(x, u), y = h(x).

Jacobians (question 1).  The student's ``jacobian_A(x, u)``, ``jacobian_B(x, u)``,
``jacobian_C(x)`` are compared with central differences of the package's f and h at the nominal
point and at random points (seeded)::

    ∂f/∂xⱼ ≈ [f(x + εeⱼ) − f(x − εeⱼ)] / 2ε,     ε = 1e-6 · max(1, |xⱼ|)

(bearing differences wrapped to [−π, π)); truncation error O(ε²), rounding O(1e-16/ε) ≈ 1e-10,
so an element counts as right within 1e-6 + 1e-6·|value|.

DT linearization (question 2), the course's Euler form: F = I + ΔT·A, G = ΔT·B, H = C, with A, B, C
from the finite differences above.

EKF (question 3).  The student's ``ekf(y, x0, P0, Q, R) -> (x_hat, P)`` against the package's EKF
(:func:`gpsaccel.coop.filters.run_ekf`): predict with the exact step φ_ΔT (``model.step``) and
M = F P Fᵀ + Q with F = I + ΔT·A(x̂), update with the rows of y that are not NaN, H = C(x̄), the
bearing residuals wrapped.  Distances are in units of the reference σ = √diag P_ref; both must be
within 1e-6.  A failing filter is matched against the typical mistakes (:data:`EKF_MISTAKES`),
each a variant of a small reference EKF written here (:func:`reference_ekf`).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from gpsaccel.assignments._answers import array, assert_report, call, compare
from gpsaccel.check.report import Report
from gpsaccel.coop.model import (
    MEASUREMENTS,
    STATES,
    CoopModel,
    measurement_residual,
    state_residual,
    wrap_state,
)

__all__ = ["assert_report", "dt_linearization", "ekf", "jacobians", "reference_ekf"]

#: Relative and absolute tolerance of a Jacobian element against the finite difference.
RTOL = ATOL = 1e-6

#: Distance (units of the reference σ) within which the EKF's x̂ and P count as equal.
EKF_TOL = 1e-6

INPUTS = ("vg", "φg", "va", "ωa")

#: The EKF mistakes recognised (code -> what it is), in the order they are tried.
EKF_MISTAKES = {
    "innovation-not-wrapped": "the bearing residuals y − h(x̄) are not wrapped to [−π, π)",
    "euler-prediction": "x̄ = x̂ + ΔT·f(x̂) (one Euler step) instead of the exact step",
    "jacobian-at-previous": "H = C(x̂ₖ₋₁) evaluated at the previous estimate instead of x̄ₖ",
    "returns-a-priori": "the filter returns x̄, M (before the update) instead of x̂, P",
}


# ------------------------------------------------------------------------ finite differences
def points(seed: int = 0, n: int = 3) -> list[tuple[np.ndarray, np.ndarray]]:
    """(x, u) test points: the nominal (x0, u0) and ``n`` random ones around it (seeded)."""
    model = CoopModel()
    rng = np.random.default_rng(seed)
    out = [(model.x0.copy(), model.u0.copy())]
    for _ in range(n):
        x = model.x0 + rng.uniform(-40, 40, 6) * np.array([1, 1, 0, 1, 1, 0])
        x[[2, 5]] = rng.uniform(-math.pi, math.pi, 2)
        u = model.u0 * rng.uniform(0.5, 1.5, 4)
        out.append((x, u))
    return out


def _central(fun, x: np.ndarray, diff) -> np.ndarray:
    cols = []
    for j in range(x.size):
        eps = 1e-6 * max(1.0, abs(x[j]))
        e = np.zeros_like(x)
        e[j] = eps
        cols.append(diff(fun(x + e), fun(x - e)) / (2 * eps))
    return np.stack(cols, axis=-1)


def fd_A(x: np.ndarray, u: np.ndarray, L: float = 0.5) -> np.ndarray:
    """∂f/∂x by central differences (6 x 6)."""
    from gpsaccel.coop.model import f
    return _central(lambda xx: f(xx, u, L), x, np.subtract)


def fd_B(x: np.ndarray, u: np.ndarray, L: float = 0.5) -> np.ndarray:
    """∂f/∂u by central differences (6 x 4)."""
    from gpsaccel.coop.model import f
    return _central(lambda uu: f(x, uu, L), u, np.subtract)


def fd_C(x: np.ndarray) -> np.ndarray:
    """∂h/∂x by central differences, bearing differences wrapped (5 x 6)."""
    from gpsaccel.coop.model import h
    return _central(h, x, measurement_residual)


def _state_name(j: int) -> str:
    return STATES[j][0]


def _meaning_A(ix):
    return f"∂ẋ{ix[0] + 1}/∂{_state_name(ix[1])}"


def _meaning_B(ix):
    return f"∂ẋ{ix[0] + 1}/∂{INPUTS[ix[1]]}"


def _meaning_C(ix):
    return f"∂{MEASUREMENTS[ix[0]][0].split(' ')[0]}/∂{_state_name(ix[1])}"


def _at(x: np.ndarray, u: np.ndarray | None) -> str:
    xs = ", ".join(f"{v:.4g}" for v in x)
    return f"at x = [{xs}]" + ("" if u is None else f", u = [{', '.join(f'{v:.4g}' for v in u)}]")


def jacobians(jacobian_A: object, jacobian_B: object, jacobian_C: object, seed: int = 0,
              n_points: int = 3) -> Report:
    """Check the student's A(x, u), B(x, u), C(x) against finite differences; never raises."""
    report = Report("question 1: Jacobians A, B, C")
    for name, func, shape, fd, meaning, needs_u in (
            ("A", jacobian_A, (6, 6), fd_A, _meaning_A, True),
            ("B", jacobian_B, (6, 4), fd_B, _meaning_B, True),
            ("C", jacobian_C, (5, 6), fd_C, _meaning_C, False)):
        for x, u in points(seed, n_points):
            args = (x.copy(), u.copy()) if needs_u else (x.copy(),)
            sig = f"jacobian_{name}({'x, u' if needs_u else 'x'})"
            value = call(report, sig, func, *args)
            arr = None if value is None else array(report, sig, value, shape)
            if arr is None:
                break
            want = fd(x, u) if needs_u else fd(x)
            if not compare(report, name, arr, want, RTOL, ATOL,
                           "(central finite difference of " + ("f" if name != "C" else "h") + ") "
                           + _at(x, u if needs_u else None), "jacobian-element", meaning,
                           sign_code="jacobian-sign"):
                break  # one point is enough to show the mistake
    if report.passed:
        report.add("ok", f"A, B and C match central finite differences of f and h at "
                   f"{n_points + 1} points (tolerance {RTOL:g}).", "note")
    report.sort()
    return report


def dt_linearization(func: object, seed: int = 0, n_points: int = 2,
                     dts: tuple[float, ...] = (0.1, 0.05)) -> Report:
    """Check ``func(x, u, dt) -> (F, G, H)`` against F = I + ΔT·A, G = ΔT·B, H = C."""
    report = Report("question 2: DT linearization F, G, H")
    for x, u in points(seed + 1, n_points):
        for dt in dts:
            out = call(report, "dt_linearization(x, u, dt)", func, x.copy(), u.copy(), dt)
            if out is None:
                break
            if not isinstance(out, (tuple, list)) or len(out) != 3:
                report.add("return-value", "dt_linearization must return three matrices "
                           f"(F, G, H); it returned a {type(out).__name__}.")
                break
            A, B, C = fd_A(x, u), fd_B(x, u), fd_C(x)
            F, G, H = (array(report, n, v, s) for n, v, s in
                       zip("FGH", out, ((6, 6), (6, 4), (5, 6)), strict=True))
            if F is None or G is None or H is None:
                break
            where = f"(ΔT = {dt:g} s, {_at(x, u)})"
            ok = True
            if not compare(report, "F", F, np.eye(6) + dt * A, RTOL, ATOL, where, "dt-F"):
                ok = False
                last = report.findings.pop()
                if not (np.abs(F - dt * A) > ATOL + RTOL * np.abs(dt * A)).any():
                    report.add("dt-missing-identity", f"F = ΔT·A: the identity is missing. "
                               f"x_(k+1) ≈ x_k + ΔT·ẋ, so F = I + ΔT·A {where}.")
                else:
                    report.findings.append(last)
            if not compare(report, "G", G, dt * B, RTOL, ATOL, where, "dt-G"):
                ok = False
                last = report.findings.pop()
                if not (np.abs(G - B) > ATOL + RTOL * np.abs(B)).any():
                    report.add("dt-input-not-scaled", f"G = B: the input acts for ΔT, so "
                               f"G = ΔT·B {where}.")
                else:
                    report.findings.append(last)
            if not compare(report, "H", H, C, RTOL, ATOL, where, "dt-H", _meaning_C,
                           sign_code="jacobian-sign"):
                ok = False
            if not ok:
                break
        if not report.passed:
            break
    if report.passed:
        report.add("ok", "F = I + ΔT·A, G = ΔT·B and H = C at every point and step checked.",
                   "note")
    report.sort()
    return report


# ------------------------------------------------------------------------------------ EKF
def reference_ekf(model: CoopModel, y: np.ndarray, x0: np.ndarray, P0: np.ndarray,
                  Q: np.ndarray, R: np.ndarray, mistake: str | None = None
                  ) -> tuple[np.ndarray, np.ndarray]:
    """The course EKF (module docstring), or with one of :data:`EKF_MISTAKES` made.

    Returns (x̂ (K+1, 6), P (K+1, 6, 6)); row 0 is (x0, P0).  Equal to
    :func:`gpsaccel.coop.filters.run_ekf` (tests), written out so that each mistake is one switch.
    """
    from gpsaccel.coop.model import f, h, jacobian_A, jacobian_C

    n = model.n_steps + 1
    xs, Ps = np.empty((n, 6)), np.empty((n, 6, 6))
    x, P = np.array(x0, dtype=float), np.array(P0, dtype=float)
    xs[0], Ps[0] = x, P
    for k in range(1, n):
        F = np.eye(6) + model.dt * jacobian_A(x, model.u0)
        x_prev = x
        if mistake == "euler-prediction":
            x = wrap_state(x + model.dt * f(x, model.u0, model.L))
        else:
            x = model.step(x)
        M = F @ P @ F.T + Q
        m = np.isfinite(y[k])
        if mistake == "returns-a-priori":
            xs[k], Ps[k] = x, M
        if m.any():
            Hk = jacobian_C(x_prev if mistake == "jacobian-at-previous" else x)[m]
            r = (y[k] - h(x))[m] if mistake == "innovation-not-wrapped" else \
                measurement_residual(y[k], h(x))[m]
            Rm = R[np.ix_(m, m)]
            S = Hk @ M @ Hk.T + Rm
            K = np.linalg.solve(S, Hk @ M).T
            x = wrap_state(x + K @ r)
            A = np.eye(6) - K @ Hk
            P = A @ M @ A.T + K @ Rm @ K.T
        else:
            P = M
        if mistake != "returns-a-priori":
            xs[k], Ps[k] = x, P
    return xs, Ps


@lru_cache(maxsize=4)
def _reference(y_bytes: bytes, shape: tuple[int, ...], mistake: str | None,
               x0: bytes, P0: bytes, Q: bytes, R: bytes) -> tuple[np.ndarray, np.ndarray]:
    def arr(b, s):
        return np.frombuffer(b, dtype=float).reshape(s)
    return reference_ekf(CoopModel(), arr(y_bytes, shape), arr(x0, (6,)), arr(P0, (6, 6)),
                         arr(Q, (6, 6)), arr(R, (5, 5)), mistake)


def _ref(y, x0, P0, Q, R, mistake=None):
    c = [np.ascontiguousarray(a, dtype=float) for a in (y, x0, P0, Q, R)]
    return _reference(c[0].tobytes(), c[0].shape, mistake, *(a.tobytes() for a in c[1:]))


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
        report.add("return-value", f"ekf must return a pair (x_hat, P); it returned a "
                   f"{type(out).__name__}.")
        return report
    x = array(report, "x_hat", out[0], (n, 6))
    P = array(report, "P", out[1], (n, 6, 6))
    if x is None or P is None:
        return report
    x_ref, P_ref = _ref(y, x0, P0, Q, R)
    dx, dP, first = _distances(x, P, x_ref, P_ref)
    report.details.update({"dx_sigma": dx, "dP_sigma2": dP})
    if first < 0:
        report.add("matches-reference", f"x̂ and P match the course EKF on {label} to "
                   f"{EKF_TOL:g} σ (largest distances {dx:.2g} σ, {dP:.2g} σσ).", "note")
        return report
    for code, what in EKF_MISTAKES.items():
        xm, Pm = _ref(y, x0, P0, Q, R, code)
        if _distances(x, P, xm, Pm)[2] < 0:
            report.add(code, f"Your EKF matches the course EKF with one mistake: {what}. "
                       + _EKF_HINTS[code])
            return report
    t = model.t
    report.add("ekf-mismatch", f"Your EKF differs from the course EKF from t = {t[first]:g} s "
               f"(step {first}) on: x̂ by up to {dx:.3g} σ, P by up to {dP:.3g} σσ, and matches "
               f"none of the typical mistakes ({', '.join(EKF_MISTAKES)}). "
               + ("Row 0 must be (x0, P0): nothing is measured at t = 0. " if first == 0 else "")
               + "Check the prediction (x̄ = model.step(x̂), M = F P Fᵀ + Q with "
               "F = I + ΔT·A(x̂)) and the update (H = C(x̄), only the rows of y that are not NaN).")
    return report


_EKF_HINTS = {
    "innovation-not-wrapped": "The course log's bearings jump between −π and π: an unwrapped "
    "residual of almost 2π then drags the estimate away. Wrap the bearing rows (0 and 2) of "
    "y − h(x̄) with (r + π) % 2π − π.",
    "euler-prediction": "Predict the state with the exact solution over ΔT (model.step(x)); the "
    "Euler step is only the linearization used for F.",
    "jacobian-at-previous": "The measurement Jacobian belongs to the point the measurement is "
    "predicted from: H = C(x̄ₖ) after the prediction.",
    "returns-a-priori": "Store x̂ and P after the update at each step.",
}

