"""What grading a class writes about the whole class once every notebook is graded: the LMS
gradebook files (with a roster) and the similarity report.  Both read the grades the run holds
(every student's row, a regrade of one included) and change none of them.  :func:`write` is
called by :func:`gpsaccel.classrun.grading.grade_class`, so ``grade()`` from Python writes what
``gpsaccel grade`` writes.

The gradebooks are the same totals in the columns each gradebook's import reads, every row
mapped through the class roster (:mod:`gpsaccel.assignments.roster`) from the submission's id to
the LMS's identifiers:

* ``canvas.csv``: Canvas's gradebook CSV (Grades > Import): ``Student, ID, SIS User ID, SIS Login
  ID, Section, <homework>``, then a ``Points Possible`` row, as Canvas exports it.  Canvas matches
  a row by ``ID`` (its user id; the roster's ``canvas_id``), else ``SIS User ID`` / ``SIS Login
  ID`` (``sis_id``, ``login_id``).  The grade column is named ``canvas_column`` (an assignment
  column of Canvas's own gradebook export, "Homework 1 (5501)", which the import fills), else
  the homework's title, which Canvas imports as a new assignment.
* ``moodle.csv``: for Moodle's grade import (Grades > Import > CSV file): ``First name, Last name,
  ID number, Email address, <homework>``; map "Email address" (or "ID number") to the user and the
  homework column to a grade item.
* ``gradescope-roster.csv``: Gradescope's roster upload (``First Name, Last Name, Email, SID,
  Section``), and ``gradescope-scores.csv``: ``First Name, Last Name, SID, Email, Total Score,
  Max Points, Status`` and one column per question (``q1 (3.0 pts)``, as its score export names
  them), for an offline assignment's score upload (matched by email or SID).

A submission whose name maps to no one (:data:`UNMAPPED`) is in no row.  Rows meet grades by
the students' names as shown (:func:`gpsaccel._untrusted.shown`, applied to the roster's ids).
A student on the roster without a submission gets an empty cell (the LMS keeps what it has);
so does a grade whose status the student did not cause (:mod:`gpsaccel.classrun.statuses`:
``id-collision``, ``grader-error``, ``not-graded``, ...): a grade that was not computed is never
a score.  A status the student caused holds the total its table says.  A graded student absent
from the roster is not written: the lines returned name them.

The similarity and integrity report (:mod:`gpsaccel.assignments.similarity`: groups of copies,
the published solutions, hidden code) is asked for through one function, :func:`similar`, and
flags, never grades.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from gpsaccel import registry
from gpsaccel._atomic import write_text
from gpsaccel._untrusted import cell, shown
from gpsaccel.assignments.roster import Student
from gpsaccel.assignments.scoring import Grade
from gpsaccel.classrun import statuses
from gpsaccel.classrun.writing import Outputs, csv_text

#: The statuses of a submission whose name maps to no one on the roster, or to several
#: (:mod:`gpsaccel.classrun.exports`): nobody's grade, in no roster row.
UNMAPPED = ("not-on-roster", "ambiguous-student", "unrecognised-name")

#: The gradebook files :func:`write_gradebooks` writes.
FILES = ("canvas.csv", "moodle.csv", "gradescope-roster.csv", "gradescope-scores.csv")


#: The similarity report's files (:func:`similar`).
REPORT = ("similarity.csv", "similarity.html")


def files(roster: bool, similarity: bool) -> tuple[str, ...]:
    """The files :func:`write` writes, with a roster or not, the similarity report or not."""
    return (FILES if roster else ()) + (REPORT if similarity else ())


def write(submissions: Path, out: Path, name: str, grades: Sequence[Grade],
          possible: dict[str, float], roster: Sequence[Student] | None,
          similarity: bool = True, outputs: Outputs | None = None,
          compare_with: Path | None = None, canvas_column: str | None = None) -> list[str]:
    """Write the gradebook files (with a roster) and the similarity report (with
    ``compare_with``: against earlier submissions too) into ``out``; the lines to show the
    instructor.  ``canvas_column``: the name of ``canvas.csv``'s grade column (module
    docstring).  ``outputs``: where a write the file system refuses is recorded (the other files
    are still written); without it, the error is raised."""
    def each(names: Sequence[str], writer: Callable[..., Any], *args: Any) -> Any:
        return outputs.write(names, writer, *args) if outputs is not None else writer(*args)

    lines = statuses.unscored_lines(grades) + statuses.scored_zero_lines(grades)
    if roster is not None:
        missing = each(FILES, write_gradebooks, grades, possible, roster,
                       registry.assignment(name).title or name, out, canvas_column)
        if missing is not None:
            lines.append("gradebooks: " + ", ".join(str(out / f) for f in FILES))
        if missing:
            lines.append(f"not on the roster (in grades.csv only): {', '.join(missing)}")
    if similarity:
        # the report, then its counts at the end of summary.csv: a file refused is named
        lines += each(REPORT + ("summary.csv",), similar, out, name, grades, compare_with) or []
    return lines


# --------------------------------------------------------------------------------- gradebooks
def _num(x: float) -> str:
    return f"{x:g}"


def _key(student: str) -> str:
    """The key a roster row meets its grade by: the id as a grade shows its student
    (:func:`gpsaccel._untrusted.shown`, the one rule for folder names), so an id matches the
    export's name whatever its characters (a newline, a comma, NFD), and never a look-alike's
    (a zero-width character is written out, not dropped)."""
    return shown(student)


def _total(grades: dict, s: Student) -> str:
    g = grades.get(_key(s.id))
    return "" if g is None else statuses.cell(g.status, g.total)


def _by_student(grades: Sequence[Grade]) -> dict[str, Grade]:
    """Each roster key's grade (:func:`_key`), none of a submission mapped to no one.  Two
    grades under one name (two folders that show alike, one of them named exactly by the roster
    and graded, the other an ``id-collision``): the one that is not a collision; when that does
    not single one out, none (the cell stays empty)."""
    found: dict[str, list[Grade]] = {}
    for g in grades:
        if g.status not in UNMAPPED:
            found.setdefault(g.student, []).append(g)
    out = {}
    for key, gs in found.items():
        if len(gs) > 1:
            gs = [g for g in gs if g.status != "id-collision"]
        if len(gs) == 1:
            out[key] = gs[0]
    return out


def canvas_rows(grades: dict, possible: dict[str, float], roster: Sequence[Student],
                title: str) -> list[list[str]]:
    rows = [["Student", "ID", "SIS User ID", "SIS Login ID", "Section", title],
            ["    Points Possible", "", "", "", "", _num(sum(possible.values()))]]
    for s in roster:
        rows.append([cell(s.full_name), cell(s.canvas_id), cell(s.sis_id), cell(s.login_id),
                     cell(s.section), _total(grades, s)])
    return rows


def moodle_rows(grades: dict, roster: Sequence[Student], title: str) -> list[list[str]]:
    rows = [["First name", "Last name", "ID number", "Email address", title]]
    for s in roster:
        first, last = s.split_name
        rows.append([cell(first), cell(last), cell(s.sis_id), cell(s.email), _total(grades, s)])
    return rows


def gradescope_rows(grades: dict, possible: dict[str, float], roster: Sequence[Student]
                    ) -> tuple[list[list[str]], list[list[str]]]:
    people = [["First Name", "Last Name", "Email", "SID", "Section"]]
    scores = [["First Name", "Last Name", "SID", "Email", "Total Score", "Max Points", "Status",
               *(f"{q} ({p:.1f} pts)" for q, p in possible.items())]]
    for s in roster:
        first, last = s.split_name
        people.append([cell(first), cell(last), cell(s.email), cell(s.sis_id or s.id),
                       cell(s.section)])
        g = grades.get(_key(s.id))
        done = g is not None and statuses.scored(g.status)
        scores.append([cell(first), cell(last), cell(s.sis_id or s.id), cell(s.email),
                       _total(grades, s), _num(sum(possible.values())),
                       g.status if g is not None else "missing",
                       *((_num(g.scores.get(q, 0.0)) if done and g is not None else "")
                         for q in possible)])
    return people, scores


def write_gradebooks(grades: Sequence[Grade], possible: dict[str, float],
                     roster: Sequence[Student], title: str, out: str | Path,
                     canvas_column: str | None = None) -> list[str]:
    """Write :data:`FILES` into ``out`` (module docstring; ``canvas.csv``'s grade column named
    ``canvas_column``, else ``title``); returns the students graded but not on the roster
    (written nowhere but ``grades.csv``)."""
    out = Path(out)
    by_id = _by_student(grades)
    ids = {_key(s.id) for s in roster}
    write_text(out / "canvas.csv", csv_text(canvas_rows(by_id, possible, roster,
                                                            canvas_column or title)))
    write_text(out / "moodle.csv", csv_text(moodle_rows(by_id, roster, title)))
    people, scores = gradescope_rows(by_id, possible, roster)
    write_text(out / "gradescope-roster.csv", csv_text(people))
    write_text(out / "gradescope-scores.csv", csv_text(scores))
    return sorted(g.student for g in grades if g.status not in UNMAPPED  # said by the run
                  and g.student not in ids)


# --------------------------------------------------------------------------------- similarity
def similar(out: Path, name: str, grades: Sequence[Grade], compare_with: Path | None = None
            ) -> list[str]:
    """The similarity and integrity report of the graded notebooks (``similarity.csv``,
    ``.html``, and its counts at the end of ``summary.csv``): the one place the class run asks
    for it; the lines to show.  Each notebook's record was made by its grading, from the
    grader's own parse (:attr:`Grade.similarity`): nothing is parsed again here, and a notebook
    without one is named "not compared", never a reason to lose the report.  ``compare_with``:
    a folder of earlier submissions every answer is compared with too."""
    from gpsaccel.assignments import similarity as sim
    from gpsaccel.classrun.entries import notebooks, walk

    earlier: list[tuple[str, Path | None]] = []
    if compare_with is not None:  # walked as a class is: no link followed, bounded depth
        entries, _ = walk(compare_with, notebooks(name))
        earlier = [(e.shown, e.path) for e in entries]
    rep = sim.class_report(grades, name, earlier)
    sim.write_report(rep, out)  # an OSError (a full disk): the caller's Outputs names the files
    _add_to_summary(out / "summary.csv", sim.summary_rows(rep))
    return sim.summary_lines(rep, out)


#: The line that starts the integrity block of ``summary.csv``.
_MARK = "integrity report,similarity.html,,,,,\r\n"


def _add_to_summary(path: Path, rows: list[list[str]]) -> None:
    """The integrity counts appended to the class's ``summary.csv`` (written before the report;
    rewritten whole, once, with them; an earlier report's block replaced, never repeated)."""
    if not path.is_file():
        return
    text = path.read_bytes().decode("utf-8")  # as written: csv's \r\n line ends kept
    kept = text.split("\r\n" + _MARK, 1)[0].rstrip("\r\n")
    write_text(path, f"{kept}\r\n\r\n{_MARK}{csv_text(rows)}")
