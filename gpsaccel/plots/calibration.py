"""The calibration system's figures (reports 000, 001, 003): the sensors of one realization, its
filtered errors and gains, the system diagram, the ensembles' statistics and the forms' sweep."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from gpsaccel.plots.kinds import (
    STYLE,
    axes,
    error_band,
    estimate_vs_truth,
    figure,
    finish,
    outside_legend,
    panels,
    state_grid,
    time_series,
)
from gpsaccel.plots.units import CALIBRATION_STATES, _ratio_unit, _state_label, product_unit

# --------------------------------------------------------------------------------------------------
# One realization: the sensors (report 001, figures 1-5)

def truth_kinematics(run, *, fig: Figure | None = None) -> Figure:
    """The true acceleration, velocity and position of one realization ``run`` (a Realization)."""
    return time_series(run.t, [(run.a, "a", "m/s²"), (run.v, "v", "m/s"), (run.p, "p", "m")],
                       title="Truth: acceleration, velocity, position", fig=fig)


def accelerometer_drift(run, *, fig: Figure | None = None) -> Figure:
    """What integrating the accelerometer alone does: p_c − p and v_c − v over time (= −δp, −δv)."""
    return time_series(run.t, [(run.p_c - run.p, "p_c − p", "m"), (run.v_c - run.v, "v_c − v", "m/s")],
                       title="Accelerometer-integrated minus truth", fig=fig)


def gps_minus_accelerometer(run, *, with_truth: bool = False, fig: Figure | None = None) -> Figure:
    """The filter's measurement z = GPS − accelerometer at the GPS times (dots).

    With ``with_truth`` the quantity it measures, δp = p − p_c and δv = v − v_c, is drawn as a line
    underneath: the dots scatter about it by the GPS noise.
    """
    fig, axs = panels(2, fig, title=("Truth − accelerometer against GPS − accelerometer"
                                     if with_truth else "GPS minus accelerometer"))
    for i, ax in enumerate(axs):
        name, unit = _state_label(i)
        if with_truth:
            ax.plot(run.t, run.x[:, i], color=STYLE["truth"], lw=1.2,
                    label=f"{name} = truth − accelerometer")
        ax.plot(run.t_gps, run.z[:, i], ".", color=STYLE["estimate"], ms=3,
                label=f"z{i + 1} = GPS − accelerometer")
        finish(ax, "", "time (s)" if i == 1 else "", f"{name} ({unit})", legend=with_truth)
    return fig


def gps_noise(run, *, fig: Figure | None = None) -> Figure:
    """GPS minus truth: the GPS noise η (white, N(0, V)) at the GPS times."""
    return time_series(run.t_gps, [(run.gps_p - run.p[run.gps_steps], "η_p = GPS p − p", "m"),
                                   (run.gps_v - run.v[run.gps_steps], "η_v = GPS v − v", "m/s")],
                       title="GPS minus truth (the GPS noise)", marker=".", fig=fig)


# --------------------------------------------------------------------------------------------------
# One realization filtered (reports 000 figures 1-6, 001 figures 6-10, 003 figures 2-3)

def errors_with_sigma(run, result, states: Sequence[int] = (0, 1, 2), k: float = 1.0, *,
                      title: str = "Estimation errors with the filter's ±σ",
                      between_fixes: bool = False, shade: tuple[float, float] | None = None,
                      window: tuple[float, float] | None = None,
                      fig: Figure | None = None) -> Figure:
    """Errors x − x̂ of one run (Realization ``run``, MultirateResult ``result``) with ±kσ, stacked.

    ``between_fixes`` also draws the a priori ±kσ on the accelerometer grid (the saw-tooth between
    GPS fixes) and the error of the propagated estimate there; ``shade`` = (t0, t1) marks an
    interval (a GPS outage); ``window`` = (t0, t1) draws only that time span (s).
    """
    fig, axs = panels(len(states), fig, title=title)
    e = run.x_gps - result.x_hat
    lo, hi = (-np.inf, np.inf) if window is None else window
    slow = (result.t_gps >= lo) & (result.t_gps <= hi)
    fast = (result.t >= lo) & (result.t <= hi)
    for ax, i in zip(axs, states, strict=True):
        name, unit = _state_label(i)
        if between_fixes:
            sd_fast = np.sqrt(result.M_fast[fast, i, i])
            ax.plot(result.t[fast], run.x[fast, i] - result.x_fast[fast, i], color=STYLE["error"],
                    lw=0.6, alpha=0.5, label="error between fixes")
            kk = f"{k:g}" if k != 1 else ""
            ax.plot(result.t[fast], k * sd_fast, color=STYLE["bound"], lw=0.6, alpha=0.6,
                    label=f"±{kk}σ between fixes (a priori, √M)")
            ax.plot(result.t[fast], -k * sd_fast, color=STYLE["bound"], lw=0.6, alpha=0.6)
        error_band(result.t_gps[slow], e[slow, i], result.sigma[slow, i], k,
                   label=f"{name} − {name}̂", unit=unit, ax=ax,
                   bound_label=("±σ at the fixes (a posteriori, √P)" if between_fixes and k == 1
                                else None))
        if shade is not None:
            ax.axvspan(*shade, color=STYLE["measurement"], alpha=0.3, lw=0, label="no GPS")
            outside_legend(ax)
        if ax is not axs[-1]:
            ax.set_xlabel("")
    return fig


def estimates_with_truth(run, result, states: Sequence[int] = (0, 1, 2), *,
                         title: str = "Estimates against the truth",
                         fig: Figure | None = None) -> Figure:
    """Total estimates p̂ = p_c + δp̂, v̂ = v_c + δv̂, b̂ at the GPS times against the truth, stacked."""
    fig, axs = panels(len(states), fig, title=title)
    gps = run.gps_steps
    totals = [(run.p, run.p_c[gps] + result.x_hat[:, 0], "position p", "m"),
              (run.v, run.v_c[gps] + result.x_hat[:, 1], "velocity v", "m/s"),
              (np.full_like(run.t, run.b), result.x_hat[:, 2], "bias b", "m/s²")]
    for ax, i in zip(axs, states, strict=True):
        truth, est, quantity, unit = totals[i]
        estimate_vs_truth(run.t, truth, result.t_gps, est, quantity=quantity, unit=unit, ax=ax)
        if ax is not axs[-1]:
            ax.set_xlabel("")
    return fig


def error_comparison(run, result, *, fig: Figure | None = None) -> Figure:
    """|error| of the accelerometer alone, of the GPS alone and of the filter, on a log scale.

    Position and velocity: accelerometer-only |p − p_c|, GPS-only |η|, filter |p − p̂|.
    """
    fig, axs = panels(2, fig, title="Errors of the estimates against the sensors' own errors")
    e = run.x_gps - result.x_hat
    for i, ax in enumerate(axs):
        name, unit = _state_label(i)
        ax.semilogy(run.t, np.abs(run.x[:, i]), color=STYLE["truth"], lw=1.0,
                    label=f"accelerometer alone |{name}|")
        ax.semilogy(run.t_gps, np.abs(run.eta[:, i]), ".", color=STYLE["measurement"], ms=3,
                    label="GPS alone |η|")
        ax.semilogy(result.t_gps, np.abs(e[:, i]), color=STYLE["error"], lw=1.0,
                    label=f"filter |{name} − {name}̂|")
        ax.semilogy(result.t_gps, result.sigma[:, i], color=STYLE["bound"], ls="--", lw=1.0,
                    label="filter σ")
        finish(ax, "", "time (s)" if i == 1 else "", f"|{name} error| ({unit})")
    return fig


def gains(result, *, title: str = "Kalman gains over time", fig: Figure | None = None) -> Figure:
    """Every element K_ij of the gain at the update epochs (MultirateResult ``result``), a grid."""
    n, p = result.K.shape[1:]
    fig = fig or figure((9.0, 7.0))
    grid = fig.subplots(n, p, sharex=True, squeeze=False)
    z_units = [u for _, u in CALIBRATION_STATES[:p]]
    for i in range(n):
        name, unit = CALIBRATION_STATES[i]
        for j in range(p):
            ax = grid[i, j]
            ax.plot(result.t_meas, result.K[:, i, j], color=STYLE["estimate"], lw=1.0)
            gain_unit = _ratio_unit(unit, z_units[j])
            finish(ax, f"K{i + 1}{j + 1}: {name} from z{j + 1}", "time (s)",
                   f"K{i + 1}{j + 1} ({gain_unit})", legend=False)
    fig.suptitle(title)
    return fig


# --------------------------------------------------------------------------------------------------
# Ensembles (report 000 figure 7, 001 figures 10b-12, 003 figures 4-6)

def matrix_lines(t: np.ndarray, values: np.ndarray, *, title: str, quantity: str,
                 ax: Axes | None = None, unitless: bool = False) -> Figure:
    """All n² elements of a matrix over time on one axes (report 000's figure 7): values (n_t, n, n).

    The elements have different units; each legend entry names its own (``unitless``: the values
    are already normalised, one axis in 1).
    """
    fig, ax = axes(ax, figsize=(8.5, 4.5))
    n = values.shape[1]
    for i in range(n):
        for j in range(n):
            unit = product_unit(CALIBRATION_STATES[i][1], CALIBRATION_STATES[j][1])
            ax.plot(t, values[:, i, j], lw=1.0,
                    label=f"({i + 1},{j + 1})" + ("" if unitless else f" [{unit}]"))
    finish(ax, title, "time (s)",
           f"{quantity} (1)" if unitless else f"{quantity} (element's unit, see legend)",
           legend=False)
    outside_legend(ax, fontsize="x-small")
    return fig


def system_diagram(ax: Axes | None = None) -> Figure:
    """Report 003's figure 1: truth, sensors, the difference z and the Kalman filter, as blocks."""
    fig, ax = axes(ax, figsize=(9.0, 4.2))
    ax.set_xlim(0, 10.4)
    ax.set_ylim(0.3, 4.6)
    ax.set_axis_off()
    boxes = {
        "truth": (0.2, 2.1, "vehicle\na(t) = A sin(ωt)"),
        "acc": (3.0, 3.4, "accelerometer 200 Hz\na_c = a + b + w"),
        "gps": (3.0, 0.8, "GPS 5 Hz\np + η_p, v + η_v"),
        "int": (5.6, 3.4, "Euler integration\np_c, v_c"),
        "kf": (5.6, 0.8, "Kalman filter\nx = [δp, δv, b]"),
        "out": (8.2, 2.1, "p̂ = p_c + δp̂\nv̂ = v_c + δv̂\nb̂"),
    }
    width, height = 2.0, 0.95
    for key, (x, y, text) in boxes.items():
        ax.add_patch(_box(x, y, width, height, key))
        ax.text(x + width / 2, y + height / 2, text, ha="center", va="center", fontsize="small")

    def arrow(x0, y0, x1, y1, text="", dx=0.0, dy=0.12, ha="center"):
        ax.annotate("", (x1, y1), (x0, y0), arrowprops={"arrowstyle": "->", "lw": 1.2})
        if text:
            ax.text((x0 + x1) / 2 + dx, (y0 + y1) / 2 + dy, text, ha=ha, fontsize="small")

    arrow(2.2, 2.8, 3.0, 3.85, "a(t)", dx=-0.25)
    arrow(2.2, 2.4, 3.0, 1.25, "p, v", dx=-0.25, dy=-0.2)
    arrow(5.0, 3.85, 5.6, 3.85, "a_c")
    arrow(6.6, 3.4, 6.6, 1.75, "p_c, v_c\n(z = GPS − [p_c, v_c])", dx=-0.1, dy=0.0, ha="right")
    arrow(5.0, 1.25, 5.6, 1.25, "GPS")
    arrow(7.6, 1.25, 8.2, 2.3, "δp̂, δv̂, b̂", dx=0.35, dy=-0.3)
    arrow(7.6, 3.85, 8.2, 2.8, "p_c, v_c", dx=0.35, dy=0.1)
    ax.set_title("System diagram: GPS-aided accelerometer calibration")
    return fig


def _box(x: float, y: float, w: float, h: float, key: str):
    from matplotlib.patches import FancyBboxPatch

    face = {"kf": "#dbe9f6", "out": "#e8f4e0"}.get(key, "#f3f3f3")
    return FancyBboxPatch((x, y), w, h, boxstyle="round,pad=0.05", fc=face, ec=STYLE["truth"])


def actual_vs_claimed(stats, baseline=None, states: Sequence[int] = (0, 1, 2), *,
                      title: str = "Actual error against what the filter claims",
                      labels: tuple[str, str] = ("mistaken filter", "correct filter"),
                      fig: Figure | None = None) -> Figure:
    """Exact RMS actual error and claimed σ over time (log scale), one panel per state.

    ``stats`` and ``baseline`` are :class:`gpsaccel.calibration.errata.ErrorStatistics`; |mean error| is drawn
    dotted where it is not negligible (a bias the filter does not know of).
    """
    fig, axs = panels(len(states), fig, title=title)
    for ax, i in zip(axs, states, strict=True):
        name, unit = _state_label(i)
        if baseline is not None:
            ax.semilogy(baseline.t, baseline.rms[:, i], color=STYLE["truth"], lw=1.0,
                        label=f"{labels[1]}: RMS error")
        ax.semilogy(stats.t, stats.rms[:, i], color=STYLE["error"], lw=1.4,
                    label=f"{labels[0]}: RMS error")
        ax.semilogy(stats.t, stats.claimed_sigma[:, i], color=STYLE["bound"], ls="--", lw=1.2,
                    label=f"{labels[0]}: claimed σ")
        mean = np.abs(stats.mean[:, i])
        if mean.max() > 1e-3 * stats.rms[:, i].max():
            ax.semilogy(stats.t, mean, color=STYLE["estimate"], ls=":", lw=1.2,
                        label=f"{labels[0]}: |mean error|")
        finish(ax, "", "time (s)" if ax is axs[-1] else "", f"{name} error ({unit})")
    return fig


def ensemble_mean_error(mc, *, sigma: bool = False, k: float = 1.0,
                        title: str | None = None, fig: Figure | None = None) -> Figure:
    """Ensemble-mean error e_ave over time (a :class:`gpsaccel.calibration.montecarlo.MonteCarloResult`).

    Shaded: ±2 standard errors 2σ/√N, where e_ave of a consistent filter stays 95 % of the time.
    Dotted: the mean error theory predicts (zero for the error-model truth; the filter's error on
    the Euler integration error for the closed-form truth).  With ``sigma`` also the filter's
    ±kσ (what report 003 draws).
    """
    title = title or f"Ensemble-mean error, N = {mc.n_runs:,} ({mc.truth} truth)"
    fig, axs = panels(3, fig, title=title)
    se = mc.e_ave_se
    for i, ax in enumerate(axs):
        name, unit = _state_label(i)
        ax.fill_between(mc.t, -2 * se[:, i], 2 * se[:, i], color=STYLE["band"], alpha=0.25, lw=0,
                        label="±2σ/√N")
        if sigma:
            ax.plot(mc.t, k * mc.sigma[:, i], color=STYLE["bound"], ls="--", lw=1.0,
                    label=f"±{k:g}σ (filter)" if k != 1 else "±σ (filter)")
            ax.plot(mc.t, -k * mc.sigma[:, i], color=STYLE["bound"], ls="--", lw=1.0)
        if np.any(mc.predicted_mean_error[:, i] != 0):
            ax.plot(mc.t, mc.predicted_mean_error[:, i], color=STYLE["truth"], ls=":", lw=1.2,
                    label="predicted mean")
        ax.plot(mc.t, mc.e_ave[:, i], color=STYLE["error"], lw=1.0, label="e_ave")
        finish(ax, "", "time (s)" if i == 2 else "", f"e_ave {name} ({unit})")
    return fig


def pave_minus_p(mc, *, grid: bool = True, normalised: bool = False, title: str | None = None,
                 fig: Figure | None = None) -> Figure:
    """P_ave − P over time: a 3x3 grid with ±2 standard errors of P_ave shaded (``grid``), or all
    nine elements on one axes as report 000's figure 7.

    ``normalised`` divides each element by its own standard error (one axis, unitless): on report
    000's layout element (1,1) (m², ~0.01) hides the others (the bias terms are ~1e-8); in
    standard errors all nine are visible and comparable with ±2.
    """
    title = title or (f"{'(P_ave − P) / standard error' if normalised else 'P_ave − P'}, "
                      f"N = {mc.n_runs:,} ({mc.truth} truth)")
    diff = mc.P_ave - mc.P
    if normalised:
        fig = matrix_lines(mc.t, diff / mc.P_ave_se, title=title, unitless=True,
                           quantity="(P_ave − P) / standard error", ax=None if fig is None
                           else fig.add_subplot())
        ax = fig.axes[0]
        for z in (-2.0, 2.0):
            ax.axhline(z, color=STYLE["bound"], ls="--", lw=1.0)
        ax.text(0.01, 0.02, "dashed: ±2 (about 95 % of a consistent filter's values inside)",
                transform=ax.transAxes, fontsize="x-small", color=STYLE["bound"])
        return fig
    if not grid:
        if fig is not None:
            return matrix_lines(mc.t, diff, title=title, quantity="P_ave − P", ax=fig.add_subplot())
        return matrix_lines(mc.t, diff, title=title, quantity="P_ave − P")
    return state_grid(mc.t, diff, title=title + "; shaded ±2 s.e.", ylabel="P_ave − P",
                      bands=2 * mc.P_ave_se, fig=fig)


def orthogonality(mc, *, title: str | None = None, fig: Figure | None = None) -> Figure:
    """The orthogonality matrix (1/N) Σ (e − e_ave) x̂ᵀ over time, 3x3, ±2 standard errors shaded."""
    title = title or (f"Orthogonality (1/N) Σ (e − e_ave) x̂ᵀ, N = {mc.n_runs:,} ({mc.truth} "
                      f"truth); shaded ±2 s.e.")
    return state_grid(mc.t, mc.orthogonality, title=title, ylabel="E[e x̂ᵀ]",
                      bands=2 * mc.orthogonality_se, fig=fig)


# --------------------------------------------------------------------------------------------------
# Filter forms in finite precision (gpsaccel compare --sweep)

#: One colour and marker per filter form, the same in every sweep figure.
FORM_STYLE = {
    "standard": ("#d62728", "o"),
    "joseph": ("#1f77b4", "s"),
    "information": ("#2ca02c", "^"),
    "filterpy-information": ("#9467bd", "v"),
    "square-root": ("#ff7f0e", "D"),
}


def form_sweep(sweeps: Sequence, *, fig: Figure | None = None) -> Figure:
    """Each form's error against the exact answer, over the update's condition number κ.

    ``sweeps``: :class:`gpsaccel.calibration.compare.Sweep` s, one column each; top row the
    covariance error max|ΔP_ij|/√(P*_ii P*_jj), bottom row the estimate error max|Δx̂|/σ*.  Grey
    dashes: the exact answer rounded to float64 (the floor); dotted guides ε κ and ε √κ
    (ε = 2⁻⁵³); a ring marks a P that is no longer positive definite, a triangle at the top a form
    that broke down (inf/NaN or an exception).
    """
    if fig is None:  # constrained: only a layout engine makes room for an "outside" fig.legend
        fig = Figure(figsize=(5.2 * len(sweeps) + 0.6, 7.6), layout="constrained")
    axs = fig.subplots(2, len(sweeps), squeeze=False, sharex="col")
    eps = np.finfo(float).eps / 2
    for col, sw in enumerate(sweeps):
        k = np.asarray(sw.kappa)
        for row, (get, floor, ylabel) in enumerate((
                (sw.dP, [e.dP_rel for e in sw.floor], "max |P − P*|ᵢⱼ / √(P*ᵢᵢ P*ⱼⱼ)"),
                (sw.dx, [e.dx_sigma for e in sw.floor], "max |x̂ − x̂*| / σ*"))):
            ax = axs[row, col]
            ax.loglog(k, eps * k, ":", color="#555555", lw=1.0, label="ε κ")
            ax.loglog(k, eps * np.sqrt(k), ":", color="#999999", lw=1.0, label="ε √κ")
            ax.loglog(k, floor, "--", color="#777777", lw=1.2, label="exact, rounded to float64")
            top = 1e3
            broke_down = any(not np.all(np.isfinite(get(n))) for n in sw.errors)
            for name in sw.errors:
                colour, marker = FORM_STYLE.get(name, ("#222222", "x"))
                y = np.asarray(get(name), dtype=float)
                bad = ~np.isfinite(y)
                ax.loglog(k, np.where(bad, np.nan, y), marker=marker, color=colour, lw=1.3,
                          ms=4.5, alpha=0.85, label=name)
                if bad.any():
                    ax.plot(k[bad], np.full(bad.sum(), top), marker="^", color=colour, ls="none",
                            ms=8)
                lost = np.asarray(sw.min_eig(name)) < 0
                if lost.any():
                    ax.plot(k[lost & ~bad], y[lost & ~bad], "o", ms=12, mfc="none", mec="black",
                            mew=1.3, label="P not positive definite" if not bad.all() else None)
            finite = np.concatenate([np.asarray(get(n), dtype=float) for n in sw.errors] + [floor])
            finite = finite[np.isfinite(finite) & (finite > 0)]
            high = top * 3 if broke_down else 10.0 ** np.ceil(np.log10(finite.max()) + 0.5)
            ax.set_ylim(10.0 ** np.floor(np.log10(finite.min()) - 0.5), high)
            finish(ax, "", "κ = max λ(M P⁻¹)  (update's condition number)" if row == 1 else "",
                   ylabel, legend=False)
            if row == 0:  # the sweep's own factor along the top, at the points it produced
                top_axis = ax.secondary_xaxis("top")
                every = max(1, len(k) // 5)
                top_axis.set_xticks(k[::every], labels=[f"{f:.0e}".replace("e+0", "e").replace(
                    "e-0", "e-").replace("e+", "e") for f in sw.factors[::every]])
                top_axis.minorticks_off()
                top_axis.set_xlabel(f"sweep '{sw.kind}': {sw.label}")
    handles, labels = axs[0, 0].get_legend_handles_labels()
    seen = dict(zip(labels, handles, strict=True))
    fig.legend(list(seen.values()), list(seen.keys()), loc="outside lower center",
               ncol=min(5, len(seen)), fontsize="small")
    fig.suptitle("Filter forms in float64 against the exact answer (mpmath, 50 digits)")
    return fig
