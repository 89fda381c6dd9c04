"""Report 000's exact answer: the core's mpmath filter (:mod:`gpsaccel.kalman.exact`), which runs
any linear model; these names stay importable here for the calibration lessons and tools."""

from gpsaccel.kalman.exact import (
    DIGITS,
    Errors,
    ExactResult,
    epoch_transition_exact,
    errors,
    exact_filter,
    min_eigenvalue_exact,
)

__all__ = ["DIGITS", "Errors", "ExactResult", "epoch_transition_exact", "errors", "exact_filter",
           "min_eigenvalue_exact"]
