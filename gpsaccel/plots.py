"""Kinds of figure, reused by every report, lesson and the CLI.

Each function takes results objects (and an optional matplotlib ``Axes``) and returns the
``Figure``; the house style lives in :data:`STYLE` and :func:`axes`.  Report modules in
:mod:`gpsaccel.figures` only choose which kind of figure shows what.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

#: The house style: colours by role, so truth, estimate, measurement and bounds read the same in
#: every figure.
STYLE = {
    "truth": "#222222",
    "estimate": "#1f77b4",
    "measurement": "#aaaaaa",
    "error": "#d62728",
    "bound": "#ff7f0e",
    "band": "#ff7f0e",
    "figsize": (7.5, 4.0),
    "grid_figsize": (10.0, 8.0),
}

#: Names and units of the calibration error state, used in labels.
CALIBRATION_STATES = (("δp", "m"), ("δv", "m/s"), ("b", "m/s²"))


def axes(ax: Axes | None = None, figsize: tuple[float, float] | None = None) -> tuple[Figure, Axes]:
    """The axes to draw on: ``ax`` if given, else a new figure in the house size."""
    if ax is not None:
        return ax.figure, ax
    fig = Figure(figsize=figsize or STYLE["figsize"], layout="constrained")
    return fig, fig.add_subplot()


def finish(ax: Axes, title: str, xlabel: str, ylabel: str, legend: bool = True) -> None:
    """Title, labelled axes, grid and (optionally) a legend, the same on every figure."""
    ax.set_title(title)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    if legend and ax.get_legend_handles_labels()[0]:
        ax.legend(loc="best", fontsize="small")


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
        ax.plot(t_meas, measured, ".", color=STYLE["measurement"], ms=3, label="measured")
    ax.plot(t_truth, truth, color=STYLE["truth"], lw=1.2, label="truth")
    ax.plot(t_est, estimate, "+", color=STYLE["estimate"], ms=4, label="estimate")
    finish(ax, title, "time (s)", f"{quantity} ({unit})")
    return fig


def state_grid(t: np.ndarray, values: np.ndarray, *, title: str, ylabel: str,
               names: Sequence[str] | None = None, bands: np.ndarray | None = None,
               fig: Figure | None = None) -> Figure:
    """A 3x3 (or n x n) grid of the elements of a matrix over time: values (n_t, n, n).

    ``bands`` (same shape), if given, is drawn as ±band around zero (e.g. two standard errors).
    """
    n = values.shape[1]
    names = names or [s for s, _ in CALIBRATION_STATES][:n]
    fig = fig or Figure(figsize=STYLE["grid_figsize"], layout="constrained")
    grid = fig.subplots(n, n, sharex=True)
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
            if i == n - 1:
                ax.set_xlabel("time (s)")
    fig.suptitle(title)
    fig.supylabel(ylabel)
    return fig
