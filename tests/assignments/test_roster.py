"""The roster read as each LMS writes it (gpsaccel.assignments.roster): the files below are laid
out as Canvas, Moodle and Gradescope download them (header, the rows that are no student, the
locale's separator, a byte order mark), each read to the same students; a malformed one is an
error naming the file and what was expected."""

from __future__ import annotations

import pytest

from gpsaccel.assignments.roster import read, read_roster, unmatchable

#: Canvas: Grades > Export > Export Entire Gradebook (a "Points Possible" row, read-only columns,
#: the course's test student).
CANVAS = (
    "Student,ID,SIS User ID,SIS Login ID,Section,Homework 1 (5501),Current Score,"
    "Unposted Current Score,Final Score,Unposted Final Score\n"
    "    Points Possible,,,,,10.00,(read only),(read only),(read only),(read only)\n"
    '"Nguyen, An",84500,S1001,anguyen,Kalman 101,,,,,\n'
    '"Doe, Jane",84501,S1002,jdoe,Kalman 101,8.00,80.00,80.00,80.00,80.00\n')

#: Canvas with a "Manual Posting" row under the header (assignments posted by hand).
CANVAS_MANUAL = (
    "Student,ID,SIS User ID,SIS Login ID,Integration ID,Root Account,Section,Homework 1 (5501)\n"
    ",,,,,,,Manual Posting\n"
    "    Points Possible,,,,,,,10.00\n"
    '"Nguyen, An",84500,S1001,anguyen,,u.edu,Kalman 101,\n')

#: Moodle: Participants > select all > Download table data as CSV.
MOODLE_PARTICIPANTS = (
    "First name,Last name,Email address,Roles,Groups,Last access to course\n"
    "An,Nguyen,an@u.edu,Student,No groups,Never\n"
    "Jane,Doe,jane@u.edu,Student,No groups,Never\n")

#: Moodle: Grades > Export > Plain text file (semicolons, as some locales write it).
MOODLE_GRADES = (
    "First name;Surname;ID number;Institution;Department;Email address;"
    "Assignment: Homework 1 (Real);Last downloaded from this course\n"
    "An;Nguyen;S1001;;;an@u.edu;-;1700000000\n")

#: Moodle: the assignment's View all submissions > Download grading worksheet.
MOODLE_WORKSHEET = (
    "\ufeffIdentifier,\"Full name\",\"Email address\",Status,Grade,\"Maximum Grade\","
    "\"Grade can be changed\",\"Last modified (submission)\",\"Last modified (grade)\","
    "\"Feedback comments\"\n"
    "\"Participant 1234567\",\"An Nguyen\",an@u.edu,\"Submitted for grading\",,10.00,Yes,"
    "\"Monday, 4 March 2024, 10:00 AM\",-,\n")

#: Gradescope: Roster > Download roster (staff rows too).
GRADESCOPE = ("First Name,Last Name,SID,Email,Role,Sections\n"
              "An,Nguyen,S1001,an@u.edu,Student,Kalman 101\n"
              "Ted,Teach,,ted@u.edu,Instructor,\n")


def _read(tmp_path, text: str):
    path = tmp_path / "roster.csv"
    path.write_text(text, encoding="utf-8")
    return read(path)


def test_canvas_gradebook_export_is_a_roster_by_user_id(tmp_path):
    r = _read(tmp_path, CANVAS)
    assert r.form == "canvas" and [s.id for s in r.students] == ["84500", "84501"]
    an = r.students[0]
    assert (an.canvas_id, an.sis_id, an.login_id, an.section, an.full_name) == \
        ("84500", "S1001", "anguyen", "Kalman 101", "An Nguyen")
    manual = _read(tmp_path, CANVAS_MANUAL)
    assert [(s.id, s.full_name) for s in manual.students] == [("84500", "An Nguyen")]


