"""One walk of a class (gpsaccel.classrun.entries) for ``gpsaccel check`` and ``gpsaccel grade``:
what each kind takes, nothing skipped silently, one rule for names and ids, collisions, and the
naming seam where an LMS export is mapped to the roster (late, resubmissions, nobody)."""

from __future__ import annotations

import os
import re
import unicodedata
from pathlib import Path

import pytest

from gpsaccel import _untrusted
from gpsaccel.assignments.roster import Student
from gpsaccel.assignments.scoring import Grade
from gpsaccel.classrun import PYTHON, Name, notebooks, walk
from gpsaccel.classrun.classwide import write_gradebooks


def _class(folder):
    for rel in ("alice.py", "bob/kf.py", "bob/helpers.py", "carol.ipynb", "Dan/x/hw.IPYNB",
                "notes.txt", "__init__.py", ".DS_Store", "__pycache__/a.pyc",
                "__MACOSX/carol.ipynb", "erin/README"):
        (folder / rel).parent.mkdir(parents=True, exist_ok=True)
        (folder / rel).write_text("{}")
    os.symlink(folder / "alice.py", folder / "mallory.py")
    os.mkfifo(folder / "pipe.py")


def test_each_kind_takes_its_submissions_and_notes_everything_else(tmp_path):
    _class(tmp_path)
    entries, notes = walk([tmp_path], PYTHON)
    assert [(e.found, e.student) for e in entries] == [
        ("alice.py", "alice"), ("bob", "bob"), ("Dan", "Dan"), ("erin", "erin"),
        ("mallory.py", "mallory")]  # the link stays: its check refuses it in the student's report
    assert entries[1].path == tmp_path / "bob"  # a folder is the submission, helpers and all
    shown = {n.split(": skipped ")[0].rsplit("/", 1)[-1]: n.split(": skipped ")[1]
             for n in notes}
    assert shown == {"__init__.py": "(a package's __init__.py)", ".DS_Store": "(hidden)",
                     "__MACOSX": "(hidden)", "__pycache__": "(Python's cache)",
                     "carol.ipynb": "(not a .py file or a folder)",
                     "notes.txt": "(not a .py file or a folder)",
                     "pipe.py": "(not a file or folder)"}
    assert all(n.startswith(str(tmp_path)) for n in notes)  # a list of paths: named by path

    entries, notes = walk(tmp_path, notebooks("hw"))
    got = {e.found: (e.path.relative_to(tmp_path).as_posix() if e.path else e.problem[0])
           for e in entries}
    assert got == {"bob": "no-notebook", "carol.ipynb": "carol.ipynb", "Dan": "Dan/x/hw.IPYNB",
                   "erin": "no-notebook", "__pycache__": "no-notebook"}  # any name a student's
    assert {n.split(":")[0] for n in notes} == {  # one folder: named as found in it
        ".DS_Store", "__MACOSX", "__init__.py", "alice.py", "mallory.py", "notes.txt",
        "pipe.py"}
    assert "mallory.py: skipped (a symbolic link)" in notes


def test_a_file_given_is_an_entry_even_when_missing(tmp_path):
    (tmp_path / "a.py").write_text("")
    entries, notes = walk([tmp_path / "a.py", tmp_path / "gone.py"], PYTHON)
    assert [(e.path, e.student, e.problem) for e in entries] == [
        (tmp_path / "a.py", "a", None), (tmp_path / "gone.py", "gone", None)]
    (tmp_path / "empty").mkdir()
    assert walk([tmp_path / "empty"], PYTHON) == (
        [], [f"{tmp_path / 'empty'}: no submission in it (a .py file or a folder each)"])


NAMES = ["Doe, Jane", "Doe_ Jane", unicodedata.normalize("NFD", "Jos\u00e9"),
         os.fsdecode(b"bad\xff\xfe"), "e\x1b[2Jvil", "bidi\u202etxt", "nbsp\u00a0x", "\u00e9" * 120]


@pytest.mark.parametrize("kind", [PYTHON, notebooks("hw")], ids=["check", "grade"])
def test_any_name_gets_a_printable_unique_id_and_a_printable_shown_name(tmp_path, kind):
    for name in NAMES:
        (tmp_path / (name + kind.suffix)).write_text("{}")
    entries, notes = walk(tmp_path, kind)
    assert not notes and len({e.id for e in entries}) == len(NAMES)
    for e in entries:
        assert e.id == _untrusted.clean(e.id) and e.id.isprintable() and "/" not in e.id
        assert e.shown.isprintable() and len(e.shown) <= 200, e.shown
        assert os.fsencode(e.found) in {os.fsencode(n + kind.suffix) for n in NAMES}
    shown = {e.shown for e in entries}
    assert {"bad\\xff\\xfe", "e\\x1b[2Jvil", "bidi\\u202etxt", "nbsp\\xa0x",
            "Jos\u00e9"} <= shown  # written out, never dropped; NFC


