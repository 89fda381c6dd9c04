"""The cv2d homework's graded questions (the instructor's own: nothing of it is in gpsaccel).

q1 reads the student's model matrices (values) and checks them for the student's own noise levels
(their variant); q2 is the file ``kalman_filter.py`` the notebook writes, checked by
``gpsaccel.check.submission`` against the problem of ``problems.py`` on fresh realizations, in a
box without gpsaccel.  The grader imports this file by path; ``gpsaccel grade --assignment
course/cv2d`` and ``gpsaccel assignment course/cv2d`` find it beside ``cv2d.ipynb``.
"""

from pathlib import Path

from gpsaccel.check.own import load_module, load_problem

HERE = Path(__file__).resolve().parent
PROBLEMS = load_module(HERE / "problems.py", "gpsaccel_problems")
PROBLEM = load_problem(f"{HERE / 'problems.py'}:cv2d")  # registered for check.submission

#: The student's noise levels: σ_a (m/s²) 0.20 .. 0.99 and σ_p (m) 1.0 .. 5.9, 80 × 50 = 4000
#: variants (the public 0.5 / 3.0 is never handed out).
SIGMAS_A = tuple(round(0.20 + 0.01 * i, 2) for i in range(80))
SIGMAS_P = tuple(round(1.0 + 0.1 * i, 1) for i in range(50))

#: The public notebook's variant: the problem's own numbers.
DEFAULT_VARIANT = {"sigma_a": 0.5, "sigma_p": 3.0}


def variant(number: int) -> dict:
    """The student's numbers (never the public ones)."""
    from gpsaccel.assignments.variants import pick

    return pick(number, {"sigma_a": SIGMAS_A, "sigma_p": SIGMAS_P}, DEFAULT_VARIANT)


def variant_model(sigma_a: float, sigma_p: float):
    from gpsaccel import check

    return check.Problem.linear("cv2d-variant", **PROBLEMS.model(0.1, sigma_a, sigma_p), every=10,
                                n_epochs=31, dt=0.1, register=False).model


def _q1_reads(draw):
    from gpsaccel.assignments.linear import MATRICES, shapes
    from gpsaccel.assignments.notebook import Read

    want = shapes(variant_model(**draw.variant))
    return [Read(name, (), (want[name],), value=True) for name in MATRICES]


def _q1_grade(draw, answers):
    from gpsaccel.assignments.linear import MATRICES, matrices_answer
    from gpsaccel.assignments.questions import value
    from gpsaccel.check.report import Report

    report = Report("question 1: model matrices")
    given = {name: value(report, name, a) for name, a in zip(MATRICES, answers, strict=True)}
    if not report.passed:
        return report
    return matrices_answer(variant_model(**draw.variant), given, "question 1: model matrices")


def _q2_grade(path, draw, timeout):
    from gpsaccel.check import submission

    return submission(path, problem=PROBLEM, n_runs=10, seed=draw.seed % 2**32, timeout=timeout)


def graded_questions():
    from gpsaccel.assignments.questions import Question

    return (Question("q1", 4, _q1_reads, _q1_grade),
            Question("q2", 6, file="kalman_filter.py", grade_file=_q2_grade))