def test_moodle_exports_are_rosters_by_email_and_the_worksheet_carries_participants(tmp_path):
    r = _read(tmp_path, MOODLE_PARTICIPANTS)
    assert r.form == "moodle"
    assert [(s.id, s.full_name) for s in r.students] == [("an@u.edu", "An Nguyen"),
                                                         ("jane@u.edu", "Jane Doe")]
    g = _read(tmp_path, MOODLE_GRADES)
    assert [(s.id, s.sis_id, s.last_name) for s in g.students] == [("an@u.edu", "S1001",
                                                                     "Nguyen")]
    w = _read(tmp_path, MOODLE_WORKSHEET)
    assert w.form == "moodle-worksheet"
    assert [(s.id, s.participant, s.full_name) for s in w.students] == [
        ("an@u.edu", "1234567", "An Nguyen")]


def test_gradescope_roster_leaves_out_staff(tmp_path):
    r = _read(tmp_path, GRADESCOPE)
    assert r.form == "gradescope"
    assert [(s.id, s.sis_id, s.email, s.section) for s in r.students] == [
        ("an@u.edu", "S1001", "an@u.edu", "Kalman 101")]


def test_a_plain_roster_keeps_commas_and_a_csv_roster_its_columns(tmp_path):
    r = _read(tmp_path, "Doe, Jane (1001)\nbob\n")
    assert r.form == "plain" and [s.id for s in r.students] == ["Doe, Jane (1001)", "bob"]
    c = _read(tmp_path, "id,name,participant\nan,An Nguyen,77\n")
    assert c.form == "csv" and c.students[0].participant == "77"


@pytest.mark.parametrize("text, message", [
    ("Student,ID,SIS User ID,SIS Login ID,Section\n\"Doe, Jane\",,,,A\n", "line 2 has no ID"),
    ("First name,Last name,Roles\nAn,Nguyen,Student\n", None),  # no identity column: plain?
    ("Identifier,Full name,Email address\nParticipant,An Nguyen,an@u.edu\n",
     "no participant number"),
    ("First Name,Last Name,SID,Email,Role\nAn,Nguyen,1,,Student\n", "line 2 has no Email"),
    ("Student,ID,SIS User ID,SIS Login ID,Section\n    Points Possible,,,,\n", "lists no student"),
])
def test_a_malformed_lms_file_is_an_error_naming_the_line(tmp_path, text, message):
    if message is None:  # a header of no known form is the first line of a plain roster
        assert _read(tmp_path, text).form == "plain"
        return
    with pytest.raises(ValueError, match=message):
        _read(tmp_path, text)


def test_the_ids_no_file_or_folder_can_be_named_are_named(tmp_path):
    path = tmp_path / "r.csv"
    path.write_text('id\n"a/b"\n.hidden\n' + "x" * 256 + '\n"new\nline"\nfine\n',
                    encoding="utf-8")
    students = read_roster(path)
    assert unmatchable(students) == ["a/b", ".hidden", "x" * 256]  # a newline can be a name


def test_canvas_gradebook_export_names_its_assignment_columns_not_its_scores(tmp_path):
    """The columns a canvas.csv can fill (``gpsaccel grade --canvas-column``): an assignment's
    "Name (id)", never Canvas's read-only score columns; no other form has any."""
    for text, n in ((CANVAS, 1), (CANVAS_MANUAL, 1)):
        (tmp_path / "r.csv").write_text(text)
        assert read(tmp_path / "r.csv").assignments == ("Homework 1 (5501)",), n
    (tmp_path / "two.csv").write_text(CANVAS.replace(
        "Homework 1 (5501),", "Homework 1 (5501),Quiz (2) (5502),").replace(
        "10.00,", "10.00,5.00,"))
    assert read(tmp_path / "two.csv").assignments == ("Homework 1 (5501)", "Quiz (2) (5502)")
    (tmp_path / "m.csv").write_text(MOODLE_GRADES)
    assert read(tmp_path / "m.csv").assignments == ()
