"""The cv2d homework's graded questions: an instructor's own homework, written with
:mod:`gpsaccel.homework` alone (``gpsaccel assignment --example DIR`` writes this folder).

q1 reads the student's model matrices for their own noise levels (their variant) and names a wrong
one with the catalogue of linear-filter mistakes, each matrix a part of its own (partial credit);
q2 grades the file ``kalman_filter.py`` the notebook writes against the problem of
``problems.py``, in a box without gpsaccel; q3 calls the student's ``predict(x, P, Phi, Q)`` on fresh
numbers and grades its two outputs as two parts.  The grader imports this file by path:
``gpsaccel assignment DIR/cv2d`` and ``gpsaccel grade CLASS --assignment DIR/cv2d`` find it
beside ``cv2d.ipynb``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gpsaccel import homework as hw

HERE = Path(__file__).resolve().parent
PROBLEMS = hw.load_module(HERE / "problems.py")
#: The problem of problems.py, registered: q2's filter is checked against it.
PROBLEM = hw.load_problem(HERE / "problems.py", "cv2d")

#: The public notebook's numbers (the problem's): never a student's.
DEFAULT_VARIANT = {"sigma_a": 0.5, "sigma_p": 3.0}

#: The student's noise levels: σ_a (m/s²) 0.20 .. 0.99 and σ_p (m) 1.0 .. 5.9, 80 × 50 = 4000
#: points; a class of 200 shares a variant in about 5 pairs (``variant.shared_pairs(200)``).
variant = hw.Variants({"sigma_a": tuple(round(0.20 + 0.01 * i, 2) for i in range(80)),
                       "sigma_p": tuple(round(1.0 + 0.1 * i, 1) for i in range(50))},
                      DEFAULT_VARIANT)


def variant_model(v: dict) -> hw.LinearModel:
    """The problem with the student's noise levels (q1 and q3 are about it)."""
    return hw.problem_model(PROBLEM, **PROBLEMS.model(0.1, v["sigma_a"], v["sigma_p"]))


# ------------------------------------------------------------------ q3: a function of the student
#: q3's propagation steps: one second between two fixes, ten steps of 0.1 s.
STEPS = 10


def _q3_inputs(draw: hw.Draw) -> tuple[np.ndarray, ...]:
    """predict's arguments: fresh x and P from the question's seed (every student their own), and
    the Φ and Q of the student's model (so q1's mistakes do not cost q3 too)."""
    rng = draw.rng()
    L = rng.normal(size=(4, 4))
    m = variant_model(draw.variant)
    return rng.normal(0.0, 10.0, 4), L @ L.T + 0.1 * np.eye(4), m.Phi, m.Gamma @ m.W @ m.Gamma.T


def _q3_reads(draw: hw.Draw) -> list[hw.Read]:
    return [hw.function("predict", *_q3_inputs(draw), returns=[(4,), (4, 4)])]


def _q3_grade(draw: hw.Draw, answers: list[hw.Answer]) -> hw.Report:
    x, P, Phi, Q = _q3_inputs(draw)
    report = hw.Report("question 3: from one fix to the next")
    predict = hw.replay(_q3_reads(draw), answers, "predict")
    out = hw.call(report, "predict(x, P, Phi, Q)", predict, x, P, Phi, Q)  # failed: all of q3
    if out is None or not report.passed:
        return report
    x_bar, M = out
    want_x, want_M = x, P
    for _ in range(STEPS):                             # x̄ = Φ x̂, M = Φ P Φᵀ + Q at each step
        want_x, want_M = Phi @ want_x, Phi @ want_M @ Phi.T + Q
    hw.compare(report, "x̄", x_bar, want_x, part="x_bar", code="predict-mean",
               advice="Propagate the mean ten times with Φ.")
    Phi_10, M = np.linalg.matrix_power(Phi, STEPS), np.asarray(M, dtype=float)
    if M.shape == P.shape and np.allclose(M, Phi_10 @ P @ Phi_10.T + Q, rtol=1e-6):  # one Q
        report.add("process-noise-interval", text="M adds the process noise of one step only; "
                   "each of the ten steps adds its own.", where="M", part="M")
    else:
        hw.compare(report, "M", M, want_M, part="M", code="predict-covariance",
                   advice="Propagate the covariance ten times with Φ and Q.")
    return report


def graded_questions() -> tuple[hw.Question, ...]:
    """q1 (4 points, a part per matrix; σ where σ² belongs keeps half its matrix's points),
    q2 (4), q3 (2, a point per output)."""
    return (hw.matrices_question("q1", variant_model, {"Phi": 1.0, "Gamma": 0.5, "Q": 1.0,
                                                       "H": 0.5, "V": 0.5, "M0": 0.5},
                                 credit={"std-as-variance": 0.5}),
            hw.filter_question("q2", 4, "kalman_filter.py", PROBLEM, n_runs=10),
            hw.Question("q3", 2, _q3_reads, _q3_grade, parts={"x_bar": 1.0, "M": 1.0}))
