"""Each report's model and truth (calibration.reports)."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel.calibration.reports import REPORT_TRUTH, report_model


def test_report_models_use_each_reports_frequency_convention():
    assert report_model("000").angular_frequency == pytest.approx(0.1)
    assert report_model("001").angular_frequency == pytest.approx(2 * np.pi * 0.1)
    assert report_model("003").angular_frequency == pytest.approx(2 * np.pi * 0.1)
    with pytest.raises(ValueError, match="report must be one of '000', '001', '003'"):
        report_model("005")


def test_each_report_simulates_its_own_truth():
    assert REPORT_TRUTH == {"000": "error-model", "001": "kinematic", "003": "kinematic"}
    for report in REPORT_TRUTH:  # every other number is the problem statement's
        m = report_model(report)
        assert (m.dt, m.gps_every, m.duration) == (0.005, 40, 30.0)
        np.testing.assert_array_equal(m.M0, np.diag([100.0, 1.0, 0.01]))
