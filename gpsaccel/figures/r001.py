"""Report 001 (MAE 271A, 5,000-run Monte Carlo): figures 1-12.

The report's truth is the closed form of a(t) = 10 sin(2π·0.1·t) (``truth="kinematic"``); its
printed Φ₁₃, M0 and W are wrong (see :mod:`gpsaccel.calibration.errata`), so the figures use the corrected
model :func:`gpsaccel.calibration.errata.report_model` ("001").  Figures 1-10a are one realization (seed
``seed``) filtered by filterpy under the multirate driver; 10b-12 the Monte Carlo ensemble.  The
report numbers two different figures 10; they are 10a (gains) and 10b (ensemble-mean error) here.
"""

from __future__ import annotations

from collections.abc import Iterator

from gpsaccel import plots, registry
from gpsaccel.figures import ReportFigure
from gpsaccel.figures.runs import single_run

REPORT = "001"
TITLE = "Calibration of an accelerometer using GPS measurements (MAE 271A, 5,000-run Monte Carlo)"
DEFAULT_RUNS = 5_000

#: The figures the report lists (a lesson walks through each); its two figures 10
#: are drawn as 10a (the gains) and 10b (the ensemble average)
FIGURES = tuple(str(i) for i in range(1, 13))
registry.add_report("001", __name__, FIGURES, title=TITLE)


def figures(runs: int, seed: int) -> Iterator[ReportFigure]:
    model, run, res = single_run("001", seed)
    one = f" One realization, seed {seed}, a(t) = 10 sin(2π·0.1·t) m/s²."

    def fig(number: str, slug: str, caption: str, figure) -> ReportFigure:
        return ReportFigure(REPORT, number, slug, caption, figure)

    yield fig("01", "truth", "True acceleration, velocity and position (closed form)." + one,
              plots.truth_kinematics(run))
    yield fig("02", "accelerometer-minus-truth",
              "Accelerometer-integrated minus truth, p_c − p and v_c − v: the bias integrated "
              "once and twice, plus the integrated noise." + one, plots.accelerometer_drift(run))
    yield fig("03", "gps-minus-accelerometer",
              "GPS minus accelerometer-integrated position and velocity: the filter's "
              "measurement z at 5 Hz." + one, plots.gps_minus_accelerometer(run))
    yield fig("04", "gps-noise", "GPS minus truth: the GPS noise η, σ = 1 m and 0.04 m/s." + one,
              plots.gps_noise(run))
    yield fig("05", "truth-vs-gps-minus-accelerometer",
              "Truth minus accelerometer (δp, δv, line) against GPS minus accelerometer (z, dots)."
              + one, plots.gps_minus_accelerometer(run, with_truth=True))
    yield fig("06", "error-comparison",
              "|Error| of the accelerometer alone, of the GPS alone and of the filter's estimate, "
              "with the filter's σ (log scale)." + one, plots.error_comparison(run, res))
    yield fig("07", "bias-estimate", "Bias estimate b̂ against the actual bias." + one,
              plots.estimates_with_truth(run, res, states=(2,),
                                         title="Bias estimate and actual bias"))
    yield fig("08", "position-velocity-errors",
              "Position and velocity errors p − p̂, v − v̂ with the filter's ±σ." + one,
              plots.errors_with_sigma(run, res, states=(0, 1),
                                      title="Position and velocity errors with ±σ"))
    yield fig("09", "bias-error", "Accelerometer bias error b − b̂ with the filter's ±σ." + one,
              plots.errors_with_sigma(run, res, states=(2,), title="Bias error with ±σ"))
    yield fig("10a", "gains", "Kalman gains K over time (the report's first figure 10); they "
              "settle within a few seconds." + one, plots.gains(res))
    yield from ensemble_figures(runs, seed)


def ensemble_figures(runs: int, seed: int) -> Iterator[ReportFigure]:
    from gpsaccel.figures._ensemble import ensemble_set

    yield from ensemble_set(REPORT, runs, seed, [("10b", "ensemble-mean-error"),
                                                 ("11", "pave-minus-p"),
                                                 ("12", "orthogonality")])
