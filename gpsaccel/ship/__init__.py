"""The AAUSHIP ship (report 004): 9 states, monorate and multirate GPS/IMU filtering.

* :mod:`~gpsaccel.ship.model`: ``ShipModel`` (Φ, Γ, H, V, W, M0, B), states and units;
* :mod:`~gpsaccel.ship.plan`: the racetrack thrust/torque input;
* :mod:`~gpsaccel.ship.simulation`: a voyage or an ensemble of voyages;
* :mod:`~gpsaccel.ship.zeroed_gain`: the report's full-gain-then-zero-columns update;
* :mod:`~gpsaccel.ship.mistakes`: the homework's known mistakes as runnable filters;
* :mod:`~gpsaccel.ship.comparison`: the four multirate filters compared by Monte Carlo.
"""

from typing import TYPE_CHECKING

from gpsaccel import _lazy

if TYPE_CHECKING:  # for mypy and editors; at run time each name loads on first use (_lazy)
    from gpsaccel.ship import comparison, mistakes, model, plan, simulation, zeroed_gain
    from gpsaccel.ship.model import ShipModel

__all__ = ["ShipModel", "comparison", "mistakes", "model", "plan", "simulation", "zeroed_gain"]

# a notebook's ``from gpsaccel.ship.simulation import simulate_ship`` imports this package first:
# it must not import the comparison and the mistakes' filters for that.
__getattr__, __dir__ = _lazy.attach(
    __name__,
    submodules=("comparison", "mistakes", "model", "plan", "simulation", "zeroed_gain"),
    attributes={"model": ("ShipModel",)})
