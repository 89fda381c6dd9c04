r"""Check a student's cooperative-localization Jacobians A, B, C (report 002).

The model (state x = [ξg, ηg, θg, ξa, ηa, θa], input u = [vg, φg, va, ωa], wheelbase L)::

    A = ∂f/∂x:  A₁₃ = −vg sin θg   A₂₃ = vg cos θg   A₄₆ = −va sin θa   A₅₆ = va cos θa
    B = ∂f/∂u:  B₁₁ = cos θg  B₂₁ = sin θg  B₃₁ = tan φg / L  B₃₂ = vg / (L cos² φg)
                B₄₃ = cos θa  B₅₃ = sin θa  B₆₄ = 1
    C = ∂h/∂x, with Δξ = ξa − ξg, Δη = ηa − ηg, ρ² = Δξ² + Δη²:
        bearing rows 1 and 3 (both relative to a heading):  ∂/∂ξg = Δη/ρ²  ∂/∂ηg = −Δξ/ρ²
            ∂/∂ξa = −Δη/ρ²  ∂/∂ηa = Δξ/ρ²;  C₁₃ = ∂γag/∂θg = −1,  C₃₆ = ∂γga/∂θa = −1
        range row 2: ∂ρ/∂ξg = −Δξ/ρ  ∂ρ/∂ηg = −Δη/ρ  ∂ρ/∂ξa = Δξ/ρ  ∂ρ/∂ηa = Δη/ρ
        GPS rows 4, 5: C₄₄ = C₅₅ = 1

:func:`jacobians` calls the student's ``A(x, u)``, ``B(x, u)`` and ``C(x)`` at :func:`check_states`:
states along the course's nominal trajectory and random states around it, headings at and near
±π and 0, geometries that put a bearing at ±π (the UAV straight behind the UGV's heading, so the
wrapped measurement jumps there), and near-coincident vehicles (ρ = 1 cm).  An element is right
when it agrees with the analytic value to ``rtol`` relative to the element's own size plus
``rtol`` times the largest element of that matrix at that state (the analytic matrices are exact
to rounding; a central finite difference with a good step is 1e-8 relative away, and passes).

Every wrong element is named in 1-based course notation (A₁₃), with the student's value at the
first state where it differs and, for the recognised mistakes, the likely cause: the student reads
what their element does and what it depends on; the instructor also reads the expected expression,
its value and the derivative that is right (never the student: that is the answer).  Codes:
``jacobian-A``, ``jacobian-B``, ``jacobian-C``; ``not-callable``, ``exception``, ``returns-none``,
``shape``, ``not-finite`` for what cannot be checked.  The DT linearization built from these
Jacobians is checked by :mod:`gpsaccel.check.dt_model`, with the same states and element-by-element
findings.
"""

from __future__ import annotations

import math
import time
import traceback
from collections.abc import Callable
from typing import Any

import numpy as np

from gpsaccel.check.report import Report, as_array
from gpsaccel.coop.model import (
    CoopModel,
    jacobian_A,
    jacobian_B,
    jacobian_C,
)

#: Relative tolerance of an element (see the module docstring).
RTOL = 1e-6

#: The most wrong elements one finding lists (the rest are counted).
MAX_LISTED = 6

_SUB = str.maketrans("0123456789", "₀₁₂₃₄₅₆₇₈₉")

#: The expected expression of every element that is not identically zero.
FORMULAS: dict[str, dict[tuple[int, int], str]] = {
    "A": {(0, 2): "−vg·sin θg", (1, 2): "vg·cos θg", (3, 5): "−va·sin θa", (4, 5): "va·cos θa"},
    "B": {(0, 0): "cos θg", (1, 0): "sin θg", (2, 0): "tan φg / L", (2, 1): "vg / (L·cos² φg)",
          (3, 2): "cos θa", (4, 2): "sin θa", (5, 3): "1"},
    "C": {(0, 0): "Δη/ρ²", (0, 1): "−Δξ/ρ²", (0, 2): "−1", (0, 3): "−Δη/ρ²", (0, 4): "Δξ/ρ²",
          (1, 0): "−Δξ/ρ", (1, 1): "−Δη/ρ", (1, 3): "Δξ/ρ", (1, 4): "Δη/ρ",
          (2, 0): "Δη/ρ²", (2, 1): "−Δξ/ρ²", (2, 3): "−Δη/ρ²", (2, 4): "Δξ/ρ²", (2, 5): "−1",
          (3, 3): "1", (4, 4): "1"},
}
SHAPES = {"A": (6, 6), "B": (6, 4), "C": (5, 6)}
ARGS = {"A": "A(x, u)", "B": "B(x, u)", "C": "C(x)"}


