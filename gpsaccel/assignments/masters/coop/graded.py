"""The coop homework's graded questions (instructor side: in the repository, not the wheel).

q1 calls the Jacobians at the states of :func:`gpsaccel.check.jacobians` drawn from the student's
seed; q2 calls ``dt_linearization`` (and the student's own Jacobians, to grade F, G, H against
them) at the states of :func:`gpsaccel.check.dt_model`; q3 calls ``ekf`` on the course log and on
a log simulated from the student's seed.  See :mod:`gpsaccel.assignments.questions`.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from gpsaccel.assignments.coop import dt_linearization, ekf, jacobians, states
from gpsaccel.check.report import Report
from gpsaccel.coop.model import CoopModel

# ----------------------------------------------------------------------- graded questions
#: No question of the coop homework has a numeric answer: no variant.
DEFAULT_VARIANT: dict = {}


def variant(number: int) -> dict:
    """The coop homework has no per-student numbers (its answers are functions)."""
    return {}


def _jacobian_reads(X: np.ndarray, U: np.ndarray) -> list:
    from gpsaccel.assignments.notebook import Read

    reads = []
    for name, shape, needs_u in (("jacobian_A", (6, 6), True), ("jacobian_B", (6, 4), True),
                                 ("jacobian_C", (5, 6), False)):
        reads += [Read(name, (x, u) if needs_u else (x,), (shape,)) for x, u in
                  zip(X, U, strict=True)]
    return reads


def _q1_reads(draw):
    return _jacobian_reads(*states(draw.seed % 2**32, 20))


def _replays(reads, answers, *names):
    from gpsaccel.assignments.questions import replay

    return [replay(reads, answers, n) for n in names]


def _q1_grade(draw, answers) -> Report:
    reads = _q1_reads(draw)
    return jacobians(*_replays(reads, answers, "jacobian_A", "jacobian_B", "jacobian_C"),
                     seed=draw.seed % 2**32, n_random=20)


def _q2_reads(draw):
    from gpsaccel.assignments.notebook import Read

    X, U = states(draw.seed % 2**32, 5)
    dt = np.array(CoopModel().dt)
    return [Read("dt_linearization", (x, u, dt), ((6, 6), (6, 4), (5, 6))) for x, u in
            zip(X, U, strict=True)] + _jacobian_reads(X, U)


def _q2_grade(draw, answers) -> Report:
    reads = _q2_reads(draw)
    fn, A, B, C = _replays(reads, answers, "dt_linearization", "jacobian_A", "jacobian_B",
                           "jacobian_C")
    return dt_linearization(fn, seed=draw.seed % 2**32, n_random=5, jacobian_A=A,
                            jacobian_B=B, jacobian_C=C)


def _logs(draw) -> list[tuple[str, np.ndarray]]:
    return [(label, y.copy()) for label, y in _logs_of(draw.seed)]


@lru_cache(maxsize=2)
def _logs_of(seed: int) -> tuple[tuple[str, np.ndarray], ...]:
    """The logs of q3 for a draw's seed, simulated once per notebook: q3's reads and its grade
    ask for them three times (a simulation is most of the grader's own CPU for a coop
    notebook).  Inputs of the student's ``ekf``, not answers; callers get copies."""
    from gpsaccel.coop.model import course_ydata

    model = CoopModel()
    return (("the course log", course_ydata().T.copy()),
            ("a simulated log", model.simulate(np.random.default_rng(seed)).y[0]))


def _q3_reads(draw):
    from gpsaccel.assignments.notebook import Read

    model = CoopModel()
    n = model.n_steps + 1
    return [Read("ekf", (y, model.x0, model.P0, model.Qtrue, model.Rtrue), ((n, 6), (n, 6, 6)))
            for _, y in _logs(draw)]


def _q3_grade(draw, answers) -> Report:
    reads = _q3_reads(draw)
    (fn,) = _replays(reads, answers, "ekf")
    report = Report("question 3: EKF")
    for label, y in _logs(draw):
        sub = ekf(fn, y, label=label)
        report.findings.extend(sub.findings)
        if not sub.passed:
            break
    report.sort()
    return report


def warm() -> None:
    """Imported once in the class's parent (:func:`gpsaccel.assignments.grading.warm`), not in
    every notebook's process: the checker's modules q1 and q2 grade with.  Modules only."""
    import gpsaccel.check.dt_model  # noqa: F401
    import gpsaccel.check.jacobians  # noqa: F401

def graded_questions():
    """The coop homework's graded questions (:mod:`gpsaccel.assignments.questions`): q1 and q2
    a part per matrix (A, B, C; F, G, H), the packaged homeworks' one rule (the calibration
    homework's): a wrong matrix loses its own points, no recognised slip keeps any of them."""
    from gpsaccel.assignments.questions import Question

    return (Question("q1", 3, _q1_reads, _q1_grade, parts=(("A", 1), ("B", 1), ("C", 1))),
            Question("q2", 2, _q2_reads, _q2_grade, parts=(("F", 1), ("G", 0.5), ("H", 0.5))),
            Question("q3", 5, _q3_reads, _q3_grade))
