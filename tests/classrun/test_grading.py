"""A class's grade (gpsaccel.classrun.grading) around its items, without running a notebook: an
export mapped to the roster by a naming is graded and written under the roster's ids, and the
class-wide files come from grade() itself.  (Classes graded for real: tests/assignments/.)"""

from __future__ import annotations

import csv
from dataclasses import asdict

from gpsaccel.assignments import grading as item
from gpsaccel.assignments.roster import Student
from gpsaccel.classrun import grade, running

from .test_entries import canvas_like


def _fake_run(seen: list):
    """The class run with every runnable entry "graded" at 1 point per question and its
    student key recorded (what the item would key the variant and the data on)."""
    def fake(task, entries, jobs, executor, on_result):
        for i, e in enumerate(entries):
            seen.append((e.student, e.late, e.attempt))
            if e.problem is not None:
                on_result(i, task.refused(e))
                continue
            g = item.unusable(task.name, e.student, e.found, "graded", "", e.id)
            g.scores = dict.fromkeys(g.scores, 1.0)
            on_result(i, asdict(g))
        return [None] * len(entries)
    return fake


def test_an_export_mapped_by_a_naming_is_graded_and_written_under_the_rosters_ids(
        tmp_path, monkeypatch):
    sub = tmp_path / "export"
    sub.mkdir()
    for name in ("nguyenan_84500_678900_calibration.ipynb",
                 "nguyenan_84500_678950_calibration-1.ipynb",
                 "doejane_LATE_84501_678902_calibration.ipynb",
                 "stranger_99999_678903_calibration.ipynb"):
        (sub / name).write_text("{}")
    seen: list = []
    monkeypatch.setattr(running, "run", _fake_run(seen))
    roster = [Student("an.nguyen", name="An Nguyen", canvas_id="84500"),
              Student("jane.doe", name="Jane Doe", canvas_id="84501")]
    grades = grade(sub, "calibration", out=tmp_path / "out", seed=1, roster=roster,
                   similarity=False, naming=canvas_like({"84500": "an.nguyen",
                                                         "84501": "jane.doe"}))
    stranger = "stranger_99999_678903_calibration.ipynb"
    assert seen == [("jane.doe", True, 0), ("an.nguyen", False, 1), (stranger, False, 0)]
    assert [(g.student, g.status) for g in grades] == [
        ("jane.doe", "graded"), ("an.nguyen", "graded"), (stranger, "not-on-roster")]
    with open(tmp_path / "out" / "canvas.csv", newline="", encoding="utf-8") as f:
        canvas = {r[0]: r[-1] for r in csv.reader(f)}
    full = str(sum(1 for _ in item.possible_of("calibration")))
    assert canvas["An Nguyen"] == canvas["Jane Doe"] == full  # the roster's rows, filled
    feedback = sorted(p.name for p in (tmp_path / "out" / "feedback").iterdir())
    assert feedback[:2] == ["an.nguyen.txt", "jane.doe.txt"]
