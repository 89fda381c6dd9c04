"""The tracker homework's graded questions (instructor side: in the repository, not the wheel).

q1 reads the matrices (values) and checks them for the student's rate and noise levels (variant)
with the tracker's catalogue; q2 is the file ``kalman_filter.py`` the notebook writes, checked by
:func:`gpsaccel.check.submission` (``problem="tracker"``) on fresh realizations in a box without
gpsaccel.  See :mod:`gpsaccel.assignments.questions`.
"""

from __future__ import annotations

from gpsaccel.assignments.linear import MATRICES, matrices_answer, shapes
from gpsaccel.assignments.tracker import variant_model
from gpsaccel.check.report import Report

# ----------------------------------------------------------------------- graded questions
#: The student's tracker of question 1: propagation rate (Hz, a multiple of the 2 Hz fixes, 4 to
#: 100 Hz), acceleration noise σ_a (m/s², 0.10 to 0.99) and position-fix σ_p (m, 1.0 to 4.9):
#: 49 x 90 x 40 = 176 400 trackers.
RATES_HZ = tuple(range(4, 101, 2))
SIGMAS_A = tuple(round(0.10 + 0.01 * i, 2) for i in range(90))
SIGMAS_P = tuple(round(1.0 + 0.1 * i, 1) for i in range(40))

#: The public notebook's variant (the checker's tracker): never a student's.
DEFAULT_VARIANT = {"rate_hz": 10, "sigma_a": 0.3, "sigma_p": 2.0}


def variant(number: int) -> dict:
    """The student's numbers: rate and noise levels of question 1."""
    from gpsaccel.assignments.variants import pick

    return pick(number, {"rate_hz": RATES_HZ, "sigma_a": SIGMAS_A, "sigma_p": SIGMAS_P},
                DEFAULT_VARIANT)


def _q1_reads(draw):
    from gpsaccel.assignments.notebook import Read

    want = shapes(variant_model(**draw.variant))
    return [Read(name, (), (want[name],), value=True) for name in MATRICES]


def _q1_grade(draw, answers) -> Report:
    """Each matrix the box read (a finding of its part when it is missing or not a matrix), then
    the defined ones against the student's model: every finding is its matrix's part."""
    from gpsaccel.assignments.questions import value

    title = "question 1: model matrices"
    report = Report(title)
    given = {name: value(report, name, a, name)
             for name, a in zip(MATRICES, answers, strict=True)}
    defined = {k: v for k, v in given.items() if v is not None}
    if defined:
        checked = matrices_answer(variant_model(**draw.variant), defined, title, tuple(defined))
        report.findings += checked.findings
    report.sort()
    return report


def _q2_grade(path, draw, timeout: float) -> Report:
    from gpsaccel.check import submission

    return submission(path, problem="tracker", n_runs=10, seed=draw.seed % 2**32,
                      timeout=timeout)


#: q1's parts, a matrix each: the packaged homeworks' one rule (the calibration homework's), a
#: wrong or missing matrix loses its own points and no recognised slip keeps any of them (σ for
#: σ² in V: 3.5 / 4).  Φ and Q, the ones with the model's working in them, a point each.
Q1_PARTS = {"Phi": 1.0, "Gamma": 0.5, "Q": 1.0, "H": 0.5, "V": 0.5, "M0": 0.5}


def graded_questions():
    """The tracker homework's graded questions (:mod:`gpsaccel.assignments.questions`)."""
    from gpsaccel.assignments.questions import Question

    return (Question("q1", 4, _q1_reads, _q1_grade, parts=Q1_PARTS),
            Question("q2", 6, file="kalman_filter.py", grade_file=_q2_grade))
