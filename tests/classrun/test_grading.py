"""A class's grade (gpsaccel.classrun.grading) around its items, without running a notebook: an
export mapped to the roster by a naming is graded and written under the roster's ids, and the
class-wide files come from grade() itself.  (Classes graded for real: tests/assignments/.)"""

from __future__ import annotations

import csv
from dataclasses import asdict

import pytest

from gpsaccel.assignments import grading as item
from gpsaccel.assignments.roster import Student
from gpsaccel.classrun import grade, grade_class, running

from .test_entries import canvas_like


def _fake_run(seen: list):
    """The class run with every runnable entry "graded" at 1 point per question and its
    student key recorded (what the item would key the variant and the data on)."""
    def fake(task, entries, jobs, executor, on_result, warm_boxes=False):
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


def _canvas(out) -> dict[str, str]:
    with open(out / "canvas.csv", newline="", encoding="utf-8") as f:
        return {r[0]: r[-1] for r in csv.reader(f)}


def _case_collision(tmp_path, monkeypatch, roster: list[Student]):
    """Folders "Jane Doe" and "JANE DOE", each with a notebook, graded with ``roster``."""
    sub = tmp_path / "export"
    for name in ("Jane Doe", "JANE DOE"):
        (sub / name).mkdir(parents=True)
        (sub / name / "calibration.ipynb").write_text("{}")
    seen: list = []
    monkeypatch.setattr(running, "run", _fake_run(seen))
    graded = grade_class(sub, "calibration", out=tmp_path / "out", seed=1, roster=roster,
                         similarity=False)
    return graded, seen


def test_a_case_collision_is_never_a_score(tmp_path, monkeypatch):
    """Both folders on the roster: neither can be told to be the one a roster row means, both
    are id-collision, and their cells are empty in every gradebook (canvas.csv wrote 0 for the
    victim), named on the terminal."""
    graded, seen = _case_collision(tmp_path, monkeypatch, [
        Student("Jane Doe", name="Jane Doe", canvas_id="1"),
        Student("JANE DOE", name="Jane Other", canvas_id="2")])
    assert [(g.student, g.status) for g in graded.grades] == [
        ("JANE DOE", "id-collision"), ("Jane Doe", "id-collision")]
    canvas = _canvas(graded.out)
    assert canvas["Jane Doe"] == canvas["Jane Other"] == ""
    rows = {r["student"]: r for r in csv.DictReader(
        (graded.out / "grades.csv").open(newline="", encoding="utf-8"))}
    assert rows["Jane Doe"]["total"] == rows["JANE DOE"]["total"] == ""
    named = [ln for ln in graded.classwide if ln.startswith("  id-collision")]
    assert len(named) == 1 and named[0].endswith("JANE DOE, Jane Doe")


def test_the_roster_naming_one_folder_exactly_grades_that_student(tmp_path, monkeypatch):
    """The roster's id is "Jane Doe", byte for byte the victim's folder and not the other's: the
    victim is graded into her row; "JANE DOE" stays id-collision (and is on no roster row)."""
    graded, seen = _case_collision(tmp_path, monkeypatch, [
        Student("Jane Doe", name="Jane Doe", canvas_id="1")])
    assert [(g.student, g.status) for g in graded.grades] == [
        ("JANE DOE", "id-collision"), ("Jane Doe", "graded")]
    assert ("Jane Doe", False, 0) in seen  # graded as herself: her variant, her data
    full = str(len(item.possible_of("calibration")))  # the fake run's 1 point a question
    assert _canvas(graded.out)["Jane Doe"] == full
    assert (graded.out / "feedback" / "Jane Doe.txt").is_file()
    assert any(ln.startswith("  id-collision") and ln.endswith("): JANE DOE")
               for ln in graded.classwide)


def test_a_roster_that_names_neither_folder_exactly_leaves_both_refused(tmp_path, monkeypatch):
    graded, _ = _case_collision(tmp_path, monkeypatch, [Student("jane doe", name="Jane Doe")])
    assert [g.status for g in graded.grades] == ["id-collision", "id-collision"]
    assert _canvas(graded.out)["Jane Doe"] == ""


