r"""Homework checks for any linear model: the student's model matrices, named with the catalogue.

A question "build Φ, Γ, Q, H, V, M0 for this system" has one answer, the
:class:`~gpsaccel.kalman.epochs.LinearModel`'s (Q = Γ W Γᵀ per propagation step).  A wrong matrix
is explained, where it can be, by the mistakes of the system's catalogue
(:class:`~gpsaccel.kalman.epochs.LinearCatalogue`: Φᵀ for Φ, Q without Γ, σ for σ² in V, W or
M0, a permuted M0), alone or two together: each ingredient mistake is applied to the model's
ingredients and the matrix it gives compared with the student's.  So the homework's codes are
the checker's (``phi-transposed``, ``q-without-gamma``, ``std-as-variance``, ``m0-order``); a
wrong matrix no mistake explains is ``matrix-value``, with the elements that differ named (never
the value they should have).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from gpsaccel.assignments._answers import array
from gpsaccel.check.findings import mistake_finding
from gpsaccel.check.report import Report
from gpsaccel.kalman.linear_catalogue import LinearCatalogue
from gpsaccel.kalman.linear_model import LinearIngredients, LinearModel
from gpsaccel.kalman.mistakes import Mistake, combinations, with_changes

#: The matrices the question asks for, in the order it lists them (a question may ask for W
#: instead of Q, or for both: :func:`matrices_answer`'s ``names``).
MATRICES = ("Phi", "Gamma", "Q", "H", "V", "M0")

#: Relative tolerance of an element (students type numbers such as 0.0025 by hand).
RTOL = 1e-6

#: The ingredients a matrix question can show a mistake in (the catalogue's other entries are
#: about the recursion: skipped updates, the number of steps, what is returned).
_INGREDIENTS = frozenset({"Phi", "Gamma", "W", "V", "M0"})

_SUB = str.maketrans("0123456789", "₀₁₂₃₄₅₆₇₈₉")
_SYMBOL = {"Phi": "Φ", "Gamma": "Γ"}


def shapes(model: LinearModel) -> dict[str, tuple[int, int]]:
    """Name -> shape of each matrix of :data:`MATRICES` (and ``W``) for ``model``."""
    n, m, p = model.n, model.Gamma.shape[1], model.H.shape[0]
    return {"Phi": (n, n), "Gamma": (n, m), "Q": (n, n), "H": (p, n), "V": (p, p), "M0": (n, n),
            "W": (m, m)}


def matrices(g: LinearIngredients) -> dict[str, np.ndarray]:
    """The matrices of :data:`MATRICES` (and ``W``) a filter with ingredients ``g`` uses
    (Q = Γ W Γᵀ)."""
    return {"Phi": g.Phi, "Gamma": g.Gamma, "Q": g.Gamma @ g.W @ g.Gamma.T, "H": g.H, "V": g.V,
            "M0": g.M0, "W": g.W}


def _close(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    scale = max(float(np.abs(b).max()), 1e-300)
    return np.isclose(a, b, rtol=RTOL, atol=RTOL * 1e-6 * scale)


def _elem(name: str, idx: tuple[int, ...]) -> str:
    """Course notation, 1-based: Φ₁₂, V₁₁."""
    return _SYMBOL.get(name, name) + "".join(str(i + 1) for i in idx).translate(_SUB)


def compare(report: Report, name: str, given: np.ndarray, expected: np.ndarray, *,
            part: str = "", code: str = "value", advice: str = "", rtol: float = RTOL,
            reference: str = "the reference") -> bool:
    """Whether the student's array ``given`` (named ``name``) is ``expected`` to ``rtol``
    relative (of its largest element); if not, a finding ``code`` of ``part`` names the elements
    that differ in course notation (Φ₁₂, V₁₁) and how many, never the value they should have
    (``expected`` is the instructor's only), then ``advice``; ``reference`` says what it was
    compared with.  A ``given`` of another shape, or not numbers, is a finding ``shape`` or
    ``not-a-matrix`` of ``part`` (the student's; the shape asked for is the question's).

    Examples
    --------
    >>> report = Report("q")
    >>> compare(report, "F", np.array([[1.0, 0.2], [0.0, 1.0]]), np.array([[1.0, 0.1], [0, 1]]))
    False
    >>> print(report.findings[0].for_student().message)
    F: F₁₂ differs from the reference (wrong at 1 of 4 elements).
    """
    expected = np.asarray(expected, dtype=float)
    found = Report(report.subject)
    array_ = array(found, name, given, expected.shape)
    report.findings += found.tag(part).findings if part else found.findings
    if array_ is None:
        return False
    given = array_
    scale = max(float(np.abs(expected).max(initial=0.0)), 1e-300)
    ok = np.isclose(given, expected, rtol=rtol, atol=rtol * 1e-6 * scale)
    if ok.all():
        return True
    bad = [_elem(name, tuple(int(i) for i in idx)) for idx in np.argwhere(~ok)]
    verb = "differs" if len(bad) == 1 else "differ"
    report.add(code, text="{where}: {elements} {verb} from {reference} (wrong at {n_bad} of "
               "{n} elements)." + (" {advice}" if advice else ""), where=name, part=part,
               observed={"elements": ", ".join(bad[:6]) + (" ..." if len(bad) > 6 else ""),
                         "verb": verb, "n_bad": len(bad), "n": ok.size, "advice": advice,
                         "reference": reference},
               expected={name: expected})
    return False


def explanations(model: LinearModel, name: str, given: np.ndarray, max_combined: int = 2
                 ) -> tuple[Mistake, ...]:
    """The fewest catalogue mistakes (up to ``max_combined``, touching different ingredients)
    that turn the model's matrix ``name`` into ``given``; () when none does."""
    correct = LinearIngredients.correct(model)
    right = matrices(correct)[name]
    mistakes = [m for m in LinearCatalogue(model).covariance_mistakes()
                if {c[0] for c in m.changes} <= _INGREDIENTS]
    for size in range(1, max_combined + 1):
        for combo in combinations(mistakes, size):
            g = correct
            for m in combo:
                g = with_changes(g, m.changes)
            made = matrices(g)[name]
            if made.shape != right.shape:
                continue  # the mistake changes its shape (Q without Γ makes W n×n)
            if not _close(made, right).all() and _close(given, made).all():
                return combo
    return ()


def matrices_answer(model: LinearModel, given: Mapping[str, object],
                    title: str = "model matrices", names: Sequence[str] = MATRICES) -> Report:
    """Check the student's matrices ``names`` (of :data:`MATRICES` and ``W``; name -> value in
    ``given``) against ``model``; never raises.  Every finding names its matrix as its part
    (:class:`~gpsaccel.assignments.questions.Question`'s partial credit).

    Examples
    --------
    ::

        report = matrices_answer(model, {"Phi": Phi, "Gamma": Gamma, "Q": Q, "H": H, "V": V,
                                         "M0": M0})
        print(report)   # e.g. "std-as-variance: V: A standard deviation is used where ..."
    """
    unknown = sorted(set(names) - set(MATRICES) - {"W"})
    if unknown:
        raise ValueError(f"names must be among {', '.join(MATRICES)}, W; got {unknown}")
    report = Report(title)
    want = shapes(model)
    arrays = {}
    for k in names:
        found = Report(title)
        arrays[k] = array(found, k, given.get(k), want[k])
        report.findings += found.tag(k).findings
    right = matrices(LinearIngredients.correct(model))
    for k in names:
        a = arrays[k]
        if a is None:
            continue
        ok = _close(a, right[k])
        if ok.all():
            continue
        combo = explanations(model, k, a)
        if combo:
            for m in combo:
                mistake_finding(report, m, f"{k}: ", where=k, part=k)
            continue
        compare(report, k, a, right[k], part=k, code="matrix-value", reference="the model's",
                advice="Check it against the model's equations and your variant's numbers.")
    if report.passed:
        report.add("ok", severity="note", text="{names} are the model's (to {rtol:g} "
                   "relative).", observed={"names": ", ".join(names), "rtol": RTOL})
    report.sort()
    return report
