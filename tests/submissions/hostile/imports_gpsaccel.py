"""Hostile: hands back the checker's own reference filter instead of computing anything."""
import numpy as np


def kalman_filter(z):
    from gpsaccel.calibration.mistakes import reference
    from gpsaccel.calibration.model import CalibrationModel

    x, P = reference(CalibrationModel()).apply(z[None])
    return np.asarray(x)[0], np.asarray(P)
