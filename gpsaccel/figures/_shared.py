"""What several report figure modules (and ``gpsaccel run``) share: one ensemble, computed once.

``ensemble(10_000, 0, "error-model")`` is report 000's Monte Carlo on the default
:class:`~gpsaccel.models.calibration.CalibrationModel`; the first call runs it (about a second),
later calls with the same arguments return the same :class:`~gpsaccel.montecarlo.MonteCarloResult`
object.  Treat it as read-only: its arrays are shared by every caller.
"""

from __future__ import annotations

from functools import lru_cache

from gpsaccel.models.calibration import CalibrationModel
from gpsaccel.montecarlo import MonteCarloResult, monte_carlo


@lru_cache(maxsize=8)
def ensemble(runs: int, seed: int, truth: str) -> MonteCarloResult:
    """``monte_carlo(CalibrationModel(), runs, seed=seed, truth=truth, progress=False)``, cached.

    runs : ensemble size (≥ 2); seed : non-negative integer; truth : ``"error-model"`` or
    ``"kinematic"``.  Bad arguments raise ValueError naming them (and are not cached).
    """
    return monte_carlo(CalibrationModel(), runs, seed=seed, truth=truth, progress=False)
