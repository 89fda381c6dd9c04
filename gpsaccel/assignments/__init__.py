"""Ready-to-hand-out homework, graded with otter-grader (``pip install gpsaccel[assignments]``).

Three homeworks on the course reports, each a master notebook in otter's assign format under
``assignments/NAME/`` (solutions and hidden tests only there):

* ``calibration``: Φ, Γ, H, V, W, M0 (:func:`gpsaccel.check.model_matrices`), a
  ``kalman_filter(z)`` (:func:`gpsaccel.check.submission`), a Monte Carlo NEES
  (:mod:`~gpsaccel.assignments.calibration`);
* ``coop``: the Jacobians A, B, C and the DT linearization by finite differences of the coop model,
  an EKF on the course log (:mod:`~gpsaccel.assignments.coop`);
* ``ship``: the multirate update with the rows that arrived, against the report's zeroed gain
  (:mod:`~gpsaccel.assignments.ship`).

:func:`generate` (``gpsaccel assignment NAME --out DIR``) runs ``otter assign``;
:func:`grade` (``gpsaccel grade DIR --assignment NAME``) grades a folder of notebooks with
``otter run``, one isolated job per notebook, in parallel, and writes ``grades.csv`` and feedback.
"""

from gpsaccel.assignments.generate import ASSIGNMENTS, Generated, generate, master_notebook, questions
from gpsaccel.assignments.grading import Grade, grade, grade_one

__all__ = ["ASSIGNMENTS", "Generated", "Grade", "generate", "grade", "grade_one",
           "master_notebook", "questions"]
