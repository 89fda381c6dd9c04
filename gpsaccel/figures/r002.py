"""Report 002 (ASEN 5044, cooperative air/ground localization): figures 1-19, and the UKF.

Figures 1-5 are the linearization study of part 1c (the report's perturbation
δx0 = [0, 1, 0, 0, 0, 0.1]); 6-15 one Monte Carlo truth set (``runs`` runs from ``seed``, run 0 the
"typical" one) filtered by the LKF, the EKF and the UKF with their tuned Q; 16-19 the course's
100-second log.  Sub-figures with letters go beyond the report: 8b how far the truth wanders from
the nominal (why the LKF fails), 14b/15b the EKF with Q = Qtrue, 14c/15c the UKF, 18b/19b the UKF
on the log, 19c the NIS of the three filters on the log.

One module past 500 lines, as each report's figures are one module (r000-r004): the nineteen
figures share one Monte Carlo set, filtered on demand (:class:`_MonteCarlo`), and the log's runs.
"""

from __future__ import annotations

from collections.abc import Collection, Iterator, Mapping

import numpy as np
from matplotlib.figure import Figure

from gpsaccel import _validation as _v
from gpsaccel import plots, registry
from gpsaccel.coop.filters import FilterResult, run_batch, run_filter, tuned_q
from gpsaccel.coop.model import (
    MEASUREMENTS,
    STATES,
    CoopModel,
    Truth,
    h,
    state_residual,
    wrap_angle,
)
from gpsaccel.coop.montecarlo import ConsistencyRun, consistency_test, truth_runs
from gpsaccel.figures import ReportFigure

TITLE = "Cooperative air/ground localization: LKF, EKF and UKF with NEES/NIS tests (ASEN 5044)"
#: The report's EKF NEES/NIS used 100 runs (its LKF 50).
DEFAULT_RUNS = 100

#: The figures the report lists (a lesson walks through each)
FIGURES = tuple(str(i) for i in range(1, 20))
registry.add_report("002", __name__, FIGURES, title=TITLE)

#: Report 002's initial perturbation for the linearization study (part 1c).
DX0 = np.array([0.0, 1.0, 0.0, 0.0, 0.0, 0.1])
S = plots.STYLE
NAMES = {"lkf": "LKF", "ekf": "EKF", "ukf": "UKF", "ekf-qtrue": "EKF, Q = Qtrue"}
#: The Monte Carlo set's filters, in the order of their figures (06-09, 10-15, 14b/15b, 14c/15c).
MONTE_CARLO = ("lkf", "ekf", "ekf-qtrue", "ukf")


def _breaks(v: np.ndarray, unit: str) -> np.ndarray:
    """A copy for line plots with NaN where a wrapped angle jumps across ±π (no vertical lines)."""
    v = np.array(v, dtype=float, copy=True)
    if unit == "rad":
        jump = np.abs(np.diff(v)) > np.pi
        v[1:][jump] = np.nan
    return v


def _no_roundoff_zoom(ax) -> None:
    """Keep a nearly constant curve from being zoomed into its rounding noise."""
    lo, hi = ax.get_ylim()
    c = 0.5 * (lo + hi)
    if hi - lo < 1e-6 * max(1.0, abs(c)):
        half = max(0.1 * abs(c), 0.1)
        ax.set_ylim(c - half, c + half)
    ax.ticklabel_format(axis="y", useOffset=False)


