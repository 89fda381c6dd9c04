"""gpsaccel: Kalman filtering lessons built on filterpy.

The calibration core (reports 000, 001, 003)::

    import numpy as np, gpsaccel
    model = gpsaccel.CalibrationModel()             # report 000's numbers
    run = gpsaccel.simulate(model, np.random.default_rng(0))
    result = gpsaccel.run_multirate(model, run.z)   # filterpy; method="information" for the other form
    mc = gpsaccel.monte_carlo(model, 10_000)        # the reports' Monte Carlo, as arrays
    print(mc.consistency())                         # each statistic against its sampling error
"""

from gpsaccel._version import __version__ as __version__  # the one place it is written
from gpsaccel.calibration.model import CalibrationModel
from gpsaccel.calibration.montecarlo import MonteCarloResult, monte_carlo
from gpsaccel.calibration.simulation import Realization, simulate
from gpsaccel.coop.model import CoopModel
from gpsaccel.kalman.multirate import MultirateResult, run_multirate
from gpsaccel.kalman.schedule import Schedule
from gpsaccel.kalman.update import NumericalWarning
from gpsaccel.ship.model import ShipModel

__all__ = [
    "CalibrationModel",
    "CoopModel",
    "MonteCarloResult",
    "MultirateResult",
    "NumericalWarning",
    "Realization",
    "Schedule",
    "ShipModel",
    "monte_carlo",
    "run_multirate",
    "simulate",
]

#: Sub-packages reachable as attributes after a bare ``import gpsaccel`` (a lesson's
#: ``gpsaccel.check.model_matrices(...)`` typed as given), imported on first use.
_LAZY = ("calibration", "check", "coop", "figures", "kalman", "lessons", "plots", "ship")


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        return importlib.import_module(f"gpsaccel.{name}")
    raise AttributeError(f"module 'gpsaccel' has no attribute {name!r}")