# ------------------------------------------------------------ runs that resume (issue 38.4)
def test_a_rerun_keeps_the_grades_of_unchanged_notebooks_and_the_record_every_regrade(
        tmp_path, monkeypatch):
    import json

    sent: list = []

    def fake(task, entries, jobs, executor, on_result, warm_boxes=False):
        sent.append(sorted(e.student for e in entries))
        for i, e in enumerate(entries):
            g = item.unusable(task.name, e.student, e.found, "graded", "", e.id)
            g.scores = dict.fromkeys(g.scores, float(len(e.path.read_text()) % 2))
            on_result(i, asdict(g))
        return [None] * len(entries)

    monkeypatch.setattr(running, "run", fake)
    sub, out = tmp_path / "class", tmp_path / "out"
    for who, text in (("ann", "{}"), ("ben", "{ }"), ("cy", "{}")):
        (sub / who).mkdir(parents=True)
        (sub / who / "calibration.ipynb").write_text(text)

    def again(**kw):
        g = grade(sub, "calibration", out=out, similarity=False, **kw)
        return g, json.loads((out / "grading.json").read_text())

    first, rec1 = again()
    assert sent == [["ann", "ben", "cy"]] and len(first) == 3
    rows1 = (out / "grades.csv").read_text()
    now, rec2 = again()  # nothing changed: nothing graded, the same seed, the same rows
    assert sent[1:] == [] and now == [] and rec2["seed"] == rec1["seed"]
    assert (out / "grades.csv").read_text().replace("0.0", "") == rows1.replace("0.0", "")
    assert rec2["reused"] == 3 and rec2["graded"] == 0
    for _ in range(2):  # plain reruns that grade nothing on the same seed: no new earlier
        now, rec = again()
        assert now == [] and rec["earlier"] == rec2["earlier"] and len(rec["earlier"]) == 1
    (sub / "ben" / "calibration.ipynb").write_text("{  }")  # ben hands in again
    now, rec3 = again()
    assert sent[1:] == [["ben"]] and [g.student for g in now] == ["ben"]
    assert rec3["seed"] == rec1["seed"]
    now, _ = again(student=["ann", "cy"])  # several students at once, the recorded seed
    assert sent[2:] == [["ann", "cy"]]
    now, rec5 = again(regrade=True)  # everyone, a new seed; the earlier records kept
    assert sent[3:] == [["ann", "ben", "cy"]] and rec5["seed"] != rec1["seed"]
    # the first run and the one that graded ben; the rerun that graded nothing is not kept
    assert [(r["seed"], r["graded"]) for r in rec5["earlier"]] == [(rec1["seed"], 3),
                                                                   (rec1["seed"], 1)]
    assert [x["student"] for x in rec5["earlier"][-1]["regrades"]] == [["ann", "cy"]]
    now, rec6 = again(student="ann")  # one student: a list of one id, as several are
    assert [x["student"] for x in rec6["regrades"]] == [["ann"]]
    with pytest.raises(ValueError, match="'dan'"):
        again(student=["ann", "dan"])


def test_a_rerun_that_keeps_every_grade_prints_no_empty_table(tmp_path, monkeypatch, capsys):
    """`gpsaccel grade ... | head -1` after a rerun that graded nothing showed an empty line:
    the table of no grades. Its first line is now what the run wrote."""
    from gpsaccel.cli import main

    def fake(task, entries, jobs, executor, on_result, warm_boxes=False):
        for i, e in enumerate(entries):
            g = item.unusable(task.name, e.student, e.found, "graded", "", e.id)
            on_result(i, asdict(g))
        return [None] * len(entries)

    monkeypatch.setattr(running, "run", fake)
    sub = tmp_path / "class"
    for who in ("ann", "ben"):
        (sub / who).mkdir(parents=True)
        (sub / who / "calibration.ipynb").write_text("{}")
    argv = ["grade", str(sub), "--assignment", "calibration", "--no-similarity"]
    assert main(argv) == 0
    first = capsys.readouterr().out.splitlines()
    assert [ln.split()[0] for ln in first[:2]] == ["ann", "ben"]  # the table of the grading
    assert main(argv) == 0
    again = capsys.readouterr().out.splitlines()
    assert again[0].startswith("wrote ") and "" not in again
    assert any("2 unchanged notebook(s) not graded again" in ln for ln in again)


