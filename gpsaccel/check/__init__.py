"""Homework checkers for the course's three systems, one kind of answer for all.

Every check returns a :class:`Report` of :class:`Finding` s with stable codes::

    from gpsaccel import check
    print(check.model_matrices(Phi=Phi, Gamma=Gamma, H=H, V=V, W=W, M0=M0))   # report 000
    print(check.jacobians(A=A, B=B, C=C))                # report 002: the student's Jacobians
    print(check.dt_model(F=F, G=G, H=H))                 # report 002: F = I + ΔT·A, G, H
    print(check.submission("my_filter.py"))              # kalman_filter(z) (calibration)
    print(check.submission("coop.py", problem="coop"))   # ekf(y, Q, R) and/or lkf(y, Q, R)
    print(check.submission("ship.py", problem="ship"))   # multirate_filter(z, u)
    print(check.submission("bob/", problem="tracker"))   # a folder; any registered problem
    check.Problem.linear("mine", Phi=..., Gamma=..., W=..., H=..., V=..., M0=..., x0=...,
                         every=5, n_epochs=41)           # a problem for any linear model

What a problem is (contract, simulated data, reference, tolerance, catalogue of mistakes) is
:mod:`gpsaccel.check.problem`; the problems, one per file, are :mod:`gpsaccel.check.problems`.
Every ``assert_*`` form raises ``AssertionError`` with the findings instead, for a grader's
test cell (nbgrader, otter-grader).  The catalogues of known mistakes live with their systems
(:mod:`gpsaccel.calibration.mistakes`, :mod:`gpsaccel.coop.mistakes`,
:mod:`gpsaccel.ship.mistakes`); ``gpsaccel check PATH --problem ...`` checks many files
(:mod:`gpsaccel.check.batch`).  :func:`student_filter` makes a file a ``kalman_filter(z)``
callable (run in its own box) for :func:`gpsaccel.calibration.compare.compare`.
Students' code runs only inside a sandbox (:mod:`gpsaccel.sandbox`: bubblewrap namespaces or
a portable basic box, with limits), whose generic interface (named functions, numpy inputs,
declared outputs) every problem uses through :meth:`Problem.check`.
"""

from typing import TYPE_CHECKING

import gpsaccel.problems  # noqa: F401 - declares the problems (not bound here: check.problems)
from gpsaccel import _lazy

if TYPE_CHECKING:  # for mypy and editors; at run time each name loads on first use (_lazy)
    from gpsaccel.calibration.mistakes import codes
    from gpsaccel.check.dt_model import assert_dt_model, dt_model
    from gpsaccel.check.jacobians import assert_jacobians, jacobians
    from gpsaccel.check.linear import TOLERANCE, LinearProblem
    from gpsaccel.check.matrices import assert_model_matrices, model_matrices
    from gpsaccel.check.problems import Problem, assert_submission, submission
    from gpsaccel.check.report import Finding, Report
    from gpsaccel.check.student_filter import StudentFilterError, student_filter

__all__ = [
    "TOLERANCE",
    "Finding",
    "LinearProblem",
    "Problem",
    "Report",
    "StudentFilterError",
    "assert_dt_model",
    "assert_jacobians",
    "assert_model_matrices",
    "assert_submission",
    "codes",
    "dt_model",
    "jacobians",
    "model_matrices",
    "student_filter",
    "submission",
]

# ``gpsaccel.check.report`` or ``.batch`` (the grader, the CLI) import this package first: it must
# not import every problem and its filters for that.
__getattr__, __dir__ = _lazy.attach(
    __name__,
    attributes={
        "gpsaccel.calibration.mistakes": ("codes",),
        "dt_model": ("assert_dt_model", "dt_model"),
        "jacobians": ("assert_jacobians", "jacobians"),
        "linear": ("TOLERANCE", "LinearProblem"),
        "matrices": ("assert_model_matrices", "model_matrices"),
        "problems": ("Problem", "assert_submission", "submission"),
        "report": ("Finding", "Report"),
        "student_filter": ("StudentFilterError", "student_filter"),
    })
