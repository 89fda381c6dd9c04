"""The calibration homework's graded questions (instructor side: in the repository, not the wheel).

q1 reads the matrices (values) and checks them for the student's accelerometer rate (variant);
q2 is the file ``kalman_filter.py`` the notebook writes, checked by :func:`gpsaccel.check.submission`
on fresh realizations in a box without gpsaccel; q3 calls ``average_nees`` and ``nees_bounds`` on a
fresh consistent ensemble.  See :mod:`gpsaccel.assignments.questions`.
"""

from __future__ import annotations

import numpy as np

from gpsaccel.assignments._answers import call
from gpsaccel.assignments.calibration import nees_answer, nees_data, rate_model
from gpsaccel.check.report import Report

# ----------------------------------------------------------------------- graded questions
#: Accelerometer rates (Hz) of the per-student variant of question 1: every multiple of 5 Hz
#: (so the 5 Hz GPS falls on an accelerometer step) from 10 Hz to 10 kHz, 1999 rates.  Only Δt
#: enters question 1's matrices (V, W, M0 stay report 000's: the checker's hints name those
#: numbers); 200 students share a rate in about 10 pairs (docs/grading.md).
RATES_HZ = tuple(5 * k for k in range(2, 2001))

#: The public notebook's variant (report 000's numbers): never a student's.
DEFAULT_VARIANT = {"rate_hz": 200}


def variant(number: int) -> dict:
    """The student's numbers: the accelerometer rate of question 1 (never the public 200 Hz)."""
    from gpsaccel.assignments.variants import pick

    return pick(number, {"rate_hz": RATES_HZ}, DEFAULT_VARIANT)


_MATRICES = {"Phi": (3, 3), "Gamma": (3, 1), "H": (2, 3), "V": (2, 2), "W": (1, 1), "M0": (3, 3)}


def _q1_reads(draw):
    from gpsaccel.assignments.notebook import Read

    return [Read(name, (), (shape,), value=True) for name, shape in _MATRICES.items()]


def _q1_grade(draw, answers) -> Report:
    from gpsaccel.assignments.questions import value
    from gpsaccel.check import model_matrices

    report = Report("question 1: model matrices")
    given = {name: value(report, name, a) for name, a in zip(_MATRICES, answers, strict=True)}
    if not report.passed:
        return report
    rate = draw.variant["rate_hz"]
    return model_matrices(**given, dt=1.0 / rate, model=rate_model(rate))


def _q2_grade(path, draw, timeout: float) -> Report:
    from gpsaccel.check import submission

    return submission(path, n_runs=10, seed=draw.seed % 2**32, timeout=timeout)



def _q3_draw(draw):
    rng = draw.rng()
    N = int(rng.integers(20, 61))
    return N, nees_data(rng, N)


def _q3_reads(draw):
    from gpsaccel.assignments.notebook import Read

    N, (x_true, x_hat, P) = _q3_draw(draw)
    return [Read("average_nees", (x_true, x_hat, P), ((),)),
            Read("nees_bounds", (np.array(N),), ((2,),))]


def _q3_grade(draw, answers) -> Report:
    from gpsaccel.assignments.questions import replay

    N, (x_true, x_hat, P) = _q3_draw(draw)
    reads = _q3_reads(draw)
    report = Report("question 3: NEES")
    out = {}
    for name, args in (("average_nees", (x_true, x_hat, P)), ("nees_bounds", (np.array(N),))):
        fn = replay(reads, answers, name)
        out[name] = call(report, f"{name}(...)", fn, *args)
    if not report.passed:
        return report
    return nees_answer(out["average_nees"], out["nees_bounds"], N, x_true, x_hat, P)


def graded_questions():
    """The calibration homework's graded questions (:mod:`gpsaccel.assignments.questions`)."""
    from gpsaccel.assignments.questions import Question

    return (Question("q1", 3, _q1_reads, _q1_grade),
            Question("q2", 4, file="kalman_filter.py", grade_file=_q2_grade),
            Question("q3", 3, _q3_reads, _q3_grade))
