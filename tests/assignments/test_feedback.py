"""Feedback a student can read: no answer in it, no noise from otter's cells, partial credit
(issue 27 items 3, 6 and 7).

A small calibration class at a fixed seed and secret (each student has their own variant): one
right notebook as otter hands it out (its init cell and a ``grader.check`` cell per question
kept), one with realistic mistakes in every question, one with one of q3's two functions wrong.
The feedback is searched for every reference number the grader computed for that student.
"""

from __future__ import annotations

import nbformat
import numpy as np
import pytest

from gpsaccel.assignments import grading
from gpsaccel.assignments.calibration import nees_reference
from gpsaccel.assignments.grading import is_otter_cell
from gpsaccel.assignments.questions import Draw, question_seed
from gpsaccel.check.report import see
from gpsaccel.classrun import grade

from .conftest import CHI2_SPECIAL, write_variant

SEED, SECRET = 31, b"feedback-test-secret-0123456789ab"
PHI = ('dt = 1 / VARIANT["rate_hz"]\n'
       "Phi = np.array([[1.0, dt, -dt**2 / 2], [0.0, 1.0, -dt], [0.0, 0.0, 1.0]])")
V = "V = np.diag([1.0**2, 0.04**2])"
SUM = "return float(np.mean([ei @ np.linalg.solve(Pi, ei) for ei, Pi in zip(e, P[:, -1])]))"
BOUNDS = "return tuple(stats.chi2.ppf([0.025, 0.975], 3 * N) / N)"
FILTER_W = "Q = Gamma @ Gamma.T * 0.02**2"
OTTER_INIT = '# Initialize Otter\nimport otter\ngrader = otter.Notebook("calibration.ipynb")'
MISTAKES = [(PHI, PHI.replace("-dt**2 / 2", "dt**2 / 2")),        # q1: Φ₁₃'s sign
            (V, "V = np.diag([1.0**2, 0.04])"),                     # q1: σ for σ²
            (FILTER_W, "Q = Gamma @ Gamma.T * 0.02"),               # q2: σ_w for W
            (SUM, SUM.replace("np.mean", "np.sum")),                # q3: the sum, not the mean
            (BOUNDS, "return tuple(stats.chi2.ppf([0.025, 0.975], 3))")]  # q3: one run's


def _as_otter_hands_it_out(path):
    """otter's init cell first and a ``grader.check("qN")`` cell after each question."""
    nb = nbformat.read(str(path), as_version=4)
    cells = [nbformat.v4.new_code_cell(OTTER_INIT)]
    for c in nb.cells:
        cells.append(c)
        for q, mark in (("q1", "M0 = np.diag"), ("q2", "%%writefile"), ("q3", "def nees_bounds")):
            if c.cell_type == "code" and mark in c.source:
                cells.append(nbformat.v4.new_code_cell(f'grader.check("{q}")'))
    nb.cells = cells
    nbformat.write(nb, str(path))


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    sub = tmp_path_factory.mktemp("feedback") / "class"
    # the bounds of the right ones with scipy.special (conftest.CHI2_SPECIAL: a cheaper box)
    one_run = ("return tuple(chdtri(3 * N, [0.975, 0.025]) / N)",  # MISTAKES' last, so
               "return tuple(chdtri(3, [0.975, 0.025]))")
    for student, edits in (("right", [CHI2_SPECIAL]),
                           ("mistakes", [*MISTAKES[:-1], CHI2_SPECIAL, one_run]),
                           ("half", [MISTAKES[3], CHI2_SPECIAL])):
        path = write_variant("calibration", sub / student / "calibration.ipynb", edits)
        _as_otter_hands_it_out(path)
    grades = grade(sub, "calibration", jobs=2, timeout=120, seed=SEED, secret=SECRET)
    return {g.student: g for g in grades}


def test_otters_cells_are_recognised_and_nothing_else():
    assert is_otter_cell(OTTER_INIT) and is_otter_cell('grader.check("q1")')
    assert is_otter_cell("grader.check_all()\ngrader.export(pdf=False)")
    for other in ("import otter\nx = 1", "grader = 1", 'grader.check("q1"); import os',
                  "grader.check(os.system('ls'))", "otter = 2", "", "import otter as o",
                  "grader.check(" * 500):
        assert not is_otter_cell(other), other


def test_a_right_notebook_gets_feedback_without_otters_cells(graded):
    g = graded["right"]
    assert g.total == 10 and g.status == "graded", g.feedback
    for word in ("Cell", "otter", "grader", "NameError", "FileNotFoundError", "raised"):
        assert word not in g.feedback, g.feedback


def test_partial_credit_for_one_of_two_functions(graded):
    g = graded["half"]
    assert g.scores == {"q1": 3.0, "q2": 4.0, "q3": 1.5}, g.feedback
    assert g.codes["q3"] == ["nees-sum"]


def test_mistakes_are_named_and_partly_credited(graded):
    g = graded["mistakes"]
    assert g.scores == {"q1": 2.0, "q2": 0.0, "q3": 0.0}, g.feedback
    assert set(g.codes["q1"]) == {"phi-sign", "std-as-variance"}
    assert "std-as-variance" in g.codes["q2"]
    assert set(g.codes["q3"]) == {"nees-sum", "nees-bounds-one-run"}


def test_each_mistake_says_which_lesson_section_teaches_its_fix(graded):
    lines = graded["mistakes"].feedback.splitlines()
    for code in ("phi-sign", "std-as-variance", "nees-sum", "nees-bounds-one-run"):
        i = next(i for i, ln in enumerate(lines) if ln.startswith(f"    - {code}: "))
        assert lines[i + 1] == "      " + see(code), lines[i:i + 2]
    assert "      → lesson 02, 'The derivation' (exercise 5)" in lines


def _reference_numbers(student: str) -> set[str]:
    """Every number the grader computed as an answer for ``student``, as feedback would print
    it: Φ's, V₂₂, W (q1, at their rate), the filter's W (q2), ε̄ and the bounds (q3)."""
    mod = grading.assignment_module("calibration")
    variant = grading.student_variant("calibration", student, SECRET)
    dt = 1.0 / variant["rate_hz"]
    values = [-dt**2 / 2, -dt, 0.04**2, 0.02**2]
    N, (x_true, x_hat, P) = mod._q3_draw(Draw(question_seed(SEED, "calibration", "q3", student),
                                              variant))
    eps, (lo, hi) = nees_reference(x_true, x_hat, P)
    values += [eps, lo, hi]
    out = {f"{v:{spec}}" for v in values for spec in (".6g", ".4g", ".3g")}
    return out | {f"{v:{spec}}" for v in (lo, hi) for spec in (".2f", ".3f")}


@pytest.mark.parametrize("student", ["mistakes", "half"])
def test_feedback_holds_no_reference_number(graded, student):
    text = graded[student].feedback
    found = {s for s in _reference_numbers(student) if s in text}
    assert not found, (found, text)
    assert "expected" not in text.lower()
    assert np.isfinite(graded[student].total)
