"""The class roster: who the students are, and how each LMS names them.

One file serves the hand-out (one notebook per student, its variant keyed by the student's id),
the mapping of an LMS's submission export to the students (:mod:`gpsaccel.classrun.exports`)
and the gradebook exports (:mod:`gpsaccel.classrun.classwide`).  It is read as it comes:

* **plain text**, one student id a line (``#`` starts a comment): the id is how the submissions
  are named (a folder or notebook per student), or the name Gradescope shows;
* **gpsaccel's CSV**: a header with an ``id`` column and any of :data:`FIELDS`;
* **Canvas's gradebook export** (Grades > Export > Export Entire Gradebook): ``Student, ID, SIS
  User ID, SIS Login ID, [Integration ID, Root Account,] Section``, then the assignments, a
  "Points Possible" row (and a "Manual Posting" row) that are not students.  The id is Canvas's
  user id (``ID``), which every Canvas submission export carries; ``Student`` is the sortable
  name ("Doe, Jane"), or ``LastName, FirstName`` where the course exports names split;
* **Moodle's participants or grades export** (Participants > select all > Download table data;
  Grades > Export > Plain text file): ``First name, Last name`` (``Surname`` in older English
  packs) and the identity fields, ``ID number``, ``Email address``, ...; the id is the email
  address (else the ID number where the site shows no email);
* **Moodle's grading worksheet** (the assignment's Submissions > Download grading worksheet):
  ``Identifier`` ("Participant 123456"), ``Full name``, ``Email address``, ...; the same ids, and
  each student's participant number of that assignment, which its submission download carries;
* **Gradescope's roster** (Roster > Download): ``First Name, Last Name, SID, Email, Role,
  [Sections]``; staff rows are not students; the id is the email.

A header is recognised by its exact column names (comma, semicolon or tab separated, as Canvas
and Moodle write them in some locales); any other first line is the first id of a plain roster
(an id may hold commas and spaces, as LMS folder names do: "Doe, Jane (1001)").  An id is kept as
the file has it, without its surrounding spaces; :func:`unmatchable` names the ids no file or
folder can be named.
"""

from __future__ import annotations

import csv
import io
import os
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

#: Columns a gpsaccel CSV roster may have besides ``id`` (anything else is refused: a misspelt
#: column would silently leave a gradebook column empty).  ``participant``: Moodle's
#: participant number of one assignment (its grading worksheet's "Participant 123456").
FIELDS = ("name", "first_name", "last_name", "email", "sis_id", "login_id", "canvas_id",
          "section", "participant")

#: Largest roster read (bytes): a class list, or a gradebook of a large course.
MAX_BYTES = 16 << 20

#: Separators an LMS writes a CSV file with (Canvas and Moodle: a semicolon in some locales).
DELIMITERS = (",", ";", "\t")


@dataclass(frozen=True)
class Student:
    """One student: the id of the hand-out and the grades, and the LMS's own identifiers ("" if
    unknown)."""

    id: str
    name: str = ""
    first_name: str = ""
    last_name: str = ""
    email: str = ""
    sis_id: str = ""
    login_id: str = ""
    canvas_id: str = ""
    section: str = ""
    participant: str = ""

    @property
    def full_name(self) -> str:
        """"First Last": the roster's first and last names, else its name ("Doe, Jane", as
        Canvas sorts it, turned round), else the id."""
        if self.first_name or self.last_name:
            return " ".join(p for p in (self.first_name, self.last_name) if p)
        last, comma, first = self.name.partition(", ")
        if comma and last and first:
            return f"{first} {last}"
        return self.name or self.id

    @property
    def split_name(self) -> tuple[str, str]:
        """(first, last): the roster's, else the full name split at its last space."""
        if self.first_name or self.last_name:
            return self.first_name, self.last_name
        first, _, last = self.full_name.rpartition(" ")
        return (first, last) if first else (last, "")


@dataclass(frozen=True)
class Roster:
    """A roster file read: its students, what it was (``form``: ``plain``, ``csv``, ``canvas``,
    ``moodle``, ``moodle-worksheet``, ``gradescope``) and which of its columns the ids are."""

    students: list[Student]
    form: str
    ids: str
    #: Canvas's assignment columns ("Homework 1 (5501)": a name and Canvas's id in brackets),
    #: the columns a ``canvas.csv`` can fill (``gpsaccel grade --canvas-column``); () else.
    assignments: tuple[str, ...] = ()

    def describe(self) -> str:
        return f"{FORMS[self.form]} ({len(self.students)} students; ids: {self.ids})"


