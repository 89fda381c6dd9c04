"""The house layout: a figure of :mod:`gpsaccel.plots` places its axes itself, once, when it is
drawn, from what each axes carries; no layout engine.

matplotlib draws a figure that has a layout engine twice on every save (once, rendering nothing,
to lay it out), and constrained layout measures every tick label of every axes for it: the four
figures of ``gpsaccel montecarlo`` spent most of the command's CPU there.  Here the margins come
from the font sizes of the titles and axis labels, the widths of the tick labels as each axis
formats them, and the extent of a legend placed outside its axes (:func:`~gpsaccel.plots.kinds.
outside_legend`), measured with the draw's own renderer; then the figure is drawn once.  What a
caller adds after the figure is made (a title, a legend, another line) is laid out too.

The axes must sit in one grid (``fig.subplots``, ``fig.add_subplot``), as every house figure's
do; a figure given a layout engine afterwards (``fig.set_layout_engine("constrained")``) is left
to it, and one with axes in two grids is left as matplotlib places it.

A hat written the course's way, a letter and U+0302 (``b̂``), is drawn by matplotlib at x-height:
on a letter with an ascender it lands on the stem and ``b − b̂`` reads ``b − b``.  Before the
layout such a letter becomes mathtext's upright ``\\hat`` (:func:`hats_above_ascenders`).
"""

from __future__ import annotations

import re
from typing import Any

import matplotlib
from matplotlib import cbook
from matplotlib.axes import Axes
from matplotlib.axis import Axis
from matplotlib.figure import Figure
from matplotlib.font_manager import FontProperties
from matplotlib.gridspec import GridSpec, SubplotSpec
from matplotlib.text import Text

#: Inches: the space kept at the figure's edges, and between one axes' labels and the next's.
EDGE = 0.08
GAP = 0.15
#: A text line's height over its font size (matplotlib's default line spacing).
LINE = 1.2

#: matplotlib's settings, read as they are at each draw (an ``rc_context`` changes this object)
rc: Any = matplotlib.rcParams


class HouseFigure(Figure):
    """A :class:`~matplotlib.figure.Figure` laid out by :func:`lay_out` each time it is drawn."""

    def draw(self, renderer: Any) -> None:
        hats_above_ascenders(self)
        if self.get_layout_engine() is None:
            lay_out(self, renderer)
        super().draw(renderer)


#: A letter with an ascender (or a capital) and a combining circumflex.
_TALL_HAT = re.compile("([A-Zbdfhklt])\u0302")


def hats_above_ascenders(fig: Figure) -> None:
    """Every text of ``fig`` with a hat on a tall letter (``b̂``) rewritten as mathtext
    (``$\\hat{\\mathrm{b}}$``), whose hat clears the stem; a text already holding a ``$`` (mathtext
    or a dollar) is left as it is."""
    for text in fig.findobj(Text):
        s = text.get_text()
        if "\u0302" in s and "$" not in s:
            text.set_text(_TALL_HAT.sub(r"$\\hat{\\mathrm{\1}}$", s))


def lay_out(fig: Figure, renderer: Any) -> None:
    """Set the grid's margins and spacing of ``fig`` (inches, converted to its fractions) so that
    every axes' tick labels, axis labels, title and outside legend fit beside its neighbours."""
    grid: list[tuple[Axes, SubplotSpec]] = []
    for ax in fig.axes:
        spec = ax.get_subplotspec()
        if ax.get_visible() and spec is not None:
            grid.append((ax, spec))
    specs = {spec.get_gridspec() for _, spec in grid}
    gs = specs.pop() if len(specs) == 1 else None
    if not isinstance(gs, GridSpec):
        return
    for _ in range(2):  # the tick labels follow the axes' size: measure again once placed
        params = _grid_params(fig, gs, grid, renderer)
        if params is None:
            return
        fig.subplots_adjust(**params)  # the figure's, which the grid follows: it moves the axes


def _grid_params(fig: Figure, gs: GridSpec, grid: list[tuple[Axes, SubplotSpec]],
                 renderer: Any) -> dict | None:
    """The GridSpec parameters that give each side of every axes what :func:`_needs` says."""
    nrows, ncols = gs.get_geometry()
    left, right, top, bottom = ([0.0] * ncols, [0.0] * ncols, [0.0] * nrows, [0.0] * nrows)
    for ax, spec in grid:
        cols, rows = spec.colspan, spec.rowspan
        need = _needs(ax, renderer)
        left[cols.start] = max(left[cols.start], need["left"])
        right[cols.stop - 1] = max(right[cols.stop - 1], need["right"])
        top[rows.start] = max(top[rows.start], need["top"])
        bottom[rows.stop - 1] = max(bottom[rows.stop - 1], need["bottom"])
    width, height = fig.get_size_inches()
    title = fig.get_suptitle()
    above = (0.02 * height + _text_height(title, rc["figure.titlesize"]) + EDGE
             if title else 0.0)
    margin = {"left": EDGE + left[0], "right": EDGE + right[-1],
              "top": EDGE + above + top[0], "bottom": EDGE + bottom[-1]}
    wgap = GAP + max((right[j] + left[j + 1] for j in range(ncols - 1)), default=0.0)
    hgap = GAP + max((bottom[i] + top[i + 1] for i in range(nrows - 1)), default=0.0)
    ax_w = (width - margin["left"] - margin["right"] - (ncols - 1) * wgap) / ncols
    ax_h = (height - margin["top"] - margin["bottom"] - (nrows - 1) * hgap) / nrows
    if ax_w < 0.3 or ax_h < 0.2:  # no room: leave matplotlib's default rather than nothing
        return None
    return {"left": margin["left"] / width, "right": 1 - margin["right"] / width,
            "bottom": margin["bottom"] / height, "top": 1 - margin["top"] / height,
            "wspace": wgap / ax_w, "hspace": hgap / ax_h}


