"""Shared by the report figures' tests."""

from __future__ import annotations

import pytest


def assert_legends_beside_their_axes(figure, where: str) -> None:
    """Draw ``figure`` and fail if a visible axes legend overlaps its axes (``loc="best"`` still
    covers a panel whose data fill it; ``plots.outside_legend`` puts it to the right)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    renderer = FigureCanvasAgg(figure).get_renderer()
    figure.draw(renderer)
    for ax in figure.axes:
        legend = ax.get_legend()
        if legend is not None and legend.get_visible():
            box = ax.get_window_extent(renderer)
            assert not legend.get_window_extent(renderer).overlaps(box), \
                f"{where}: the legend lies over the axes {ax.get_title()!r}"


@pytest.fixture
def legends_beside_axes():
    """:func:`assert_legends_beside_their_axes`, for every report's figure test."""
    return assert_legends_beside_their_axes
