"""Report 003 (MAE 271A, 10,000-run Monte Carlo, MATLAB listing): figures 1-6.

The report's truth is the closed form of a(t) = 10 sin(2π·0.1·t) (``truth="kinematic"``).  Its
code builds Φ and Γ on the GPS interval and mixes up variances and standard deviations (see
:mod:`gpsaccel.calibration.errata`); the figures use the corrected model, filtered at 200 Hz by filterpy under
the multirate driver.  Figures 2-3 are one realization (seed ``seed``), 4-6 the ensemble.
"""

from __future__ import annotations

from collections.abc import Iterator

from gpsaccel import plots, registry
from gpsaccel.figures import ReportFigure
from gpsaccel.figures.runs import single_run

REPORT = "003"
TITLE = "Calibration of an accelerometer using GPS measurements (MAE 271A, 10,000-run Monte Carlo)"
DEFAULT_RUNS = 10_000

#: The figures the report lists (a lesson walks through each)
FIGURES = tuple(str(i) for i in range(1, 7))
registry.add_report("003", __name__, FIGURES, title=TITLE)


def figures(runs: int, seed: int) -> Iterator[ReportFigure]:
    model, run, res = single_run("003", seed)
    one = f" One realization, seed {seed}, a(t) = 10 sin(2π·0.1·t) m/s²."
    yield ReportFigure(REPORT, "01", "system-diagram",
                       "System diagram: the accelerometer is integrated, GPS minus the "
                       "integrated accelerometer is the filter's measurement, and the filter's "
                       "error estimate corrects the integrated solution.", plots.system_diagram())
    yield ReportFigure(REPORT, "02", "single-run-estimates",
                       "Estimates of a single run (+, at the GPS times) against the truth "
                       "(line): position, velocity, bias." + one,
                       plots.estimates_with_truth(run, res, title="Estimates from a single run"))
    yield ReportFigure(REPORT, "03", "single-run-errors",
                       "Errors of a single run with the filter's ±1σ: position, velocity, bias."
                       + one, plots.errors_with_sigma(run, res,
                                                      title="Errors of a single run with ±1σ"))
    yield from ensemble_figures(runs, seed)


def ensemble_figures(runs: int, seed: int) -> Iterator[ReportFigure]:
    from gpsaccel.figures._ensemble import ensemble_set

    yield from ensemble_set(REPORT, runs, seed, [("04", "ensemble-mean-error-sigma"),
                                                 ("05", "pave-minus-p"),
                                                 ("06", "orthogonality")])