#: How each form is named in messages.
FORMS = {"plain": "one id a line", "csv": "gpsaccel's CSV", "canvas": "Canvas's gradebook export",
         "moodle": "Moodle's participants or grades export",
         "moodle-worksheet": "Moodle's grading worksheet", "gradescope": "Gradescope's roster"}


def read_roster(path: str | os.PathLike) -> list[Student]:
    """The students of the roster file at ``path`` (:func:`read`)."""
    return read(path).students


def read(path: str | os.PathLike) -> Roster:
    """The roster file at ``path``, read as it comes (module docstring); ValueError naming the
    line and what was expected on a malformed file, a repeated id or an empty roster."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"roster: {path} is not a file (one student id a line, a CSV file with "
                         f"an id column, or an LMS's roster export: docs/grading.md)")
    if path.stat().st_size > MAX_BYTES:
        raise ValueError(f"roster: {path} is larger than {MAX_BYTES >> 20} MB")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ValueError(f"roster: {path} is not UTF-8 text ({exc}); export it as UTF-8 "
                         f"(Canvas and Moodle offer it)") from None
    first = next((ln for ln in text.splitlines() if ln.strip()), "")
    form, delimiter = _form(first)
    if form == "plain":
        roster = Roster([Student(ln.strip()) for ln in text.splitlines()
                         if ln.strip() and not ln.lstrip().startswith("#")], "plain", "as listed")
    else:
        rows = csv.reader(io.StringIO(text), delimiter=delimiter)
        header = [h.strip() for h in next(rows)]
        roster = _READERS[form](path, header, rows)
    if not roster.students:
        raise ValueError(f"roster: {path} lists no student")
    seen: dict[str, int] = {}
    for n, s in enumerate(roster.students):
        if s.id in seen:
            raise ValueError(f"roster: {path} lists the student id {s.id!r} twice")
        seen[s.id] = n
    return roster


# ------------------------------------------------------------------------ which form it is
def _form(first_line: str) -> tuple[str, str]:
    """(form, delimiter) of a roster whose first non-empty line is ``first_line``."""
    if first_line.strip().lower() == "id":  # a CSV roster of ids alone (quoted: any character)
        return "csv", ","
    for delimiter in DELIMITERS:
        if delimiter not in first_line:
            continue
        header = {h.strip() for h in next(csv.reader([first_line], delimiter=delimiter))}
        for form, test in _HEADERS:
            if test(header):
                return form, delimiter
    return "plain", ""


def _canvas(h: set[str]) -> bool:
    return {"ID", "SIS Login ID", "Section"} <= h and ("Student" in h or
                                                       {"LastName", "FirstName"} <= h)


def _moodle(h: set[str]) -> bool:
    named = ("First name" in h and bool({"Last name", "Surname"} & h)) or "Full name" in h
    return named and bool({"Email address", "ID number"} & h)


_HEADERS: tuple[tuple[str, Callable[[set[str]], bool]], ...] = (
    ("canvas", _canvas),
    ("moodle-worksheet", lambda h: {"Identifier", "Full name", "Email address"} <= h),
    ("moodle", _moodle),
    ("gradescope", lambda h: {"Email", "SID"} <= h and ({"First Name", "Last Name"} <= h
                                                        or bool({"Name", "Full Name"} & h))),
    ("csv", lambda h: "id" in {x.lower() for x in h}),
)


# ---------------------------------------------------------------------------------- readers
def _cells(header: list[str], row: list[str]) -> dict[str, str]:
    return {h: (row[i].strip() if i < len(row) else "") for i, h in enumerate(header) if h}


def _read_csv(path: Path, header: list[str], rows) -> Roster:  # noqa: ANN001 - a csv reader
    names = [h.lower() for h in header]
    unknown = [h for h in names if h and h != "id" and h not in FIELDS]
    if unknown:
        raise ValueError(f"roster: {path} has unknown column(s) {', '.join(unknown)}; expected "
                         f"id and any of {', '.join(FIELDS)}")
    out = []
    for n, row in enumerate(rows, start=2):
        values = _cells(names, row)
        if not values.get("id"):
            if any(values.values()):
                raise ValueError(f"roster: {path} line {n} has no id")
            continue
        out.append(Student(**{k: v for k, v in values.items() if k == "id" or k in FIELDS}))
    return Roster(out, "csv", "the id column")


def _canvas_name(cell: str) -> str:
    """A name as Canvas writes it: one that starts with ``=`` is written ``="..."`` (so a
    spreadsheet shows it as text)."""
    return cell[2:-1] if cell.startswith('="') and cell.endswith('"') else cell


def _read_canvas(path: Path, header: list[str], rows) -> Roster:  # noqa: ANN001
    out = []
    for n, row in enumerate(rows, start=2):
        c = _cells(header, row)
        name = _canvas_name(c.get("Student", ""))
        first, last = _canvas_name(c.get("FirstName", "")), _canvas_name(c.get("LastName", ""))
        if name == "Points Possible" or not any(c.values()):
            continue
        if not c.get("ID"):
            if name or first or last:
                raise ValueError(f"roster: {path} line {n} has no ID (Canvas's user id)")
            continue  # the "Manual Posting" row under the header
        out.append(Student(c["ID"], name=name, first_name=first, last_name=last,
                           sis_id=c.get("SIS User ID", ""), login_id=c.get("SIS Login ID", ""),
                           canvas_id=c["ID"], section=c.get("Section", "")))
    return Roster(out, "canvas", "Canvas user ids (its ID column)",
                  tuple(h for h in header if _ASSIGNMENT.search(h)))


#: A Canvas assignment column: its name, then the assignment's id in brackets (the score
#: columns, "Current Score", ..., have none).
_ASSIGNMENT = re.compile(r"\(\d+\)$")


def _id_column(path: Path, header: list[str], form: str) -> str:
    for column in ("Email address", "ID number"):
        if column in header:
            return column
    raise ValueError(f"roster: {path} ({FORMS[form]}) has neither an 'Email address' nor an "
                     f"'ID number' column: export it with one of them")


def _read_moodle(path: Path, header: list[str], rows) -> Roster:  # noqa: ANN001
    column = _id_column(path, header, "moodle")
    out = []
    for n, row in enumerate(rows, start=2):
        c = _cells(header, row)
        if not any(c.values()):
            continue
        if not c.get(column):
            raise ValueError(f"roster: {path} line {n} has no {column} (the student's id)")
        out.append(Student(c[column], name=c.get("Full name", ""),
                           first_name=c.get("First name", ""),
                           last_name=c.get("Last name", c.get("Surname", "")),
                           email=c.get("Email address", ""), sis_id=c.get("ID number", "")))
    return Roster(out, "moodle", f"Moodle's {column!r} column")


#: The participant number in a grading worksheet's Identifier ("Participant 123456", in the
#: site's language).
_PARTICIPANT = re.compile(r"(\d+)\s*$")


def _read_worksheet(path: Path, header: list[str], rows) -> Roster:  # noqa: ANN001
    out = []
    for n, row in enumerate(rows, start=2):
        c = _cells(header, row)
        if not any(c.values()):
            continue
        m = _PARTICIPANT.search(c.get("Identifier", ""))
        if not c.get("Email address") or m is None:
            raise ValueError(f"roster: {path} line {n} has no Email address or no participant "
                             f"number in its Identifier")
        out.append(Student(c["Email address"], name=c.get("Full name", ""),
                           email=c["Email address"], sis_id=c.get("ID number", ""),
                           participant=m.group(1)))
    return Roster(out, "moodle-worksheet", "Moodle's 'Email address' column")


def _read_gradescope(path: Path, header: list[str], rows) -> Roster:  # noqa: ANN001
    out = []
    for n, row in enumerate(rows, start=2):
        c = _cells(header, row)
        if not any(c.values()) or c.get("Role", "Student").lower() != "student":
            continue  # instructors, TAs and readers are on Gradescope's roster too
        if not c.get("Email"):
            raise ValueError(f"roster: {path} line {n} has no Email (the student's id)")
        out.append(Student(c["Email"], name=c.get("Name", c.get("Full Name", "")),
                           first_name=c.get("First Name", ""), last_name=c.get("Last Name", ""),
                           email=c["Email"], sis_id=c.get("SID", ""),
                           section=c.get("Sections", c.get("Section", ""))))
    return Roster(out, "gradescope", "Gradescope's Email column")


_READERS = {"csv": _read_csv, "canvas": _read_canvas, "moodle": _read_moodle,
            "moodle-worksheet": _read_worksheet, "gradescope": _read_gradescope}


# -------------------------------------------------------------------------- what can match
#: Longest file or folder name (bytes) on the file systems an export is unpacked on.
NAME_MAX = 255


def unmatchable(students: Sequence[Student]) -> list[str]:
    """The roster's ids that no file or folder can be named (``/`` or NUL in them, ``.`` or
    ``..``, longer than :data:`NAME_MAX` bytes), nor a hidden one the walk skips (a leading
    ``.``): under a layout of one folder or notebook per student, no submission matches them
    (an LMS export maps by the ids its names carry instead)."""
    return [s.id for s in students
            if "/" in s.id or "\0" in s.id or s.id.startswith(".") or s.id == "__MACOSX"
            or len(os.fsencode(s.id)) > NAME_MAX]
