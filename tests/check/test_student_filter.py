"""A student's file as a filter callable: run in its own process, compared against the exact answer;
what the sandbox refuses of it is a StudentFilterError, under every backend."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gpsaccel import check
from gpsaccel.calibration.compare import compare

SUBMISSIONS = Path(__file__).resolve().parents[1] / "submissions"


def test_student_files_sit_in_the_table_beside_the_forms():
    filters = {name: check.student_filter(SUBMISSIONS / f"{name}.py", timeout=30, repeat=2)
               for name in ("correct_gps_rate", "mutant_phi_sign", "broken_raises")}
    t = compare("joseph", filters=filters, repeat=1)
    good = t.row("correct_gps_rate")
    assert good.errors.dx_sigma < 1e-10 and good.errors.dP_rel < 1e-10
    assert 0 < good.seconds == filters["correct_gps_rate"].seconds
    assert t.row("mutant_phi_sign").errors.dP_rel > 1e-4  # the smallest catalogued mistake
    broken = t.row("broken_raises")
    assert broken.errors is None and "raised an exception on run 0" in broken.problem
    assert "broken_raises.py" in broken.problem  # the student's own traceback line
    assert "failed:" in str(t)


def test_a_student_file_is_not_imported_here():
    import sys

    check.student_filter(SUBMISSIONS / "correct_joseph.py", timeout=30, repeat=1)(
        np.zeros((151, 2)))
    assert "student_submission" not in sys.modules


def test_bad_arguments_are_named(tmp_path):
    with pytest.raises(ValueError, match="path"):
        check.student_filter(tmp_path / "missing.py")
    with pytest.raises(ValueError, match="timeout"):
        check.student_filter(SUBMISSIONS / "correct_joseph.py", timeout=0)
    with pytest.raises(ValueError, match="repeat"):
        check.student_filter(SUBMISSIONS / "correct_joseph.py", repeat=0)


def test_student_filter_reports_instead_of_raising_something_else(backend, hostile):
    from gpsaccel.check.student_filter import StudentFilterError, student_filter

    f = student_filter(hostile.DIR / "frame_forger.py", timeout=20, repeat=1, sandbox=backend)
    with pytest.raises(StudentFilterError, match="refused"):
        f(np.zeros((151, 2)))
