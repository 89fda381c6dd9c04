r"""Check a student's DT linearization of the cooperative-localization model (report 002, part 1).

:func:`dt_model` checks the DT perturbation model F = I + ΔT·A, G = ΔT·B, H = C (and, if given,
the process noise Ω / Q of the course: Qtrue is already the covariance per DT step, so Ω = I).
A is nilpotent here (A² = 0), so the exact e^{ΔT·A} equals I + ΔT·A and passes too.  F, G, H
given as functions are checked at the states of :func:`gpsaccel.check.jacobians.check_states`,
as matrices at one state; a recognised slip (F = A, F = ΔT·A, F = I + A, G = B, H = ΔT·C) is named,
anything else is located element by element as the Jacobians' findings are
(:mod:`gpsaccel.check.jacobians`).  Codes: ``dt-linearization``, ``omega-dt-gamma``;
``not-a-matrix``, ``shape`` and those of the Jacobians for what cannot be checked.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from gpsaccel.check.jacobians import (
    ARGS,
    FORMULAS,
    RTOL,
    analytic,
    check_states,
    close,
    matrix_finding,
    state_inputs,
    student_matrices,
)
from gpsaccel.check.report import Report, as_array
from gpsaccel.coop.model import CoopModel, wrap_state


def _dt_value(report: Report, name: str, value: object, X: np.ndarray, U: np.ndarray,
              shape: tuple[int, int]) -> np.ndarray | None:
    """The student's F, G or H at every state: a callable is evaluated, an array is taken as the
    value at the first state (X has one state then)."""
    base = {"F": "A", "G": "B", "H": "C"}[name]
    if callable(value):
        return student_matrices(report, base, value, X, U, display=name)
    arr = as_array(report, name, value, shape, _VALUE,
                   signature=ARGS[base].replace(base, name, 1))
    return None if arr is None else arr[None]


#: The wording of a value's findings where a function may stand (:func:`as_array`).
_VALUE = {
    "not-a-matrix": "{name} must be an array of numbers (or a function {signature}); "
                    "np.array({name}, dtype=float) fails: {error}",
    "shape": "{name} has shape {shape}; it must be {want_x}.",
}


def dt_model(F: object = None, G: object = None, H: object = None, Omega: object = None,
             Q: object = None, x: object = None, u: object = None,
             model: CoopModel | None = None, n_random: int = 20, seed: int = 0,
             rtol: float = RTOL) -> Report:
    """Check the student's DT linearization F = I + ΔT·A, G = ΔT·B, H = C (report 002, part 1).

    Parameters
    ----------
    F, G, H : each either a callable (F(x, u) → 6x6, G(x, u) → 6x4, H(x) → 5x6, checked at the
        same states as :func:`jacobians`) or a matrix, checked at the state ``x`` and input ``u``.
    Omega : the process-noise input matrix Ω of x_{k+1} = F x_k + G u_k + Ω w_k (6x6), if the
        student forms one; with the course's per-step Qtrue it is the identity.
    Q : the DT process-noise covariance the student's filter adds per step (6x6): Qtrue for the
        truth model (any Q is allowed in a filter; only Q = ΔT·Qtrue or ΔT²·Qtrue is flagged).
    x, u : state (6,) and input (4,) for matrix-valued F, G, H (default the nominal x0, u0).
    model, n_random, seed, rtol : as in :func:`jacobians`.
    """
    t0 = time.perf_counter()
    model = CoopModel() if model is None else model
    if F is None and G is None and H is None and Omega is None and Q is None:
        raise ValueError("pass at least one of F, G, H, Omega, Q")
    X, U, labels = _dt_states(model, (F, G, H), x, u, n_random, seed)
    report = Report("DT linearization F, G, H")
    report.details.update({"n_states": len(X), "rtol": rtol, "dt": model.dt})
    for name, value in (("F", F), ("G", G), ("H", H)):
        if value is not None:
            _check_dt_matrix(report, name, value, X, U, labels, model, rtol)
    _check_noise(report, Omega, Q, model, rtol)
    if report.passed:
        given = [DT_RIGHT[k] for k, v in (("F", F), ("G", G), ("H", H), ("Omega", Omega),
                                          ("Q", Q)) if v is not None]
        where = f"at all {len(X)} states" if len(X) > 1 else "at the given state"
        report.add("dt-model-right", severity="note", text="{names} {where} (ΔT = {dt:g} s), "
                   "to {rtol:g} relative.", observed={"names": ", ".join(given), "where": where,
                                                      "dt": model.dt, "rtol": rtol})
    report.sort()
    report.seconds = time.perf_counter() - t0
    return report


#: What each DT matrix is, as the note of a right DT model says it.
DT_RIGHT = {"F": "F = I + ΔT·A", "G": "G = ΔT·B", "H": "H = C", "Omega": "Ω = I",
            "Q": "Q not scaled by ΔT"}


@dataclass(frozen=True)
class _DTForm:
    """One DT matrix: the Jacobian it is built from, its right form, the slips recognised (a
    wrong form, what the student reads of it — what their matrix does, after "Your " — and what
    the instructor reads, the right form too), the formulas element by element and the
    instructor's hint of an element finding.  ``{dt}`` in the texts is ΔT."""

    jacobian: str
    shape: tuple[int, int]
    right: Callable[[np.ndarray, float], np.ndarray]
    slips: tuple[tuple[Callable[[np.ndarray, float], np.ndarray], str, str], ...]
    formulas: Callable[[], dict[tuple[int, int], str]]
    hint: str


