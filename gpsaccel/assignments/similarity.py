"""The class similarity report: pairs of students whose answer code is suspiciously alike.

Per-student data and variants already make a copied *output* worthless; this looks at copied
*code*.  It flags, never grades: no score depends on it.

For each graded question, each student's answer is the code that question grades: the
``%%writefile`` body of a file question, else the top-level definitions of the names the question
reads (``kalman_filter``, ``Phi``, ``average_nees`` ...) and of the helpers they use.  The code is
normalised by Python itself (``ast.unparse``: comments, blank lines and layout gone) and compared
by copydetect (winnowing fingerprints of the token stream, identifiers and literals folded, as
MOSS does; maintained, on PyPI, pure Python): renaming variables or reformatting changes nothing.
Fingerprints that many students share (what any solution of a short question looks like: the
matrices of a model are the same for everybody) are discarded as boilerplate, so what is left
is what a *pair* shares.  A pair is flagged when each of the two has at least
:data:`THRESHOLD` of its remaining code in common with the other.

The notebooks are the students' (attackers') files: each is read with the grader's size limit
(:func:`gpsaccel.assignments.notebook.read`), each answer cut at :data:`MAX_CHARS`, and the
whole report is computed in a child process under CPU-time and memory limits
(:func:`report_in_child`), so a notebook built to choke the parser loses the report, never a
grade.
"""

from __future__ import annotations

import ast
import html
import io
import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

#: Shortest shared token run that counts (characters of the filtered token stream).
K = 20

#: A pair is flagged when both students share at least this fraction of their (non-common) code.
THRESHOLD = 0.7

#: A fingerprint held by more than this many students (or this fraction of the class) is common
#: code, not copying.
COMMON_STUDENTS = 3
COMMON_FRACTION = 0.25

#: Answers shorter than this (filtered characters, after removing common code) are not compared:
#: too little to tell copying from convergence.
MIN_CHARS = 60

#: Longest answer code read per student and question.
MAX_CHARS = 64_000


@dataclass(frozen=True)
class Pair:
    """Two students' answers to one question that share most of their code."""

    question: str
    a: str
    b: str
    similarity_a: float  # share of a's code found in b's
    similarity_b: float
    code_a: str = ""
    code_b: str = ""


def _defined(node: ast.stmt) -> set[str]:
    if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
        return {node.name}
    if isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
        targets = node.targets if isinstance(node, ast.Assign) else [node.target]
        return {n.id for t in targets for n in ast.walk(t) if isinstance(n, ast.Name)}
    return set()


_DEFS = ("FunctionDef", "AsyncFunctionDef", "ClassDef")


def _used(node: ast.AST) -> set[str]:
    return {n.id for n in ast.walk(node) if isinstance(n, ast.Name)}


def answer_code(sources: Sequence[str], names: set[str]) -> str:
    """The normalised code defining ``names`` (and the helpers it uses) in ``sources``, the
    notebook's code cells in order (a cell Python cannot parse is left out)."""
    from gpsaccel.assignments.notebook import transform

    stmts: list[ast.stmt] = []
    for src in sources:
        try:
            stmts += ast.parse(transform(src)).body
        except (SyntaxError, ValueError, RecursionError, MemoryError):
            continue
    funcs = {s.name for s in stmts
             if isinstance(s, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))}
    wanted, keep = set(names), []
    for _ in range(4):  # the names' definitions, then what they use, a few levels down
        keep = [s for s in stmts if _defined(s) & wanted]
        more: set[str] = set()
        for s in keep:  # a function's helpers; a value's inputs (dt of Phi)
            more |= _used(s) & funcs if s.__class__.__name__ in _DEFS else _used(s)
        if more <= wanted:
            break
        wanted |= more
    try:
        return "\n".join(ast.unparse(s) for s in keep)[:MAX_CHARS]
    except (RecursionError, ValueError):
        return ""


def normalise_file(text: str) -> str:
    """A file question's text, normalised as :func:`answer_code` does (unparsable: as written)."""
    try:
        return ast.unparse(ast.parse(text[:MAX_CHARS]))
    except (SyntaxError, ValueError, RecursionError, MemoryError):
        return text[:MAX_CHARS]


def answers(notebook: Path, questions: Sequence, draw) -> dict[str, str]:
    """Question -> the student's normalised answer code in ``notebook`` ("" if none)."""
    from gpsaccel.assignments import notebook as nbm

    try:
        nb = nbm.read(notebook)
    except nbm.NotebookError:
        return {}
    sources = [c.source[:MAX_CHARS] for c in nb.cells]
    out = {}
    for q in questions:
        if q.file:
            found = nb.writefile(q.file)
            out[q.name] = normalise_file(found[1]) if found else ""
        else:
            out[q.name] = answer_code(sources, {r.name for r in q.reads(draw)})
    return out


def _fingerprint(code: str):
    import copydetect

    return copydetect.CodeFingerprint("answer.py", K, 1, language="python",
                                      fp=io.StringIO(code))


