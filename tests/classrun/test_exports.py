"""Submissions as each LMS downloads them, mapped to the roster by the ids their names carry
(gpsaccel.classrun.exports): Canvas's flat files, Moodle's folders (and flat files), Gradescope's
submission folders with its metadata.  A name that maps to no one, or to two, is a named status,
never a graded guess; a class graded as downloaded gets the grades it gets from one folder per
roster id (issue 38's done-when)."""

from __future__ import annotations

import csv
import unicodedata
from dataclasses import asdict

import pytest

from gpsaccel.assignments import grading as item
from gpsaccel.assignments.roster import Student, read
from gpsaccel.assignments.scoring import variant_number
from gpsaccel.classrun import grade, notebooks, running, walk
from gpsaccel.classrun.exports import Export, detect

from ..assignments.test_roster import CANVAS, MOODLE_WORKSHEET

NB = notebooks("calibration")


def _roster(tmp_path, text: str) -> list[Student]:
    (tmp_path / "roster.csv").write_text(text, encoding="utf-8")
    return read(tmp_path / "roster.csv").students


def _files(root, names: dict[str, str]) -> None:
    """``names``: relative path -> text (a folder is made for each path's parents)."""
    for rel, text in names.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_text(text, encoding="utf-8")


def _walk(root, roster, layout="auto"):
    export = Export(NB, layout, roster)
    entries, notes = walk(root, NB, layout=export)
    return [(e.student, e.late, e.attempt, e.problem[0] if e.problem else e.path.name)
            for e in entries], notes, export.found


def test_canvas_flat_export_maps_user_ids_through_its_gradebook(tmp_path):
    sub = tmp_path / "sub"
    _files(sub, {"nguyenan_84500_678900_calibration.ipynb": "{}",
                 "nguyenan_84500_678950_calibration-1.ipynb": "{}",
                 "doejane_LATE_84501_678902_calibration.ipynb": "{}",
                 "stranger_99999_678903_calibration.ipynb": "{}"})
    got, notes, found = _walk(sub, _roster(tmp_path, CANVAS))
    assert got == [("84501", True, 0, "doejane_LATE_84501_678902_calibration.ipynb"),
                   ("84500", False, 1, "nguyenan_84500_678950_calibration-1.ipynb"),
                   ("stranger_99999_678903_calibration.ipynb", False, 0, "not-on-roster")]
    assert notes == ["nguyenan_84500_678900_calibration.ipynb: superseded by a later attempt "
                     "of 84500"]
    assert found == ["canvas: Canvas user ids through the roster's canvas_id"]


def test_canvas_needs_a_roster_with_its_user_ids(tmp_path):
    _files(tmp_path / "sub", {"nguyenan_84500_678900_calibration.ipynb": "{}"})
    with pytest.raises(ValueError, match="Canvas user id.*canvas_id"):
        _walk(tmp_path / "sub", [Student("an.nguyen", name="An Nguyen")])


def test_moodle_folders_map_by_full_name_or_participant_number(tmp_path):
    sub = tmp_path / "sub"
    _files(sub, {"An Nguyen_1234567_assignsubmission_file_/calibration.ipynb": "{}",
                 "Jane Doe_1234568_assignsubmission_file_/calibration.ipynb": "{}",
                 "Jane Doe_1234568_assignsubmission_onlinetext_/onlinetext.html": "<p/>",
                 "Eve Other_1234569_assignsubmission_file_/calibration.ipynb": "{}"})
    got, notes, found = _walk(sub, _roster(tmp_path, CANVAS))  # Canvas's roster, by name
    assert got == [("84500", False, 0, "calibration.ipynb"),
                   ("Eve Other_1234569_assignsubmission_file_", False, 0, "not-on-roster"),
                   ("84501", False, 0, "calibration.ipynb")]
    assert notes == ["Jane Doe_1234568_assignsubmission_onlinetext_: skipped (Moodle's "
                     "onlinetext submission, not a file)"]
    assert found == ["moodle: Moodle's full name through the roster"]
    got, _, found = _walk(sub, _roster(tmp_path, MOODLE_WORKSHEET))  # by participant number
    assert [g[0] for g in got] == ["an@u.edu", "Eve Other_1234569_assignsubmission_file_",
                                   "Jane Doe_1234568_assignsubmission_file_"]
    assert found == ["moodle: Moodle's participant through the roster"]


