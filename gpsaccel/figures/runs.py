"""The runs the report figures draw: the single run of a report and each Monte Carlo ensemble,
computed once, and shared by several report modules and ``gpsaccel run`` (which prints from the
same results it draws, so the command imports this module: it is not private to the figures).

``ensemble(10_000, 0, "error-model")`` is report 000's Monte Carlo on the default
:class:`~gpsaccel.calibration.model.CalibrationModel`; the first call runs it (about a second),
later calls with the same arguments return the same :class:`~gpsaccel.calibration.montecarlo.MonteCarloResult`
object.  Treat it as read-only: its arrays are shared by every caller.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from gpsaccel.calibration.model import CalibrationModel
from gpsaccel.calibration.montecarlo import MonteCarloResult, monte_carlo
from gpsaccel.calibration.reports import REPORT_TRUTH, report_model
from gpsaccel.calibration.simulation import Realization, simulate
from gpsaccel.kalman.multirate import MultirateResult, run_multirate


@lru_cache(maxsize=8)
def ensemble(runs: int, seed: int, truth: str, problem: str = "000") -> MonteCarloResult:
    """``monte_carlo(report_model(problem), runs, seed=seed, truth=truth, progress=False)``, cached.

    runs : ensemble size (≥ 2); seed : non-negative integer; truth : ``"error-model"`` or
    ``"kinematic"``; problem : the report whose (corrected) model to use, ``"000"`` (the default
    model, a = 10 sin(0.1 t)) or ``"001"`` (a = 10 sin(2π·0.1·t), also report 003's).  Bad
    arguments raise ValueError naming them (and are not cached).
    """
    return monte_carlo(report_model(problem), runs, seed=seed, truth=truth, progress=False)


def report_ensemble(report: str, runs: int, seed: int) -> MonteCarloResult:
    """The ensemble behind ``report``'s figures: its model and its truth (001 and 003 share one)."""
    problem = "000" if report == "000" else "001"  # 001 and 003 state the same problem
    report_model(report)  # ValueError naming the reports for anything else
    return ensemble(runs, seed, REPORT_TRUTH[report], problem)


def single_run(report: str, seed: int) -> tuple[CalibrationModel, Realization, MultirateResult]:
    """(model, realization, filterpy result) of ``report``'s single run: its corrected model and
    its truth (error-model for 000, closed-form for 001 and 003), ``default_rng(seed)``."""
    model = report_model(report)
    run = simulate(model, np.random.default_rng(seed), truth=REPORT_TRUTH[report])
    return model, run, run_multirate(model, run.z)
