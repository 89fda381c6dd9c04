"""Issue 31 item 8: four mistakes an instructor hit, each with its own code in the generic linear
catalogue (so every linear problem has them) and in the calibration catalogue.

* P never updated (``covariance-update-skipped``, "P never updated"; it was ``p-mismatch`` with a
  misleading units hint);
* an update at every fast step instead of only at the measurements (``update-every-step``; it
  was blamed on the propagation);
* Φ's sign flipped in the entries that carry one state into the others (``phi-sign``; on the
  calibration problem both bias entries, which was "not catalogued");
* H written for another state order (``state-order``, [x, y, vx, vy] for [x, vx, y, vy]).

Each is made by a student-style filter (tests/submissions/cv2d/student.py, a 2-D
constant-velocity problem defined here, and tests/submissions/calibration_gaps/student.py),
checked in the basic sandbox on a fixed seed and two runs (the verdicts compare run by run);
the correct filters pass.  Each problem's checks
share its catalogue's candidate filters (:func:`keeping_answers`: computed once for the module
instead of after every box).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gpsaccel import check

from .conftest import keeping_answers

SUBMISSIONS = Path(__file__).resolve().parents[1] / "submissions"
GAPS = ("covariance-update-skipped", "update-every-step", "phi-sign", "state-order")
DT, EVERY, SIGMA_A = 0.1, 5, 0.5
G = np.array([[DT**2 / 2, 0], [DT, 0], [0, DT**2 / 2], [0, DT]])

#: a 2-D constant-velocity problem of the instructor's own: state [x, vx, y, vy], 10 Hz
#: propagation, position fixes (x, y) at 2 Hz for 10 s
CV2D = check.Problem.linear(
    "cv2d-test", Phi=[[1, DT, 0, 0], [0, 1, 0, 0], [0, 0, 1, DT], [0, 0, 0, 1]], Gamma=G,
    W=SIGMA_A**2 * np.eye(2), H=[[1, 0, 0, 0], [0, 0, 1, 0]], V=3.0**2 * np.eye(2),
    M0=np.diag([25.0, 4.0, 25.0, 4.0]), x0=[0.0, 1.0, 0.0, -1.0], every=EVERY, n_epochs=21,
    dt=DT, states=("x", "vx", "y", "vy"), measurements=("x", "y"), register=False,
    title="2-D constant velocity (test)")


def _student(tmp_path: Path, folder: str, mistake: str | None) -> Path:
    path = tmp_path / f"{mistake or 'correct'}.py"
    src = (SUBMISSIONS / folder / "student.py").read_text()
    path.write_text(src.replace("MISTAKE = None", f"MISTAKE = {mistake!r}", 1))
    return path


def test_every_linear_problem_has_the_four_codes():
    assert set(GAPS) <= set(CV2D.codes())
    assert set(GAPS) <= set(check.problems.get("calibration").codes())
    assert set(GAPS) <= set(check.problems.get("tracker").codes())


@pytest.fixture(scope="module")
def kept():
    """CV2D and the calibration problem, each keeping its candidates between checks."""
    return {"cv2d": keeping_answers(CV2D), "calibration": keeping_answers("calibration")}


@pytest.mark.parametrize("mistake", [None, *GAPS])
def test_the_2d_constant_velocity_problem_names_each_gap(kept, tmp_path, mistake):
    report = check.submission(_student(tmp_path, "cv2d", mistake), problem=kept["cv2d"], n_runs=2,
                              seed=3, sandbox="basic")
    if mistake is None:
        assert report.passed, report
    else:
        assert report.codes == [mistake], report


@pytest.mark.slow
@pytest.mark.parametrize("mistake", [None, *GAPS])
def test_the_calibration_problem_names_each_gap(kept, tmp_path, mistake):
    report = check.submission(_student(tmp_path, "calibration_gaps", mistake),
                              problem=kept["calibration"], n_runs=2, seed=5, sandbox="basic")
    if mistake is None:
        assert report.passed, report
    else:
        assert report.codes == [mistake], report
        text = " ".join(f.message for f in report.findings)
        assert "units?" not in text and "power of ten" not in text  # no misleading hint


def test_state_orders_and_phi_signs_of_the_cv_problem():
    from gpsaccel.kalman.linear_catalogue import phi_sign_variants, state_orders

    assert (0, 2, 1, 3) in state_orders(4)          # [x, vx, y, vy] read as [x, y, vx, vy]
    variants = [v for v, _ in phi_sign_variants(np.array(CV2D.model.Phi))]
    assert "Φ₁₂ and Φ₃₄" in variants
