r"""What every student can read: the hand-out, and the solutions the package publishes.

The wheel carries every packaged homework's master (``gpsaccel/assignments/masters/NAME/``,
every solution in it), the example of a homework of one's own (``gpsaccel/homework/example/``)
and the lessons' solutions (``gpsaccel/_lessons/solutions/``); so does the public repository.
The similarity report (:mod:`gpsaccel.assignments.similarity`) therefore compares each answer
with them, as copydetect's *reference* files, and leaves out the hand-out's code, as
copydetect's *boilerplate*:

* :func:`boilerplate` — per question, the fingerprints of the hand-out: the master with its
  solutions and tests taken out (otter's rules: the lines between ``# BEGIN SOLUTION`` and
  ``# END SOLUTION``, and every line marked ``# SOLUTION``), read as a student's answer to that
  question and as a whole.  A ``def kalman_filter(z):`` every student was given is nobody's copy;
* :func:`references` — every published solution: per question, the master's own answer (an
  answer inside it, or it inside an answer, is a match), and as whole documents every packaged
  master and every lesson solution (an answer inside one is a match).  An instructor's own
  homework folder adds its own master's answers ("your master's solution").

These files are the package's own, read as trusted text (IPython's transformer for their
magics, Python's parser); nothing here reads a student's file.
"""

from __future__ import annotations

import ast
import json
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from gpsaccel.assignments import answercode, fingerprint

_SOLUTION_BLOCK = ("# BEGIN SOLUTION", "# END SOLUTION")
_ASSIGNED = re.compile(r"^(\s*[A-Za-z_][\w.\[\], ]*?)\s*=(?!=)")


@dataclass(frozen=True)
class Reference:
    """A published text an answer is compared with: ``question`` set for a master's answer to
    that question (compared both ways), None for a whole document (an answer inside it)."""

    label: str
    prints: frozenset[int]
    question: str | None = None


def _cells(path: Path) -> list[tuple[str, str]]:
    """(kind, source) of a notebook's cells, otter's test cells left out."""
    data = json.loads(path.read_text(encoding="utf-8"))
    out, in_tests = [], False
    for c in data.get("cells", []):
        src = c.get("source", "")
        src = "".join(src) if isinstance(src, list) else src
        first = src.strip().splitlines()[0].strip() if src.strip() else ""
        if c.get("cell_type") == "raw":
            in_tests = {"# BEGIN TESTS": True, "# END TESTS": False}.get(first, in_tests)
        elif not in_tests and c.get("cell_type") == "code":
            out.append(("code", src))
    return out


def handout_source(source: str) -> str:
    """A master's code cell as otter hands it out: a solution block becomes ``...``, a line
    ``NAME = value  # SOLUTION`` becomes ``NAME = ...``, any other ``# SOLUTION`` line goes."""
    lines, inside = [], False
    for line in source.splitlines():
        mark = line.strip()
        indent = line[:len(line) - len(line.lstrip())]
        if mark in _SOLUTION_BLOCK:
            inside = mark == _SOLUTION_BLOCK[0]
            if inside:
                lines.append(indent + "...")
            continue
        if inside:
            continue
        if line.rstrip().endswith("# SOLUTION"):
            target = _ASSIGNED.match(line)
            if target:
                lines.append(f"{target.group(1)} = ...")
            continue
        lines.append(line)
    return "\n".join(lines)


def _python(source: str) -> str:
    from gpsaccel.assignments.notebook import transform

    try:
        return transform(source)
    except Exception:  # noqa: BLE001 - a cell IPython cannot transform stays as written
        return source


def _record(sources: Sequence[str], asked: Mapping[str, answercode.Asked]) -> dict:
    return answercode.record([(i, _python(s)) for i, s in enumerate(sources, 1)],
                             answercode.written_files(sources), asked)


def _document(sources: Sequence[str], k: int) -> frozenset[int]:
    """The fingerprints of a whole notebook's code (its written files included)."""
    stmts: list[ast.stmt] = []
    texts = [_python(s) for s in sources] + list(answercode.written_files(sources).values())
    for text in texts:
        try:
            stmts += ast.parse(text).body
        except (SyntaxError, ValueError):
            continue
    return fingerprint.kgrams(fingerprint.answer_tokens(stmts), k)


def _prints(rec: dict, q: str, k: int) -> frozenset[int]:
    entry = rec.get("questions", {}).get(q)
    return fingerprint.kgrams(answercode.unpack(entry["tokens"]), k) if entry else frozenset()


def boilerplate(master: Path, asked: Mapping[str, answercode.Asked], k: int = fingerprint.K
                ) -> dict[str, frozenset[int]]:
    """Question -> fingerprints of the hand-out (module docstring), ``k`` tokens each."""
    sources = [handout_source(s) for _, s in _cells(master)]
    whole = _document(sources, k)
    rec = _record(sources, asked)
    return {q: whole | _prints(rec, q, k) for q in asked}


def _label(path: Path) -> str:
    if path.parent.name == "solutions":
        return f"lesson {path.stem} (solution, published)"
    if path.parent.parent.name == "example":
        return f"the example homework {path.stem} (master with solutions, published)"
    return f"homework {path.stem} (master with solutions, published)"


@lru_cache(maxsize=4)
def package_documents(k: int) -> tuple[Reference, ...]:
    """Every packaged master and lesson solution as a whole document (computed once per process
    and ``k``; public so that benchmarks/similarity.py can time a report cold with
    ``package_documents.cache_clear()``)."""
    from gpsaccel.assignments.homework import packaged_masters

    package = Path(__file__).resolve().parents[1]
    paths = sorted(packaged_masters().glob("*/*.ipynb"))
    paths += sorted((package / "homework" / "example").glob("*/*.ipynb"))  # read, not imported
    paths += sorted((package / "_lessons" / "solutions").glob("*.ipynb"))
    return tuple(Reference(_label(p), _document([s for _, s in _cells(p)], k)) for p in paths)


def references(name: str, master: Path, asked: Mapping[str, answercode.Asked],
               k: int = fingerprint.K) -> list[Reference]:
    """The published solutions an answer to homework ``name`` is compared with (module
    docstring); ``master`` is the homework's own master (packaged or the instructor's)."""
    from gpsaccel.assignments.homework import packaged_masters

    packaged = master.resolve().is_relative_to(packaged_masters().resolve())
    rec = _record([s for _, s in _cells(master)], asked)
    own = (f"the published solution of {name} {{q}}" if packaged
           else f"your master's solution of {{q}} ({master.parent.name}, not published)")
    mine = [Reference(own.format(q=q), _prints(rec, q, k), q) for q in asked]
    # published first: an answer that matches both is named as the published solution's
    docs = list(package_documents(k))
    return mine + docs if packaged else docs + mine
