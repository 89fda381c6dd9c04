"""Kinds of figure, reused by every report, lesson and the CLI.

Each function takes results objects (and an optional matplotlib ``Axes``) and returns the
``Figure``; the house style lives in :data:`STYLE` and :func:`axes`.  Report modules in
:mod:`gpsaccel.figures` only choose which kind of figure shows what.

Two modules, by system: :mod:`~gpsaccel.plots.kinds` draws any system's arrays (the house style,
bands, panels, a matrix's elements in a grid, χ² bounds, tracks: the ship and coop figures use only these)
and :mod:`~gpsaccel.plots.calibration` the calibration system's own figures;
:mod:`~gpsaccel.plots.units` names the calibration states' units.  Every name is read here as
``plots.NAME``.
"""

from gpsaccel.plots.calibration import (
    FORM_STYLE,
    accelerometer_drift,
    actual_vs_claimed,
    ensemble_mean_error,
    error_comparison,
    errors_with_sigma,
    estimates_with_truth,
    form_sweep,
    gains,
    gps_minus_accelerometer,
    gps_noise,
    matrix_lines,
    orthogonality,
    pave_minus_p,
    system_diagram,
    truth_kinematics,
)
from gpsaccel.plots.kinds import (
    STYLE,
    axes,
    chi2_band,
    error_band,
    estimate_vs_truth,
    figure,
    finish,
    outside_legend,
    overlay_panels,
    panels,
    state_grid,
    time_series,
    track,
)
from gpsaccel.plots.units import (
    CALIBRATION_STATES,
    product_unit,
)

__all__ = [
    "CALIBRATION_STATES",
    "FORM_STYLE",
    "STYLE",
    "accelerometer_drift",
    "actual_vs_claimed",
    "axes",
    "chi2_band",
    "ensemble_mean_error",
    "error_band",
    "error_comparison",
    "errors_with_sigma",
    "estimate_vs_truth",
    "estimates_with_truth",
    "figure",
    "finish",
    "form_sweep",
    "gains",
    "gps_minus_accelerometer",
    "gps_noise",
    "matrix_lines",
    "orthogonality",
    "outside_legend",
    "overlay_panels",
    "panels",
    "pave_minus_p",
    "product_unit",
    "state_grid",
    "system_diagram",
    "time_series",
    "track",
    "truth_kinematics",
]
