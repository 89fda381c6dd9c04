"""check.problems.coop: the coop check on fixtures of correct styles and of each catalogued mistake.

Every correct style passes; every mistake fixture gets its catalogue code on two seeds.  The
checks run with n_runs=2 (three logs: two truth runs and the course log) to keep the suite
short; the decision compares with the one reference answer, so it does not need more.  Each file
is still checked in its own box, but the module's checks share the reference filters and the
catalogue's (:func:`keeping_answers`: computed once per seed instead of once per check, which
was 6-9 CPU s of each check); tests/check/test_problem.py and test_folders.py check coop through
the registered problem, which forgets them before every box.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from gpsaccel import check
from gpsaccel.check import problems

from ..conftest import keeping_answers
from ..heldout.confusion import named

pytestmark = pytest.mark.usefixtures("warm_boxes")  # conftest.py: the course's zygote

COOP = Path(__file__).resolve().parents[2] / "submissions" / "coop"

COOP_CORRECT = ["correct_ekf_closed_form.py", "correct_ekf_filterpy.py", "correct_ekf_solve_ivp.py",
                "correct_lkf_solve_ivp.py", "correct_both.py", "honest_p_short_form.py"]
COOP_MUTANTS = {
    "mutant_no_angle_wrap.py": "no-angle-wrap", "mutant_lkf_no_angle_wrap.py": "no-angle-wrap",
    "mutant_no_state_wrap.py": "no-state-wrap", "mutant_dt_linearization.py": "dt-linearization",
    "mutant_jacobian_point.py": "jacobian-point", "mutant_process_noise.py": "process-noise",
    "mutant_std_as_variance.py": "std-as-variance", "mutant_epoch_shift.py": "measurement-late",
    "mutant_epoch_shift_output.py": "epoch-shift", "mutant_euler.py": "euler-propagation",
    "mutant_lkf_relinearized.py": "jacobian-point",
}


@pytest.fixture(scope="module")
def coop():
    return keeping_answers("coop")


@pytest.mark.parametrize("name", COOP_CORRECT)
def test_coop_correct_styles_pass(coop, name):
    report = check.submission(COOP / name, problem=coop, n_runs=2, seed=0)
    assert report.passed, report
    assert "matches-reference" in {f.code for f in report.findings}
    assert "nees-nis" in {f.code for f in report.findings}  # information, never an error


@pytest.mark.parametrize("name, code", sorted(COOP_MUTANTS.items()))
@pytest.mark.parametrize("seed", [0, 1])  # the id starts with it: seed 1 is slow (conftest.py)
def test_coop_mistakes_get_their_code(coop, name, code, seed):
    report = check.submission(COOP / name, problem=coop, n_runs=2, seed=seed)
    assert report.codes == [code], report


def test_every_coop_code_has_a_fixture():
    """Here, or in the held-out set of students' filters (tests/check/heldout/coop)."""
    informational = {"p-not-symmetric"}
    covered = set(COOP_MUTANTS.values()) | named("coop")
    assert set(problems.get("coop").codes()) - informational == covered


def test_two_coop_mistakes_are_located_not_misnamed(coop):
    report = check.submission(COOP / "mutant_two_mistakes.py", problem=coop, n_runs=2)
    assert report.codes == ["filter-mismatch"], report
    assert "first departs at t = " in str(report)
