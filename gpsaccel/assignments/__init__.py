"""Ready-to-hand-out homework: authored with otter-grader, graded in the checker's sandbox.

Three homeworks on the course reports, each a master notebook in otter's assign format under
``assignments/NAME/`` of the source repository (solutions and otter's tests only there):

* ``calibration``: Φ, Γ, H, V, W, M0 for the student's accelerometer rate, a ``kalman_filter(z)``
  in its own file (:func:`gpsaccel.check.submission`), the ensemble NEES and its bounds
  (:mod:`~gpsaccel.assignments.calibration`);
* ``coop``: the Jacobians A, B, C (:func:`gpsaccel.check.jacobians`), the DT linearization
  (:func:`gpsaccel.check.dt_model`), an EKF on the course log (:mod:`~gpsaccel.assignments.coop`);
* ``ship``: the multirate update with the rows that arrived, what the report's zeroed gain costs
  on the student's voyage (:mod:`~gpsaccel.assignments.ship`).

:func:`generate` (``gpsaccel assignment NAME --out DIR``) runs ``otter assign`` (the student
notebook and otter's autograder zip for students' ``grader.check`` and Gradescope);
:func:`grade_notebook` grades one notebook: only in the sandbox, every score computed outside it
(:mod:`~gpsaccel.assignments.grading`).  A class (``gpsaccel grade DIR --assignment NAME``) is
graded by the class run one floor up, ``gpsaccel.classrun.grade``, one notebook at a time.
"""

from typing import TYPE_CHECKING

from gpsaccel import _lazy, registry

#: The package's own homework, each registered by its module ``gpsaccel.assignments.NAME`` when
#: imported, in the order they are listed (a new homework: its module, and one line here).
registry.provide("assignment", tuple(f"{__name__}.{name}" for name in
                                     ("calibration", "coop", "ship", "tracker")))

if TYPE_CHECKING:  # for mypy and editors; at run time each name loads on first use (_lazy)
    from gpsaccel.assignments.generate import Generated, generate, master_notebook, questions
    from gpsaccel.assignments.grading import Grade, grade_notebook

__all__ = ["Generated", "Grade", "generate", "grade_notebook", "master_notebook", "questions"]

# the homework modules (``gpsaccel.assignments.calibration``, read by the registry) import this
# package first: it must not import otter's generator or the grader for that.
__getattr__, __dir__ = _lazy.attach(
    __name__, attributes={"generate": ("Generated", "generate", "master_notebook", "questions"),
                          "grading": ("Grade", "grade_notebook")})
