"""Shared by the report figures' tests."""

from __future__ import annotations

import pytest


def legends_over_their_axes(figure, renderer) -> list[str]:
    """The titles of the axes that their own visible legend overlaps, as ``renderer`` drew them."""
    over = []
    for ax in figure.axes:
        legend = ax.get_legend()
        if legend is not None and legend.get_visible() and \
                legend.get_window_extent(renderer).overlaps(ax.get_window_extent(renderer)):
            over.append(ax.get_title())
    return over


def watch_legends(figure) -> dict[str, list[str]]:
    """The legends of ``figure`` checked at each draw of it, the one ``savefig`` makes included:
    ``{"over": legends_over_their_axes(...)}`` of the last draw.  A test then asserts on the
    figure as it was written instead of drawing it once more (a draw costs as much as the PNG)."""
    seen: dict[str, list[str]] = {}

    def drawn(event) -> None:
        seen["over"] = legends_over_their_axes(figure, event.renderer)

    figure.canvas.mpl_connect("draw_event", drawn)
    return seen


def assert_legends_beside_their_axes(figure, where: str,
                                     seen: dict[str, list[str]] | None = None) -> None:
    """Fail if a visible axes legend overlaps its axes (``loc="best"`` still covers a panel whose
    data fill it; ``plots.outside_legend`` puts it to the right).  ``seen``: what
    :func:`watch_legends` found when the figure was drawn (saved); without it the figure is drawn
    here."""
    if seen is None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        renderer = FigureCanvasAgg(figure).get_renderer()
        figure.draw(renderer)
        over = legends_over_their_axes(figure, renderer)
    else:
        assert "over" in seen, f"{where}: the figure was never drawn"
        over = seen["over"]
    assert not over, f"{where}: the legend lies over the axes {over[0]!r}"


@pytest.fixture
def legends_beside_axes():
    """:func:`assert_legends_beside_their_axes`, for every report's figure test."""
    return assert_legends_beside_their_axes


@pytest.fixture(scope="session")
def legend_watch():
    """:func:`watch_legends`, for the module fixtures that draw a report's figures."""
    return watch_legends
