"""compare(): filter forms side by side, and a student's callable beside the reference."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel import CalibrationModel, run_multirate
from gpsaccel.calibration.compare import compare, reference_filter


@pytest.mark.parametrize("truth", ["error-model", "kinematic"])
def test_information_form_agrees_with_filterpy(truth):
    table = compare(seed=3, truth=truth, repeat=1)
    (row,) = table.rows
    assert row.max_dx_sigma < 1e-10 and row.max_dP_rel < 1e-10
    assert row.seconds > 0 and table.reference_seconds > 0
    text = str(table)
    assert "information form" in text and "filterpy" in text


def test_a_mistaken_filter_shows_up():
    wrong = CalibrationModel(W=0.0004**0.5)  # a standard deviation where a variance belongs

    def student(z):
        res = run_multirate(wrong, z)
        return res.x_hat, res.P

    table = compare(filters={"student": student, "same": reference_filter(CalibrationModel())},
                    repeat=1)
    student_row, same_row = table.rows
    assert student_row.max_dP_rel > 0.1 and student_row.max_dx_sigma > 0.1
    assert same_row.max_dx_sigma == 0.0 and same_row.max_dP_rel == 0.0


def test_bad_filters_are_named():
    with pytest.raises(ValueError, match=r"filters\['x'\] must be callable"):
        compare(filters={"x": 3}, repeat=1)
    with pytest.raises(ValueError, match="short: x_hat must have shape"):
        compare(filters={"short": lambda z: (np.zeros((3, 3)), np.zeros((151, 3, 3)))}, repeat=1)
    with pytest.raises(ValueError, match="truth"):
        compare(truth="euler")
