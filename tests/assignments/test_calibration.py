"""The calibration homework: otter assign, otter run on the solution, the blank and the mistakes;
``gpsaccel grade`` over a class with a full-marks, an empty, a broken and a hostile notebook."""

from __future__ import annotations

import shutil

import nbformat
import pytest

from gpsaccel.assignments import generate, grade, master_notebook, questions
from gpsaccel.assignments.calibration import calibration_ensemble, nees_answer, nees_reference

PHI = "Phi = np.array([[1.0, dt, -dt**2 / 2], [0.0, 1.0, -dt], [0.0, 0.0, 1.0]])  # SOLUTION"
W_VAR = "Q = Gamma @ Gamma.T * 0.02**2"
BOUNDS = "stats.chi2.ppf([0.025, 0.975], 3 * N) / N"

# a notebook that kills the process grading it (otter run), then its own kernel
HOSTILE = "import os, signal\nos.kill(os.getppid(), signal.SIGKILL)\nos.kill(os.getpid(), signal.SIGKILL)"


@pytest.fixture(scope="module")
def dist(tmp_path_factory):
    return generate("calibration", tmp_path_factory.mktemp("dist") / "calibration",
                    run_tests=False)


@pytest.fixture(scope="module")
def graded(dist, tmp_path_factory, make_variant, read_grades):
    """Six notebooks graded in one parallel call."""
    folder = tmp_path_factory.mktemp("class")
    shutil.copy(dist.solution, folder / "solved.ipynb")
    shutil.copy(dist.student, folder / "blank.ipynb")
    make_variant(dist.solution, folder / "mistakes_q1_q3.ipynb",
                 [(PHI, PHI.replace("-dt**2", "+dt**2")),
                  (BOUNDS, "stats.chi2.ppf([0.025, 0.975], 3)")])
    make_variant(dist.solution, folder / "mistake_q2.ipynb", [(W_VAR, "Q = Gamma @ Gamma.T * 0.02")])
    make_variant(dist.solution, folder / "hostile.ipynb", [], extra_first_cell=HOSTILE)
    (folder / "broken.ipynb").write_text("{ this is not a notebook", encoding="utf-8")
    out = folder / "grades"
    grades = grade(folder, "calibration", out=out, autograder=dist.autograder, jobs=2,
                   timeout=300)
    return {g.submission: g for g in grades}, read_grades(out / "grades.csv"), out


def test_assign_writes_student_notebook_without_solutions_or_hidden_tests(dist):
    assert dist.autograder.is_file() and dist.student.is_file()
    nb = nbformat.read(str(dist.student), as_version=4)
    code = "\n".join(c.source for c in nb.cells if c.cell_type == "code")
    for solution_line in (PHI, W_VAR, BOUNDS):
        assert solution_line not in code
    public = "\n".join(nb.metadata["otter"]["tests"].values())
    assert "check.assert_submission" in public and "_graded" not in public


def test_questions_and_points():
    assert questions(master_notebook("calibration")) == {"q1": 3.0, "q2": 4.0, "q3": 3.0}


def test_solution_scores_full_marks(graded):
    grades, rows, _ = graded
    g = grades["solved.ipynb"]
    assert g.status == "graded"
    assert g.scores == {"q1": 3.0, "q2": 4.0, "q3": 3.0}
    assert rows["solved.ipynb"]["total"] == "10" and rows["solved.ipynb"]["possible"] == "10"


def test_blank_student_notebook_scores_zero_with_feedback(graded):
    grades, rows, _ = graded
    g = grades["blank.ipynb"]
    assert g.status == "graded" and g.total == 0
    assert "Define Phi, Gamma, H, V, W, M0" in g.feedback
    assert "return-value" in g.feedback  # the whole-filter checker's finding on `...`


def test_mistakes_lose_exactly_their_questions_and_name_the_codes(graded):
    grades, _, _ = graded
    a, b = grades["mistakes_q1_q3.ipynb"], grades["mistake_q2.ipynb"]
    assert a.scores == {"q1": 0.0, "q2": 4.0, "q3": 0.0}
    assert "phi-sign" in a.outputs["q1"] and "nees-bounds-one-run" in a.outputs["q3"]
    assert b.scores == {"q1": 3.0, "q2": 0.0, "q3": 3.0}
    assert "std-as-variance" in b.outputs["q2"]  # W = σ_w = 0.02 in the filter


def test_broken_and_hostile_notebooks_cost_only_their_own_grade(graded):
    grades, rows, out = graded
    for name in ("hostile.ipynb", "broken.ipynb"):
        assert grades[name].status == "error" and grades[name].total == 0
        assert rows[name]["status"] == "error" and rows[name]["total"] == "0"
        assert "could not be graded" in (out / "feedback" / name.replace(".ipynb", ".txt")
                                          ).read_text(encoding="utf-8")
    assert set(rows) == {"solved.ipynb", "blank.ipynb", "mistakes_q1_q3.ipynb",
                         "mistake_q2.ipynb", "hostile.ipynb", "broken.ipynb"}


# ------------------------------------------------------------------ question 3's checker alone
@pytest.fixture(scope="module")
def ensemble():
    return calibration_ensemble(n_runs=50, seed=2026)


def test_nees_answer_accepts_the_reference_and_names_each_mistake(ensemble):
    N, x, xh, P = ensemble
    eps, (lo, hi) = nees_reference(x, xh, P)
    assert nees_answer(eps, (lo, hi), N, x, xh, P).passed
    e = x[:, -1] - xh[:, -1]
    wrong = {
        "nees-sum": N * eps,
        "nees-not-inverted": float((e[:, None, :] @ P[:, -1] @ e[..., None]).mean()),
        "nees-per-state": eps / 3,
        "nees-value": eps * 1.01,
    }
    for code, value in wrong.items():
        assert nees_answer(value, (lo, hi), N, x, xh, P).codes == [code]
    from scipy import stats
    one = tuple(stats.chi2.ppf([0.025, 0.975], 3))
    assert nees_answer(eps, one, N, x, xh, P).codes == ["nees-bounds-one-run"]
    assert nees_answer("abc", "x", N, x, xh, P).codes == ["not-a-number", "nees-bounds"]


def test_calibration_ensemble_returns_fresh_copies(ensemble):
    N, x, xh, P = calibration_ensemble(n_runs=50, seed=2026)
    x[:] = 0.0
    assert calibration_ensemble(n_runs=50, seed=2026)[1].any()
