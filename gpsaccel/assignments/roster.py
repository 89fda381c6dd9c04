"""The class roster: who the students are, and how each LMS names them.

One file serves the hand-out (one notebook per student) and the gradebook exports
(:mod:`gpsaccel.classrun.classwide`).  Two forms:

* plain text, one student id a line (the id is how the LMS names the student's folder or
  notebook in its export): enough to hand out and for ``grades.csv``;
* a CSV file with a header holding an ``id`` column (the same id) and any of ``name`` (or
  ``first_name`` and ``last_name``), ``email``, ``sis_id``, ``login_id``, ``canvas_id``,
  ``section``: what Canvas, Moodle and Gradescope match a grade row by.

A file whose first line has a comma and names an ``id`` column is read as CSV; anything else as
plain text (an id may hold commas and spaces, as LMS folder names do: "Doe, Jane (1001)").
"""

from __future__ import annotations

import csv
import io
import os
from dataclasses import dataclass
from pathlib import Path

#: Columns a CSV roster may have besides ``id`` (anything else is refused: a misspelt column
#: would silently leave a gradebook column empty).
FIELDS = ("name", "first_name", "last_name", "email", "sis_id", "login_id", "canvas_id",
          "section")

#: Largest roster read (bytes): a class list, not a data file.
MAX_BYTES = 4 << 20


@dataclass(frozen=True)
class Student:
    """One student: the id of the submissions and the LMS's own identifiers ("" if unknown)."""

    id: str
    name: str = ""
    first_name: str = ""
    last_name: str = ""
    email: str = ""
    sis_id: str = ""
    login_id: str = ""
    canvas_id: str = ""
    section: str = ""

    @property
    def full_name(self) -> str:
        return self.name or " ".join(p for p in (self.first_name, self.last_name) if p) or self.id

    @property
    def split_name(self) -> tuple[str, str]:
        """(first, last): the roster's, else the full name split at its last space."""
        if self.first_name or self.last_name:
            return self.first_name, self.last_name
        first, _, last = self.full_name.rpartition(" ")
        return (first, last) if first else (last, "")


def _is_csv(first_line: str) -> bool:
    if "," not in first_line:
        return False
    header = next(csv.reader([first_line]))
    return "id" in (h.strip().lower() for h in header)


def read_roster(path: str | os.PathLike) -> list[Student]:
    """The students of the roster file at ``path`` (module docstring); ValueError naming the
    line and what was expected on a malformed file, a repeated id or an empty roster."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"roster: {path} is not a file (one student id a line, or a CSV file "
                         f"with an id column)")
    if path.stat().st_size > MAX_BYTES:
        raise ValueError(f"roster: {path} is larger than {MAX_BYTES >> 20} MB")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ValueError(f"roster: {path} is not UTF-8 text ({exc})") from None
    lines = text.splitlines()
    first = next((ln for ln in lines if ln.strip()), "")
    students = _read_csv(path, text) if _is_csv(first) else \
        [Student(ln.strip()) for ln in lines if ln.strip() and not ln.lstrip().startswith("#")]
    if not students:
        raise ValueError(f"roster: {path} lists no student")
    seen: set[str] = set()
    for s in students:
        if s.id in seen:
            raise ValueError(f"roster: {path} lists the student id {s.id!r} twice")
        seen.add(s.id)
    return students


def _read_csv(path: Path, text: str) -> list[Student]:
    reader = csv.DictReader(io.StringIO(text))
    header = [h.strip().lower() for h in reader.fieldnames or []]
    unknown = [h for h in header if h and h != "id" and h not in FIELDS]
    if unknown:
        raise ValueError(f"roster: {path} has unknown column(s) {', '.join(unknown)}; expected "
                         f"id and any of {', '.join(FIELDS)}")
    out = []
    for n, row in enumerate(reader, start=2):
        values = {k.strip().lower(): (v or "").strip() for k, v in row.items() if k}
        if not values.get("id"):
            if any(values.values()):
                raise ValueError(f"roster: {path} line {n} has no id")
            continue
        out.append(Student(**{k: v for k, v in values.items() if k == "id" or k in FIELDS}))
    return out
