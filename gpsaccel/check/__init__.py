"""Homework checkers for the report-000 calibration filter.

Two checks, one kind of answer (a :class:`Report` of :class:`Finding` s with stable codes)::

    from gpsaccel import check
    print(check.model_matrices(Phi=Phi, Gamma=Gamma, H=H, V=V, W=W, M0=M0))
    print(check.submission("my_filter.py"))       # the file defines kalman_filter(z) -> (x_hat, P)

:func:`assert_model_matrices` and :func:`assert_submission` raise ``AssertionError`` with the
findings instead, for a grader's test cell (nbgrader, otter-grader).  The known mistakes and their
codes are in :mod:`gpsaccel.calibration.mistakes`; ``gpsaccel check PATH ...`` checks many files
(:mod:`gpsaccel.check.batch`).  :func:`student_filter` makes a file a ``kalman_filter(z)`` callable
(run in its own box) for :func:`gpsaccel.calibration.compare.compare`.  Students' code runs only
inside a sandbox (:mod:`gpsaccel.check.sandbox`: bubblewrap namespaces or a portable basic box,
with limits), whose generic interface (named functions, numpy inputs, declared outputs) other
checkers build on.
"""

from gpsaccel.calibration.mistakes import codes
from gpsaccel.check.jacobians import assert_jacobians, dt_model, jacobians
from gpsaccel.check.matrices import assert_model_matrices, model_matrices
from gpsaccel.check.report import Finding, Report
from gpsaccel.check.student_filter import StudentFilterError, student_filter
from gpsaccel.check.whole_filter import TOLERANCE, assert_submission, submission

__all__ = [
    "TOLERANCE",
    "Finding",
    "Report",
    "StudentFilterError",
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
