"""The tracker homework: graded in the sandbox (solved, blank, one mistake per question), its codes
the tracker catalogue's; the matrices check on its own for every variant."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel import registry
from gpsaccel.assignments.grading import assignment_module, student_variant
from gpsaccel.assignments.linear import matrices, matrices_answer
from gpsaccel.assignments.tracker import variant_model
from gpsaccel.check.problems.tracker import TRACKER
from gpsaccel.classrun import grade
from gpsaccel.kalman.linear_model import LinearIngredients

from .conftest import tracker_with_numpy_filter, write_variant

PHI = "Phi = np.array([[1.0, dt], [0.0, 1.0]])"
M0 = "M0 = np.diag([5.0**2, 2.0**2])"
#: the two filter mistakes, in the numpy filter (conftest.TRACKER_NUMPY_FILTER: a file box
#: without filterpy, whose import is most of that box's CPU); the master's own, with filterpy,
#: is the solved notebook
V = "V = np.array([[2.0**2]])"
STORE = "        x_hat[k], P_all[k] = x, P\n"
UPDATE = "        K = P @ H.T"
SECRET = b"tracker-test-secret-0123456789"
graded_module = assignment_module("tracker")


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    sub = tmp_path_factory.mktemp("class")
    write_variant("tracker", sub / "solved" / "tracker.ipynb")
    write_variant("tracker", sub / "blank" / "tracker.ipynb",
                  [("def kalman_filter(z):\n", "def kalman_filter(z):\n    return None\n"),
                   # nothing imports filterpy (scipy.stats: most of a box's CPU) for nothing
                   ("from filterpy.kalman import KalmanFilter\n", "")],
                  last_cell="Phi = Gamma = Q = H = V = M0 = ...")
    # its q2 is right: the filter written with numpy (no filterpy, 1.5 CPU s, in its file's box)
    tracker_with_numpy_filter(sub / "transposed" / "tracker.ipynb",
                              [(PHI, "Phi = np.array([[1.0, 0.0], [dt, 1.0]])")])
    tracker_with_numpy_filter(sub / "sigma_in_R" / "tracker.ipynb",
                              filter_edits=[(V, V.replace("2.0**2", "2.0"))])
    tracker_with_numpy_filter(sub / "a_priori" / "tracker.ipynb",  # stored before the update
                              filter_edits=[(STORE, ""), (UPDATE, STORE + UPDATE)])
    grades = grade(sub, "tracker", out=sub.parent / "tracker-grades", jobs=2, timeout=120,
                   seed=5, secret=SECRET)
    return {g.student: g for g in grades}


def test_an_honest_notebook_gets_full_marks_a_blank_one_nothing(graded):
    assert graded["solved"].scores == {"q1": 4.0, "q2": 6.0}, graded["solved"].feedback
    blank = graded["blank"]
    assert blank.status == "graded" and blank.total == 0
    assert "not-defined" in blank.codes["q1"] and blank.codes["q2"]


def test_each_mistake_loses_exactly_its_part_with_the_catalogue_code(graded):
    codes = set(TRACKER.codes())
    # q1's Φᵀ costs Φ's point (a part per matrix); q2, the whole filter, is all or nothing
    for student, question, code, score in (("transposed", "q1", "phi-transposed", 3.0),
                                           ("sigma_in_R", "q2", "std-as-variance", 0.0),
                                           ("a_priori", "q2", "returns-a-priori", 0.0)):
        g = graded[student]
        full = {"q1": 4.0, "q2": 6.0}
        assert g.scores == {**full, question: score}, (student, g.feedback)
        assert g.codes[question] == [code] and code in codes, (student, g.codes)


def _q1_score(model, changes: dict) -> tuple[float, list[str]]:
    """q1's score and codes when the matrices are the model's but for ``changes`` (a matrix, or
    an Answer: what the box sent back for it)."""
    from gpsaccel.assignments.linear import MATRICES
    from gpsaccel.assignments.questions import Answer, Draw

    q1 = graded_module.graded_questions()[0]
    draw = Draw(1, graded_module.DEFAULT_VARIANT)
    given = {**_right(model), **changes}
    answers = [v if isinstance(v, Answer) else Answer("ok", values=(np.asarray(v, float),))
               for v in (given[k] for k in MATRICES)]
    report = q1.grade(draw, answers)
    return q1.score(report), report.codes


def test_a_wrong_or_missing_matrix_costs_only_its_part():
    """The packaged homeworks' one rule (the calibration homework's: V as σ 2.5 / 3): a part per
    matrix, no recognised slip keeps any of it. At main q1 was all or nothing: 0 / 4 for each."""
    from gpsaccel.assignments.questions import Answer

    model = variant_model(**graded_module.DEFAULT_VARIANT)
    right, W = _right(model), model.W[0, 0]
    assert _q1_score(model, {}) == (4.0, [])
    for changes, score, codes in (
            ({"V": np.sqrt(right["V"])}, 3.5, ["std-as-variance"]),
            ({"Phi": right["Phi"].T}, 3.0, ["phi-transposed"]),
            ({"Q": W * np.eye(2)}, 3.0, ["q-without-gamma"]),
            ({"M0": Answer("not-defined")}, 3.5, ["not-defined"]),
            ({"V": np.sqrt(right["V"]), "M0": np.sqrt(right["M0"])}, 3.0, ["std-as-variance"]),
            ({k: Answer("not-defined") for k in right if k != "W"}, 0.0, ["not-defined"])):
        assert _q1_score(model, changes) == (score, codes), changes


def test_question_1_is_the_students_own_variant(graded):
    v = student_variant("tracker", "transposed", SECRET)
    assert f"rate_hz = {v['rate_hz']}" in graded["transposed"].feedback


# ------------------------------------------------------------------ the checks on their own
def _right(model):
    return {k: np.array(v) for k, v in matrices(LinearIngredients.correct(model)).items()}


@pytest.mark.parametrize("number", range(27))
def test_every_variant_passes_its_own_matrices_and_fails_anothers(number):
    v = graded_module.variant(number)
    model = variant_model(**v)
    assert matrices_answer(model, _right(model)).passed
    other = variant_model(**graded_module.variant(number + 1))
    assert not matrices_answer(model, _right(other)).passed


def test_each_ingredient_mistake_is_named_with_the_catalogues_code():
    model = variant_model(rate_hz=20, sigma_a=0.5, sigma_p=3.0)
    right = _right(model)
    G, dt = right["Gamma"], model.dt
    cases = {
        "phi-transposed": {"Phi": right["Phi"].T},
        "q-without-gamma": {"Q": 0.25 * np.eye(2)},
        "std-as-variance": {"V": np.array([[3.0]]), "M0": np.diag([5.0, 2.0]),
                            "Q": G @ G.T * 0.5},     # σ where σ² belongs: in V, M0 and W
        "m0-order": {"M0": np.diag([4.0, 25.0])},
        "matrix-value": {"Q": G @ G.T * 0.3**2},      # another variant's σ_a
    }
    for code, wrong in cases.items():
        report = matrices_answer(model, {**right, **wrong})
        assert report.codes == [code], (code, report)
        assert all(f.message.split(":")[0] in wrong for f in report.findings
                   if f.severity == "error")
    slip = {**right, "Phi": np.array([[1.0, 2 * dt], [0.0, 1.0]])}
    found = matrices_answer(model, slip).findings[0]
    msg = found.for_student().message  # the instructor's text has the right matrix
    assert "Φ₁₂ differs" in msg and f"{dt:g}" not in msg.split("differs")[1]
    assert f"{dt:g}" in found.for_instructor()


def test_the_homework_is_registered_where_it_is_defined():
    assert "tracker" in registry.assignments()
    entry = registry.assignment("tracker")
    assert entry.problem == "tracker" and entry.problem in registry.problems()
    with pytest.raises(ValueError, match="assignment must be one of"):
        registry.assignment("no-such-homework")


def test_feedback_names_the_mistake_without_the_expected_value(graded):
    text = graded["sigma_in_R"].feedback
    assert "std-as-variance" in text and "(V = 2, the p measurement's variance)" in text
    assert "should be 4" not in text and "σ² = 4" not in text
    q1 = graded["transposed"].feedback
    assert "phi-transposed" in q1 and "Φᵀ" in q1