def test_a_file_name_that_carries_another_participant_is_still_its_senders(tmp_path):
    """A student names the file they hand in; Moodle's flat download puts that name after theirs:
    the participant number read is the one Moodle wrote, never one the file name holds."""
    sub = tmp_path / "sub"
    _files(sub, {"Eve Other_1234569_assignsubmission_file_x_1234567_assignsubmission_file_"
                 "calibration.ipynb": "{}",
                 "evother_84509_1_x_84500_2_calibration.ipynb": "{}"})
    got, _, _ = _walk(sub, _roster(tmp_path, MOODLE_WORKSHEET), "moodle")
    assert [g[3] for g in got if "assignsubmission" in g[0]] == ["not-on-roster"]
    (sub / "Eve Other_1234569_assignsubmission_file_x_1234567_assignsubmission_file_"
           "calibration.ipynb").unlink()
    got, _, _ = _walk(sub, _roster(tmp_path, CANVAS), "canvas")
    assert [g[3] for g in got] == ["not-on-roster"]  # user 84509, not 84500


def test_moodle_flat_files_and_two_students_of_one_name(tmp_path):
    sub = tmp_path / "sub"
    _files(sub, {"An Nguyen_1234567_assignsubmission_file_calibration.ipynb": "{}"})
    roster = [Student("a1", first_name="An", last_name="Nguyen"),
              Student("a2", name="Nguyen, An")]
    got, _, _ = _walk(sub, roster)
    assert got == [("An Nguyen_1234567_assignsubmission_file_calibration.ipynb", False, 0,
                    "ambiguous-student")]
    got, _, _ = _walk(sub, roster[:1])
    assert got == [("a1", False, 0, "An Nguyen_1234567_assignsubmission_file_calibration.ipynb")]


#: Gradescope's Export Submissions: Ruby's YAML (symbol keys, a tagged value).
METADATA = """---
submission_201:
  :submitters:
  - :name: An Nguyen
    :sid: S1001
    :email: An@U.edu
  :created_at: 2024-03-04 10:00:00.000000000 -08:00
  :score: !ruby/object:BigDecimal 18:0.8e1
submission_202:
  :submitters:
  - :name: Jane Doe
    :sid: S1002
    :email: jane.personal@example.com
submission_203:
  :submitters:
  - :name: Eve Other
    :sid: S9
    :email: eve@u.edu
submission_204:
  :submitters:
  - :name: An Nguyen
    :sid: S1001
    :email: an@u.edu
  - :name: Jane Doe
    :sid: S1002
    :email: jane@u.edu
"""


def test_gradescope_export_maps_its_submitters_by_email_else_sid(tmp_path):
    sub = tmp_path / "sub"
    _files(sub, {"submission_metadata.yml": METADATA,
                 **{f"submission_{n}/calibration.ipynb": "{}" for n in (201, 202, 203, 204)}})
    roster = [Student("an@u.edu", email="an@u.edu", sis_id="S1001"),
              Student("jane@u.edu", email="jane@u.edu", sis_id="S1002")]
    got, _, found = _walk(sub, roster)
    assert [(g[0], g[3]) for g in got] == [
        ("an@u.edu", "calibration.ipynb"), ("jane@u.edu", "calibration.ipynb"),  # by SID
        ("submission_203", "not-on-roster"), ("submission_204", "ambiguous-student")]
    assert found[0].startswith("gradescope")
    (sub / "submission_metadata.yml").unlink()
    assert detect(sub, ["submission_201"], NB) == "plain"
    with pytest.raises(ValueError, match="submission_metadata.yml is missing"):
        _walk(sub, roster, "gradescope")


def test_a_plain_class_matches_roster_ids_whatever_their_characters(tmp_path):
    """Issue 42 item 5: an id with a newline or in NFD matches the folder named so; a folder
    that is no roster id is not graded on a variant nobody was handed."""
    sub = tmp_path / "sub"
    nfd = unicodedata.normalize("NFD", "José")
    _files(sub, {f"{nfd}/calibration.ipynb": "{}", "new\nline/calibration.ipynb": "{}",
                 "Bob\u200b/calibration.ipynb": "{}"})
    roster = [Student("José"), Student("new\nline"), Student("Bob")]
    got, _, found = _walk(sub, roster)
    assert got == [("Bob\u200b", False, 0, "not-on-roster"), ("José", False, 0,
                   "calibration.ipynb"), ("new\nline", False, 0, "calibration.ipynb")]
    assert found == ["plain: each name as a roster id"]


# --------------------------------------------------------------------- issue 38's done-when
SECRET = b"an instructor's secret for the test"


def _fake_run(task, entries, jobs, executor, on_result, warm_boxes=False):
    """The class run with each notebook "graded" from what a real grade depends on: the
    student's variant under the secret (keyed by the entry's student) and the notebook's
    bytes."""
    for i, e in enumerate(entries):
        if e.problem is not None:
            on_result(i, task.refused(e))
            continue
        g = item.unusable(task.name, e.student, e.found, "graded", "", e.id)
        v = variant_number(SECRET, task.name, e.student)
        text = e.path.read_text()
        for k, q in enumerate(g.scores):
            g.scores[q] = float((v + k + len(text)) % (int(g.possible[q]) + 1))
        on_result(i, asdict(g))
    return [None] * len(entries)


