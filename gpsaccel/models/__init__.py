"""System models in course notation (Φ, Γ, H, V, W, M0): one module per system.

* :mod:`~gpsaccel.models.calibration`: GPS-aided accelerometer calibration (reports 000, 001, 003).
* :mod:`~gpsaccel.models.ship`: the AAUSHIP ship, 9 states, monorate and multirate (report 004).
* :mod:`~gpsaccel.models.coop`: cooperative air/ground localization, nonlinear (report 002).
"""

from gpsaccel.models.calibration import CalibrationModel
from gpsaccel.models.coop import CoopModel
from gpsaccel.models.ship import ShipModel

__all__ = ["CalibrationModel", "CoopModel", "ShipModel"]
