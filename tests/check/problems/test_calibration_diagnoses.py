"""Sharper calibration diagnoses: mistakes in what is returned, recognised before the catalogue.

Each fixture would otherwise be reported as a generic p-mismatch ("M0, H or V is wrong"); each gets
its own code on two seeds.  Each diagnosis compares the returned x̂ and P with the optimal filter's
run by run (or between two runs: ``state-between-calls``), never a statistic over the ensemble, so
N_RUNS = 2 runs show it; the module's checks share the catalogue's candidate filters
(:func:`keeping_answers`).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from gpsaccel import check

from ..conftest import keeping_answers

pytestmark = pytest.mark.usefixtures("warm_boxes")  # conftest.py: the course's zygote

HERE = Path(__file__).parents[2] / "submissions"
N_RUNS = 2

SHARPER = [
    ("mutant_float32.py", "low-precision", ["float32", "not a wrong M0"]),
    ("mutant_p_scaled.py", "p-scaled", ["same factor", "without the /2", "x̂ is right",
                                        "factor = 2"]),
    ("mutant_epoch_shift.py", "epoch-shift", ["one GPS time late"]),
    ("mutant_last_update_missing.py", "last-update-missing", ["t = 30 s", "z[150]"]),
    ("mutant_aliased_output.py", "aliased-output", ["same array object", "copy"]),
    ("mutant_global_m0.py", "state-between-calls", ["first differs on run 1", "M0.copy()"]),
    ("mutant_state_between_calls.py", "wrong-shape", ["on run 1", "between calls"]),
    ("mutant_p_update_skipped_at_0.py", "first-update-skipped", ["did use z₀"]),
    ("mutant_predict_before_update.py", "predict-before-first-update",
     ["propagates before its first update", "GPS fix at t = 0", "40 accelerometer step"]),
]


@pytest.fixture(scope="module")
def calibration():
    return keeping_answers("calibration")


@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("name, code, words", SHARPER, ids=[n[:-3] for n, _, _ in SHARPER])
def test_sharper_diagnosis(calibration, name, code, words, seed):
    report = check.submission(HERE / name, problem=calibration, n_runs=N_RUNS, seed=seed)
    assert report.codes == [code], report
    msg = next(f.message for f in report.findings if f.code == code)
    for w in words:
        assert w in msg, (w, msg)
    assert "M0, H or V" not in msg or code == "low-precision"


def test_first_update_skipped_keeps_its_wording_when_z0_was_unused(calibration):
    report = check.submission(HERE / "mutant_first_update_skipped.py", problem=calibration,
                              n_runs=N_RUNS)
    msg = next(f.message for f in report.findings if f.code == "first-update-skipped")
    assert "does not use the GPS fix at t = 0" in msg and "did use z₀" not in msg


def test_nearest_mistake_hint_only_when_close(calibration, tmp_path):
    far = check.submission(HERE / "mutant_diagonal_q.py", problem=calibration, n_runs=N_RUNS)
    found = next(f for f in far.findings if f.code == "p-mismatch")
    msg = found.for_student().message
    assert "No catalogued mistake matches" in msg and "first departs at t = 3.2 s" in msg
    # where and how it departs, never the optimal filter's value: no number but times and sizes
    # (the instructor's text has it)
    assert "expected: P31 at t = 3.2 s = " in found.for_instructor()
    depart = msg[msg.index("first departs"):]
    assert re.search(r"P\d\d (is |has |should |about |a few |10–50 |slightly )", depart), depart
    assert "optimal filter's is" not in msg and not re.search(r"\d\.\d{3,}", depart), depart
    src = (HERE / "correct_covariance.py").read_text(encoding="utf-8")
    near = tmp_path / "near.py"  # V₂₂ = σ (the std-as-variance slip) off by 2e-7 relative
    near.write_text(src.replace("V = np.diag([1.0, 0.04**2])",
                                "V = np.diag([1.0, 0.04 * (1 + 2e-7)])"), encoding="utf-8")
    report = check.submission(near, problem=calibration, n_runs=N_RUNS)
    msg = next(f.message for f in report.findings if f.code == "p-mismatch")
    assert "nearest known mistake is std-as-variance" in msg and "look there first" in msg
