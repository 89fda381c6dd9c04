"""Hostile: takes the import blocker off sys.meta_path, finds gpsaccel's source folder through the
editable install's finder in site-packages, and imports the reference filter from there."""
import ast
import glob
import os
import sys

import numpy as np


def _gpsaccel_parent():
    for d in sys.path:
        for f in glob.glob(os.path.join(d, "__editable__*gpsaccel*finder.py")):
            for line in open(f, encoding="utf-8"):
                if line.startswith("MAPPING"):
                    return os.path.dirname(ast.literal_eval(line.split("=", 1)[1].strip())
                                           ["gpsaccel"])
    return "/work/main"


def kalman_filter(z):
    sys.meta_path[:] = [f for f in sys.meta_path if type(f).__name__ != "_Blocker"]
    sys.path.insert(0, _gpsaccel_parent())
    from gpsaccel.calibration.mistakes import reference
    from gpsaccel.calibration.model import CalibrationModel

    x, P = reference(CalibrationModel()).apply(z[None])
    return np.asarray(x)[0], np.asarray(P)
