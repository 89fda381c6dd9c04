"""Every status a class's grade can give a student, who caused it, and what each gradebook
cell holds for it: the one table ``grades.csv``, the LMS gradebooks and the terminal read
(``docs/grading.md`` shows it; a test holds the two to each other and to the statuses the
grader's code gives).

A status the student caused (what they handed in, what their code did) is graded: the cell holds
the grader's total, the points of the questions graded before the notebook stopped, 0 when
nothing of theirs could be run.  A status the student did not cause (their grade was not
computed: two folders that cannot be told apart, the grader's or the machine's failure, a run
stopped before them, an export's name that maps to no one on the roster or to several) is never
a score: the cell is left empty in every export (the LMS keeps what it has), and the run names
those students on the terminal with what to do.  A status missing from the table is treated as
not the student's (empty, named): a new status is never silently a zero.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from gpsaccel import _untrusted


@dataclass(frozen=True)
class Status:
    """theirs : the student caused it (the cell is the total); cell : what the gradebook cell
    holds, in words; means : what happened; todo : for a status not theirs, what the instructor
    does."""

    theirs: bool
    cell: str
    means: str
    todo: str = ""


#: What a stopped notebook's cell holds.
_STOPPED = "the points graded before it stopped"
#: The cell of a submission nothing of which could be run.
_NOTHING = "0"
#: The cell of a status that is not a score.
EMPTY = "empty"
#: Regrade one student (the recorded seed).
_REGRADE = "grade them again with --student NAME"

#: status -> its :class:`Status` (module docstring); the order of ``docs/grading.md``'s table.
STATUSES: dict[str, Status] = {
    "graded": Status(True, "the total", "every question graded (a blank notebook is graded: 0)"),
    "timeout": Status(True, _STOPPED, "the notebook was still running at its time limit"),
    "memory-limit": Status(True, _STOPPED, "the notebook ran out of its memory"),
    "output-limit": Status(True, _STOPPED, "the notebook printed more than a box keeps"),
    "process-limit": Status(True, _STOPPED, "the notebook started too many processes"),
    "file-limit": Status(True, _STOPPED + " (0: nothing ran)",
                         "the notebook wrote too large a file, or the student's folder is deeper "
                         "or holds more entries than the checker's limits"),
    "crashed": Status(True, _STOPPED, "the notebook's process ended (os._exit, a signal)"),
    "result-refused": Status(True, _STOPPED, "the notebook wrote to the grader's channel"),
    "uses-checker": Status(True, _STOPPED, "the notebook imported the grader's own checks"),
    "unreadable": Status(True, _NOTHING, "not a notebook the grader can read (the feedback "
                                         "says why, in words)"),
    "no-notebook": Status(True, _NOTHING, "the student's folder holds no .ipynb file"),
    "ambiguous": Status(True, _NOTHING, "several notebooks, none named after the homework"),
    "id-collision": Status(False, EMPTY, "two entries whose names differ only in case or "
                                         "punctuation, or show one name under two numbers of "
                                         "the export (Moodle's participant numbers: the "
                                         "id-collision lines below name them): neither graded",
                           "rename one folder (or give the roster, as the student's id, the "
                           "exact name of one folder: that one is graded; for Moodle, its "
                           "grading worksheet: each is graded as its own participant) and "
                           "grade the class again"),
    "grader-error": Status(False, EMPTY, "the grader or the machine failed on this notebook "
                                         "(a process lost, a box on a machine too busy to give "
                                         "it its time)", _REGRADE),
    "machine-busy": Status(False, EMPTY, "the machine was too busy to give the box its time "
                                         "(recorded as grader-error)", _REGRADE),
    "not-graded": Status(False, EMPTY, "the run was stopped (Ctrl-C, SIGTERM) before this "
                                       "notebook", _REGRADE + ", or the class again"),
    "not-on-roster": Status(False, EMPTY, "the export's name maps to no student of the roster",
                            "add the student to the roster (or correct the export's name) and "
                            + _REGRADE),
    "ambiguous-student": Status(False, EMPTY, "the export's name maps to several students of "
                                              "the roster",
                                "make the roster's identifiers unique and " + _REGRADE),
    "unrecognised-name": Status(False, EMPTY, "the name is not written as its export (Canvas, "
                                              "Moodle, Gradescope) writes a submission's",
                                "give --export, or rename it as the export names it, and "
                                + _REGRADE),
}


def scored(status: str) -> bool:
    """Whether a grade of ``status`` is a score (its total goes in the gradebooks): a status the
    student caused; an unknown one is not."""
    known = STATUSES.get(status)
    return known is not None and known.theirs


def cell(status: str, total: float) -> str:
    """The gradebook cell of a grade: its total, or empty (module docstring)."""
    return f"{total:g}" if scored(status) else ""


def unscored_lines(grades: Iterable, width: int = 60) -> list[str]:
    """The terminal's lines on the students whose cells were left empty: which, why, and what to
    do, one status a line (none when every student was scored)."""
    by: dict[str, list[str]] = {}
    for g in grades:
        if not scored(g.status):
            by.setdefault(g.status, []).append(_untrusted.shown(g.student, width))
    if not by:
        return []
    lines = [f"left empty in grades.csv and every gradebook (not a score, not the student's "
             f"doing): {sum(map(len, by.values()))} student(s)"]
    for status, names in by.items():
        known = STATUSES.get(status)
        why = f"{known.means}; {known.todo}" if known else \
            "a status the gradebooks do not know; grade them again with --student NAME"
        lines.append(f"  {status} ({why}): {_listed(names)}")
    return lines


def scored_zero_lines(grades: Sequence) -> list[str]:
    """One line naming the students scored 0 because nothing of theirs could be run
    (``unreadable``, ``no-notebook``, ``ambiguous``), by the table (none when there are none)."""
    nothing = [g for g in grades if STATUSES.get(g.status, STATUSES["graded"]).cell == _NOTHING]
    if not nothing:
        return []
    return [f"scored 0, as docs/grading.md's table of statuses says (their feedback says why): "
            f"{_listed([f'{_untrusted.shown(g.student, 60)} ({g.status})' for g in nothing])}"]


def _listed(names: Sequence[str], most: int = 20) -> str:
    more = f", and {len(names) - most} more (grades.csv)" if len(names) > most else ""
    return ", ".join(names[:most]) + more
