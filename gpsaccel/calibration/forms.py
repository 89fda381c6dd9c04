"""Report 000's filter forms: the core's (:mod:`gpsaccel.kalman.forms`), which run any linear
model; these names stay importable here for the calibration lessons and tools."""

from gpsaccel.kalman.forms import (
    FORMS,
    FilterpyInformation,
    FilterpySquareRoot,
    StandardKalmanFilter,
    make_form,
    run_form,
)

__all__ = ["FORMS", "FilterpyInformation", "FilterpySquareRoot", "StandardKalmanFilter",
           "make_form", "run_form"]