DT_FORMS = {
    "F": _DTForm("A", (6, 6), lambda J, dt: np.eye(6) + dt * J, (
        (lambda J, dt: J, "F = A, the continuous-time Jacobian of the derivative ẋ, not a step",
         "F = A, the continuous-time Jacobian; the DT transition is F = I + ΔT·A (ΔT = {dt:g} "
         "s)"),
        (lambda J, dt: dt * J, "F = ΔT·A: it maps δx_k to the change of δx over the step, not "
                               "to δx_(k+1)",
         "F = ΔT·A: the identity is missing; F = I + ΔT·A"),
        (lambda J, dt: np.eye(6) + J, "F = I + A: a step of 1 s, where the step is ΔT = {dt:g} s",
         "F = I + A: ΔT = {dt:g} s is missing; F = I + ΔT·A")),
        lambda: {(i, i): "1" for i in range(6)} | {k: f"ΔT·({v})"
                                                   for k, v in FORMULAS["A"].items()},
        "F = I + ΔT·A with ΔT = {dt:g} s."),
    "G": _DTForm("B", (6, 4), lambda J, dt: dt * J, (
        (lambda J, dt: J, "G = B, the continuous-time ∂f/∂u of the derivative ẋ, not a step",
         "G = B, the continuous-time ∂f/∂u; the DT input matrix is G = ΔT·B (ΔT = {dt:g} s)"),),
        lambda: {k: f"ΔT·{v}" for k, v in FORMULAS["B"].items()},
        "G = ΔT·B with ΔT = {dt:g} s."),
    "H": _DTForm("C", (5, 6), lambda J, dt: J, (
        (lambda J, dt: dt * J, "H = ΔT·C: a measurement is taken at an instant, not over a step",
         "H = ΔT·C; the measurement is taken at an instant, so H = C (no ΔT)"),),
        lambda: dict(FORMULAS["C"]), "H = C = ∂h/∂x."),
}


def _dt_states(model: CoopModel, matrices: tuple[object, ...], x: object, u: object,
               n_random: int, seed: int) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """The states (and inputs) the DT model is checked at: those of :func:`jacobians` when every
    matrix given is a function, else the one state ``x`` (default the nominal x0, u0)."""
    if all(callable(v) or v is None for v in matrices):
        X, labels = check_states(model, n_random, seed)
        return X, state_inputs(model, len(X), seed), labels
    xs = model.x0 if x is None else np.asarray(x, dtype=float)
    us = model.u0 if u is None else np.asarray(u, dtype=float)
    if xs.shape != (6,) or us.shape != (4,) or not (np.isfinite(xs).all()
                                                     and np.isfinite(us).all()):
        raise ValueError(f"x must be a finite state (6,) and u a finite input (4,), got "
                         f"shapes {xs.shape} and {us.shape}")
    return wrap_state(xs)[None], us[None], [f"x = {np.round(xs, 4).tolist()}"]


