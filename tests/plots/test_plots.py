"""The figure kinds of gpsaccel.plots draw what they say, in the units they say."""

from __future__ import annotations

import matplotlib
import numpy as np
import pytest
from matplotlib.figure import Figure

from gpsaccel import plots, run_multirate, simulate
from gpsaccel.calibration.montecarlo import monte_carlo
from gpsaccel.calibration.reports import report_model
from gpsaccel.plots.units import _ratio_unit

matplotlib.use("Agg")


@pytest.fixture(scope="module")
def one_run():
    model = report_model("001")
    run = simulate(model, np.random.default_rng(5), truth="kinematic")
    return model, run, run_multirate(model, run.z)


@pytest.fixture(scope="module")
def ensemble():
    return monte_carlo(report_model("001"), 20, seed=1, truth="kinematic", progress=False)


def _line(ax, label):
    lines = [ln for ln in ax.get_lines() if ln.get_label() == label]
    assert len(lines) == 1, f"no single line labelled {label!r} in {ax.get_title()!r}"
    return lines[0]


@pytest.mark.parametrize("a, b, unit", [("m", "m", "m²"), ("m", "m/s", "m²/s"),
                                        ("m/s", "m/s²", "m²/s³"), ("m/s²", "m/s²", "m²/s⁴")])
def test_product_unit(a, b, unit):
    assert plots.product_unit(a, b) == unit


@pytest.mark.parametrize("a, b, unit", [("m", "m", "1"), ("m", "m/s", "s"),
                                        ("m/s²", "m", "1/s²"), ("m/s²", "m/s", "1/s")])
def test_gain_units(a, b, unit):
    assert _ratio_unit(a, b) == unit


def test_errors_with_sigma_draws_the_error_and_its_bounds(one_run):
    _, run, res = one_run
    fig = plots.errors_with_sigma(run, res, k=2.0)
    assert isinstance(fig, Figure) and len(fig.axes) == 3
    e = run.x_gps - res.x_hat
    for i, ax in enumerate(fig.axes):
        name = ["δp", "δv", "b"][i]
        np.testing.assert_array_equal(_line(ax, f"{name} − {name}̂").get_ydata(), e[:, i])
        np.testing.assert_array_equal(_line(ax, "±2σ (filter)").get_ydata(), 2 * res.sigma[:, i])
    assert fig.axes[0].get_ylabel() == "δp − δp̂ (m)"


def test_errors_with_sigma_window_and_outage_shading(one_run):
    _, run, res = one_run
    fig = plots.errors_with_sigma(run, res, states=(1,), between_fixes=True, shade=(10, 12),
                                  window=(9.0, 13.0))
    ax = fig.axes[0]
    for line in ax.get_lines():
        t = np.asarray(line.get_xdata())
        assert t.min() >= 9.0 and t.max() <= 13.0
    fast = _line(ax, "error between fixes")
    assert len(fast.get_xdata()) == 4 * 200 + 1  # 200 Hz over 4 s, both ends
    assert "no GPS" in [t.get_text() for t in ax.get_legend().get_texts()]


def test_estimates_with_truth_adds_the_integrated_accelerometer(one_run):
    _, run, res = one_run
    ax = plots.estimates_with_truth(run, res, states=(0,)).axes[0]
    np.testing.assert_allclose(_line(ax, "estimate").get_ydata(),
                               run.p_c[run.gps_steps] + res.x_hat[:, 0])
    np.testing.assert_array_equal(_line(ax, "truth").get_ydata(), run.p)


def test_sensor_figures(one_run):
    _, run, _ = one_run
    ax_p = plots.gps_noise(run).axes[0]
    np.testing.assert_allclose(ax_p.get_lines()[0].get_ydata(), run.eta[:, 0], atol=1e-9)
    fig = plots.gps_minus_accelerometer(run, with_truth=True)
    np.testing.assert_array_equal(_line(fig.axes[1], "z2 = GPS − accelerometer").get_ydata(),
                                  run.z[:, 1])
    drift = plots.accelerometer_drift(run).axes[1].get_lines()[0].get_ydata()
    np.testing.assert_allclose(drift, -run.x[:, 1], atol=1e-9)
    assert [ax.get_ylabel() for ax in plots.truth_kinematics(run).axes] == \
        ["a (m/s²)", "v (m/s)", "p (m)"]


def test_gains_grid(one_run):
    _, _, res = one_run
    fig = plots.gains(res)
    assert len(fig.axes) == 6
    np.testing.assert_array_equal(fig.axes[1].get_lines()[0].get_ydata(), res.K[:, 0, 1])
    assert fig.axes[1].get_ylabel() == "K12 (s)"


def test_ensemble_figures_draw_the_ensemble(ensemble):
    mc = ensemble
    fig = plots.ensemble_mean_error(mc, sigma=True)
    for i, ax in enumerate(fig.axes):
        np.testing.assert_array_equal(_line(ax, "e_ave").get_ydata(), mc.e_ave[:, i])
    # the closed-form truth: the predicted mean is drawn where it is not zero
    _line(fig.axes[1], "predicted mean")
    grid = plots.pave_minus_p(mc)
    assert len(grid.axes) == 9
    np.testing.assert_array_equal(grid.axes[5].get_lines()[0].get_ydata(),
                                  mc.P_ave[:, 1, 2] - mc.P[:, 1, 2])
    assert grid.axes[5].get_ylabel() == "P_ave − P (m²/s³)"
    lines = plots.pave_minus_p(mc, grid=False).axes[0]
    assert len(lines.get_lines()) == 9
    ortho = plots.orthogonality(mc)
    np.testing.assert_array_equal(ortho.axes[0].get_lines()[0].get_ydata(),
                                  mc.orthogonality[:, 0, 0])


def test_draws_into_a_given_figure_or_axes(one_run):
    _, run, res = one_run
    fig = Figure()
    assert plots.errors_with_sigma(run, res, fig=fig) is fig
    ax = Figure().add_subplot()
    assert plots.error_band(res.t_gps, res.x_hat[:, 0], res.sigma[:, 0], ax=ax) is ax.figure
    assert plots.system_diagram(ax=Figure().add_subplot()).axes[0].axison is False


def test_actual_vs_claimed_draws_exact_statistics():
    from gpsaccel.calibration import errata

    wrong, base = errata.process_noise_on_gps_interval().statistics()
    fig = plots.actual_vs_claimed(wrong, base, states=(1,))
    ax = fig.axes[0]
    np.testing.assert_array_equal(_line(ax, "mistaken filter: RMS error").get_ydata(),
                                  wrong.rms[:, 1])
    np.testing.assert_array_equal(_line(ax, "mistaken filter: claimed σ").get_ydata(),
                                  wrong.claimed_sigma[:, 1])
    assert ax.get_yscale() == "log"


def test_legends_sit_beside_the_data_not_over_it():
    """Lesson 9's NEES panels and 6-panel accelerations, lesson 11's slider figure: the legend of
    every panel that has one lies right of its axes (``loc="best"`` still covered full panels)."""
    t = np.arange(200.0)
    fig, axs = plots.panels(2)
    plots.chi2_band(t, 6 + np.sin(t), (4.0, 8.0), dof=6, n_runs=10, ax=axs[0])
    plots.chi2_band(t, 5 + np.cos(t), (3.5, 6.5), statistic="NIS", dof=5, n_runs=10, ax=axs[1])
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw(renderer)
    for ax in axs:
        legend, box = ax.get_legend().get_window_extent(renderer), ax.get_window_extent(renderer)
        assert legend.x0 >= box.x1, "the legend overlaps its axes"