def _ann_graded_by_a_fake_run(tmp_path, monkeypatch) -> tuple[list, list[str]]:
    """A class of one notebook (ann's) whose runs grade without a box (every grade "graded");
    (the students each run sent, the command's argv)."""
    sent: list = []

    def fake(task, entries, jobs, executor, on_result, warm_boxes=False):
        sent.append([e.student for e in entries])
        for i, e in enumerate(entries):
            on_result(i, asdict(item.unusable(task.name, e.student, e.found, "graded", "", e.id)))
        return [None] * len(entries)

    monkeypatch.setattr(running, "run", fake)
    sub = tmp_path / "class"
    (sub / "ann").mkdir(parents=True)
    (sub / "ann" / "calibration.ipynb").write_text("{}")
    return sent, ["grade", str(sub), "--assignment", "calibration", "--no-similarity"]


def test_a_rerun_that_keeps_nothing_names_the_setting_that_changed(tmp_path, monkeypatch, capsys):
    """A rerun of a class graded with ``--timeout 60`` and run again without it (the default,
    120 s, as an instructor who forgot the flag does) said only "the earlier run's homework,
    secret, sandbox, time limit or gpsaccel differ": which, and the flag that keeps the grades,
    are in the record."""
    from gpsaccel.cli import main

    _, argv = _ann_graded_by_a_fake_run(tmp_path, monkeypatch)
    assert main([*argv, "--timeout", "60"]) == 0
    capsys.readouterr()
    assert main(argv) == 0
    said = [ln for ln in capsys.readouterr().out.splitlines() if "nothing kept" in ln]
    assert said == ["rerun: nothing kept: the earlier run's time limit was 60 s, now 120 s "
                    "(give --timeout 60 to match it)"], said
    # a regrade of one student under another limit than the class's is graded, and says so
    assert main([*argv, "--timeout", "30", "--student", "ann"]) == 0
    said = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("rerun:")]
    assert said == ["rerun: regraded under other settings than the class: the earlier run's "
                    "time limit was 120 s, now 30 s (give --timeout 120 to match it)"], said


def test_a_rerun_under_other_code_of_the_same_version_grades_again(tmp_path, monkeypatch,
                                                                     capsys):
    """A wheel rebuilt under the same version string with a fix to the grader kept every old
    grade on rerun (the record held the version alone); the package's files are in it now."""
    from gpsaccel.classrun import record
    from gpsaccel.cli import main

    sent, argv = _ann_graded_by_a_fake_run(tmp_path, monkeypatch)
    assert main(argv) == 0 and main(argv) == 0
    assert sent == [["ann"]]  # the same code: kept
    digest = record.package_digest()
    assert len(digest) == 64 and digest == record.package_digest()
    monkeypatch.setattr(record, "package_digest", lambda: "0" * 64)  # one file of it changed
    capsys.readouterr()
    assert main(argv) == 0
    assert sent == [["ann"], ["ann"]]
    said = [ln for ln in capsys.readouterr().out.splitlines() if "nothing kept" in ln]
    assert said == ["rerun: nothing kept: the earlier run's secret, homework files or gpsaccel "
                    "(its version or its files) differ"], said


def test_an_exports_zip_is_refused_with_how_to_unzip_it(tmp_path):
    """The LMS downloads a zip; the grader reads it unzipped (docs/grading.md). Given the zip,
    it said only that submissions must be a folder."""
    (tmp_path / "submissions.zip").write_bytes(b"PK\x05\x06" + bytes(18))
    with pytest.raises(ValueError, match=r"got .*submissions\.zip: unzip the LMS's download "
                                         r"first \(unzip -d .*submissions .*submissions\.zip\)"):
        grade(tmp_path / "submissions.zip", "calibration", out=tmp_path / "out")
