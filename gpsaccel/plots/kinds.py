"""Kinds of figure that draw any system's arrays: the house style (:data:`STYLE`, :func:`axes`,
:func:`finish`), a signal with its ±kσ band, stacked panels, a matrix's elements over time in a
grid (labelled with the calibration states unless given others), a χ² statistic against its
bounds, overlaid signals and x–y tracks (the ship's and coop's figures use only these)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, cast

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from gpsaccel.plots._layout import HouseFigure
from gpsaccel.plots.units import CALIBRATION_STATES, product_unit

#: The house style: colours by role, so truth, estimate, measurement and bounds read the same in
#: every figure.
STYLE: dict[str, Any] = {
    "truth": "#222222",
    "estimate": "#1f77b4",
    "measurement": "#aaaaaa",
    "error": "#d62728",
    "bound": "#ff7f0e",
    "band": "#ff7f0e",
    "figsize": (7.5, 4.0),
    "grid_figsize": (10.0, 8.0),
}


def figure(figsize: tuple[float, float] | None = None) -> Figure:
    """A new figure in the house size and layout: its axes placed once, when it is drawn, from
    what they carry (:mod:`gpsaccel.plots._layout`; no layout engine, which doubles every save)."""
    return HouseFigure(figsize=figsize or STYLE["figsize"])


def axes(ax: Axes | None = None, figsize: tuple[float, float] | None = None) -> tuple[Figure, Axes]:
    """The axes to draw on: ``ax`` if given, else a new figure in the house size."""
    if ax is not None:
        return cast(Figure, ax.figure), ax
    fig = figure(figsize)
    return fig, fig.add_subplot()


def finish(ax: Axes, title: str, xlabel: str, ylabel: str, legend: bool = True) -> None:
    """Title, labelled axes, grid and (optionally) a legend, the same on every figure."""
    ax.set_title(title)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    if legend and ax.get_legend_handles_labels()[0]:
        outside_legend(ax)


def outside_legend(ax: Axes, **kwargs) -> None:
    """The legend to the right of the axes, never over the data ("best" still covers a panel
    whose data fill it: the NEES bands, the stacked accelerations)."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0,
              **{"fontsize": "small", **kwargs})


def error_band(t: np.ndarray, error: np.ndarray, sigma: np.ndarray, k: float = 1.0, *,
               label: str = "error", unit: str = "", title: str = "", ax: Axes | None = None,
               bound_label: str | None = None) -> Figure:
    """An error over time with its ±kσ bounds (the filter's claim about that error)."""
    fig, ax = axes(ax)
    ax.plot(t, error, color=STYLE["error"], lw=1.0, label=label)
    kk = f"{k:g}" if k != 1 else ""
    lab = bound_label or f"±{kk}σ (filter)"
    ax.plot(t, k * sigma, color=STYLE["bound"], lw=1.0, ls="--", label=lab)
    ax.plot(t, -k * sigma, color=STYLE["bound"], lw=1.0, ls="--")
    finish(ax, title, "time (s)", f"{label} ({unit})" if unit else label)
    return fig


def estimate_vs_truth(t_truth: np.ndarray, truth: np.ndarray, t_est: np.ndarray,
                      estimate: np.ndarray, *, quantity: str, unit: str, title: str = "",
                      t_meas: np.ndarray | None = None, measured: np.ndarray | None = None,
                      ax: Axes | None = None) -> Figure:
    """An estimate against the truth (and optionally the raw measurement) over time."""
    fig, ax = axes(ax)
    if measured is not None:
        if t_meas is None:
            raise ValueError("estimate_vs_truth: measured needs t_meas, the times of the measurements")
        ax.plot(t_meas, measured, ".", color=STYLE["measurement"], ms=3, label="measured")
    ax.plot(t_truth, truth, color=STYLE["truth"], lw=1.2, label="truth")
    ax.plot(t_est, estimate, "+", color=STYLE["estimate"], ms=4, label="estimate")
    finish(ax, title, "time (s)", f"{quantity} ({unit})")
    return fig


def state_grid(t: np.ndarray, values: np.ndarray, *, title: str, ylabel: str,
               names: Sequence[str] | None = None, bands: np.ndarray | None = None,
               units: Sequence[str] | None = None, fig: Figure | None = None) -> Figure:
    """A 3x3 (or n x n) grid of the elements of a matrix over time: values (n_t, n, n).

    ``bands`` (same shape), if given, is drawn as ±band around zero (e.g. two standard errors).
    Each panel's y label is ``ylabel`` in the unit of its element: the product of the units of
    states i and j (``units`` per state; the calibration states' units by default).
    """
    n = values.shape[1]
    names = names or [s for s, _ in CALIBRATION_STATES][:n]
    units = units or [u for _, u in CALIBRATION_STATES][:n]
    fig = fig or figure(STYLE["grid_figsize"])
    grid = fig.subplots(n, n, sharex=True, squeeze=False)
    for i in range(n):
        for j in range(n):
            ax = grid[i, j]
            if bands is not None:
                ax.fill_between(t, -bands[:, i, j], bands[:, i, j], color=STYLE["band"],
                                alpha=0.25, lw=0)
            ax.plot(t, values[:, i, j], color=STYLE["estimate"], lw=0.8)
            ax.axhline(0.0, color=STYLE["truth"], lw=0.5)
            ax.set_title(f"({names[i]}, {names[j]})", fontsize="small")
            ax.grid(True, alpha=0.3)
            ax.tick_params(labelsize="x-small")
            ax.yaxis.get_offset_text().set_fontsize("x-small")  # "1e-5" clear of the title
            ax.set_xlabel("time (s)", fontsize="x-small")
            ax.set_ylabel(f"{ylabel} ({product_unit(units[i], units[j])})", fontsize="x-small")
    fig.suptitle(title)
    return fig


