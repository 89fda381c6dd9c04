"""The house layout (gpsaccel.plots._layout): every figure kind drawn once per save, with nothing
cut at the figure's edge and no axes' labels, ticks, title or legend over a neighbour's frame."""

from __future__ import annotations

import io

import matplotlib
import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

from gpsaccel import plots, run_multirate, simulate
from gpsaccel.calibration.montecarlo import monte_carlo
from gpsaccel.calibration.reports import report_model

matplotlib.use("Agg")


@pytest.fixture(scope="module")
def one_run():
    model = report_model("001")
    run = simulate(model, np.random.default_rng(5), truth="kinematic")
    return run, run_multirate(model, run.z)


@pytest.fixture(scope="module")
def ensemble():
    return monte_carlo(report_model("000"), 20, seed=1, progress=False)


def _chi2_with_a_long_legend():
    t = np.arange(200.0)
    fig, axs = plots.panels(2, title="two χ² panels")
    plots.chi2_band(t, 6 + np.sin(t), (4.0, 8.0), dof=6, n_runs=10, ax=axs[0])
    plots.chi2_band(t, 5 + np.cos(t), (3.5, 6.5), statistic="a much longer statistic's name",
                    dof=5, n_runs=10000, ax=axs[1])
    return fig


def _added_afterwards():
    """A lesson's way: a house figure, then its own titles, labels and legend."""
    fig, axs = plots.panels(2, title="made, then added to")
    for i, ax in enumerate(axs):
        ax.semilogy(np.arange(1, 50), 1e-6 * np.arange(1, 50) ** 3, label=f"curve {i} " * 4)
        ax.set_title(f"panel {i}, titled after the figure was made")
        plots.finish(ax, f"panel {i}\non two lines", "time (s)", "value (m²/s⁴)")
    return fig


#: Each figure kind the command, the reports and the lessons draw, on small data.
FIGURES = {
    "error_band": lambda run, res, mc: plots.error_band(
        res.t_gps, run.x_gps[:, 0] - res.x_hat[:, 0], res.sigma[:, 0], label="p − p̂", unit="m",
        title="Position error"),
    "estimate_vs_truth": lambda run, res, mc: plots.estimate_vs_truth(
        run.t, run.p, res.t_gps, run.p_c[run.gps_steps] + res.x_hat[:, 0], quantity="p",
        unit="m", title="estimate"),
    "errors_with_sigma": lambda run, res, mc: plots.errors_with_sigma(run, res,
                                                                      between_fixes=True),
    "error_comparison": lambda run, res, mc: plots.error_comparison(run, res),
    "gains": lambda run, res, mc: plots.gains(res),
    "pave_minus_p_grid": lambda run, res, mc: plots.pave_minus_p(mc),
    "pave_minus_p_lines": lambda run, res, mc: plots.pave_minus_p(mc, grid=False),
    "pave_minus_p_normalised": lambda run, res, mc: plots.pave_minus_p(mc, normalised=True),
    "ensemble_mean_error": lambda run, res, mc: plots.ensemble_mean_error(mc, sigma=True),
    "orthogonality": lambda run, res, mc: plots.orthogonality(mc),
    "system_diagram": lambda run, res, mc: plots.system_diagram(),
    "track": lambda run, res, mc: plots.track([(run.t, run.p, "true", "truth")]),
    "chi2_long_legend": lambda run, res, mc: _chi2_with_a_long_legend(),
    "added_afterwards": lambda run, res, mc: _added_afterwards(),
}


def _decorations(ax, renderer):
    """(what, extent) of everything an axes draws beyond its frame: each axis' drawn tick
    labels, label and offset text, the titles, the legend."""
    found = [(f"{ax.get_title()!r}'s {axis.axis_name} axis", axis.get_tightbbox(renderer))
             for axis in (ax.xaxis, ax.yaxis) if ax.axison]
    found += [(repr(t.get_text()), t.get_window_extent(renderer))
              for t in (ax.title, ax._left_title, ax._right_title)
              if t.get_visible() and t.get_text()]
    legend = ax.get_legend()
    if legend is not None and legend.get_visible():
        found.append((f"{ax.get_title()!r}'s legend", legend.get_window_extent(renderer)))
    return [(what, box) for what, box in found if box is not None and box.width > 0]