def _gradebook(path) -> dict[str, str]:
    with open(path, newline="", encoding="utf-8") as f:
        return {r[1]: r[-1] for r in csv.reader(f)}


def test_canvas_and_moodle_exports_graded_as_downloaded_match_a_folder_per_roster_id(
        tmp_path, monkeypatch):
    monkeypatch.setattr(running, "run", _fake_run)
    roster = tmp_path / "gradebook.csv"
    roster.write_text(CANVAS + '"Ray, Bob",84502,S1003,bray,Kalman 101,,,,,\n', encoding="utf-8")
    people = {"84500": ("nguyenan", "An Nguyen", 11), "84501": ("doejane", "Jane Doe", 12),
              "84502": ("raybob", "Bob Ray", 13)}
    work = {uid: "{" + " " * n + "}" for uid, (_, _, n) in people.items()}  # each their own
    _files(tmp_path / "ids", {f"{uid}/calibration.ipynb": work[uid] for uid in people})
    _files(tmp_path / "canvas", {f"{login}_{uid}_7{uid}_calibration.ipynb": work[uid]
                                 for uid, (login, _, _) in people.items()})
    _files(tmp_path / "moodle", {f"{name}_{n}_assignsubmission_file_/calibration.ipynb": work[uid]
                                 for uid, (_, name, n) in people.items()})
    books = {}
    for layout in ("ids", "canvas", "moodle"):
        grades = grade(tmp_path / layout, "calibration", out=tmp_path / f"{layout}-out", seed=3,
                       secret=SECRET, roster=roster, similarity=False)
        assert sorted((g.student, g.status) for g in grades) == [
            (uid, "graded") for uid in sorted(people)]
        books[layout] = _gradebook(tmp_path / f"{layout}-out" / "canvas.csv")
    assert books["canvas"] == books["moodle"] == books["ids"]
    totals = [books["ids"][uid] for uid in people]
    assert all(totals) and len(set(totals)) > 1  # filled, and each student's own


def test_a_regrade_names_a_student_as_the_export_names_them(tmp_path, monkeypatch):
    """``--student`` takes "the roster's id, the name as in the export, or the id grades.csv
    shows" (docs/grading.md); a mapped export's names (Canvas's file, Moodle's folder) were
    refused as "no submission of ..." (tried from the wheel). Each is taken, for that student
    only; a name nobody handed in is still an error naming it."""
    import json

    monkeypatch.setattr(running, "run", _fake_run)
    roster = tmp_path / "roster.csv"
    roster.write_text(CANVAS, encoding="utf-8")
    files = {"canvas": {"nguyenan_84500_784500_calibration.ipynb": "{ }",
                        "doejane_LATE_84501_784501_calibration.ipynb": "{  }"},
             "moodle": {"An Nguyen_1_assignsubmission_file_/calibration.ipynb": "{ }",
                        "Jane Doe_2_assignsubmission_file_/calibration.ipynb": "{  }"}}
    for layout, names in files.items():
        _files(tmp_path / layout, names)
        out = tmp_path / f"{layout}-out"
        grade(tmp_path / layout, "calibration", out=out, seed=3, secret=SECRET, roster=roster,
              similarity=False)
        found = [n.split("/")[0] for n in names][1]
        grade(tmp_path / layout, "calibration", out=out, secret=SECRET, roster=roster,
              similarity=False, student=[found])
        record = json.loads((out / "grading.json").read_text(encoding="utf-8"))
        assert record["regrades"][-1]["student"] == ["84501"], record["regrades"]
        with pytest.raises(ValueError, match="no submission of 'raybob_84502_1_calibration"):
            grade(tmp_path / layout, "calibration", out=out, secret=SECRET, roster=roster,
                  similarity=False, student=["raybob_84502_1_calibration.ipynb"])


def test_an_export_read_without_a_roster_says_so(tmp_path):
    """Canvas's files graded without ``--roster`` printed "export read as canvas: Canvas user ids
    through the roster's nothing" (tried from the wheel); each LMS's export says its ids are
    taken as found."""
    _files(tmp_path / "canvas", {"nguyenan_84500_678900_calibration.ipynb": "{}"})
    _files(tmp_path / "moodle", {"An Nguyen_1_assignsubmission_file_/calibration.ipynb": "{}"})
    for layout, ids in (("canvas", "Canvas user ids"), ("moodle", "Moodle's full name")):
        got, _, found = _walk(tmp_path / layout, None)
        assert found == [f"{layout}: {ids} as found (no roster given: each is the student's "
                         f"id)"], found
        assert [g[0] for g in got] == [{"canvas": "84500", "moodle": "An Nguyen"}[layout]]
