"""Report 004 (AAUSHIP, monorate vs multirate): figures 1-11, and 12-14 on what it left open.

Figures 1-11 are one voyage (seed ``seed``) of :class:`~gpsaccel.ship.model.ShipModel`, filtered
monorate (every sensor every step) and multirate (GPS 1 Hz, IMU 10 Hz) with the optimal update of
the multirate driver; the same realization feeds both, so their difference is the filters' alone
(the report drew a new realization for its multirate run).  Figures 9-11 add the report's
zeroed-gain multirate.  Figure 11 plots accelerations (the report's plots velocity by mistake).
Figures 12-14 are not in the report: the Monte Carlo NEES of the five filters, their claimed and
true position σ, and the wind states the report proposes.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from gpsaccel import plots, registry
from gpsaccel.figures import ReportFigure
from gpsaccel.kalman.multirate import MultirateResult, run_multirate
from gpsaccel.ship.comparison import (
    DESCRIPTIONS,
    FILTERS,
    ShipComparison,
    WindComparison,
    compare_ship_filters,
    compare_wind,
)
from gpsaccel.ship.model import STATES, ShipModel
from gpsaccel.ship.simulation import ShipRealization, simulate_ship
from gpsaccel.ship.zeroed_gain import ZeroedGainResult, run_zeroed_gain

TITLE = "AAUSHIP ship: monorate vs multirate Kalman filter (GPS 1 Hz, IMU 10 Hz)"
#: The report has no Monte Carlo; this is the size of figures 12-14's.
DEFAULT_RUNS = 200

#: The figures the report lists (a lesson walks through each)
FIGURES = tuple(str(i) for i in range(1, 12))
registry.add_report("004", __name__, FIGURES, title=TITLE)

GROUPS = (("position", (0, 3, 6)), ("velocity", (1, 4, 7)), ("acceleration", (2, 5, 8)))


def single_voyage(seed: int, model: ShipModel | None = None
                  ) -> tuple[ShipModel, ShipRealization, dict[str, MultirateResult]]:
    """(model, realization, {"monorate", "multirate", "zeroed"} results) of one voyage."""
    model = ShipModel() if model is None else model
    run = simulate_ship(model, np.random.default_rng(seed))
    mono, multi = model.schedule(multirate=False), model.schedule(multirate=True)
    results = {
        "monorate": run_multirate(model, run.measurements(mono), schedule=mono, u=run.u),
        "multirate": run_multirate(model, run.measurements(multi), schedule=multi, u=run.u),
        "zeroed": run_zeroed_gain(model, run.measurements(multi), schedule=multi, u=run.u,
                                  covariance="report"),
    }
    return model, run, results


def _estimate_figure(run: ShipRealization, res: MultirateResult, group: str,
                     states: tuple[int, ...], label: str):
    sched_mask = res.used
    panels = []
    for j in states:
        name, unit = STATES[j]
        measured = sched_mask[:, j]
        panels.append((name, unit, [
            (res.t_meas[measured], run.z[res.steps[measured], j], "measured", "measurement"),
            (run.t, run.x[:, j], "true", "truth"),
            (res.t_meas, res.x_hat[:, j], "filtered", "estimate"),
        ]))
    if group != "acceleration":
        return plots.overlay_panels(panels, title=f"{group.capitalize()} estimation – {label}")
    # The accelerometer is so precise that measured, filtered and true lie on one line: add the
    # differences that matter, measured − true and filtered − true, each under its signal.
    with_residuals = []
    for (name, unit, lines), j in zip(panels, states, strict=True):
        measured = res.used[:, j]
        truth_at = run.x[res.steps, j]
        with_residuals += [(name, unit, lines), (f"{name} − true", unit, [
            (res.t_meas[measured], run.z[res.steps[measured], j] - truth_at[measured],
             "measured − true", "measurement"),
            (res.t_meas, res.x_hat[:, j] - truth_at, "filtered − true", "estimate"),
        ])]
    return plots.overlay_panels(with_residuals, height=1.5,
                                title=f"{group.capitalize()} estimation – {label}")


def _track_figure(run: ShipRealization, res: MultirateResult, label: str):
    gps = res.used[:, 0] & res.used[:, 3]
    steps = res.steps[gps]
    return plots.track([
        (run.z[steps, 0], run.z[steps, 3], "measured (GPS)", "measurement"),
        (run.x[:, 0], run.x[:, 3], "true", "truth"),
        (res.x_hat[:, 0], res.x_hat[:, 3], "filtered", "estimate"),
    ], title=f"x–y track – {label}")


def figures(runs: int, seed: int) -> Iterator[ReportFigure]:
    model, run, res = single_voyage(seed)
    labels = {"monorate": "monorate (all sensors every 0.1 s)",
              "multirate": "multirate (GPS 1 Hz, IMU 10 Hz; optimal update)"}
    number = 1
    for key in ("monorate", "multirate"):
        for group, states in GROUPS:
            fig = _estimate_figure(run, res[key], group, states, labels[key])
            yield ReportFigure("004", f"{number:02d}", f"{key}-{group}",
                               f"{group.capitalize()} in x, y and heading ψ: measured, filtered "
                               f"and true, {labels[key]} (seed {seed}).", fig)
            number += 1
        yield ReportFigure("004", f"{number:02d}", f"{key}-track", (
            f"x–y track, {labels[key]}: the world-frame positions (x, y) themselves; the GPS "
            f"fixes, the filter's estimate and the truth (seed {seed})."),
            _track_figure(run, res[key], labels[key]))
        number += 1

    mono, multi, zeroed = res["monorate"], res["multirate"], res["zeroed"]
    for group, states in GROUPS:
        panels = []
        for j in states:
            name, unit = STATES[j]
            lines = []
            for r, label, role in [(multi, "monorate − multirate (optimal)", "estimate"),
                                   (zeroed, "monorate − multirate (report's zeroed gain)",
                                    "alternative")]:
                d = mono.x_hat[:, j] - r.x_hat[:, j]
                scale = max(1.0, float(np.abs(mono.x_hat[:, j]).max()))
                largest = float(np.abs(d).max())
                if largest <= 1e-12 * scale:
                    # Identical up to rounding: a curve of 1e-16 wiggles would read as a signal.
                    d = np.zeros_like(d)
                    label += f": identical (|Δ| ≤ {largest:.0e})"
                lines.append((r.t_meas, d, label, role))
            panels.append((f"Δ{name}", unit, lines))
        fig = plots.overlay_panels(panels, title=f"Difference monorate − multirate: {group}")
        extra = " (the report's figure plots velocity here by mistake)" \
            if group == "acceleration" else ""
        yield ReportFigure("004", f"{number:02d}", f"difference-{group}", (
            f"Monorate − multirate estimates, {group}, on the same voyage (seed {seed}): optimal "
            f"multirate and the report's zeroed-gain multirate{extra}. The two multirate curves "
            f"overlap (the zeroed gain loses ~1e-5 relative here); the heading panel is zero: the "
            f"ψ block is decoupled from x, y and measured at 10 Hz in both, so the two filters "
            f"agree to rounding (drawn as 0, not as rounding noise)."), fig)
        number += 1

    comp = compare_ship_filters(model, n_runs=runs, seed=seed)
    yield nees_figure(comp)
    yield sigma_figure(comp)
    yield wind_figure(compare_wind(model.replace(wind=True), n_runs=runs, seed=seed))


def nees_figure(comp: ShipComparison) -> ReportFigure:
    """Figure 12 from a :func:`~gpsaccel.ship.comparison.compare_ship_filters` result (lesson
    09b draws it from the comparison it prints, instead of running it again)."""
    runs, seed = comp.n_runs, comp.seed
    fig, axs = plots.panels(len(FILTERS), title=f"NEES over time, {runs} runs, 9 states")
    for ax, name in zip(axs, FILTERS, strict=True):
        plots.chi2_band(comp.t_epochs, comp.filters[name].nees, comp.bounds, dof=9, n_runs=runs,
                        ax=ax)
        ax.set_title(DESCRIPTIONS[name], fontsize="small")
        if ax is not axs[-1]:
            ax.set_xlabel("")
    return ReportFigure("004", "12", "nees", (
        f"Not in the report: run-averaged NEES of the five filters with the covariance each one "
        f"reports, against the 95 % chi-square bounds ({runs} runs, seed {seed})."), fig)


def sigma_figure(comp: ShipComparison) -> ReportFigure:
    """Figure 13 from a :func:`~gpsaccel.ship.comparison.compare_ship_filters` result."""
    zr = comp.filters["zeroed-report"].result
    ra = comp.filters["report-as-written"].result
    assert isinstance(ra, ZeroedGainResult)  # the report's filter carries its true P
    t = comp.t_epochs
    window = t <= 30.0
    lines = [(t[window], np.sqrt(comp.filters["multirate"].result.P[window, 0, 0]),
              "optimal multirate", "estimate"),
             (t[window], np.sqrt(comp.filters["zeroed-joseph"].result.P[window, 0, 0]),
              "zeroed gain, Joseph (= its true σ)", "alternative"),
             (t[window], np.sqrt(np.abs(zr.P[window, 0, 0])), "zeroed gain, report's (I−KH)M",
              "bound"),
             (t[window], np.sqrt(ra.P_actual[window, 0, 0]), "report as written: true σ",
              "error"),
             (t[window], np.sqrt(np.abs(ra.P[window, 0, 0])), "report as written: claimed σ",
              "truth")]
    fig = plots.overlay_panels([("σ of x", "m", lines)],
                               title="Position standard deviation, claimed and true (first 30 s)")
    return ReportFigure("004", "13", "sigma-x", (
        "Not in the report: the x-position σ of the multirate filters over the first 30 s. The "
        "zeroed gain's curves lie on the optimal one (the loss is ~1e-5 relative); the report "
        "as written, with the monorate gain at GPS fixes, has about twice the σ and claims "
        "more still."), fig)


def wind_figure(wind: WindComparison) -> ReportFigure:
    """Figure 14 from a :func:`~gpsaccel.ship.comparison.compare_wind` result."""
    runs = wind.track_error_plain.shape[0]
    wind_panels: list[tuple[str, str, list[tuple[np.ndarray, np.ndarray, str | None, str]]]] = []
    for c, (name, unit) in enumerate((("b_x", "N"), ("b_y", "N"))):
        wind_lines: list[tuple[np.ndarray, np.ndarray, str | None, str]] = [
            (wind.t, wind.wind[0, :, c], "true wind force", "truth"),
            (wind.t, wind.wind_hat[0, :, c], "estimate (11-state filter)", "estimate"),
            (wind.t, wind.wind_hat[0, :, c] + wind.wind_sigma[:, c], "±1σ", "bound"),
            (wind.t, wind.wind_hat[0, :, c] - wind.wind_sigma[:, c], None, "bound"),
        ]
        wind_panels.append((name, unit, wind_lines))
    rms_plain = np.sqrt(np.mean(wind.track_error_plain**2, axis=0))
    rms_wind = np.sqrt(np.mean(wind.track_error_wind**2, axis=0))
    wind_panels.append(("track error", "m", [
        (wind.t, rms_plain, "9-state filter (no wind state)", "error"),
        (wind.t, rms_wind, "11-state filter (wind states)", "estimate"),
    ]))
    fig = plots.overlay_panels(wind_panels, title="Wind bias: estimated, and the track error it removes")
    plain, with_wind = wind.track_rmse
    return ReportFigure("004", "14", "wind", (
        f"Not in the report (proposed there): a steady wind ({wind.wind_force[0]:g}, "
        f"{wind.wind_force[1]:g}) N drifting slowly. Top: one run's wind estimate ±1σ. Bottom: "
        f"RMS track error over {runs} runs; {plain:.2f} m without the wind states, "
        f"{with_wind:.2f} m with them."), fig)
