r"""The tracker homework's own checks: the model matrices for the student's numbers.

The constant-velocity tracker of :mod:`gpsaccel.check.problems.tracker` (x = [p, v], a position
fix at 2 Hz).  Question 1 asks for Φ, Γ, Q, H, V, M0 at the student's propagation rate and noise levels
(:func:`variant_model`) and is checked by :func:`gpsaccel.assignments.linear.matrices_answer`
with the tracker's catalogue; question 2, the whole ``kalman_filter(z)``, by
:func:`gpsaccel.check.submission` with ``problem="tracker"``.  Both speak the checker's codes.
"""

from __future__ import annotations

from typing import cast

from gpsaccel import registry
from gpsaccel.assignments._answers import assert_report
from gpsaccel.assignments.linear import matrices_answer
from gpsaccel.check.linear import ModelProblem
from gpsaccel.check.problems.tracker import N_FIXES, TRACKER, model
from gpsaccel.check.report import Report
from gpsaccel.kalman.linear_model import LinearModel

#: The position fixes' rate (Hz): the same for every variant.
FIX_RATE_HZ = 2


def variant_model(rate_hz: int = 10, sigma_a: float = 0.3, sigma_p: float = 2.0) -> LinearModel:
    """The tracker propagated at ``rate_hz`` (a multiple of the 2 Hz fixes) with acceleration
    noise σ_a (m/s²) and fixes of σ_p (m); the defaults are
    :data:`gpsaccel.check.problems.tracker.TRACKER`'s."""
    if rate_hz % FIX_RATE_HZ:
        raise ValueError(f"rate_hz must be a multiple of {FIX_RATE_HZ} Hz, got {rate_hz!r}")
    dt, base = 1.0 / rate_hz, cast(ModelProblem, TRACKER).model
    return LinearModel(**model(dt, sigma_a, sigma_p), every=rate_hz // FIX_RATE_HZ,
                       n_epochs=N_FIXES, dt=dt, states=base.states,
                       measurements=base.measurements)


def check_matrices(variant: dict, **given: object) -> Report:
    """Question 1 for a test cell: AssertionError with the findings when a matrix is wrong."""
    return assert_report(matrices_answer(variant_model(**variant), given,
                                         "question 1: model matrices"))


# the homework, for `gpsaccel assignment` / `gpsaccel grade` (its master: assignments/tracker/)
registry.add_assignment("tracker", __name__, system="tracker", problem="tracker",
                        title="A constant-velocity tracker: its matrices and its filter")