def _check_dt_matrix(report: Report, name: str, value: object, X: np.ndarray, U: np.ndarray,
                     labels: list[str], model: CoopModel, rtol: float) -> None:
    """The student's F, G or H against its right form (:data:`DT_FORMS`): a slip recognised is
    named, anything else is located element by element."""
    form, dt = DT_FORMS[name], model.dt
    got = _dt_value(report, name, value, X, U, form.shape)
    if got is None:
        return
    if len(got) == 1 and len(X) > 1:
        got = np.broadcast_to(got, (len(X),) + form.shape)
    J = analytic(form.jacobian, X, U, model)
    want = form.right(J, dt)
    if close(got, want, rtol):
        return
    for slip, said, detail in form.slips:
        if close(got, slip(J, dt), rtol):
            # the student reads what their matrix is, never the right form (the instructor does)
            report.add("dt-linearization", f"Your {detail.format(dt=dt)}.", text="Your {what}.",
                       where=name, part=name, observed={"what": said.format(dt=dt)})
            return
    matrix_finding(report, "dt-linearization", name, got, want, X, labels, rtol,
                    formulas=form.formulas(), unit_hint=form.hint.format(dt=dt))


def _matrix(report: Report, name: str, value: object, n: int) -> np.ndarray | None:
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        report.add("not-a-matrix", text="{where} must be an array of numbers; {error}",
                   where=name, observed={"error": str(exc)})
        return None
    if arr.shape != (n, n) or not np.isfinite(arr).all():
        report.add("shape", text="{where} must be a finite {n} x {n} matrix, got shape {shape}.",
                   where=name, observed={"n": n, "shape": arr.shape})
        return None
    return arr


def _check_noise(report: Report, Omega: object, Q: object, model: CoopModel, rtol: float) -> None:
    dt, Qt = model.dt, model.Qtrue
    if Omega is not None:
        Om = _matrix(report, "Omega", Omega, 6)
        if Om is not None and not close(Om[None], np.eye(6)[None], rtol):
            if close(Om[None], dt * np.eye(6)[None], rtol):
                report.add("omega-dt-gamma", "x_(k+1) = F x_k + G u_k + w_k, w_k ~ N(0, "
                           "Qtrue): Ω = I", text="Your Ω = ΔT·Γ = {dt:g}·I: the course's Qtrue "
                           "is already the covariance of the noise w_k added per DT step. Ω = "
                           "ΔT·Γ belongs to a continuous-time noise intensity; here it shrinks "
                           "Q by ΔT² = {dt2:g}.", where="Ω", observed={"dt": dt, "dt2": dt**2},
                           expected={"Ω": "I"})
            else:
                report.add("omega-dt-gamma", text="Your Ω is wrong (the course's Qtrue is the "
                           "per-step DT covariance); yours has diagonal {diag}.", where="Ω",
                           observed={"diag": np.round(np.diag(Om), 6).tolist()},
                           expected={"Ω": "I"})
    if Q is not None:
        Qs = _matrix(report, "Q", Q, 6)
        if Qs is None:
            return
        for scale, what in ((dt, "ΔT·Qtrue"), (dt**2, "ΔT²·Qtrue = Ω Qtrue Ωᵀ with Ω = ΔT·I")):
            if close(Qs[None], scale * Qt[None], rtol):
                report.add("omega-dt-gamma", "The filter's Q is Qtrue, not scaled by ΔT.",
                           text="Your Q = {what}: the course's Qtrue is already the covariance "
                           "of the process noise per DT step of {dt:g} s; yours scales it once "
                           "more.", where="Q", observed={"what": what, "dt": dt})
                return


def assert_dt_model(**kwargs: Any) -> Report:
    """:func:`dt_model` for a grader cell: raise AssertionError with the findings if it fails."""
    report = dt_model(**kwargs)
    if not report.passed:
        raise AssertionError("\n" + str(report))
    return report
