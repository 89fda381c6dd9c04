r"""The homework problems, one per file, and the front door that checks a submission against one.

Each problem is a :class:`~gpsaccel.check.problem.Problem` (its contract, simulated data,
reference, tolerance and catalogue of mistakes; :mod:`gpsaccel.check.problem` says what each part
is and how :meth:`~gpsaccel.check.problem.Problem.check` runs) and registers itself in
:mod:`gpsaccel.registry` when its module is imported:

``calibration``  report 000: ``kalman_filter(z) -> (x_hat, P)``
                 (:mod:`gpsaccel.check.problems.calibration`, on the linear pipeline of
                 :mod:`gpsaccel.check.linear`).
``tracker``      a constant-velocity tracker (:mod:`gpsaccel.check.problems.tracker`), defined
                 with :meth:`Problem.linear` as an instructor would.
``coop``         report 002: ``ekf(y, Q, R)`` and/or ``lkf(y, Q, R) -> (x_hat, P)``
                 (:mod:`gpsaccel.check.problems.coop`).
``ship``         report 004: ``multirate_filter(z, u) -> (x_hat, P)``
                 (:mod:`gpsaccel.check.problems.ship`).

:mod:`gpsaccel.check.problems.compare` holds what coop and ship share to compare an output with
their reference.  :func:`submission` checks a file against a registered problem by name.

``Problem.linear`` (a problem for any linear model) is attached to the class here, above both the
class and :mod:`gpsaccel.check.linear`: the linear problems are its subclasses, and a class that
imported its own subclasses made the two modules import each other.
"""

from __future__ import annotations

import os

from gpsaccel.check.linear import linear
from gpsaccel.check.problem import Argument, Function, Problem
from gpsaccel.check.report import Report

__all__ = ["Argument", "Function", "Problem", "assert_submission", "get", "submission"]

Problem.linear = staticmethod(linear)


def get(problem: str | Problem) -> Problem:
    """The registered problem named ``problem`` (:mod:`gpsaccel.registry`: "calibration",
    "coop", "ship", "tracker", and any an instructor added), or ``problem`` itself."""
    if isinstance(problem, Problem):
        return problem
    from gpsaccel import registry

    if not isinstance(problem, str):
        raise ValueError(f"problem must be a problem name or a Problem, got {problem!r}")
    return registry.problem(problem)  # type: ignore[return-value]


def submission(path: str | os.PathLike, *, problem: str | Problem = "calibration",
               **options: object) -> Report:
    """Check the student's submission ``path`` (a ``.py`` file or one student's folder) for
    ``problem``; the options are those of :meth:`Problem.check` (n_runs, seed, timeout, sandbox,
    limits, allow_gpsaccel)."""
    return get(problem).check(path, **options)  # type: ignore[arg-type]


def assert_submission(path: str | os.PathLike, *, problem: str | Problem = "calibration",
                      **options: object) -> Report:
    """:func:`submission` for a grader cell: raise AssertionError with the findings if it fails."""
    report = submission(path, problem=problem, **options)
    if not report.passed:
        raise AssertionError("\n" + str(report))
    return report

