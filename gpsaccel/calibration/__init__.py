"""GPS-aided accelerometer calibration (reports 000, 001, 003).

* :mod:`~gpsaccel.calibration.model`: ``CalibrationModel`` (Φ, Γ, H, V, W, M0), Φ(Δt), Γ(Δt), the
  state names and units;
* :mod:`~gpsaccel.calibration.reports`: each report's model, truth and presets;
* :mod:`~gpsaccel.calibration.simulation`: one realization (error-model or kinematic truth);
* :mod:`~gpsaccel.calibration.montecarlo`: the reports' Monte Carlo as arrays, and its table;
* :mod:`~gpsaccel.calibration.compare`: two filter implementations side by side;
* :mod:`~gpsaccel.calibration.mistakes`: known mistakes as filters (used by errata and the checker);
* :mod:`~gpsaccel.calibration.errata`: the reports' mistakes and their exact cost.
"""

from gpsaccel.calibration import compare, errata, mistakes, model, montecarlo, reports, simulation
from gpsaccel.calibration.model import CalibrationModel
from gpsaccel.calibration.montecarlo import MonteCarloResult, monte_carlo
from gpsaccel.calibration.simulation import Realization, simulate

__all__ = ["CalibrationModel", "MonteCarloResult", "Realization", "compare", "errata", "mistakes",
           "model", "monte_carlo", "montecarlo", "reports", "simulate", "simulation"]
