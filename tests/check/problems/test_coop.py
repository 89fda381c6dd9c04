"""check.problems: coop and ship checks on fixtures of correct styles and of each catalogued mistake.

Every correct style passes; every mistake fixture gets its catalogue code on two seeds.  The
checks run with n_runs=2 (three logs: two truth runs and the course log, or two voyages and the
dropout voyage) to keep the suite short; the decision compares with the one reference answer, so
it does not need more.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gpsaccel import check
from gpsaccel.check import problems

SUBS = Path(__file__).resolve().parent.parent / "submissions"
COOP, SHIP = SUBS / "coop", SUBS / "ship"

COOP_CORRECT = ["correct_ekf_closed_form.py", "correct_ekf_filterpy.py", "correct_ekf_solve_ivp.py",
                "correct_lkf_solve_ivp.py", "correct_both.py", "honest_p_short_form.py"]
COOP_MUTANTS = {
    "mutant_no_angle_wrap.py": "no-angle-wrap", "mutant_lkf_no_angle_wrap.py": "no-angle-wrap",
    "mutant_no_state_wrap.py": "no-state-wrap", "mutant_dt_linearization.py": "dt-linearization",
    "mutant_jacobian_point.py": "jacobian-point", "mutant_process_noise.py": "process-noise",
    "mutant_std_as_variance.py": "std-as-variance", "mutant_epoch_shift.py": "epoch-shift",
    "mutant_epoch_shift_output.py": "epoch-shift", "mutant_euler.py": "euler-propagation",
    "mutant_lkf_relinearized.py": "jacobian-point",
}
SHIP_CORRECT = ["correct_covariance.py", "correct_filterpy.py", "correct_sequential.py",
                "correct_short_form.py"]
SHIP_MUTANTS = {"mutant_zeroed_gain.py": ["zeroed-gain"],
                "mutant_report_covariance.py": ["zeroed-gain", "report-covariance"],
                "mutant_monorate_gain.py": ["monorate-gain"], "mutant_no_input.py": ["no-input"]}


@pytest.mark.parametrize("name", COOP_CORRECT)
def test_coop_correct_styles_pass(name):
    report = check.submission(COOP / name, problem="coop", n_runs=2, seed=0)
    assert report.passed, report
    assert "matches-reference" in {f.code for f in report.findings}
    assert "nees-nis" in {f.code for f in report.findings}  # information, never an error


@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("name, code", sorted(COOP_MUTANTS.items()))
def test_coop_mistakes_get_their_code(name, code, seed):
    report = check.submission(COOP / name, problem="coop", n_runs=2, seed=seed)
    assert report.codes == [code], report


def test_every_coop_code_has_a_fixture():
    informational = {"p-not-symmetric"}
    assert set(problems.get("coop").codes()) - informational == set(COOP_MUTANTS.values())


def test_two_coop_mistakes_are_located_not_misnamed():
    report = check.submission(COOP / "mutant_two_mistakes.py", problem="coop", n_runs=2)
    assert report.codes == ["filter-mismatch"], report
    assert "first departs at t = " in str(report)


@pytest.mark.parametrize("name", SHIP_CORRECT)
def test_ship_correct_styles_pass(name):
    report = check.submission(SHIP / name, problem="ship", n_runs=2, seed=0)
    assert report.passed, report


@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("name, codes", sorted(SHIP_MUTANTS.items()))
def test_ship_mistakes_get_their_codes(name, codes, seed):
    report = check.submission(SHIP / name, problem="ship", n_runs=2, seed=seed)
    assert report.codes == codes, report


def test_zeroed_gain_says_by_how_much():
    report = check.submission(SHIP / "mutant_zeroed_gain.py", problem="ship", n_runs=2)
    text = str(report)  # the student's: what the mistake costs their own filter
    assert "% on average" in text and "near-optimal but not optimal" in report.instructor_text()


def test_every_ship_code_has_a_fixture():
    assert set(problems.get("ship").codes()) == {c for cs in SHIP_MUTANTS.values() for c in cs}


def test_contract_failures_become_findings(tmp_path):
    calib = SUBS / "correct_covariance.py"  # defines kalman_filter, not ekf/lkf
    report = check.submission(calib, problem="coop", n_runs=2)
    assert report.codes == ["no-function"] and "ekf(y, Q, R)" in str(report)
    bad = tmp_path / "shape.py"
    bad.write_text("import numpy as np\ndef multirate_filter(z, u):\n"
                   "    return np.zeros((999, 9)), np.zeros((999, 9, 9))\n")
    report = check.submission(bad, problem="ship", n_runs=2)
    assert report.codes == ["wrong-shape"] and "1000 rows" in str(report)
    nan = tmp_path / "nan.py"
    nan.write_text("import numpy as np\ndef ekf(y, Q, R):\n"
                   "    return np.full((len(y), 6), np.nan), np.zeros((len(y), 6, 6))\n")
    assert check.submission(nan, problem="coop", n_runs=2).codes == ["nan-output"]
    boom = tmp_path / "boom.py"
    boom.write_text("def lkf(y, Q, R):\n    raise RuntimeError('no nominal')\n")
    report = check.submission(boom, problem="coop", n_runs=2)
    assert report.codes == ["exception"] and "no nominal" in str(report)


def test_problem_names_are_validated():
    with pytest.raises(ValueError, match="problem"):
        check.submission(COOP / "correct_ekf_closed_form.py", problem="rocket")
    assert isinstance(problems.get("ship").describe(), str)
    assert np.isfinite(problems.get("coop").Q("ekf")).all()


def test_cli_check_problem_ship_and_coop(tmp_path, capsys):
    import json

    from gpsaccel.cli import main

    for name in ("correct_covariance.py", "mutant_no_input.py"):
        (tmp_path / name).write_text((SHIP / name).read_text(encoding="utf-8"), encoding="utf-8")
    out = tmp_path / "ship.json"
    rc = main(["check", str(tmp_path), "--problem", "ship", "--runs", "2", "--workers", "1",
               "--json", str(out)])
    assert rc == 1
    text = capsys.readouterr().out
    assert "no-input" in text and "1 of 2 passed" in text and "problem ship" in text
    data = json.loads(out.read_text(encoding="utf-8"))
    assert data["settings"]["problem"] == "ship"
    assert {r["subject"]: r["codes"] for r in data["results"]} == {
        "correct_covariance.py": [], "mutant_no_input.py": ["no-input"]}
    rc = main(["check", str(COOP / "correct_ekf_closed_form.py"), "--problem", "coop",
               "--runs", "2", "--workers", "1"])
    assert rc == 0