def _drop(fp, common: set) -> None:
    """Remove the class's common fingerprints from ``fp`` (copydetect's own boilerplate filter
    assumes unique hashes; with every k-gram kept they repeat)."""
    from copydetect.utils import get_token_coverage

    fp.hashes = fp.hashes - common
    fp.hash_idx = {h: i for h, i in fp.hash_idx.items() if h not in common}
    fp.token_coverage = get_token_coverage(fp.hash_idx, fp.k, len(fp.filtered_code))


def compare(codes: dict[str, str], question: str = "") -> list[Pair]:
    """The flagged pairs among ``codes`` (student -> normalised code of one question)."""
    import copydetect

    codes = {s: c for s, c in codes.items() if c.strip()}
    prints = {s: _fingerprint(c) for s, c in codes.items()}
    df = Counter(h for fp in prints.values() for h in fp.hashes)
    limit = max(COMMON_STUDENTS, math.ceil(COMMON_FRACTION * len(codes)))
    common = {h for h, n in df.items() if n > limit}
    for fp in prints.values():
        _drop(fp, common)
    names = sorted(s for s, fp in prints.items() if fp.token_coverage >= MIN_CHARS)
    pairs = []
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            _, (sa, sb), _ = copydetect.compare_files(prints[a], prints[b])
            if min(sa, sb) >= THRESHOLD:
                pairs.append(Pair(question, a, b, float(sa), float(sb), codes[a], codes[b]))
    return sorted(pairs, key=lambda p: -min(p.similarity_a, p.similarity_b))


def report(submissions: Path, grades: Sequence, questions: Sequence, variant: dict
           ) -> list[Pair]:
    """Every question's flagged pairs for the graded notebooks of ``grades``
    (:class:`~gpsaccel.assignments.grading.Grade`: ``file`` relative to ``submissions``)."""
    from gpsaccel.assignments.questions import Draw

    draw = Draw(0, dict(variant))
    per_student = {g.student: answers(submissions / g.file, questions, draw)
                   for g in grades if g.file}
    out: list[Pair] = []
    for q in questions:
        out += compare({s: a.get(q.name, "") for s, a in per_student.items()}, q.name)
    return out


#: Limits of the child that computes the report: CPU seconds and address space.
CHILD_CPU_S = 600
CHILD_MEMORY = 4 << 30


def _child(conn, args) -> None:
    import resource

    resource.setrlimit(resource.RLIMIT_CPU, (CHILD_CPU_S, CHILD_CPU_S))
    resource.setrlimit(resource.RLIMIT_AS, (CHILD_MEMORY, CHILD_MEMORY))
    try:
        conn.send(("ok", report(*args)))
    except Exception as exc:  # the report is lost, never a grade
        conn.send(("error", f"{type(exc).__name__}: {exc}"[:300]))
    finally:
        conn.close()


def report_in_child(submissions: Path, grades: Sequence, questions: Sequence, variant: dict
                    ) -> tuple[list[Pair] | None, str]:
    """:func:`report` in a forked child under :data:`CHILD_CPU_S` and :data:`CHILD_MEMORY`:
    (pairs, "") or (None, why it failed)."""
    import multiprocessing as mp

    ctx = mp.get_context("fork")
    parent, child = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(child, (submissions, grades, questions, variant)))
    proc.start()
    child.close()
    try:
        if parent.poll(CHILD_CPU_S * 2):
            status, value = parent.recv()
        else:
            status, value = "error", "took too long"
    except EOFError:
        status, value = "error", "the report's process died"
    finally:
        proc.kill()
        proc.join()
    return (value, "") if status == "ok" else (None, str(value))


def write_report(pairs: Sequence[Pair], out: Path, title: str) -> None:
    """``similarity.csv`` (question, student a, student b, shares) and ``similarity.html``."""
    import csv

    from gpsaccel._atomic import write_text
    from gpsaccel._untrusted import cell as _cell

    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(["question", "student a", "student b", "share of a in b", "share of b in a"])
    for p in pairs:
        w.writerow([p.question, _cell(p.a), _cell(p.b), f"{p.similarity_a:.2f}",
                    f"{p.similarity_b:.2f}"])
    write_text(out / "similarity.csv", buf.getvalue())
    write_text(out / "similarity.html", _html(pairs, title))


def _html(pairs: Sequence[Pair], title: str) -> str:
    e = html.escape
    rows = "".join(
        f"<h2>{e(p.question)}: {e(p.a)} &amp; {e(p.b)} "
        f"({p.similarity_a:.0%} / {p.similarity_b:.0%})</h2>"
        f"<div class=pair><pre>{e(p.code_a)}</pre><pre>{e(p.code_b)}</pre></div>"
        for p in pairs) or "<p>No pair of students shares most of an answer's code.</p>"
    return (f"<!doctype html><meta charset=utf-8><title>{e(title)}: similar answers</title>"
            "<style>body{font-family:sans-serif;margin:2em}.pair{display:flex;gap:1em}"
            "pre{flex:1;background:#f4f4f4;padding:.5em;overflow:auto;font-size:12px}</style>"
            f"<h1>{e(title)}: answers with most of their code in common</h1>"
            "<p>A flag to look at, not a verdict: the code shown is normalised (comments and "
            "layout removed). Grades are not affected.</p>" + rows)
