"""Schedule: which fast steps carry which measurement components."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel import CalibrationModel, Schedule


def test_calibration_schedule_is_every_40_steps():
    s = CalibrationModel().schedule()
    np.testing.assert_array_equal(s.steps, np.arange(0, 6001, 40))
    assert s.mask.shape == (151, 2) and s.mask.all()


def test_two_sensors_at_different_rates():
    s = Schedule.from_periods(25, [10, 10, 1])
    np.testing.assert_array_equal(s.steps, np.arange(26))
    np.testing.assert_array_equal(s.mask[:, 0], np.arange(26) % 10 == 0)
    assert s.mask[:, 2].all()
    r = Schedule.from_rates(25, 0.1, [1.0, 1.0, 10.0])
    np.testing.assert_array_equal(r.mask, s.mask)


def test_offsets_and_mask_roundtrip():
    s = Schedule.from_periods(9, [3], offsets=[1])
    np.testing.assert_array_equal(s.steps, [1, 4, 7])
    full = np.zeros((10, 1), bool)
    full[[1, 4, 7]] = True
    t = Schedule.from_mask(full)
    np.testing.assert_array_equal(t.steps, s.steps)
    assert t.n_steps == 9


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: Schedule.from_rates(10, 0.1, [3.0]), r"1/rates_hz\[0\]"),
        (lambda: Schedule.from_rates(10, 0.1, [0.0]), r"rates_hz\[0\]"),
        (lambda: Schedule.from_periods(10, [0]), r"periods\[0\]"),
        (lambda: Schedule.from_periods(10, [2.5]), r"periods\[0\]"),
        (lambda: Schedule.from_periods(10, [2, 2], offsets=[0]), "offsets"),
        (lambda: Schedule.from_mask(np.ones(5, bool)), "available"),
        (lambda: Schedule(5, np.array([0, 6]), np.ones((2, 1), bool)), "steps"),
        (lambda: Schedule(5, np.array([0, 2]), np.ones((3, 1), bool)), "mask"),
    ],
)
def test_bad_schedules(call, match):
    with pytest.raises(ValueError, match=match):
        call()
