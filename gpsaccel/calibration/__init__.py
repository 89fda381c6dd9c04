"""GPS-aided accelerometer calibration (reports 000, 001, 003).

* :mod:`~gpsaccel.calibration.model`: ``CalibrationModel`` (Φ, Γ, H, V, W, M0), Φ(Δt), Γ(Δt), the
  state names and units;
* :mod:`~gpsaccel.calibration.reports`: each report's model, truth and presets;
* :mod:`~gpsaccel.calibration.simulation`: one realization (error-model or kinematic truth, named
  in :mod:`~gpsaccel.calibration.truths`, which imports nothing);
* :mod:`~gpsaccel.calibration.montecarlo`: the reports' Monte Carlo as arrays, and its table (a
  package: plan, random streams, reduction to sums, engine, statistics, verdicts);
* :mod:`~gpsaccel.calibration.compare`: any filters side by side against the exact answer on
  report 000's data (the core's :mod:`gpsaccel.kalman.compare` takes any linear model), and the
  conditioning sweeps (the forms it compares and the 50-digit exact answer are the core's, which
  run any linear model: :mod:`gpsaccel.kalman.factory`, :mod:`gpsaccel.kalman.exact`);
* :mod:`~gpsaccel.calibration.mistakes`: known mistakes as filters (used by errata and the checker);
* :mod:`~gpsaccel.calibration.errata`: the reports' mistakes and their exact cost.
"""

from typing import TYPE_CHECKING

from gpsaccel import _lazy

if TYPE_CHECKING:  # for mypy and editors; at run time each name loads on first use (_lazy)
    from gpsaccel.calibration import (
        compare,
        errata,
        mistakes,
        model,
        montecarlo,
        reports,
        simulation,
    )
    from gpsaccel.calibration.model import CalibrationModel
    from gpsaccel.calibration.montecarlo import MonteCarloResult, monte_carlo
    from gpsaccel.calibration.simulation import Realization, simulate

__all__ = ["CalibrationModel", "MonteCarloResult", "Realization", "compare", "errata", "mistakes",
           "model", "monte_carlo", "montecarlo", "reports", "simulate", "simulation"]

# ``from gpsaccel.calibration.model import CalibrationModel`` imports this package first: it must
# not import compare (mpmath) or errata for that.
__getattr__, __dir__ = _lazy.attach(
    __name__,
    submodules=("compare", "errata", "mistakes", "model", "montecarlo", "reports", "simulation"),
    attributes={"model": ("CalibrationModel",), "montecarlo": ("MonteCarloResult", "monte_carlo"),
                "simulation": ("Realization", "simulate")})
