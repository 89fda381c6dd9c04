"""The AAUSHIP ship (report 004): 9 states, monorate and multirate GPS/IMU filtering.

* :mod:`~gpsaccel.ship.model`: ``ShipModel`` (Φ, Γ, H, V, W, M0, B), states and units;
* :mod:`~gpsaccel.ship.plan`: the racetrack thrust/torque input;
* :mod:`~gpsaccel.ship.simulation`: a voyage or an ensemble of voyages;
* :mod:`~gpsaccel.ship.zeroed_gain`: the report's full-gain-then-zero-columns update;
* :mod:`~gpsaccel.ship.mistakes`: the homework's known mistakes as runnable filters;
* :mod:`~gpsaccel.ship.comparison`: the four multirate filters compared by Monte Carlo.
"""

from gpsaccel.ship import comparison, mistakes, model, plan, simulation, zeroed_gain
from gpsaccel.ship.model import ShipModel

__all__ = ["ShipModel", "comparison", "mistakes", "model", "plan", "simulation", "zeroed_gain"]