def states_figure(t: np.ndarray, series: list[tuple[np.ndarray, str, dict]], title: str,
                  quantity: str = "") -> Figure:
    """The six states in a 3 x 2 grid, UGV left, UAV right: series = [(x (K,6), label, style)]."""
    fig = plots.figure((10.0, 7.5))
    axs = fig.subplots(3, 2, sharex=True)
    for i, (name, unit) in enumerate(STATES):
        ax = axs[i % 3, i // 3]
        for values, label, style in series:
            ax.plot(t, _breaks(values[:, i], unit), label=label, **style)
        plots.finish(ax, "UGV" if i == 0 else "UAV" if i == 3 else "",
                     "time (s)" if i % 3 == 2 else "", f"{quantity}{name} ({unit})",
                     legend=i == 0)
        _no_roundoff_zoom(ax)
    fig.suptitle(title)
    return fig


def measurements_figure(t: np.ndarray, series: list[tuple[np.ndarray, str, dict]],
                        title: str) -> Figure:
    """The five measurements stacked: series = [(y (K,5), label, style)]."""
    fig, axs = plots.panels(5, title=title, height=1.6)
    for i, (name, unit) in enumerate(MEASUREMENTS):
        for values, label, style in series:
            axs[i].plot(t, _breaks(values[:, i], unit), label=label, **style)
        plots.finish(axs[i], "", "time (s)" if i == 4 else "", f"{name.split(' ')[0]} ({unit})",
                     legend=i == 0)
    return fig


def vehicle_figure(t: np.ndarray, states: tuple[int, int, int], est: np.ndarray,
                   sigma: np.ndarray, title: str, truth: np.ndarray | None = None,
                   measured: np.ndarray | None = None,
                   reference: np.ndarray | None = None) -> Figure:
    """One vehicle: estimate ±2σ (and the truth) left; error ±2σ right when the truth is known.

    Without a truth, ``reference`` (e.g. the nominal x*) draws x̂ − reference ±2σ on the right,
    where the band is visible at all (σ ~ 1 m against a 200 m track).
    """
    ncol = 1 if truth is None and reference is None else 2
    fig = plots.figure((5.5 * ncol, 7.0))
    axs = fig.subplots(3, ncol, sharex=True, squeeze=False)
    for row, i in enumerate(states):
        name, unit = STATES[i]
        ax = axs[row, 0]
        lo, hi = est[:, i] - 2 * sigma[:, i], est[:, i] + 2 * sigma[:, i]
        ax.fill_between(t, _breaks(lo, unit), _breaks(hi, unit), color=S["band"], alpha=0.3,
                        lw=0, label="estimate ± 2σ")
        if measured is not None and i in (3, 4):
            ax.plot(t, measured[:, i], ".", color=S["measurement"], ms=2, label="GPS")
        if truth is not None:
            ax.plot(t, _breaks(truth[:, i], unit), color=S["truth"], lw=1.0, label="truth")
        ax.plot(t, _breaks(est[:, i], unit), color=S["estimate"], lw=0.9, label="estimate")
        plots.finish(ax, "", "time (s)" if row == 2 else "", f"{name} ({unit})", legend=row == 0)
        if truth is not None:
            ax = axs[row, 1]
            err = truth[:, i] - est[:, i]
            if unit == "rad":
                err = wrap_angle(err)
            ax.plot(t, _breaks(err, unit), color=S["error"], lw=0.9, label="error")
            ax.plot(t, 2 * sigma[:, i], color=S["bound"], ls="--", lw=1.0, label="±2σ (filter)")
            ax.plot(t, -2 * sigma[:, i], color=S["bound"], ls="--", lw=1.0)
            plots.finish(ax, "", "time (s)" if row == 2 else "", f"{name} error ({unit})",
                         legend=row == 0)
        elif reference is not None:
            ax = axs[row, 1]
            d = est[:, i] - reference[:, i]
            if unit == "rad":
                d = wrap_angle(d)
            ax.fill_between(t, _breaks(d - 2 * sigma[:, i], unit), _breaks(d + 2 * sigma[:, i], unit),
                            color=S["band"], alpha=0.4, lw=0, label="±2σ")
            ax.plot(t, _breaks(d, unit), color=S["estimate"], lw=0.9, label="x̂ − x* (nominal)")
            plots.finish(ax, "", "time (s)" if row == 2 else "", f"{name} − nominal ({unit})",
                         legend=row == 0)
    fig.suptitle(title)
    return fig


def linearization_study(model: CoopModel, dx0: np.ndarray = DX0) -> dict[str, np.ndarray]:
    """Nominal, the linearized DT perturbation run and the full nonlinear run from x0 + δx0."""
    xn = model.nominal()
    dx, dy = model.linearized_simulation(dx0, xn)
    full = model.nominal(model.x0 + dx0)
    return {"t": model.t, "nominal": xn, "dx": dx, "x_lin": xn + dx, "y_lin": h(xn) + dy,
            "x_full": full, "y_full": h(full), "dx_full": state_residual(full, xn)}


_NIS_NOTE = (" It looks like figure 15 (tuned Q): S = HMHᵀ + R hardly changes with this Q, because "
             "the range and GPS rows are about 98 % R (σ 8 m and 6 m) and the bearing rows depend "
             "on the heading uncertainty, which the tuning leaves alone; only NEES, which needs the "
             "truth, shows that Q = Qtrue is overconfident.")
#: The report's LKF NEES/NIS (figures 8-9) used 50 runs, its EKF's 100.
LKF_RUNS = 50


def monte_carlo(model: CoopModel, runs: int, seed: int) -> dict[str, ConsistencyRun]:
    """The LKF, EKF, UKF (tuned Q) and the EKF with Q = Qtrue on one truth set.

    The LKF sees the first ``min(runs, LKF_RUNS)`` runs of the set, as the report's figures 8-9.
    """
    out = _MonteCarlo(model, truth_runs(model, runs, seed))
    for m in ("lkf", "ekf", "ukf", "ekf-qtrue"):
        out[m]
    return out


class _MonteCarlo(dict):
    """:func:`monte_carlo`'s filters, each run when first asked for: a lesson that stops after
    figure 09 (10b) runs the LKF alone, not the EKFs and the UKF (most of its Run All;
    benchmarks/lessons.py measures it).  Every
    filter sees the given truth, so the order they run in changes no number.

    With an ``executor`` the four filters are submitted to it at once (one task each) and each
    is awaited when first asked for: the figures are drawn here while the pool filters (a lesson
    that draws them all, 11 and 11b, on two cores).  The numbers are those of a serial run."""

    def __init__(self, model: CoopModel, truth: Truth, executor: object = None,
                 filters: tuple[str, ...] = MONTE_CARLO,
                 done: Mapping[str, ConsistencyRun] | None = None) -> None:
        super().__init__()
        self.model, self.truth = model, truth
        self.update(_checked_done(model, truth, done or {}))
        self.futures = {} if executor is None else {
            m: executor.submit(_filter, model, m, truth)  # type: ignore[attr-defined]
            for m in dict.fromkeys(_v.choice("filters", m, MONTE_CARLO) for m in filters)
            if m not in self}

    def __missing__(self, m: str) -> ConsistencyRun:
        future = self.futures.get(m)
        self[m] = run = _filter(self.model, m, self.truth) if future is None else future.result()
        return run


def _filter(model: CoopModel, m: str, truth: Truth) -> ConsistencyRun:
    """One of :class:`_MonteCarlo`'s filters on ``truth`` (the LKF on its first LKF_RUNS runs);
    module-level, so a process pool can run it."""
    if m == "lkf":
        truth = _lkf_truth(truth)
    return consistency_test(model, m.split("-")[0], _q_of(model, m), truth=truth, keep=True)


def _lkf_truth(truth: Truth) -> Truth:
    return Truth(truth.t, truth.x[:LKF_RUNS], truth.y[:LKF_RUNS])


def _q_of(model: CoopModel, m: str) -> np.ndarray | None:
    return model.Qtrue if m == "ekf-qtrue" else None


def _checked_done(model: CoopModel, truth: Truth, done: Mapping[str, ConsistencyRun]
                  ) -> dict[str, ConsistencyRun]:
    """``done`` (filters the caller ran already), each checked to be what :func:`_filter` would
    compute: the same method and Q, its result and truth kept, on this very truth set."""
    out = {}
    for m, run in done.items():
        m = _v.choice("done", m, MONTE_CARLO)
        x = (_lkf_truth(truth) if m == "lkf" else truth).x
        Q = _q_of(model, m)
        Q = tuned_q(m.split("-")[0], model) if Q is None else Q
        if not (isinstance(run, ConsistencyRun) and run.method == m.split("-")[0]
                and np.array_equal(run.Q, Q) and run.result is not None
                and run.truth is not None and np.array_equal(run.truth.x, x)):
            raise ValueError(f"done[{m!r}] must be consistency_test(model, "
                             f"{m.split('-')[0]!r}, {'Qtrue' if m == 'ekf-qtrue' else 'None'}, "
                             f"truth=<this runs and seed's truth set>, keep=True)")
        out[m] = run
    return out


#: How many first steps of a given filter on the log :func:`_checked_log` runs again to compare.
_LOG_CHECK_STEPS = 20


def _checked_log(model: CoopModel, given: Mapping[str, FilterResult]) -> dict[str, FilterResult]:
    """``given`` if it holds :func:`on_the_log`'s three filters: each of the right method and
    length, and equal, bit for bit, on its first steps to that filter run here on them (a row
    depends only on the rows before it: :func:`run_batch`'s ``steps``)."""
    y = model.log()
    out: dict[str, FilterResult] = {}
    for m in ("lkf", "ekf", "ukf"):
        r = given.get(m)
        if not (isinstance(r, FilterResult) and r.method == m
                and r.x_hat.shape == y.shape[:1] + (6,) and _same_head(model, m, y, r)):
            raise ValueError(f"log[{m!r}] must be run_filter({m!r}, model, model.log()) with "
                             f"its tuned Q (the three filters, 'lkf', 'ekf', 'ukf')")
        out[m] = r
    return out


def _same_head(model: CoopModel, m: str, y: np.ndarray, r: FilterResult) -> bool:
    head = run_batch(m, model, y[None], steps=_LOG_CHECK_STEPS)
    return bool(np.array_equal(head.x_hat[0], r.x_hat[:_LOG_CHECK_STEPS])
                and np.array_equal(head.P[0], r.P[:_LOG_CHECK_STEPS]))


def on_the_log(model: CoopModel) -> dict[str, FilterResult]:
    """The three filters (tuned Q) on the course's 100-second log."""
    y = model.log()
    return {m: run_filter(m, model, y) for m in ("lkf", "ekf", "ukf")}


def figures(runs: int, seed: int, executor: object = None,
            filters: tuple[str, ...] = MONTE_CARLO,
            numbers: Collection[str] | None = None,
            done: Mapping[str, ConsistencyRun] | None = None,
            log: Mapping[str, FilterResult] | None = None) -> Iterator[ReportFigure]:
    """The report's figures in order; ``executor`` (a ``concurrent.futures`` executor, or None:
    here) filters the Monte Carlo set while the figures before it are drawn (:class:`_MonteCarlo`).
    ``filters``: the Monte Carlo filters started on the executor (a caller that stops before
    figure 14c leaves out the UKF, which costs five EKFs); any other runs here if a figure asks.
    ``numbers``: only these figures ("10", "15b", ...; None: all), and only what they need is
    computed: lesson 11b shows 16-19c, which need no Monte Carlo set at all (it drew and filtered
    all of them, most of its Run All; benchmarks/lessons.py).  Each figure is the one the whole
    report draws.
    ``done``: Monte Carlo filters (keys as ``filters``) the caller has run already on this
    ``runs`` and ``seed``'s truth set, ``consistency_test(..., truth=truth, keep=True)``; they
    are used, not run again (lesson 11 passes its two EKFs on its own set); anything else raises
    a ValueError.  ``log``: the three filters already run on the course's log with their tuned
    Q, ``{m: run_filter(m, model, model.log())}`` for figures 16-19c (lesson 11b's), checked on
    their first steps and used, not run again."""
    model = CoopModel()
    if numbers is not None:
        numbers = {_v.choice("numbers", n, ALL_NUMBERS) for n in numbers}
    want = _Wanted(numbers)
    mc = None
    if (executor is not None or done) and want.any(*_MC_FIGURES):
        mc = _MonteCarlo(model, truth_runs(model, runs, seed), executor, filters, done)
    lin = _Lazy(lambda: linearization_study(model))
    if want.any(*_LIN_FIGURES):
        yield from want.only(_linearization_figures(model.t, lin()))
    if want.any(*_MC_FIGURES):
        yield from _monte_carlo_figures(model, lin, runs, seed, mc, want)
    if want.any(*_LOG_FIGURES):
        # the log's figures need only the nominal (the same array the study holds)
        yield from want.only(_log_figures(model, log, lin() if lin.done else
                                          {"nominal": model.nominal()}))


#: Every figure's number as drawn ("01" ... "19c"), in the order :func:`figures` draws them
#: (a test holds it to the drawing), in its three groups: the linearization study, the Monte
#: Carlo set, the log.
ALL_NUMBERS = ("01", "02", "03", "04", "05", "06", "07", "08", "08b", "09", "10", "11", "12",
               "13", "14", "15", "14b", "15b", "14c", "15c", "16", "17", "18", "19", "18b",
               "19b", "19c")
_LIN_FIGURES, _MC_FIGURES, _LOG_FIGURES = ALL_NUMBERS[:5], ALL_NUMBERS[5:20], ALL_NUMBERS[20:]


class _Wanted:
    """Which figures a caller asked for (None: all)."""

    def __init__(self, numbers: set[str] | None) -> None:
        self.numbers = numbers

    def __call__(self, number: str) -> bool:
        return self.numbers is None or number in self.numbers

    def any(self, *numbers: str) -> bool:
        return any(self(n) for n in numbers)

    def only(self, figs: Iterator[ReportFigure]) -> Iterator[ReportFigure]:
        """The wanted ones of a group drawn together (a group is skipped whole by the caller)."""
        return (f for f in figs if self(f.number))


class _Lazy:
    """A value computed when first asked for (the linearization study: a solve_ivp run that only
    figures 01-05, 08b and 16-19c use)."""

    def __init__(self, make) -> None:
        self.make, self.done, self.value = make, False, None

    def __call__(self):
        if not self.done:
            self.value, self.done = self.make(), True
        return self.value


def _linearization_figures(t: np.ndarray, lin: dict) -> Iterator[ReportFigure]:
    """Figures 01-05: the linearized DT model against the nominal and the nonlinear run."""
    dash = {"ls": "--", "lw": 1.0, "color": S["estimate"]}
    solid = {"lw": 1.0, "color": S["truth"]}
    nom = {"lw": 0.8, "color": S["measurement"]}
    nominal = (lin["nominal"], "nominal x*", nom)
    linear = (lin["x_lin"], "linearized x* + δx", dash)
    full = (lin["x_full"], "nonlinear (solve_ivp)", solid)
    yield ReportFigure("002", "01", "linearized-states", (
        "States of the linearized DT simulation x* + δx (δx_{k+1} = (I + ΔT·A) δx_k from "
        "δx0 = [0, 1 m, 0, 0, 0, 0.1 rad]) against the nominal x*."),
        states_figure(t, [nominal, linear], "Linearized DT simulation: total states"))
    yield ReportFigure("002", "02", "perturbations", (
        "State perturbations δx of the linearized DT model against the nonlinear perturbation "
        "x(t) − x*(t) from the same initial offset: the Euler-linearized model tracks it."),
        states_figure(t, [(lin["dx_full"], "nonlinear x − x*", solid),
                          (lin["dx"], "linearized δx", dash)],
                      "Perturbations: linearized against nonlinear", "δ"))
    y_lin = (lin["y_lin"][1:], "linearized h(x*) + Hδx", dash)
    yield ReportFigure("002", "03", "linearized-measurements", (
        "Measurements of the linearized model h(x*) + H δx (noiseless)."),
        measurements_figure(t[1:], [y_lin], "Linearized DT simulation: measurements"))
    yield ReportFigure("002", "04", "nonlinear-states", (
        "States of the full nonlinear model (solve_ivp, DOP853) from x0 + δx0, with the linearized "
        "run dashed and the nominal in grey."),
        states_figure(t, [nominal, full, linear], "Nonlinear simulation: states"))
    yield ReportFigure("002", "05", "nonlinear-measurements", (
        "Measurements h(x) of the nonlinear run against those of the linearized run."),
        measurements_figure(t[1:], [(lin["y_full"][1:], "nonlinear h(x)", solid), y_lin],
                            "Nonlinear simulation: measurements"))


def _drift_figure(t: np.ndarray, truth, nominal: np.ndarray) -> ReportFigure:
    """Figure 08b: how far the Monte Carlo truth wanders from the nominal x*."""
    drift = np.hypot(*(truth.x[:, :, 3:5] - nominal[:, 3:5]).transpose(2, 0, 1))
    drift_g = np.hypot(*(truth.x[:, :, 0:2] - nominal[:, 0:2]).transpose(2, 0, 1))
    fig, ax = plots.axes()
    for d, who, c in [(drift, "UAV", S["estimate"]), (drift_g, "UGV", S["error"])]:
        ax.fill_between(t, np.percentile(d, 5, axis=0), np.percentile(d, 95, axis=0), color=c,
                        alpha=0.2, lw=0, label=f"{who}: 5-95 % of runs")
        ax.plot(t, np.median(d, axis=0), color=c, lw=1.2, label=f"{who}: median")
    plots.finish(ax, f"How far the truth wanders from the nominal ({truth.n_runs} runs)",
                 "time (s)", "‖truth − nominal‖ position (m)")
    return ReportFigure("002", "08b", "truth-drift", (
        "Distance of the Monte Carlo truth from the nominal trajectory: heading noise of "
        "0.01 rad² per step makes the UAV's heading a random walk, and by 100 s the truth is "
        "hundreds of metres from x*, far outside the LKF's linear range."), fig)


def _monte_carlo_figures(model: CoopModel, lin: _Lazy, runs: int, seed: int,
                         mc: _MonteCarlo | None = None,
                         want: _Wanted | None = None) -> Iterator[ReportFigure]:
    """Figures 06-15c: the LKF's typical run, then NEES and NIS of every filter (those ``want``
    asks for: a filter no wanted figure needs is not run)."""
    t = model.t
    want = _Wanted(None) if want is None else want
    if mc is None:
        mc = _MonteCarlo(model, truth_runs(model, runs, seed))  # each filter when first drawn
    truth = mc.truth
    # drawn before the LKF's figures, as always (the nominal's solve_ivp: the first use of lin)
    drift_fig = _drift_figure(t, truth, lin()["nominal"]) if want("08b") else None
    i0 = 0
    x0 = truth.x[i0]
    for num, m in [("06", "lkf"), ("07", "lkf")]:
        if not want(num):
            continue
        r = mc[m].result
        assert r is not None  # monte_carlo keeps each filter's result
        ugv = num == "06"
        yield ReportFigure("002", num, f"lkf-{'ugv' if ugv else 'uav'}", (
            f"LKF (tuned Q), typical run (run {i0} of seed {seed}): "
            f"{'UGV' if ugv else 'UAV'} truth, estimate ±2σ, and the errors with ±2σ."),
            vehicle_figure(t, (0, 1, 2) if ugv else (3, 4, 5), r.x_hat[i0], r.sigma[i0],
                           f"LKF, {'UGV' if ugv else 'UAV'}: typical run", truth=x0))
    for num, m, stat in [("08", "lkf", "NEES"), ("09", "lkf", "NIS"),
                         ("14", "ekf", "NEES"), ("15", "ekf", "NIS"),
                         ("14b", "ekf-qtrue", "NEES"), ("15b", "ekf-qtrue", "NIS"),
                         ("14c", "ukf", "NEES"), ("15c", "ukf", "NIS")]:
        if want(num):
            yield _consistency_figure(mc[m], num, m, stat)
        if num == "08" and drift_fig is not None:
            yield drift_fig
        if num == "09" and want.any("10", "11", "12", "13"):
            yield from want.only(_ekf_single(mc, t, x0, i0, seed))


def _consistency_figure(run: ConsistencyRun, num: str, m: str, stat: str) -> ReportFigure:
    """One filter's NEES or NIS averaged over the runs, with the two-sided χ² bounds."""
    vals, bounds = ((run.nees_mean, run.nees_bounds) if stat == "NEES"
                    else (run.nis_mean, run.nis_bounds))
    fig = plots.chi2_band(run.t, vals, bounds, statistic=stat, dof=6 if stat == "NEES" else 5,
                          n_runs=run.n_runs, log=m == "lkf",
                          title=f"{NAMES[m]}: {stat} over {run.n_runs} runs, α = {run.alpha:g}")
    qdiag = ", ".join(f"{q:.3g}" for q in np.diag(run.Q))
    return ReportFigure("002", num, f"{m}-{stat.lower()}", (
        f"{NAMES[m]} {stat} averaged over {run.n_runs} truth runs with the two-sided χ² bounds; "
        f"{run.nees_fraction if stat == 'NEES' else run.nis_fraction:.1%} of steps inside, "
        f"time-average {vals.mean():.2f} (expected {6 if stat == 'NEES' else 5}); "
        f"Q = diag({qdiag}).{_NIS_NOTE if num == '15b' else ''}"), fig)


def _log_figures(model: CoopModel, given: Mapping[str, FilterResult] | None,
                 lin: dict) -> Iterator[ReportFigure]:
    """Figures 16-19c: the three filters on the course's 100-second log."""
    t = model.t
    logs = on_the_log(model) if given is None else _checked_log(model, given)
    y = model.log()
    for num, m, ugv in [("16", "lkf", True), ("17", "lkf", False), ("18", "ekf", True),
                        ("19", "ekf", False), ("18b", "ukf", True), ("19b", "ukf", False)]:
        r = logs[m]
        who = "UGV" if ugv else "UAV"
        yield ReportFigure("002", num, f"log-{m}-{who.lower()}", (
            f"{NAMES[m]} on the course's 100-second log: {who} estimates with ±2σ"
            f"{'' if ugv else ' and the GPS fixes'}, and (right) their departure from the nominal "
            f"x* with ±2σ; NIS time-average "
            f"{r.nis()[1:].mean():.2f} (5 expected)."),
            vehicle_figure(t, (0, 1, 2) if ugv else (3, 4, 5), r.x_hat, r.sigma,
                           f"{NAMES[m]} on the logged data: {who}", measured=y,
                           reference=lin["nominal"]))
    fig, ax = plots.axes()
    for m, c in [("lkf", S["error"]), ("ekf", S["estimate"]), ("ukf", S["truth"])]:
        nis = logs[m].nis()[1:]
        k = 50  # a 5-second moving average: one run's NIS is too noisy to read
        ma = np.convolve(nis, np.ones(k) / k, mode="valid")
        ax.plot(t[k:], ma, color=c, lw=1.0, label=f"{NAMES[m]} (mean {nis.mean():.2f})")
    ax.axhline(5, color=S["bound"], ls="--", lw=1.0, label="expected 5")
    plots.finish(ax, "NIS on the course log, 5-s moving average", "time (s)", "NIS (1)")
    means = ", ".join(f"{NAMES[m]} {logs[m].nis()[1:].mean():.2f}" for m in logs)
    yield ReportFigure("002", "19c", "log-nis", (
        f"NIS of the three filters on the course log (5-second moving average); time-averages "
        f"{means} (5 expected, ±0.1 for 1000 independent steps)."), fig)


def _ekf_single(mc: dict[str, ConsistencyRun], t: np.ndarray, x0: np.ndarray, i0: int,
                seed: int) -> Iterator[ReportFigure]:
    r = mc["ekf"].result
    truth = mc["ekf"].truth
    assert r is not None and truth is not None  # monte_carlo keeps both
    for num, ugv in [("10", True), ("11", False)]:
        who = "UGV" if ugv else "UAV"
        yield ReportFigure("002", num, f"ekf-{who.lower()}", (
            f"EKF (tuned Q), typical run (run {i0} of seed {seed}): {who} truth against the "
            "estimate ±2σ, and the errors."),
            vehicle_figure(t, (0, 1, 2) if ugv else (3, 4, 5), r.x_hat[i0], r.sigma[i0],
                           f"EKF, {who}: typical run", truth=x0))
    yhat = h(r.x_bar[i0])
    yield ReportFigure("002", "12", "ekf-measurements", (
        "The simulated measurements of the typical run against the EKF's predicted h(x̄)."),
        measurements_figure(
            t[1:], [(truth.y[i0, 1:], "measured y",
                     {"ls": "", "marker": ".", "ms": 2, "color": S["measurement"]}),
                    (yhat[1:], "predicted h(x̄)", {"lw": 0.9, "color": S["estimate"]})],
            "EKF: measurements of the typical run"))
    fig = plots.figure((10.0, 7.5))
    axs = fig.subplots(3, 2, sharex=True)
    err = r.errors(truth.x)[i0]
    for i, (name, unit) in enumerate(STATES):
        ax = axs[i % 3, i // 3]
        plots.error_band(t, _breaks(err[:, i], unit), r.sigma[i0][:, i], k=2,
                         label=f"{name} error", unit=unit, ax=ax)
        ax.set_xlabel("time (s)" if i % 3 == 2 else "")
        if i:                                    # one legend (error_band's, right of the axes)
            ax.get_legend().remove()
    fig.suptitle("EKF: state errors with ±2σ, typical run")
    yield ReportFigure("002", "13", "ekf-errors", (
        "EKF state estimation errors of the typical run with the filter's ±2σ (headings wrapped: "
        "no 2π jumps)."), fig)
