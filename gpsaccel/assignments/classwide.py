"""What ``gpsaccel grade`` writes about the whole class after the grades: the LMS gradebook files
(:mod:`~gpsaccel.assignments.gradebook`) and the similarity report
(:mod:`~gpsaccel.assignments.similarity`).  Both read the grades the run kept
(``grades.json``: every student, a regrade of one included) and change none of them.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

from gpsaccel.assignments.roster import Student


def kept_grades(out: Path) -> list:
    """Every student's grade of the run in ``out`` (``grades.json``)."""
    from gpsaccel.assignments.grading import Grade

    data = json.loads((out / "grades.json").read_text(encoding="utf-8"))
    return [Grade(**d) for d in data]


def after_grading(submissions: Path, out: Path, name: str, roster: Sequence[Student] | None,
                  secret: bytes | None, similarity: bool = True) -> list[str]:
    """Write the gradebook files (with a roster) and the similarity report; the lines to show."""
    from gpsaccel import registry
    from gpsaccel.assignments.grading import questions_of, student_variant

    grades = kept_grades(out)
    qs = questions_of(name)
    possible = {q.name: float(q.points) for q in qs}
    lines = []
    if roster is not None:
        from gpsaccel.assignments.gradebook import FILES, write_exports

        title = registry.assignment(name).title or name
        missing = write_exports(grades, possible, roster, title, out)
        lines.append("gradebooks: " + ", ".join(str(out / f) for f in FILES))
        if missing:
            lines.append(f"not on the roster (in grades.csv only): {', '.join(missing)}")
    if similarity:
        from gpsaccel.assignments.similarity import report_in_child, write_report

        pairs, why = report_in_child(submissions, grades, qs, student_variant(name, "", None))
        if pairs is None:
            lines.append(f"similarity report not written: {why}")
        else:
            write_report(pairs, out, name)
            lines.append(f"similarity: {len(pairs)} pair(s) flagged for a look "
                         f"({out / 'similarity.html'}; grades unchanged)")
            for p in pairs:
                lines.append(f"  {p.question}: {_shown(p.a)} & {_shown(p.b)} "
                             f"({p.similarity_a:.0%} / {p.similarity_b:.0%} of their code)")
    return lines


def _shown(student: str) -> str:
    """A student id as printable text (it is a folder name a student chose)."""
    return "".join(c if c.isprintable() else "?" for c in student[:60])
