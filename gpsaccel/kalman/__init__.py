"""Generic linear Kalman filtering, shared by every system of the course.

* :mod:`~gpsaccel.kalman.schedule`: which fast steps carry an update and which components arrive;
* :mod:`~gpsaccel.kalman.update`: the one Joseph update, the one epoch transition (Φⁿ, Σ ΦʲQΦʲᵀ)
  and the one stepping loop over a schedule, with an update hook;
* :mod:`~gpsaccel.kalman.multirate`: ``run_multirate`` (filterpy or the information form) and its
  result in course notation;
* :mod:`~gpsaccel.kalman.information`: the hand-written information-form filter;
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
