"""Generic linear Kalman filtering, shared by every system of the course.

* :mod:`~gpsaccel.kalman.schedule`: which fast steps carry an update and which components arrive;
* :mod:`~gpsaccel.kalman.update`: the one Joseph update, the one epoch transition (Φⁿ, Σ ΦʲQΦʲᵀ)
  and the one stepping loop over a schedule, with an update hook;
* :mod:`~gpsaccel.kalman.factory`: the one place a filter object is built from a model's
  matrices (Φ, Q, H, V, x0, M0; B), for every form: the driver and each model's
  ``kalman_filter()`` build through it;
* :mod:`~gpsaccel.kalman.forms`: the forms' filter classes (standard update, filterpy's information
  and square-root filters adapted to the driver);
* :mod:`~gpsaccel.kalman.information`: the hand-written information-form filter;
* :mod:`~gpsaccel.kalman.multirate`: the driver ``run_multirate`` (any form, predicting at the fast
  rate and updating at the epochs), ``run_form``, and the result in course notation;
* :mod:`~gpsaccel.kalman.exact`: the same filter in 50-digit arithmetic (mpmath), the reference
  every form is measured against;
* :mod:`~gpsaccel.kalman.compare`: filters side by side against that exact answer;
* :mod:`~gpsaccel.kalman.epochs`: a linear filter at its epochs and its gains (one recursion for
  a whole stack of filters);
* :mod:`~gpsaccel.kalman.mistakes`: the one mechanism for a known mistake, for every system: an
  entry (code, title, message, hint) whose changes are applied to that system's ingredients;
* :mod:`~gpsaccel.kalman.linear_model`: ``LinearModel``, any linear problem an instructor
  describes by its matrices;
* :mod:`~gpsaccel.kalman.entries`: the known mistakes every system shares (σ for σ², Joseph's
  sign, V left out of S, z one epoch late, ...), one constructor per idea, applied through each
  system's ingredients;
* :mod:`~gpsaccel.kalman.linear_catalogue`: the known mistakes of any linear model, and
  :mod:`~gpsaccel.kalman.linear_messages` their texts (one table);
* :mod:`~gpsaccel.kalman.gain_sequence`: one gain sequence applied to a whole ensemble;
* :mod:`~gpsaccel.kalman.consistency`: NEES, NIS, χ² bounds, z-scores and verdicts.

This package imports no system (calibration, ship, coop) and nothing above it.
"""

from typing import TYPE_CHECKING

from gpsaccel import _lazy

if TYPE_CHECKING:  # for mypy and editors; at run time each name loads on first use (_lazy)
    from gpsaccel.kalman.information import InformationFilter
    from gpsaccel.kalman.multirate import MultirateResult, run_multirate
    from gpsaccel.kalman.schedule import Schedule

__all__ = ["InformationFilter", "MultirateResult", "Schedule", "run_multirate"]

# every system imports ``gpsaccel.kalman.schedule``, which imports this package first: it must not
# import scipy.linalg (the information form) for that.
__getattr__, __dir__ = _lazy.attach(
    __name__, attributes={"information": ("InformationFilter",),
                          "multirate": ("MultirateResult", "run_multirate"),
                          "schedule": ("Schedule",)})
