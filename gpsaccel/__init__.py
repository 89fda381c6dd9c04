"""gpsaccel: Kalman filtering lessons built on filterpy.

The calibration core (reports 000, 001, 003)::

    import numpy as np, gpsaccel
    model = gpsaccel.CalibrationModel()             # report 000's numbers
    run = gpsaccel.simulate(model, np.random.default_rng(0))
    result = gpsaccel.run_multirate(model, run.z)   # filterpy; method="information" for the other form
    mc = gpsaccel.monte_carlo(model, 10_000)        # the reports' Monte Carlo, as arrays
    print(mc.consistency())                         # each statistic against its sampling error
"""

from typing import TYPE_CHECKING

from gpsaccel import _lazy
from gpsaccel._version import __version__ as __version__  # the one place it is written

if TYPE_CHECKING:  # the names below, for mypy and editors; at run time they load on first use
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

# ``import gpsaccel`` imports nothing else (no numpy, filterpy, scipy or matplotlib; every CLI
# call, test worker and sandbox box pays for this line): each name above, and each sub-package
# (a lesson's ``gpsaccel.check.model_matrices(...)`` after a bare ``import gpsaccel``), is
# imported when first read (:mod:`gpsaccel._lazy`).
__getattr__, __dir__ = _lazy.attach(
    __name__,
    submodules=("calibration", "check", "coop", "figures", "kalman", "lessons", "plots", "ship"),
    attributes={
        "calibration.model": ("CalibrationModel",),
        "calibration.montecarlo": ("MonteCarloResult", "monte_carlo"),
        "calibration.simulation": ("Realization", "simulate"),
        "coop.model": ("CoopModel",),
        "kalman.multirate": ("MultirateResult", "run_multirate"),
        "kalman.schedule": ("Schedule",),
        "kalman.update": ("NumericalWarning",),
        "ship.model": ("ShipModel",),
    })
