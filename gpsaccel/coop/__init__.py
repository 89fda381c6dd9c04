"""Cooperative air/ground localization (report 002): a UGV and a UAV, nonlinear.

* :mod:`~gpsaccel.coop.model`: f, h, the Jacobians A, B, C, the DT linearization, the truth;
* :mod:`~gpsaccel.coop.filters`: the LKF, EKF and UKF on filterpy, and their vectorised twins;
* :mod:`~gpsaccel.coop.mistakes`: the homework's known mistakes as runnable filters;
* :mod:`~gpsaccel.coop.montecarlo`: the NEES/NIS truth-model tests and the Q tuning.
"""

from gpsaccel.coop import filters, mistakes, model, montecarlo
from gpsaccel.coop.model import CoopModel

__all__ = ["CoopModel", "filters", "mistakes", "model", "montecarlo"]