def _needs(ax: Axes, renderer: Any) -> dict[str, float]:
    """Inches that ``ax``'s decorations take beyond its frame, by side."""
    need = {"left": 0.0, "right": 0.0, "top": 0.0, "bottom": 0.0}
    offset = 0.0
    if ax.axison:
        _axis_needs(ax.xaxis, ("bottom", "top"), renderer, need)
        offset = _axis_needs(ax.yaxis, ("left", "right"), renderer, need)
    titles = [ax.get_title(loc) for loc in ("left", "center", "right")]
    pad = rc["axes.titlepad"] / 72
    heading = max((_text_height(t, ax.title.get_fontsize()) + pad for t in titles if t),
                  default=0.0)
    need["top"] += max(heading, offset)  # the y axis' offset text ("1e-5") sits beside the title
    legend = ax.get_legend()
    if legend is not None and legend.get_visible():
        _legend_needs(ax, legend, renderer, need)
    return need


def _axis_needs(axis: Axis, sides: tuple[str, str], renderer: Any, need: dict) -> float:
    """Add what ``axis``'s tick labels and label take on its two sides (x: bottom, top) to
    ``need``; return the height of its offset text above the axes (a y axis'), if any."""
    params = axis.get_tick_params()
    name = "xtick" if sides[0] == "bottom" else "ytick"
    size = FontProperties(size=params.get("labelsize", rc[f"{name}.labelsize"]))
    ticks = (params.get("length", rc[f"{name}.major.size"])
             + params.get("pad", rc[f"{name}.major.pad"])) / 72
    labels, offset = _tick_labels(axis)
    if sides[0] == "bottom":
        extent = max((_text_height(s, size.get_size_in_points()) for s in labels), default=0.0)
    else:
        extent = max((_text_width(s, size, renderer) for s in labels), default=0.0)
    for side in sides:
        if labels and params.get(f"label{side}", rc[f"{name}.label{side}"]):
            need[side] += ticks + extent
    label = axis.get_label_text()
    if label:
        need[axis.get_label_position()] += (_text_height(label, axis.label.get_fontsize())
                                            + axis.labelpad / 72)
    if offset and sides[0] == "left":  # drawn above the axes
        return _text_height(offset, size.get_size_in_points()) + 0.05
    return 0.0


def _tick_labels(axis: Axis) -> tuple[list[str], str]:
    """The major tick labels ``axis`` will draw in its view, and its offset text ("1e-5")."""
    lo, hi = sorted(axis.get_view_interval())
    slack = 1e-9 * (hi - lo)
    locs = [v for v in axis.get_majorticklocs() if lo - slack <= v <= hi + slack]
    formatter = axis.get_major_formatter()
    labels = [s for s in formatter.format_ticks(locs) if s]
    return labels, formatter.get_offset()


def _legend_needs(ax: Axes, legend: Any, renderer: Any, need: dict) -> None:
    """What a legend anchored outside ``ax`` takes beyond it (one inside takes nothing)."""
    frame, anchor = ax.bbox, legend.get_bbox_to_anchor()
    if (anchor.x0 >= frame.x0 - 1 and anchor.x1 <= frame.x1 + 1
            and anchor.y0 >= frame.y0 - 1 and anchor.y1 <= frame.y1 + 1):
        return
    box = legend.get_window_extent(renderer)
    inch = renderer.points_to_pixels(72.0)
    need["right"] += max(0.0, box.x1 - frame.x1) / inch
    need["left"] += max(0.0, frame.x0 - box.x0) / inch
    need["top"] = max(need["top"], (box.y1 - frame.y1) / inch)
    need["bottom"] += max(0.0, frame.y0 - box.y0) / inch


def _text_height(text: str, size: float | str) -> float:
    """Inches a text of font ``size`` (points, or "large", ...) takes across its lines."""
    return (text.count("\n") + 1) * LINE * FontProperties(size=size).get_size_in_points() / 72


def _text_width(text: str, font: FontProperties, renderer: Any) -> float:
    """Inches a one-line text takes along its line, as the renderer draws it."""
    ismath = "TeX" if rc["text.usetex"] else cbook.is_math_text(text)
    width, _, _ = renderer.get_text_width_height_descent(text, font, ismath=ismath)
    return width / renderer.points_to_pixels(72.0)