@pytest.mark.parametrize("kind", FIGURES)
def test_one_draw_per_save_nothing_cut_nothing_over_a_neighbour(kind, one_run, ensemble):
    fig = FIGURES[kind](*one_run, ensemble)
    assert fig.get_layout_engine() is None  # an engine draws every save twice
    draws = []
    fig.canvas.mpl_connect("draw_event", lambda event: draws.append(event.renderer))
    fig.savefig(io.BytesIO(), format="png", dpi=60)
    assert len(draws) == 1
    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw(renderer)
    page = fig.bbox.padded(-0.5)  # a pixel's rounding
    suptitle = fig._suptitle
    for ax in fig.axes:
        if not ax.get_visible():
            continue
        for what, box in _decorations(ax, renderer):
            where = f"{kind}: {what}"
            assert page.x0 <= box.x0 and box.x1 <= page.x1 + 1, f"{where} cut at a side"
            assert page.y0 <= box.y0 and box.y1 <= page.y1 + 1, f"{where} cut at top/bottom"
            for other in fig.axes:
                if other is not ax and other.get_visible() and other.get_subplotspec():
                    assert not box.overlaps(other.bbox), f"{where} over {other.get_title()!r}"
            if suptitle is not None and suptitle.get_text():
                assert not box.overlaps(suptitle.get_window_extent(renderer)), where
        legend = ax.get_legend()
        if legend is not None and legend.get_visible():
            assert not legend.get_window_extent(renderer).overlaps(ax.bbox), kind


def test_a_figure_given_a_layout_engine_is_left_to_it(ensemble):
    fig = plots.pave_minus_p(ensemble)
    fig.set_layout_engine("constrained")
    before = [ax.get_position().bounds for ax in fig.axes]
    FigureCanvasAgg(fig).draw()
    # constrained layout moved the axes; the house layout did not run on top of it
    assert [ax.get_position().bounds for ax in fig.axes] != before
    assert fig.subplotpars.left == matplotlib.rcParams["figure.subplot.left"]


def test_a_hat_on_a_tall_letter_is_drawn_above_its_stem():
    """matplotlib draws U+0302 at x-height, on the stem of b: ``b − b̂`` read ``b − b`` in every
    bias figure.  Drawn, the hat on a tall letter is mathtext's, whose glyph sits higher than the
    letter's top; the hat on p stays as written, and a text with a ``$`` is left alone."""
    fig = plots.error_band(np.arange(3.0), np.zeros(3), np.ones(3), label="b − b̂", unit="m/s²")
    ax = fig.axes[0]
    ax.set_title("δp − δp̂ costs $1")
    fig.savefig(io.BytesIO(), format="png")
    assert ax.get_ylabel() == r"b − $\hat{\mathrm{b}}$ (m/s²)"
    assert [t.get_text() for t in ax.get_legend().get_texts()][0] == r"b − $\hat{\mathrm{b}}$"
    assert ax.get_title() == "δp − δp̂ costs $1"

    def ink_runs(text):  # the bands of inked rows of ``text`` drawn alone: 2 when the hat clears
        f = matplotlib.figure.Figure(figsize=(2, 1), dpi=100)  # a notebook's inline figure
        FigureCanvasAgg(f)
        f.text(0.1, 0.3, text, fontsize=8.5)  # a legend's "small"
        f.canvas.draw()
        rows = (np.asarray(f.canvas.buffer_rgba())[..., :3].min(axis=(1, 2)) < 128).astype(int)
        return int((np.diff(rows) == 1).sum() + rows[0])

    assert ink_runs("p\u0302") == 2  # the hat on a short letter clears it
    assert ink_runs("b\u0302") == 1  # on b it touches the stem
    assert ink_runs(r"$\hat{\mathrm{b}}$") == 2