def _elem(name: str, i: int, j: int) -> str:
    return name + f"{i + 1}{j + 1}".translate(_SUB)


# --------------------------------------------------------------------------- the test states
def check_states(model: CoopModel | None = None, n_random: int = 60, seed: int = 0
                ) -> tuple[np.ndarray, list[str]]:
    """States (n, 6) the Jacobians are checked at, and a label for each.

    Every 50th step of the nominal trajectory; ``n_random`` states drawn around it (positions
    ±200 m, headings uniform on [−π, π)); headings θg, θa at −π, −π + 1e-7, 0, π − 1e-7 (with the
    other vehicle placed so the UGV's bearing to the UAV is exactly ±π, the wrap's jump, and just
    either side of it); the UAV 1 cm from the UGV.
    """
    model = CoopModel() if model is None else model
    rng = np.random.default_rng(seed)
    states, labels = [], []
    nominal = model.nominal()
    for k in range(0, model.n_steps + 1, 50):
        states.append(nominal[k])
        labels.append(f"nominal, t = {model.t[k]:g} s")
    for i in range(n_random):
        x = np.empty(6)
        x[[0, 1, 3, 4]] = rng.uniform(-200, 200, 4)
        x[[2, 5]] = rng.uniform(-math.pi, math.pi, 2)
        states.append(x)
        labels.append(f"random state {i}")
    for th in (-math.pi, -math.pi + 1e-7, 0.0, math.pi - 1e-7):
        for eps in (0.0, 1e-7, -1e-7):
            # UAV 50 m straight behind the UGV (bearing atan2 − θg = ±π) ...
            x = np.array([10.0, -5.0, th, 10.0 - 50 * math.cos(th) + eps,
                          -5.0 - 50 * math.sin(th) + eps, th])
            states.append(x)
            labels.append(f"θg = θa = {th:.7g} rad, UAV behind the UGV (bearing ≈ ±π)")
    # ... and the UGV straight behind the UAV's heading (the second bearing at ±π)
    states.append(np.array([-30.0, 0.0, 0.3, 0.0, 0.0, 0.0]))
    labels.append("UAV heading east, UGV straight behind it (γga = ±π)")
    states.append(np.array([3.0, 4.0, 1.0, 3.0 + 0.006, 4.0 + 0.008, -2.0]))
    labels.append("vehicles 1 cm apart")
    return np.array(states), labels


def state_inputs(model: CoopModel, n: int, seed: int) -> np.ndarray:
    """u for each of ``n`` states of :func:`check_states` (the same ``seed``): u0 for the first,
    then inputs drawn around it (so no element is compared only at one value of vg, φg, va).
    Public: the DT model's check and the homework's question 1 call the student at these too."""
    rng = np.random.default_rng(seed + 1)
    u = np.broadcast_to(model.u0, (n, 4)).copy()
    u[1::2] *= rng.uniform(0.5, 1.5, (len(u[1::2]), 4))
    return u


# --------------------------------------------------------------------------- calling the student
def _call(report: Report, name: str, fn: Callable[..., object], args: tuple, shape: tuple[int, int],
          what: str) -> np.ndarray | None:
    """fn(*args) as a float array of ``shape``, or None with a finding."""
    x = np.array(args[0], dtype=float)  # the state asked about, before the student's code runs
    try:
        out = fn(*args)
    except Exception as exc:  # noqa: BLE001 - the student's function may raise anything
        tb = "".join(traceback.format_exception_only(type(exc), exc)).strip()
        report.add("exception", text="{where} raised {error} at x = {x}.", where=what,
                   observed={"error": tb, "x": np.round(args[0], 4).tolist()})
        return None
    if out is None:  # a body still `...` or a missing return: say so, not "shape ()"
        report.add("returns-none", text="{where} returned None: end it with a return "
                   "statement.", where=what)
        return None
    near = np.hypot(x[3] - x[0], x[4] - x[1]) < 0.1
    return as_array(report, what, out, shape, _RETURNED, x=np.round(x, 6).tolist(),
                    near=_NEAR if near else "")


