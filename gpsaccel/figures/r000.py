"""Report 000 (MAE 271A, 10,000-run Monte Carlo): figures 1-7.

Figures 1-6 are one realization (seed ``seed``) filtered by filterpy under the multirate driver,
with the error-model truth as report 000's code builds it.  Figure 7 is the Monte Carlo ensemble
(``runs`` realizations, :func:`gpsaccel.figures.runs.ensemble`), drawn like the report: the
nine elements of P_ave − P on one axes; 7b (not in the report) the same nine elements each in
units of its own standard error, so that more than element (1,1) is visible.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from gpsaccel import plots, registry
from gpsaccel.calibration.montecarlo import MonteCarloResult
from gpsaccel.figures import ReportFigure
from gpsaccel.figures.runs import single_run

TITLE = "GPS-aided accelerometer calibration (MAE 271A, 10,000-run Monte Carlo)"
DEFAULT_RUNS = 10_000

#: The figures the report lists (a lesson walks through each); a zoom of 7, 7b, is drawn too
FIGURES = ("1", "2", "3", "3b", "4", "5", "6", "7")
registry.add_report("000", __name__, FIGURES, title=TITLE)


def figures(runs: int, seed: int, single: tuple | None = None,
            mc: MonteCarloResult | None = None) -> Iterator[ReportFigure]:
    """Report 000's figures; ``single`` (:func:`single_run`'s (model, run, result)) and ``mc``
    (the ensemble) when the caller has computed them (``gpsaccel run``), else computed here."""
    model, run, res = single_run("000", seed) if single is None else single
    e = run.x_gps - res.x_hat
    sd = res.sigma
    names = [("01", "position-error", "Position error p − p̂ with ±1σ", "m"),
             ("02", "velocity-error", "Velocity error v − v̂ with ±1σ", "m/s"),
             ("03", "bias-error", "Bias error b − b̂ with ±1σ", "m/s²")]
    for i, (num, slug, cap, unit) in enumerate(names):
        fig = plots.error_band(res.t_gps, e[:, i], sd[:, i], label=cap.split(" with")[0],
                               unit=unit, title=cap)
        yield ReportFigure("000", num, slug, cap + f" (one realization, seed {seed}).", fig)
    last = res.t_gps >= res.t_gps[-1] - 10.0
    fig = plots.error_band(res.t_gps[last], e[last, 2], sd[last, 2], label="b − b̂", unit="m/s²",
                           title="Bias error, last 10 s")
    yield ReportFigure("000", "03b", "bias-error-zoom",
                       "Bias error b − b̂ with ±1σ, the last 10 s zoomed. One run's error may sit "
                       "outside ±1σ for seconds: a third of a consistent filter's errors fall "
                       "outside, and the bias error changes slowly, so it stays out for many fixes "
                       "in a row.", fig)
    gps = run.gps_steps
    series = [("04", "position-estimate", "Position estimate p̂ = p_c + δp̂ against the truth",
               run.p, run.p_c[gps] + res.x_hat[:, 0], "position p", "m"),
              ("05", "velocity-estimate", "Velocity estimate v̂ = v_c + δv̂ against the truth",
               run.v, run.v_c[gps] + res.x_hat[:, 1], "velocity v", "m/s"),
              ("06", "bias-estimate", "Bias estimate b̂ against the true bias",
               np.full_like(run.t, run.b), res.x_hat[:, 2], "bias b", "m/s²")]
    for num, slug, cap, truth, est, q, unit in series:
        fig = plots.estimate_vs_truth(run.t, truth, res.t_gps, est, quantity=q, unit=unit,
                                      title=cap)
        yield ReportFigure("000", num, slug, cap + f" (seed {seed}).", fig)
    from gpsaccel.figures._ensemble import ensemble_set

    yield from ensemble_set("000", runs, seed, [("07", "pave-minus-p-lines"),
                                                ("07b", "pave-minus-p-normalised")], mc)
