"""check.problems.ship: the ship check on fixtures of correct styles and of each catalogued mistake.

Every correct style passes; every mistake fixture gets its catalogue codes on two seeds.  The
checks run with n_runs=2 (two voyages and the dropout voyage) to keep the suite short; the
decision compares with the one reference answer, so it does not need more.  Each file is still
checked in its own box, but the module's checks share the optimal filter and the catalogue's
variants (:func:`keeping_answers`: computed once per seed instead of once per check);
tests/check/test_problem.py and test_folders.py check ship through the registered problem, which
forgets them before every box.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from gpsaccel import check
from gpsaccel.check import problems

from ..conftest import keeping_answers
from ..heldout.confusion import named

pytestmark = pytest.mark.usefixtures("warm_boxes")  # conftest.py: the course's zygote

SHIP = Path(__file__).resolve().parents[2] / "submissions" / "ship"

SHIP_CORRECT = ["correct_covariance.py", "correct_filterpy.py", "correct_sequential.py",
                "correct_short_form.py"]
SHIP_MUTANTS = {"mutant_zeroed_gain.py": ["zeroed-gain"],
                "mutant_report_covariance.py": ["zeroed-gain", "report-covariance"],
                "mutant_monorate_gain.py": ["monorate-gain"], "mutant_no_input.py": ["no-input"]}


@pytest.fixture(scope="module")
def ship():
    return keeping_answers("ship")


@pytest.mark.parametrize("name", SHIP_CORRECT)
def test_ship_correct_styles_pass(ship, name):
    report = check.submission(SHIP / name, problem=ship, n_runs=2, seed=0)
    assert report.passed, report


@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("name, codes", sorted(SHIP_MUTANTS.items()))
def test_ship_mistakes_get_their_codes(ship, name, codes, seed):
    report = check.submission(SHIP / name, problem=ship, n_runs=2, seed=seed)
    assert report.codes == codes, report


def test_zeroed_gain_says_by_how_much(ship):
    report = check.submission(SHIP / "mutant_zeroed_gain.py", problem=ship, n_runs=2)
    text = str(report)  # the student's: what the mistake costs their own filter
    assert "% on average" in text and "near-optimal but not optimal" in report.instructor_text()


def test_every_ship_code_has_a_fixture():
    """Here, or in the held-out set of students' filters (tests/check/heldout/ship)."""
    covered = {c for cs in SHIP_MUTANTS.values() for c in cs} | named("ship")
    assert set(problems.get("ship").codes()) == covered
