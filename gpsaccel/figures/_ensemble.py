"""The Monte Carlo figures of reports 000, 001 and 003, from one cached ensemble per problem.

The ensembles come from :func:`gpsaccel.figures.runs.report_ensemble` (cached there; reports
001 and 003 state one problem, so one ensemble serves both).
"""

from __future__ import annotations

from collections.abc import Iterator

from gpsaccel import plots
from gpsaccel.calibration.montecarlo import MonteCarloResult
from gpsaccel.figures import ReportFigure
from gpsaccel.figures.runs import report_ensemble


def _captions(mc: MonteCarloResult) -> dict[str, str]:
    n = f" N = {mc.n_runs:,} realizations, seed {mc.seed}, {mc.truth} truth."
    kin = (" With the closed-form truth e_ave is not zero: the dotted line is the mean error the "
           "Euler model's integration error predicts.") if mc.truth == "kinematic" else ""
    centred = (" Centred statistics: e_ave is subtracted before averaging, so the deterministic "
               "mean error of the closed-form truth drops out and this looks like the error-model "
               "truth's.") if mc.truth == "kinematic" else ""
    return {
        "ensemble-mean-error": "Ensemble-mean error e_ave of position, velocity and bias, with "
                               "±2 standard errors (2σ/√N) shaded." + kin + n,
        "ensemble-mean-error-sigma": "Ensemble-average error with the filter's ±σ (dashed) and "
                                     "±2σ/√N (shaded)." + kin + n,
        "pave-minus-p": "P_ave − P, the sample error covariance minus the filter's, element by "
                        "element, with ±2 standard errors of P_ave shaded." + centred + n,
        "pave-minus-p-lines": "P_ave − P, all nine elements over time (each in its own unit: "
                              "m², m²/s, ...)." + n,
        "pave-minus-p-normalised": "P_ave − P, all nine elements each divided by its own standard "
                                   "error (the companion of report 000's figure 7, where element "
                                   "(1,1) hides the rest; (i,j) and (j,i) coincide); a consistent "
                                   "filter stays within ±2 about 95 % of the time." + n,
        "orthogonality": "Orthogonality of the error and the estimate, (1/N) Σ (e − e_ave) x̂ᵀ, "
                         "nine elements, ±2 standard errors shaded." + centred + n,
    }


def ensemble_set(report: str, runs: int, seed: int,
                 wanted: list[tuple[str, str]], mc: MonteCarloResult | None = None
                 ) -> Iterator[ReportFigure]:
    """``report``'s Monte Carlo figures: ``wanted`` = [(number, kind), ...] with kinds
    ensemble-mean-error[-sigma], pave-minus-p[-lines|-normalised], orthogonality.  ``mc``: the
    ensemble, when the caller has computed it (else :func:`report_ensemble`)."""
    mc = report_ensemble(report, runs, seed) if mc is None else mc
    captions = _captions(mc)
    draw = {
        "ensemble-mean-error": lambda: plots.ensemble_mean_error(mc),
        "ensemble-mean-error-sigma": lambda: plots.ensemble_mean_error(mc, sigma=True),
        "pave-minus-p": lambda: plots.pave_minus_p(mc),
        "pave-minus-p-lines": lambda: plots.pave_minus_p(mc, grid=False),
        "pave-minus-p-normalised": lambda: plots.pave_minus_p(mc, normalised=True),
        "orthogonality": lambda: plots.orthogonality(mc),
    }
    for number, kind in wanted:
        slug = kind.removesuffix("-lines").removesuffix("-sigma")
        yield ReportFigure(report, number, slug, captions[kind], draw[kind]())
