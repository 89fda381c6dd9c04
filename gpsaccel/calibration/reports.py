"""Each calibration report's problem: its (corrected) model and the truth it simulates.

Reports 000, 001 and 003 state the same problem with different slips (:mod:`errata` measures
them).  The package draws every report's figures with the corrected model of that report and the
truth the report itself simulated.
"""

from __future__ import annotations

from gpsaccel import _validation as _v
from gpsaccel.calibration.model import CalibrationModel

#: The truth each report simulates: 000 propagates the error model itself, 001 and 003 the
#: closed form of a(t) = A sin(2π f t).
REPORT_TRUTH = {"000": "error-model", "001": "kinematic", "003": "kinematic"}


def report_model(report: str) -> CalibrationModel:
    """The corrected model of a report.

    000: a(t) = 10 sin(0.1 t) (ω = 0.1 rad/s).  001 and 003: a(t) = 10 sin(2π·0.1·t) (their
    "ω = 0.1" is a frequency in Hz).  Every other number is the problem statement's: Δt = 0.005 s,
    GPS every 40 samples, W = 0.0004 (m/s²)², V = diag(1 m², (0.04 m/s)²), M0 = diag(100, 1, 0.01),
    p̄0 = 0 m, v̄0 = 100 m/s, 30 s.
    """
    _v.choice("report", report, tuple(REPORT_TRUTH))
    if report == "000":
        return CalibrationModel(omega=0.1, accel_amplitude=10.0)
    return CalibrationModel(frequency_hz=0.1, accel_amplitude=10.0)
