"""``gpsaccel grade`` on a Moodle export where one student's display name copies a classmate's
(issue 43's closing note): both folders show "Jane Doe" under two participant numbers.  Without
a roster (or with a roster of names) both are ``id-collision``, and the terminal and each
feedback name the two participant numbers and what the instructor can do (nothing about case or
punctuation, which the names do not differ in); the grading worksheet as the roster then grades
each as its own participant.  The run is faked: no notebook runs."""

from __future__ import annotations

import json

from gpsaccel.classrun import running
from gpsaccel.cli import main

from ..assignments.test_roster import MOODLE_WORKSHEET
from ..classrun.test_grading import _fake_run

JANE, COPY = "Jane Doe_1234568_assignsubmission_file_", "Jane Doe_1234569_assignsubmission_file_"
WORKSHEET = MOODLE_WORKSHEET + (
    '"Participant 1234568","Jane Doe",jane@u.edu,"Submitted for grading",,10.00,Yes,-,-,\n'
    '"Participant 1234569","Jane Doe",mallory@u.edu,"Submitted for grading",,10.00,Yes,-,-,\n')
NAMES = "First name,Last name,Email address\nJane,Doe,jane@u.edu\nAn,Nguyen,an@u.edu\n"


def _export(tmp_path):
    sub = tmp_path / "export"
    for folder in ("An Nguyen_1234567_assignsubmission_file_", JANE, COPY):
        (sub / folder).mkdir(parents=True, exist_ok=True)
        (sub / folder / "calibration.ipynb").write_text("{}")
    return sub


def _grade(tmp_path, capsys, *roster: str) -> tuple[int, str]:
    code = main(["grade", str(_export(tmp_path)), "--assignment", "calibration", "--out",
                 str(tmp_path / "out"), "--seed", "1", "--no-similarity", *roster])
    return code, capsys.readouterr().out


def _statuses(tmp_path) -> list[tuple[str, str]]:
    rows = json.loads((tmp_path / "out" / "grades.json").read_text())
    return sorted((r["student"], r["status"]) for r in rows)


def test_a_copied_display_name_names_both_participant_numbers(tmp_path, monkeypatch, capsys):
    seen: list = []
    monkeypatch.setattr(running, "run", _fake_run(seen))
    code, out = _grade(tmp_path, capsys)
    assert code == 0 and _statuses(tmp_path) == [
        ("An Nguyen", "graded"), ("Jane Doe", "id-collision"), ("Jane Doe", "id-collision")]
    said = [ln for ln in out.splitlines() if ln.startswith("id-collision: ")]
    assert said == [
        f"id-collision: '{JANE}' (participant 1234568) and '{COPY}' (participant 1234569) "
        f"show one name, 'Jane Doe' (a display name copied from a classmate's, or two students "
        f"of one name), so neither can be graded as that student: give --roster Moodle's "
        f"grading worksheet (the assignment's View all submissions > Download grading "
        f"worksheet: its Identifier column holds the participant numbers) and grade again: "
        f"each is then graded as its own participant"]
    feedback = sorted((tmp_path / "out" / "feedback").glob("Jane Doe_*.txt"))
    assert len(feedback) == 2
    texts = [f.read_text() for f in feedback]
    for text in texts:
        assert "participant 1234568" in text and "participant 1234569" in text
        assert "case" not in text and "punctuation" not in text
    assert f"Your submission '{JANE}' (participant 1234568) shows the same name as '{COPY}' " \
           f"(participant 1234569)" in "".join(texts)


def test_a_roster_of_names_still_names_them_and_the_worksheet_grades_each(
        tmp_path, monkeypatch, capsys):
    """The participants export (names and emails, no participant numbers) maps both folders to
    jane@u.edu: still a collision, named by number; the grading worksheet maps each folder by
    its number, and both are graded, each as their own participant."""
    seen: list = []
    monkeypatch.setattr(running, "run", _fake_run(seen))
    (tmp_path / "names.csv").write_text(NAMES)
    code, out = _grade(tmp_path, capsys, "--roster", str(tmp_path / "names.csv"))
    assert code == 0 and _statuses(tmp_path) == [
        ("an@u.edu", "graded"), ("jane@u.edu", "id-collision"), ("jane@u.edu", "id-collision")]
    assert any(ln.startswith(f"id-collision: '{JANE}' (participant 1234568) and '{COPY}' "
                             f"(participant 1234569)") for ln in out.splitlines())
    (tmp_path / "worksheet.csv").write_text(WORKSHEET, encoding="utf-8")
    code, out = _grade(tmp_path, capsys, "--roster", str(tmp_path / "worksheet.csv"),
                       "--regrade")
    assert code == 0 and _statuses(tmp_path) == [
        ("an@u.edu", "graded"), ("jane@u.edu", "graded"), ("mallory@u.edu", "graded")]
    assert "id-collision" not in out
