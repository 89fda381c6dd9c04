"""Gradebook files an LMS imports as they are: Canvas, Moodle, Gradescope.

``grades.csv`` is gpsaccel's own table; these are the same totals in the columns each gradebook's
import reads, every row mapped through the class roster (:mod:`gpsaccel.assignments.roster`) from
the submission's id to the LMS's identifiers:

* ``canvas.csv``: Canvas's gradebook CSV (Grades > Import): ``Student, ID, SIS User ID, SIS Login
  ID, Section, <homework>``, then a ``Points Possible`` row, as Canvas exports it.  Canvas matches
  a row by ``ID`` (its user id; the roster's ``canvas_id``), else ``SIS User ID`` / ``SIS Login
  ID`` (``sis_id``, ``login_id``).  A new column name makes a new assignment; name it as an
  existing one (with Canvas's "(id)" suffix) to fill that one.
* ``moodle.csv``: for Moodle's grade import (Grades > Import > CSV file): ``First name, Last name,
  ID number, Email address, <homework>``; map "Email address" (or "ID number") to the user and the
  homework column to a grade item.
* ``gradescope-roster.csv``: Gradescope's roster upload (``First Name, Last Name, Email, SID,
  Section``), and ``gradescope-scores.csv``: ``First Name, Last Name, SID, Email, Total Score,
  Max Points, Status`` and one column per question (``q1 (3.0 pts)``, as its score export names
  them), for an offline assignment's score upload (matched by email or SID).

A student on the roster without a submission gets an empty cell (the LMS keeps what it has);
a notebook whose run did not finish (``grader-error``, ``not-graded``) also stays empty (rerun
it).  A graded student absent from the roster is not written: :func:`write_exports` returns
their ids so the command can name them.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence
from pathlib import Path

from gpsaccel._atomic import write_text
from gpsaccel.assignments.roster import Student

#: Statuses whose total is not a grade (the run must be repeated): left empty in every export.
UNFINISHED = ("grader-error", "not-graded")

#: The files :func:`write_exports` writes.
FILES = ("canvas.csv", "moodle.csv", "gradescope-roster.csv", "gradescope-scores.csv")


def _cell(value: str) -> str:
    """A text cell a spreadsheet will not evaluate (=, +, -, @ lead a formula)."""
    return "'" + value if value[:1] in ("=", "+", "-", "@", "\t", "\r") else value


def _num(x: float) -> str:
    return f"{x:g}"


def _csv(rows: list[list[str]]) -> str:
    buf = io.StringIO()
    csv.writer(buf).writerows(rows)
    return buf.getvalue()


def _total(grades: dict, s: Student) -> str:
    g = grades.get(s.id)
    return "" if g is None or g.status in UNFINISHED else _num(g.total)


def canvas_rows(grades: dict, possible: dict[str, float], roster: Sequence[Student],
                title: str) -> list[list[str]]:
    rows = [["Student", "ID", "SIS User ID", "SIS Login ID", "Section", title],
            ["    Points Possible", "", "", "", "", _num(sum(possible.values()))]]
    for s in roster:
        rows.append([_cell(s.full_name), _cell(s.canvas_id), _cell(s.sis_id), _cell(s.login_id),
                     _cell(s.section), _total(grades, s)])
    return rows


def moodle_rows(grades: dict, roster: Sequence[Student], title: str) -> list[list[str]]:
    rows = [["First name", "Last name", "ID number", "Email address", title]]
    for s in roster:
        first, last = s.split_name
        rows.append([_cell(first), _cell(last), _cell(s.sis_id), _cell(s.email),
                     _total(grades, s)])
    return rows


def gradescope_rows(grades: dict, possible: dict[str, float], roster: Sequence[Student]
                    ) -> tuple[list[list[str]], list[list[str]]]:
    people = [["First Name", "Last Name", "Email", "SID", "Section"]]
    scores = [["First Name", "Last Name", "SID", "Email", "Total Score", "Max Points", "Status",
               *(f"{q} ({p:.1f} pts)" for q, p in possible.items())]]
    for s in roster:
        first, last = s.split_name
        people.append([_cell(first), _cell(last), _cell(s.email), _cell(s.sis_id or s.id),
                       _cell(s.section)])
        g = grades.get(s.id)
        done = g is not None and g.status not in UNFINISHED
        scores.append([_cell(first), _cell(last), _cell(s.sis_id or s.id), _cell(s.email),
                       _total(grades, s), _num(sum(possible.values())),
                       g.status if g is not None else "missing",
                       *((_num(g.scores.get(q, 0.0)) if done and g is not None else "")
                         for q in possible)])
    return people, scores


def write_exports(grades: Sequence, possible: dict[str, float], roster: Sequence[Student],
                  title: str, out: str | Path) -> list[str]:
    """Write :data:`FILES` into ``out`` (module docstring) for ``grades``
    (:class:`gpsaccel.assignments.grading.Grade` s); returns the ids graded but not on the
    roster (not written anywhere but ``grades.csv``)."""
    out = Path(out)
    by_id = {g.student: g for g in grades}
    ids = {s.id for s in roster}
    write_text(out / "canvas.csv", _csv(canvas_rows(by_id, possible, roster, title)))
    write_text(out / "moodle.csv", _csv(moodle_rows(by_id, roster, title)))
    people, scores = gradescope_rows(by_id, possible, roster)
    write_text(out / "gradescope-roster.csv", _csv(people))
    write_text(out / "gradescope-scores.csv", _csv(scores))
    return sorted(g.student for g in grades if g.student not in ids)
