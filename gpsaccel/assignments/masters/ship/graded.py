"""The ship homework's graded questions (instructor side: in the repository, not the wheel).

q1 calls ``update`` on cases drawn from the student's seed; q2 reads ``sigma_optimal`` and
``sigma_zeroed`` computed in the box on the student's own voyage (variant).  See
:mod:`gpsaccel.assignments.questions`.
"""

from __future__ import annotations

from gpsaccel.assignments.ship import cases, cost_answer, update_answer
from gpsaccel.check.report import Report

# ----------------------------------------------------------------------- graded questions
#: The public notebook's variant: report 004's ship (never a student's).
DEFAULT_VARIANT = {"mass_kg": 12.0, "gps_rate_hz": 1.0}

#: The student's ship of question 2: its mass (kg, 5 to 25 kg in steps of 10 g: each step moves
#: the answers by about 1e-4 relative, five times the tolerance) and its GPS rate (Hz; each
#: divides the 10 Hz grid): 2001 x 6 = 12006 ships.  Only these two enter question 2's answer
#: (:func:`gpsaccel.assignments.ship.zeroed_gain_cost`).
MASSES_KG = tuple(round(5.0 + 0.01 * i, 2) for i in range(2001))
GPS_RATES_HZ = (0.2, 0.25, 0.5, 1.0, 2.0, 2.5)


def variant(number: int) -> dict:
    """The student's numbers: mass and GPS rate of their ship (question 2)."""
    from gpsaccel.assignments.variants import pick

    return pick(number, {"mass_kg": MASSES_KG, "gps_rate_hz": GPS_RATES_HZ}, DEFAULT_VARIANT)


def _q1_reads(draw):
    from gpsaccel.assignments.notebook import Read

    return [Read("update", args, ((9,), (9, 9))) for _, args in cases(draw.seed % 2**32)]


def _q1_grade(draw, answers) -> Report:
    from gpsaccel.assignments.questions import replay

    return update_answer(replay(_q1_reads(draw), answers, "update"), seed=draw.seed % 2**32)


def _q2_reads(draw):
    from gpsaccel.assignments.notebook import Read

    return [Read("sigma_optimal", (), ((),), value=True),
            Read("sigma_zeroed", (), ((),), value=True)]


def _q2_grade(draw, answers) -> Report:
    from gpsaccel.assignments.questions import value

    report = Report("question 2: what the zeroed gain costs")
    got = [value(report, r.name, a, r.name)
           for r, a in zip(_q2_reads(draw), answers, strict=True)]
    checked = cost_answer(*got, **draw.variant)  # a missing σ: not-a-number there, its part's
    report.findings += [f for f in checked.findings if f.part not in report.failed_parts()]
    report.sort()
    return report


def warm() -> None:
    """Done once in the class's parent (:func:`gpsaccel.assignments.grading.warm`), not in every
    notebook's process: the modules q2's reference imports (the package's multirate filter,
    which is filterpy's, and filterpy pulls in scipy.stats: benchmarks/imports.py) and the ship's
    covariances q1's cases start from (a voyage filtered; inputs of the student's update, the same
    for every student, not an answer)."""
    import filterpy.kalman  # noqa: F401

    import gpsaccel.assignments.variants  # noqa: F401
    import gpsaccel.kalman.multirate  # noqa: F401
    import gpsaccel.ship.zeroed_gain  # noqa: F401

    cases()

#: The packaged homeworks' one rule (the calibration homework's): each output a part of its own;
#: a wrong one loses its points, no recognised slip keeps any of them.  q1: the update's x̂ and P
#: (a mistake that changes both, such as the zeroed gain, costs both); q2: the two σ.
Q1_PARTS = {"x_hat": 3.0, "P": 3.0}
Q2_PARTS = {"sigma_optimal": 2.0, "sigma_zeroed": 2.0}


def graded_questions():
    """The ship homework's graded questions (:mod:`gpsaccel.assignments.questions`)."""
    from gpsaccel.assignments.questions import Question

    return (Question("q1", 6, _q1_reads, _q1_grade, parts=Q1_PARTS),
            Question("q2", 4, _q2_reads, _q2_grade, parts=Q2_PARTS))