#: The wording of a returned value's findings (:func:`gpsaccel.check.report.as_array`).
_RETURNED = {
    "not-a-matrix": "{name} returned a {type}; np.array(..., dtype=float) fails: {error}",
    "shape": "{name} returned shape {shape}; it must be {want_x}{transposed}.",
    "not-finite": "{name} contains NaN or inf at x = {x}{near}.",
}
_NEAR = " (the vehicles are 1 cm apart there: ρ² is small but not zero)"


def student_matrices(report: Report, name: str, fn: object, X: np.ndarray, U: np.ndarray,
              display: str | None = None) -> np.ndarray | None:
    display = display or name
    if not callable(fn):
        report.add("not-callable", text="{where} must be a function {signature} returning the "
                   "matrix at a state; got a {type}. (To check matrices at one state, use "
                   "check.dt_model.)", where=display, observed={
                       "signature": ARGS[name].replace(name, display, 1),
                       "type": type(fn).__name__})
        return None
    shape = SHAPES[name]
    out = np.empty((len(X),) + shape)
    for i, (x, u) in enumerate(zip(X, U, strict=True)):
        args = (x.copy(),) if name == "C" else (x.copy(), u.copy())
        what = f"{display}({'x' if name == 'C' else 'x, u'})"
        got = _call(report, name, fn, args, shape, what)
        if got is None:
            return None
        out[i] = got
    return out


def analytic(name: str, X: np.ndarray, U: np.ndarray, model: CoopModel) -> np.ndarray:
    if name == "A":
        return np.stack([jacobian_A(x, u) for x, u in zip(X, U, strict=True)])
    if name == "B":
        return np.stack([jacobian_B(x, u, model.L) for x, u in zip(X, U, strict=True)])
    return jacobian_C(X)


# --------------------------------------------------------------------------- comparing
def _bad(actual: np.ndarray, expected: np.ndarray, rtol: float) -> np.ndarray:
    """(n, r, c) bool: elements that differ beyond the tolerance."""
    scale = np.abs(expected).max(axis=(1, 2), keepdims=True)
    return np.abs(actual - expected) > rtol * (np.abs(expected) + scale)


def close(a: np.ndarray, b: np.ndarray, rtol: float) -> bool:
    return not _bad(a, b, rtol).any()


#: A likely cause as the student reads it and as the instructor does: the student's says what
#: their element does and what the element depends on, never a derivative's value (that is the
#: answer); the instructor's may state it.
Cause = tuple[str, str]

_HEADING = "the bearing is measured relative to the vehicle's heading, γ = atan2(Δη, Δξ) − θ"
_ATAN2 = ("differentiate atan2(Δη, Δξ) through Δξ = ξa − ξg and Δη = ηa − ηg (chain rule), for "
          "the UGV's coordinates and the UAV's alike")