def test_case_collisions_are_refused_only_where_ids_name_files(tmp_path):
    for name in ("Bob", "BOB"):
        (tmp_path / name).mkdir()
        (tmp_path / name / "hw.ipynb").write_text("{}")
        (tmp_path / name / "kf.py").write_text("")
    graded, notes = walk(tmp_path, notebooks("hw"))
    assert [(e.found, e.problem[0]) for e in graded] == [("BOB", "id-collision"),
                                                         ("Bob", "id-collision")]
    assert graded[0].id != graded[1].id and all(e.path is None for e in graded)
    assert notes == ["BOB: id-collision with 'Bob'", "Bob: id-collision with 'BOB'"]
    checked, notes = walk(tmp_path, PYTHON)
    assert [e.problem for e in checked] == [None, None] and not notes
    assert checked[0].id.casefold() != checked[1].id.casefold()


def test_a_look_alike_name_is_another_student_never_a_classmates_cell(tmp_path):
    """"Bob\\u200b" was shown as "Bob" (the zero-width space dropped) and so graded into Bob's
    gradebook row; it is written out now: another name, on no roster."""
    for name in ("Bob\u200b", "Bob\u2060"):
        (tmp_path / name).mkdir()
        (tmp_path / name / "hw.ipynb").write_text("{}")
    entries, _ = walk(tmp_path, notebooks("hw"))
    assert [e.shown for e in entries] == ["Bob\\u200b", "Bob\\u2060"]
    assert all(e.problem is None for e in entries)
    possible = {"q1": 1.0}
    grades = [Grade(e.shown, "", {"q1": 1.0}, possible, "graded", id=e.id) for e in entries]
    missing = write_gradebooks(grades, possible, [Student("Bob")], "HW", tmp_path)
    assert missing == ["Bob\\u200b", "Bob\\u2060"]
    assert (tmp_path / "canvas.csv").read_text().splitlines()[-1] == "Bob,,,,,"


# ------------------------------------------------------------------ the naming seam (LMS)
#: A Canvas-like flat export name: login, [LATE,] user id, submission id, the file's own name,
#: an optional resubmission number (``-1``).
CANVAS = re.compile(r"(?P<login>[a-z]+)_(?P<late>LATE_)?(?P<uid>\d+)_(?P<sub>\d+)_"
                    r"(?P<file>.+?)(?:-(?P<again>\d+))?\.ipynb$")


def canvas_like(roster: dict[str, str]):
    """A naming that maps the user id of each file to the roster's student id."""
    def naming(found: str, is_file: bool) -> Name:
        m = CANVAS.match(found) if is_file else None
        if m is None or m["uid"] not in roster:
            return Name("", problem=("not-on-roster", f"{found} names nobody on the roster"))
        return Name(roster[m["uid"]], late=bool(m["late"]), attempt=int(m["again"] or 0))
    return naming


def test_a_naming_maps_an_export_to_the_roster_with_late_and_resubmissions(tmp_path):
    for name in ("nguyenan_84500_678900_calibration.ipynb",
                 "nguyenan_84500_678950_calibration-1.ipynb",
                 "doejane_LATE_84501_678902_calibration.ipynb",
                 "stranger_99999_678903_calibration.ipynb"):
        (tmp_path / name).write_text("{}")
    entries, notes = walk(tmp_path, notebooks("calibration"),
                          canvas_like({"84500": "an.nguyen", "84501": "jane.doe"}))
    got = [(e.student, e.late, e.attempt, e.path.name if e.path else e.problem[0])
           for e in entries]
    assert got == [("jane.doe", True, 0, "doejane_LATE_84501_678902_calibration.ipynb"),
                   ("an.nguyen", False, 1, "nguyenan_84500_678950_calibration-1.ipynb"),
                   ("stranger_99999_678903_calibration.ipynb", False, 0, "not-on-roster")]
    assert notes == ["nguyenan_84500_678900_calibration.ipynb: superseded by a later attempt "
                     "of an.nguyen"]
    assert entries[1].id == "an.nguyen"  # the roster's id names the files and keys the variant


def test_two_entries_of_one_student_and_attempt_are_both_refused(tmp_path):
    for name in ("nguyenan_84500_1_calibration.ipynb", "nguyenan_84500_2_calibration.ipynb"):
        (tmp_path / name).write_text("{}")
    entries, _ = walk(tmp_path, notebooks("calibration"), canvas_like({"84500": "an"}))
    assert [e.problem[0] for e in entries] == ["id-collision", "id-collision"]


def test_a_students_folder_too_deep_is_its_status_and_gradescope_looks_the_same_way(
        tmp_path, nested_folders):
    """The notebook of a student's folder is found one way, with the checker's limits, by a
    class's walk and by Gradescope's container (whose search was an unbounded rglob)."""
    from gpsaccel.assignments import gradescope
    from gpsaccel.assignments.grading import notebook_in

    (tmp_path / "deep").mkdir()
    nested_folders.make(tmp_path / "deep", 1500)
    try:
        entries, _ = walk(tmp_path, notebooks("hw"))
        path, problem = notebook_in(tmp_path / "deep", "hw")
    finally:
        nested_folders.remove(tmp_path / "deep")
    assert [(e.found, e.problem[0]) for e in entries] == [("deep", "file-limit")]
    assert path is None and problem == entries[0].problem
    assert "notebook_in(root" in Path(gradescope.__file__).read_text()  # its submission too
    (tmp_path / "two").mkdir()
    for name in ("a.ipynb", "HW.ipynb"):
        (tmp_path / "two" / name).write_text("{}")
    assert notebook_in(tmp_path / "two", "hw") == (tmp_path / "two" / "HW.ipynb", None)
