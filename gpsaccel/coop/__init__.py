"""Cooperative air/ground localization (report 002): a UGV and a UAV, nonlinear.

* :mod:`~gpsaccel.coop.model`: f, h, the Jacobians A, B, C, the DT linearization, the truth;
* :mod:`~gpsaccel.coop.filters`: one vectorised filter, the LKF, EKF and UKF through its
  hooks (filterpy is the tests' oracle), with :mod:`~gpsaccel.coop.unscented` (the UKF's sigma
  points) and :mod:`~gpsaccel.coop.result` (what a run returns, its NEES and NIS);
* :mod:`~gpsaccel.coop.mistakes`: the homework's known mistakes as runnable filters;
* :mod:`~gpsaccel.coop.montecarlo`: the NEES/NIS truth-model tests and the Q tuning.
"""

from typing import TYPE_CHECKING

from gpsaccel import _lazy

if TYPE_CHECKING:  # for mypy and editors; at run time each name loads on first use (_lazy)
    from gpsaccel.coop import filters, mistakes, model, montecarlo, result, unscented
    from gpsaccel.coop.model import CoopModel

__all__ = ["CoopModel", "filters", "mistakes", "model", "montecarlo", "result", "unscented"]

# a notebook's ``from gpsaccel.coop.model import course_ydata`` imports this package first: it
# must not import the filters (filterpy, scipy.stats) for that.
__getattr__, __dir__ = _lazy.attach(
    __name__, submodules=("filters", "mistakes", "model", "montecarlo", "result", "unscented"),
    attributes={"model": ("CoopModel",)})