def _element_cause(name: str, idx: tuple[int, int], a: np.ndarray, e: np.ndarray,
                   labels_bad: list[str], rtol: float) -> Cause:
    """The likely cause of element ``idx`` being wrong, from its values over all states:
    (the student's words, the instructor's); ("", "") when none is recognised."""
    i, j = idx
    tol = rtol * (np.abs(e) + np.abs(e).max() + 1e-300)
    if np.all(np.abs(a + e) <= tol) and np.abs(e).max() > 0:
        if name == "C" and j in (2, 5):
            return (f"the sign is wrong: {_HEADING}; how does γ change when θ grows?",
                    f"the sign is wrong: {_HEADING}, so ∂γ/∂θ = −1")
        if name == "C" and i in (0, 2):
            return (f"the sign is wrong: {_ATAN2}",
                    "a sign error in ∂atan2: ∂atan2(Δη, Δξ)/∂Δξ = −Δη/ρ² and ∂/∂Δη = Δξ/ρ², "
                    "and Δξ = ξa − ξg enters with − for the UGV's own position")
        if name == "C" and i == 1:
            return ("the sign is wrong: ρ depends on the two positions through "
                    "Δξ = ξa − ξg and Δη = ηa − ηg (chain rule)",
                    "the sign is wrong: ρ grows with ξa − ξg, so ∂ρ/∂ξa = +Δξ/ρ and ∂ρ/∂ξg = "
                    "−Δξ/ρ")
        return ("the sign is wrong: check the sign of each derivative that makes it (a cos or "
                "a sin differentiated, a difference taken the other way round)",
                "the sign is wrong (∂cos θ/∂θ = −sin θ, ∂sin θ/∂θ = cos θ)")
    if np.all(np.abs(a) <= tol):
        if name == "C" and j in (2, 5):
            return (f"it is missing (zero at every state): {_HEADING}, so it depends on θ",
                    f"it is missing (zero): {_HEADING}, so ∂γ/∂θ = −1")
        return "it is missing (zero at every state)", "it is missing (zero)"
    if name == "B" and idx == (2, 1):
        return ("it is the derivative of θ̇g = vg tan φg / L with respect to the steering angle "
                "φg: it depends on vg, L and φg, through the derivative of tan φg",
                "∂(vg tan φg / L)/∂φg = vg / (L cos² φg) = vg sec² φg / L (the derivative of "
                "tan is sec²)")
    if all("±π" in s or "1 cm" in s for s in labels_bad):
        said = ("it is right elsewhere and wrong only where a bearing is at ±π or the vehicles "
                "nearly coincide: a numerical derivative through the wrapped h (or a step too "
                "large for ρ = 1 cm) — differentiate the formula, not the wrapped measurement")
        return said, said
    return "", ""


def matrix_finding(report: Report, code: str, name: str, actual: np.ndarray,
                    expected: np.ndarray, X: np.ndarray, labels: list[str], rtol: float,
                    display: str | None = None, formulas: dict | None = None,
                    unit_hint: str = "") -> bool:
    """A finding for every wrong element of ``name`` (over all states); True when all right."""
    bad = _bad(actual, expected, rtol)
    if not bad.any():
        return True
    display = display or name
    formulas = FORMULAS.get(name, {}) if formulas is None else formulas
    elems = [(int(i), int(j)) for i, j in np.argwhere(bad.any(axis=0))]
    per_state = bad.reshape(len(X), -1).sum(axis=1)
    s = int(np.argmax(per_state))  # the state where most elements are wrong: show values there
    groups: dict[str, list[str]] = {}
    mine: dict[str, list[str]] = {}
    right: dict[str, str] = {}
    for idx in elems[:MAX_LISTED]:
        states = np.flatnonzero(bad[:, idx[0], idx[1]])
        k = s if bad[s][idx] else int(states[0])
        said, cause = _element_cause(name, idx, actual[:, idx[0], idx[1]],
                                     expected[:, idx[0], idx[1]], [labels[j] for j in states],
                                     rtol)
        where = "" if k == s else f" at {labels[k]}"
        formula, value = formulas.get(idx, "0"), f"{expected[k][idx]:.6g}"
        want = value if formula.replace("−", "-") == value else f"{formula} = {value}"
        groups.setdefault(cause, []).append(
            f"{_elem(display, *idx)} = {actual[k][idx]:.6g}, should be {want}{where} (wrong at "
            f"{states.size} of {len(X)} states)")
        mine.setdefault(said, []).append(  # the student's value and where: no reference
            f"{_elem(display, *idx)} = {actual[k][idx]:.6g}{where} is wrong (at {states.size} "
            f"of {len(X)} states)")
        right[f"{_elem(display, *idx)}{where}"] = want
    head = f"At {labels[s]} (x = {np.round(X[s], 4).tolist()}):"
    more = len(elems) - MAX_LISTED
    tail = [f"And {more} more elements."] if more > 0 else []

    def text(items_by_cause: dict[str, list[str]], hint: str = "") -> str:
        return " ".join([head] + ["; ".join(items) + (f". Likely cause: {c}." if c else ".")
                                  for c, items in items_by_cause.items()] + tail
                        + ([hint] if hint else []))

    # the unit hint states the right form (F = I + ΔT·A): the instructor's only
    report.add(code, text(groups, unit_hint), text="{said}", where=display, part=display,
               observed={"said": text(mine)}, expected=right)
    return False


