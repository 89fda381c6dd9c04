"""A student's folder (``bob/filter.py`` + ``bob/helpers.py``) is one submission for every problem,
and checks the same through the CLI (``gpsaccel check CLASS``) and the API (``check.submission``).

Before issue 22 the CLI expanded the class folder and ``check_many`` expanded it again, so Bob's
filter was imported without its helper (``import-error``) and the helper was checked as a
submission of its own (``no-kalman-filter``); coop and ship refused folders ("not a file").
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from gpsaccel import check
from gpsaccel.cli import main

SUBS = Path(__file__).resolve().parent.parent / "submissions"

#: problem -> a correct single-file fixture, split below into filter.py + helpers.py
CORRECT = {"calibration": SUBS / "correct_gps_rate.py",
           "coop": SUBS / "coop" / "correct_ekf_closed_form.py",
           "ship": SUBS / "ship" / "correct_covariance.py",
           "tracker": SUBS / "tracker" / "student.py"}  # MISTAKE = None: the correct tracker


def _class_folder(tmp_path: Path, problem: str) -> Path:
    """class/bob/{filter.py, helpers.py} (the filter imports the helper) and class/alice.py."""
    cls = tmp_path / "class"
    bob = cls / "bob"
    bob.mkdir(parents=True)
    (bob / "helpers.py").write_text("OFFSET = 0.0\n")
    (bob / "filter.py").write_text("import helpers\n" + CORRECT[problem].read_text())
    shutil.copy(CORRECT[problem], cls / "alice.py")
    return cls


@pytest.mark.parametrize("problem", sorted(CORRECT))
def test_a_student_folder_passes_through_the_api(tmp_path, problem):
    bob = _class_folder(tmp_path, problem) / "bob"
    report = check.submission(bob, problem=problem, n_runs=2, sandbox="basic")
    assert report.passed, report


@pytest.mark.parametrize("problem", sorted(CORRECT))
def test_a_class_folder_checks_the_same_through_the_cli(tmp_path, problem, capsys):
    cls = _class_folder(tmp_path, problem)
    out = tmp_path / "r.json"
    code = main(["check", str(cls), "--problem", problem, "--runs", "2", "--sandbox", "basic",
                 "--workers", "1", "--json", str(out)])
    results = json.loads(out.read_text())["results"]
    assert [r["subject"] for r in results] == ["alice.py", "bob"], capsys.readouterr()
    assert [r["codes"] for r in results] == [[], []]
    assert code == 0


def test_a_filterpy_column_state_is_accepted_with_a_note(tmp_path):
    """kf.x is a (3, 1) column: a student storing kf.x returns x̂ of shape (151, 3, 1)."""
    src = CORRECT["calibration"].parent / "correct_filterpy.py"
    path = tmp_path / "columns.py"
    path.write_text(src.read_text().replace("x_hat.append(kf.x[:, 0].copy())",
                                            "x_hat.append(kf.x.copy())"))
    report = check.submission(path, n_runs=2, sandbox="basic")
    assert report.passed, report
    note = next(f for f in report.findings if f.code == "filterpy-column")
    assert note.severity == "note" and "(151, 3, 1)" in note.message
    assert report.details["max_dx_sigma"] < 1e-9
