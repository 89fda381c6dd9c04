"""Every status a class's grade gives has one gradebook cell, stated in one table
(gpsaccel.classrun.statuses) that docs/grading.md shows: a status the student did not cause is
never a score (an empty cell in grades.csv and every gradebook, named on the terminal), a
status they caused is the grader's total.  The table is held to the statuses the grader's code
gives (found in the code, not listed by hand here) and to the docs."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import gpsaccel
from gpsaccel.assignments.roster import Student
from gpsaccel.assignments.scoring import Grade
from gpsaccel.classrun import statuses
from gpsaccel.classrun.classwide import write_gradebooks
from gpsaccel.classrun.writing import grades_table, write_grades
from gpsaccel.sandbox.outcomes import OUTCOMES

ROOT = Path(gpsaccel.__file__).parent
DOCS = ROOT.parent / "docs" / "grading.md"
_STATUS = re.compile(r"[a-z]+(-[a-z]+)*")


def _status(node: ast.AST) -> str | None:
    ok = isinstance(node, ast.Constant) and isinstance(node.value, str) and \
        _STATUS.fullmatch(node.value)
    return node.value if ok else None  # type: ignore[union-attr]  # a Constant when ok


def _given(node: ast.AST) -> set[str]:
    """The literal statuses an expression can be: itself, or either side of ``x or "graded"``
    and ``a if c else b``."""
    if isinstance(node, ast.BoolOp):
        return set().union(*map(_given, node.values))
    if isinstance(node, ast.IfExp):
        return _given(node.body) | _given(node.orelse)
    return {_status(node) or ""}


def _called(node: ast.Call) -> str:
    f = node.func
    return f.attr if isinstance(f, ast.Attribute) else f.id if isinstance(f, ast.Name) else ""


#: Where a status is given: the position of the status argument of these calls.
_GIVEN_AT = {"unusable": 3, "not_run": 3, "Grade": 4}


def statuses_in_code() -> set[str]:
    """Every status the grader's code gives a student: a problem ``("status", message)`` (the
    walk's and an export naming's ``problem=``, a notebook search's ``return None, (...)``),
    the status a grade is made with (``unusable``, ``not_run``, ``Grade``), a literal assigned
    to ``status`` (alone or in ``box.failure or "graded"``), and the sandbox's failures the
    grader stops a notebook on (:data:`OUTCOMES`' ``stop``)."""
    found = {code for code, o in OUTCOMES.items() if o.stop}
    files = [*(ROOT / "classrun").glob("*.py"), *(ROOT / "assignments").glob("*.py")]
    for path in files:
        if path.name == "statuses.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            problem = node.value.elts[1] if isinstance(node, ast.Return) and isinstance(
                node.value, ast.Tuple) and len(node.value.elts) == 2 else \
                node.value if isinstance(node, ast.keyword) and node.arg == "problem" else None
            if isinstance(problem, ast.Tuple) and len(problem.elts) == 2:
                found.add(_status(problem.elts[0]) or "")
            elif isinstance(node, ast.Call) and _called(node) in _GIVEN_AT:
                at = _GIVEN_AT[_called(node)]
                args = node.args[at:at + 1] + [k.value for k in node.keywords if k.arg == "status"]
                found |= {_status(a) or "" for a in args}
            elif isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "status"
                                                      for t in node.targets):
                found |= _given(node.value)
    return found - {""}


def docs_table() -> dict[str, tuple[str, str]]:
    """docs/grading.md's table of statuses: status -> (who caused it, the gradebook cell)."""
    text = DOCS.read_text(encoding="utf-8")
    part = text.split("<!-- statuses -->")[1].split("<!-- /statuses -->")[0]
    rows = re.findall(r"^\| `([a-z-]+)` \| ([^|]+) \| ([^|]+) \|", part, re.M)
    return {s: (who.strip(), cell.strip()) for s, who, cell in rows}


def test_the_table_holds_every_status_the_grader_gives():
    code = statuses_in_code()
    assert {"graded", "unreadable", "no-notebook", "ambiguous", "file-limit", "id-collision",
            "grader-error", "not-graded", "timeout", "machine-busy"} <= code  # the scan sees
    assert code <= set(statuses.STATUSES), code - set(statuses.STATUSES)


def test_the_docs_show_the_table():
    docs = docs_table()
    assert list(docs) == list(statuses.STATUSES)
    for name, s in statuses.STATUSES.items():
        assert docs[name] == ("the student" if s.theirs else "not the student", s.cell), name


def test_no_status_the_student_did_not_cause_is_a_score():
    for name in ("id-collision", "grader-error", "not-graded", "machine-busy", "not-on-roster",
                 "ambiguous-student", "a-status-nobody-knows"):
        assert not statuses.scored(name) and statuses.cell(name, 7.0) == "", name
    for name in ("graded", "timeout", "unreadable", "no-notebook", "crashed"):
        assert statuses.cell(name, 7.0) == "7" and statuses.cell(name, 0.0) == "0", name
    ours = {c for c, o in OUTCOMES.items() if o.ours}
    assert all(not statuses.scored(c) for c in ours)  # a lost or busy box is never a score


def test_every_export_leaves_an_unscored_status_empty_and_the_terminal_names_it(tmp_path):
    possible = {"q1": 4.0, "q2": 6.0}
    grades = [Grade("ann", "a.ipynb", {"q1": 4.0, "q2": 0.0}, possible, "timeout"),
              Grade("bob", "", {"q1": 0.0, "q2": 0.0}, possible, "id-collision", id="bob-1"),
              Grade("cy", "c.ipynb", {"q1": 0.0, "q2": 0.0}, possible, "grader-error"),
              Grade("di", "d.ipynb", {"q1": 0.0, "q2": 0.0}, possible, "unreadable")]
    roster = [Student(g.student, email=f"{g.student}@u.edu") for g in grades]
    write_gradebooks(grades, possible, roster, "HW", tmp_path)
    write_grades(grades, possible, tmp_path / "grades.csv")
    last = {f: [ln.split(",") for ln in (tmp_path / f).read_text().splitlines()]
            for f in ("canvas.csv", "moodle.csv", "grades.csv")}
    assert [r[-1] for r in last["canvas.csv"][2:]] == ["4", "", "", "0"]
    assert [r[-1] for r in last["moodle.csv"][1:]] == ["4", "", "", "0"]
    assert [r[3:6] for r in last["grades.csv"][2:]] == [
        ["4", "0", "4"], ["", "", ""], ["", "", ""], ["0", "0", "0"]]
    scores = (tmp_path / "gradescope-scores.csv").read_text().splitlines()[1:]
    assert [s.split(",")[4] for s in scores] == ["4", "", "", "0"]
    assert scores[1].split(",")[6:] == ["id-collision", "", ""]
    lines = statuses.unscored_lines(grades)
    assert lines[0].endswith("2 student(s)") and len(lines) == 3
    assert lines[1].startswith("  id-collision (") and lines[1].endswith("): bob")
    assert "rename one folder" in lines[1] and "grade the class again" in lines[1]
    assert lines[2].startswith("  grader-error (") and lines[2].endswith("): cy")
    assert "--student NAME" in lines[2]
    assert statuses.scored_zero_lines(grades)[0].endswith("di (unreadable)")
    assert [ln.split()[1:3] for ln in grades_table(grades).splitlines()] == [
        ["4", "/"], ["-", "/"], ["-", "/"], ["0", "/"]]