#: A whole Jacobian built for a DT step (name, what it is -> the student's words, the
#: instructor's): the student reads what their matrix holds, never the DT form it would be right
#: for (question 2 of the coop homework asks for that form).
_WHOLE = {
    ("A", "I + ΔT·A"): ("Your A is the identity plus ΔT = {dt:g} s times a Jacobian: A is the "
                        "continuous-time Jacobian ∂f/∂x of ẋ = f(x, u), with neither.",
                        "A given as the DT transition F = I + ΔT·A."),
    ("A", "ΔT·A"): ("Your A is multiplied by ΔT = {dt:g} s: A is the continuous-time Jacobian "
                    "∂f/∂x of ẋ = f(x, u), with no step in it.", "A given as ΔT·A."),
    ("B", "ΔT·B"): ("Your B is multiplied by ΔT = {dt:g} s: B is the continuous-time Jacobian "
                    "∂f/∂u of ẋ = f(x, u), with no step in it.",
                    "B given as the DT input matrix G = ΔT·B."),
}


def _whole_matrix_causes(report: Report, name: str, actual: np.ndarray, expected: np.ndarray,
                         model: CoopModel, rtol: float) -> bool:
    """Recognise a whole-matrix mistake (a Jacobian built for a DT step: :data:`_WHOLE`); True
    if found."""
    dt = model.dt
    for (matrix, form), (said, detail) in _WHOLE.items():
        if matrix != name:
            continue
        built = dt * expected + (np.eye(6) if form.startswith("I") else 0.0)
        if close(actual, built, rtol):
            report.add(f"jacobian-{name}", detail, text=said, where=name, observed={"dt": dt})
            return True
    return False


def jacobians(A: Callable | None = None, B: Callable | None = None, C: Callable | None = None,
              model: CoopModel | None = None, n_random: int = 60, seed: int = 0,
              rtol: float = RTOL) -> Report:
    """Check the student's Jacobian functions of the cooperative-localization model.

    Parameters
    ----------
    A : callable A(x, u) → (6, 6) ∂f/∂x at state x (6,) [ξg (m), ηg (m), θg (rad), ξa, ηa, θa]
        and input u (4,) [vg (m/s), φg (rad), va (m/s), ωa (rad/s)].
    B : callable B(x, u) → (6, 4) ∂f/∂u.
    C : callable C(x) → (5, 6) ∂h/∂x.
    model : the problem (report 002's defaults when None): L, the nominal trajectory, u0.
    n_random : random states beyond the fixed ones (:func:`check_states`).
    seed : seed of the random states and inputs.
    rtol : relative tolerance per element (module docstring).

    Any left as None is not checked.  Returns a :class:`~gpsaccel.check.report.Report`; nothing the
    student's functions do raises here.
    """
    t0 = time.perf_counter()
    model = CoopModel() if model is None else model
    X, labels = check_states(model, n_random, seed)
    U = state_inputs(model, len(X), seed)
    report = Report("Jacobians A, B, C")
    report.details.update({"n_states": len(X), "rtol": rtol})
    checked = []
    for name, fn in (("A", A), ("B", B), ("C", C)):
        if fn is None:
            continue
        checked.append(name)
        mine = Report(name)  # this matrix's findings, its part (partial credit)
        got = student_matrices(mine, name, fn, X, U)
        if got is not None:
            want = analytic(name, X, U, model)
            if not _whole_matrix_causes(mine, name, got, want, model, rtol):
                matrix_finding(mine, f"jacobian-{name}", name, got, want, X, labels, rtol)
        report.findings += mine.tag(name).findings
    if not checked:
        raise ValueError("pass at least one of A, B, C (the student's Jacobian functions)")
    if report.passed:
        report.add("jacobians-right", severity="note", text="{names} agree with the analytic "
                   "Jacobians at all {n} states (headings at ±π, bearings at ±π, vehicles 1 cm "
                   "apart included), to {rtol:g} relative.", observed={
                       "names": ", ".join(checked), "n": len(X), "rtol": rtol})
    report.sort()
    report.seconds = time.perf_counter() - t0
    return report


def assert_jacobians(**kwargs: Any) -> Report:
    """:func:`jacobians` for a grader cell: raise AssertionError with the findings if it fails."""
    report = jacobians(**kwargs)
    if not report.passed:
        raise AssertionError("\n" + str(report))
    return report