def panels(n: int, fig: Figure | None = None, *, title: str = "",
           height: float = 2.3) -> tuple[Figure, list[Axes]]:
    """``n`` stacked axes sharing the time axis, on ``fig`` (cleared) or on a new figure."""
    if fig is None:
        fig = figure((STYLE["figsize"][0], 0.8 + height * n))
    axs = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    if title:
        fig.suptitle(title)
    return fig, list(axs)


# --------------------------------------------------------------------------------------------------
# Signals in stacked panels (report 001's sensors, figures 1-5)

def time_series(t: np.ndarray, series: Sequence[tuple[np.ndarray, str, str]], *, title: str = "",
                marker: str | None = None, fig: Figure | None = None) -> Figure:
    """Stacked panels, one signal each: ``series`` = [(values, quantity, unit), ...] over ``t`` (s)."""
    fig, axs = panels(len(series), fig, title=title)
    for ax, (values, quantity, unit) in zip(axs, series, strict=True):
        if marker:
            ax.plot(t, values, marker, color=STYLE["estimate"], ms=3)
        else:
            ax.plot(t, values, color=STYLE["estimate"], lw=1.0)
        finish(ax, "", "time (s)" if ax is axs[-1] else "", f"{quantity} ({unit})")
    return fig


# --------------------------------------------------------------------------------------------------
# Chi-square consistency tests (NEES/NIS of any system)

def chi2_band(t: np.ndarray, values: np.ndarray, bounds: tuple[float, float], *,
              statistic: str = "NEES", dof: int | None = None, n_runs: int | None = None,
              title: str = "", log: bool = False, ax: Axes | None = None) -> Figure:
    """An N-run average of a χ² statistic over time (s) against its two-sided bounds (r1, r2).

    Points inside the bounds are drawn in the estimate colour, points outside in the error colour;
    the legend gives the fraction inside.  ``dof`` draws the expected value; ``log`` a log y-axis
    (for a statistic that runs off by orders of magnitude).
    """
    fig, ax = axes(ax)
    values = np.asarray(values, dtype=float)
    lo, hi = bounds
    inside = (values >= lo) & (values <= hi)
    runs = f", N = {n_runs}" if n_runs else ""
    ax.plot(t[inside], values[inside], ".", color=STYLE["estimate"], ms=2.5,
            label=f"{statistic} average{runs}: {inside.mean():.1%} inside")
    ax.plot(t[~inside], values[~inside], ".", color=STYLE["error"], ms=2.5, label="outside")
    ax.axhline(lo, color=STYLE["bound"], ls="--", lw=1.0, label=f"r1 = {lo:.3g}, r2 = {hi:.3g}")
    ax.axhline(hi, color=STYLE["bound"], ls="--", lw=1.0)
    if dof is not None:
        ax.axhline(dof, color=STYLE["truth"], ls=":", lw=0.8, label=f"expected {dof}")
    if log:
        ax.set_yscale("log")
    finish(ax, title, "time (s)", f"average {statistic} (–)")
    return fig


# --------------------------------------------------------------------------------------------------
# Overlaid signals in stacked panels and x–y tracks (the ship, report 004)

#: How each role is drawn by :func:`overlay_panels` and :func:`track`.
_ROLE_STYLE: dict[str, dict[str, Any]] = {
    "measurement": {"ls": "none", "marker": "+", "ms": 3, "color": STYLE["measurement"]},
    "truth": {"lw": 1.4, "color": STYLE["truth"]},
    "estimate": {"lw": 1.0, "color": STYLE["estimate"]},
    "error": {"lw": 1.0, "color": STYLE["error"]},
    "bound": {"lw": 1.0, "ls": "--", "color": STYLE["bound"]},
    "alternative": {"lw": 1.0, "ls": "--", "color": "#2ca02c"},
}


def overlay_panels(panels_: Sequence[tuple[str, str, Sequence[tuple]]], *, title: str = "",
                   xlabel: str = "time (s)", fig: Figure | None = None,
                   height: float = 2.3) -> Figure:
    """Stacked panels, several signals each: ``panels_`` = [(quantity, unit, lines), ...].

    ``lines`` = [(t, values, label, role), ...]; ``role`` is one of ``measurement`` (markers),
    ``truth``, ``estimate``, ``error``, ``bound``, ``alternative`` (lines in the house colours).
    """
    fig, axs = panels(len(panels_), fig, title=title, height=height)
    for ax, (quantity, unit, lines) in zip(axs, panels_, strict=True):
        for t, values, label, role in lines:
            ax.plot(t, values, label=label, **_ROLE_STYLE[role])
        finish(ax, "", xlabel if ax is axs[-1] else "", f"{quantity} ({unit})")
    return fig


def track(tracks: Sequence[tuple[np.ndarray, np.ndarray, str, str]], *, title: str = "",
          unit: str = "m", ax: Axes | None = None) -> Figure:
    """x–y tracks with equal axes: ``tracks`` = [(x, y, label, role), ...] (roles as above)."""
    fig, ax = axes(ax, figsize=(7.5, 5.0))
    for x, y, label, role in tracks:
        ax.plot(x, y, label=label, **_ROLE_STYLE[role])
    ax.set_aspect("equal", adjustable="datalim")
    finish(ax, title, f"x ({unit})", f"y ({unit})")
    return fig
