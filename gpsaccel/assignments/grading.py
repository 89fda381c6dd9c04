r"""Grade a class: every notebook only inside the checker's sandbox, every score computed outside.

The model (issue 19).  A student's notebook is data.  :mod:`gpsaccel.assignments.notebook` turns
its code cells into one module; :func:`gpsaccel.sandbox.run` imports that module in a box
(bubblewrap namespaces where they work) and calls, one frame each, the cells in order and then
the *reads* every question declares (:mod:`gpsaccel.assignments.questions`): the student's
functions called on data drawn from this run's seed, the variables it must define.  What comes
back is arrays of the declared shapes and a status, nothing else.  Only once the box is empty
does the grader draw the reference answers and score each question.  The hidden checks, the
reference answers, the masters' solutions, the run's seed and the instructor's secret are never
in the box (the box may import gpsaccel's models, simulations and filters, not
``gpsaccel.check`` or ``gpsaccel.assignments``; see ``docs/grading.md``).

A question graded from a file the notebook writes (calibration q2, ``%%writefile
kalman_filter.py``) is graded from the cell's text, in a box of its own without gpsaccel, by
:func:`gpsaccel.check.submission`.

The class (:func:`grade`):

* submissions as an LMS exports them (:mod:`gpsaccel.assignments.submissions`): a folder per
  student or one notebook per student at the top; every name (any bytes, NFC or NFD, any
  punctuation or length) gets once a unique printable id that names the student's files; every
  entry is either graded or reported with why not (``no-notebook``, ``ambiguous``,
  ``unreadable``, ``file-limit``, ``id-collision``), never skipped silently;
* each notebook is graded in a forked process of its own (a student who kills it loses only
  their own grade: ``grader-error``), forked from a parent that has imported what grading a
  notebook needs (:func:`warm`); the run is a child subreaper and sweeps what a dead
  process left; ``grades.csv`` is rewritten (atomically) after every notebook with a row for
  every student, so a run killed half-way leaves the grades it had; one interrupted (Ctrl-C)
  leaves ``not-graded`` rows for the rest, records ``interrupted`` and raises
  KeyboardInterrupt (the command exits 130);
* output (default: ``<submissions>-grades`` next to the submissions folder, never inside it):
  ``grades.csv`` (student name as shown, id, file, one column per question, total, possible,
  status, seconds, and a first row of the points possible), ``feedback/<id>.txt`` (stale files
  of an earlier run removed; student text in it cleaned of control and bidi characters),
  ``summary.csv`` and ``summary.png`` (per question: mean score, how many students got each
  mistake code), and ``grading.json`` — the instructor's record: the seed, the sandbox,
  which questions, when.  It holds no answer; keep it from students all the same (with the
  secret it reproduces their data);
* ``student=ID`` regrades one student with the recorded seed: the old row stays until the new
  one is written, and the regrade is appended to ``grading.json``'s ``regrades`` (the class
  record is kept);
* ``dask=...`` sends each notebook to a Dask cluster (same function, same seed: same grades)
  through the same pool and with the same deadline (:func:`gpsaccel.sandbox.run_items`).
"""

from __future__ import annotations

import ast
import csv
import io
import json
import math
import os
import secrets
import tempfile
import time
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from gpsaccel import _untrusted
from gpsaccel._atomic import write_text
from gpsaccel.assignments import notebook as nbm
from gpsaccel.assignments.questions import (
    Answer,
    Draw,
    Question,
    answer_from,
    question_seed,
    variant_number,
)
from gpsaccel.assignments.submissions import Entry, find_submissions
from gpsaccel.check.report import Report

#: Wall-clock limit (s) of one notebook's box (every cell and every read), default.
TIMEOUT = 120.0

#: Seconds a notebook's process may take beyond its boxes' limits (reference answers, feedback)
#: before it is killed as a grader error.
SLACK = 120.0

#: Memory (address space) of a notebook's box: numpy, scipy and matplotlib need about 1 GB.
BOX_MEMORY = 2 << 30

#: Processes a notebook's box may hold at once.
BOX_PROCESSES = 32

#: The first line of a master's cell that only makes data to look at: not run when graded.
SKIP_MARK = "# not run when graded"

#: The first line of the master's variant cell; grading replaces the cell with the student's.
VARIANT_MARK = "# your variant"

#: Environment variable holding the instructor's secret (or use ``secret_file``).
SECRET_ENV = "GPSACCEL_GRADING_SECRET"

_CELL_STATUS = nbm.MAX_NDIM + 3


def assignment_module(name: str):
    """The homework's graded questions: ``graded.py`` beside its master (the packaged
    ``gpsaccel/assignments/masters/NAME/``, or the instructor's own folder; ValueError for an
    unknown name)."""
    import importlib.util
    import sys

    from gpsaccel import registry
    from gpsaccel.assignments.generate import homework_dir

    registry.assignment(name)  # ValueError naming the homework registered
    key = f"gpsaccel_graded_{name}"
    if key in sys.modules:
        return sys.modules[key]
    path = homework_dir(name) / "graded.py"
    if not path.is_file():
        raise FileNotFoundError(f"{path} not found (the graded questions of {name!r})")
    spec = importlib.util.spec_from_file_location(key, path)
    assert spec is not None and spec.loader is not None  # a .py file always has both
    module = importlib.util.module_from_spec(spec)
    sys.modules[key] = module
    spec.loader.exec_module(module)
    return module


def questions_of(name: str) -> tuple[Question, ...]:
    return tuple(assignment_module(name).graded_questions())


def student_variant(name: str, student: str, secret: bytes | None) -> dict:
    """The student's numbers: from the secret when there is one, else the public notebook's."""
    mod = assignment_module(name)
    if not secret:
        return dict(mod.DEFAULT_VARIANT)
    return mod.variant(variant_number(secret, name, student))


# ------------------------------------------------------------------------------ one notebook
@dataclass
class Grade:
    """One student's grade (plain data: it crosses process and Dask boundaries).

    student : the name (LMS folder name or notebook stem) as shown (printable); id : its unique
    file-safe id (:func:`gpsaccel._untrusted.student_id`); file : the notebook graded (relative
    to the submissions folder, as found), or "" ; scores, possible : question -> points;
    status : graded, a sandbox failure (timeout, memory-limit, crashed, ...), no-notebook,
    ambiguous, unreadable, file-limit, id-collision or grader-error; codes : question ->
    mistake codes; feedback : the text for the student.
    """

    student: str
    file: str
    scores: dict[str, float]
    possible: dict[str, float]
    status: str
    feedback: str = ""
    codes: dict[str, list[str]] = field(default_factory=dict)
    seconds: float = 0.0
    id: str = ""

    @property
    def total(self) -> float:
        return sum(self.scores.values())

    @property
    def max_total(self) -> float:
        return sum(self.possible.values())


def _possible(qs: Sequence[Question]) -> dict[str, float]:
    return {q.name: float(q.points) for q in qs}


def unusable(name: str, student: str, file: str, status: str, message: str, sid: str = ""
             ) -> Grade:
    """The grade of a submission that could not be run (no notebook, several, not a notebook)."""
    possible = _possible(questions_of(name))
    g = Grade(_untrusted.shown(student), file, {q: 0.0 for q in possible}, possible, status,
              id=sid or _untrusted.student_id(student))
    g.feedback = _feedback_text(g, [message], {}, {})
    return g


#: The longest cell read as a candidate otter cell (its init, ``grader.check``: one line each).
_OTTER_CELL_CHARS = 2000


def _otter_call(node: ast.stmt) -> bool:
    """``import otter``, ``grader = otter.Notebook(...)`` or ``grader.<method>(...)`` with
    constant arguments (check, check_all, export, ...)."""
    if isinstance(node, ast.Import):
        return all(a.name == "otter" and a.asname is None for a in node.names)
    value = node.value if isinstance(node, (ast.Assign, ast.Expr)) else None
    if isinstance(node, ast.Assign) and not (
            len(node.targets) == 1 and isinstance(node.targets[0], ast.Name)
            and node.targets[0].id == "grader"):
        return False
    if not isinstance(value, ast.Call) or not isinstance(value.func, ast.Attribute):
        return False
    owner = value.func.value
    args = [*value.args, *(k.value for k in value.keywords)]
    return (isinstance(owner, ast.Name) and owner.id == ("otter" if isinstance(node, ast.Assign)
                                                         else "grader")
            and all(isinstance(a, ast.Constant) for a in args))


def is_otter_cell(source: str) -> bool:
    """True for a cell of otter's own (its init cell, a ``grader.check("q1")`` cell): every
    statement is one of :func:`_otter_call`'s.  The grader checks the answers itself, so these
    cells are not run (they would only fail: no otter, no ``grader``, no tests in the box)."""
    if len(source) > _OTTER_CELL_CHARS or "otter" not in source and "grader" not in source:
        return False
    try:
        tree = ast.parse(source)
    except (SyntaxError, ValueError, RecursionError, MemoryError):
        return False
    return bool(tree.body) and all(_otter_call(node) for node in tree.body)


def _prepare(nb: nbm.Notebook, variant: dict) -> nbm.Notebook:
    """The cells to run: the variant cell replaced by the student's, data-only cells and otter's
    own cells (:func:`is_otter_cell`) left out."""
    cells = [nbm.Cell(0, f"VARIANT = {variant!r}")]
    for cell in nb.cells:
        first = cell.source.lstrip().split("\n", 1)[0].strip().lower()
        if first.startswith(SKIP_MARK) or is_otter_cell(cell.source):
            continue
        if first.startswith(VARIANT_MARK):
            cells.append(nbm.Cell(cell.number, f"VARIANT = {variant!r}"))
            continue
        cells.append(cell)
    return nbm.Notebook(cells, nb.notes)


def _calls(n_cells: int, reads: list[nbm.Read]):
    from gpsaccel.sandbox import Call, Output

    head = (Output("status", (_CELL_STATUS,), "int64"),
            Output("message", (nbm.MESSAGE_BYTES,), "uint8"))
    calls = [Call("_gpsaccel_cell", (np.array(i),), head) for i in range(n_cells)]
    for k, r in enumerate(reads):
        outs = tuple(Output(f"out{j}", tuple(s)) for j, s in enumerate(r.shapes))
        calls.append(Call(f"_gpsaccel_probe_{k}", tuple(np.asarray(a, dtype=float)
                                                        for a in r.args), head + outs))
    return calls


_STOPS = {
    "timeout": "it was still running at the time limit of {limit:g} s",
    "memory-limit": "it ran out of memory (the limit is {memory} GB)",
    "process-limit": "it started too many processes",
    "output-limit": "it printed too much",
    "file-limit": "it wrote too large a file",
    "crashed": "its process ended (a crash, os._exit or a signal)",
    "result-refused": "the grader's channel received something that is not an answer",
    "uses-checker": "it tried to use the grader's own checks",
}


def _stop_message(failure: str, where: str, limits) -> str:
    why = _STOPS.get(failure, failure).format(limit=limits.time, memory=limits.memory >> 30)
    return f"The notebook stopped {where}: {why}. Nothing after that was graded."


def _cell_notes(cells: Sequence, results: Sequence) -> list[str]:
    """The notes on the student's own cells: which raised, which lines were not run."""
    notes: list[str] = []
    skipped: list[str] = []
    for cell, res in zip(cells, results, strict=True):
        if res is None:
            break
        msg = answer_from(res, 0)
        if msg.status == "exception" and cell.number:
            notes.append(f"Cell {cell.number} raised {msg.message.split(': ', 1)[-1]}")
        elif msg.message and msg.status == "ok":
            skipped += [m for m in msg.message.split() if m not in skipped]
    if skipped:
        notes.append("Not run when graded (IPython magics and shell lines other than %%time, "
                     "%%capture, %%writefile): " + ", ".join(skipped[:10]))
    return notes


def _where_stopped(k: int, cells: Sequence, reads: Sequence[nbm.Read],
                   spans: dict[str, tuple[int, int]]) -> str:
    """Where a box that returned ``k`` results stopped: a cell, a read of a question, or after."""
    if k < len(cells):
        number = cells[k].number
        return f"in cell {number}" if number else "before the first cell"
    if k - len(cells) < len(reads):
        failed = reads[k - len(cells)]
        asked = next(q for q, (a, b) in spans.items() if a <= k - len(cells) < b)
        return f"while {'reading' if failed.value else 'calling'} {failed.name} ({asked})"
    return "after its last answer"


def _question_report(q: Question, nb: nbm.Notebook, draw: Draw, answers: list[Answer],
                     timeout: float) -> Report:
    """One question's report: graded from a file, not run (the notebook stopped before it),
    or graded from its answers."""
    if q.file is not None:
        return _grade_file(q, nb, draw, timeout)
    if any(x.status == "not-run" for x in answers):
        rep = Report(q.name)
        rep.add("not-run", text="Not graded: the notebook stopped before this question "
                "(see above).")
        return rep
    return _safe_grade(q, draw, answers)


def grade_notebook(path: str | os.PathLike, name: str, student: str, seed: int,
                   secret: bytes | None = None, sandbox: str = "auto",
                   timeout: float = TIMEOUT, file: str = "", sid: str = "") -> Grade:
    """Grade one notebook (see the module docstring); never raises for what it holds.

    student : the name as found (its bytes key the variant and the data); sid : its id."""
    from gpsaccel import sandbox as sb

    t0 = time.perf_counter()
    qs = questions_of(name)
    possible = _possible(qs)
    try:
        nb = nbm.load(path)  # parsed and transformed under limits, in a process of its own
    except nbm.NotebookError as exc:
        return unusable(name, student, file, "unreadable", str(exc), sid)
    variant = student_variant(name, student, secret)
    draws = {q.name: Draw(question_seed(seed, name, q.name, student), variant) for q in qs}
    run = _prepare(nb, variant)
    reads: list[nbm.Read] = []
    spans: dict[str, tuple[int, int]] = {}
    for q in qs:
        r = list(q.reads(draws[q.name]))
        spans[q.name] = (len(reads), len(reads) + len(r))
        reads += r
    limits = sb.Limits(memory=BOX_MEMORY, time=float(timeout), processes=BOX_PROCESSES)
    notes: list[str] = []
    with tempfile.TemporaryDirectory(prefix="gpsaccel-nb-") as tmp:
        folder = Path(tmp) / "submission"
        folder.mkdir()
        (folder / "notebook.py").write_text(nbm.module_source(run, reads), encoding="utf-8")
        sub = sb.load_submission(folder / "notebook.py", "_gpsaccel_cell")
        calls = _calls(len(run.cells), reads)
        box = sb.run(sub, calls, limits, backend=sandbox, allow_gpsaccel=True)
    # ---- the box is empty from here on: nothing of the student's runs while answers exist
    results = box.results + [None] * (len(calls) - len(box.results))
    notes += _cell_notes(run.cells, results[:len(run.cells)])
    answers = [answer_from(res, len(r.shapes)) for r, res in
               zip(reads, results[len(run.cells):], strict=True)]
    status = "graded"
    if box.failure is not None:
        status = box.failure
        where = _where_stopped(len(box.results), run.cells, reads, spans)
        notes.append(_stop_message(box.failure, where, limits))
    reports = {q.name: _question_report(q, nb, draws[q.name], answers[slice(*spans[q.name])],
                                        timeout) for q in qs}
    scores = {q.name: q.score(reports[q.name]) for q in qs}
    codes = {k: r.codes for k, r in reports.items()}
    g = Grade(_untrusted.shown(student), file, scores, possible, status, "", codes,
              time.perf_counter() - t0, sid or _untrusted.student_id(student))
    g.feedback = _feedback_text(g, notes, reports, variant)
    return g


def _safe_grade(q: Question, draw: Draw, answers: list[Answer]) -> Report:
    assert q.grade is not None  # a question read from the box has its grade
    try:
        return q.grade(draw, answers)
    except Exception as exc:  # noqa: BLE001 - a bug of the grader: this question only
        rep = Report(q.name)
        rep.add("grader-error", f"{type(exc).__name__}: {exc}", text="The grader failed on "
                "this question ({type}); tell your instructor.",
                observed={"type": type(exc).__name__})
        return rep


def _grade_file(q: Question, nb: nbm.Notebook, draw: Draw, timeout: float) -> Report:
    assert q.file is not None and q.grade_file is not None  # a file question has both
    found = nb.writefile(q.file)
    if found is None:
        rep = Report(q.name)
        rep.add("no-file", text="The notebook has no cell `%%writefile {file}`: the question "
                "asks for the function in that file (keep the cell's first line as it is).",
                observed={"file": q.file})
        return rep
    with tempfile.TemporaryDirectory(prefix="gpsaccel-file-") as tmp:
        path = Path(tmp) / q.file
        path.write_text(found[1], encoding="utf-8", errors="replace")  # a lone surrogate too
        try:
            return q.grade_file(path, draw, timeout)
        except Exception as exc:  # noqa: BLE001 - a bug of the grader: this question only
            rep = Report(q.name)
            rep.add("grader-error", f"{type(exc).__name__}: {exc}", text="The grader failed on "
                    "this question ({type}); tell your instructor.",
                    observed={"type": type(exc).__name__})
            return rep


# --------------------------------------------------------------------------------- feedback
def _feedback_text(g: Grade, notes: list[str], reports: dict[str, Report],
                   variant: dict) -> str:
    """The student's feedback: the notes about their notebook (its own cells' errors, where it
    stopped) and, per question, the student's projection of each finding
    (:meth:`gpsaccel.check.report.Finding.for_student`: no expected value reaches this text)."""
    lines = [f"{g.student}: {g.total:g} / {g.max_total:g} points ({g.status})"]
    if variant:
        lines.append("Your variant: " + ", ".join(f"{k} = {v}" for k, v in variant.items()))
    lines.append("")
    for n in dict.fromkeys(notes):
        lines.append(n)
    if notes:
        lines.append("")
    for q, points in g.possible.items():
        lines.append(f"{q}: {g.scores.get(q, 0):g} / {points:g}")
        rep = reports.get(q)
        seen = set()
        for f in rep.for_student().findings if rep else []:
            if f.severity == "note" and f.code not in ("uses-own-jacobian",):
                continue
            text = f"{f.code}: {f.message.splitlines()[0]}"
            if text in seen:
                continue  # each failure once
            seen.add(text)
            lines.append("    - " + text)
        lines.append("")
    return "\n".join(lines)


# ------------------------------------------------------------------------- running a class
def _file(entry: Entry, folder: Path) -> str:
    """The notebook's path relative to the submissions (as found: the similarity report opens
    it again; ``grades.csv`` shows it printable)."""
    return os.path.relpath(entry.path, folder) if entry.path else ""


def _task(entry: Entry, folder: Path, settings: dict) -> dict:
    if entry.path is None:
        assert entry.problem is not None  # an entry without a notebook says why
        g = unusable(settings["name"], entry.student, "", *entry.problem, sid=entry.id)
    else:
        g = grade_notebook(entry.path, settings["name"], entry.student, settings["seed"],
                           settings["secret"], settings["sandbox"], settings["timeout"],
                           _file(entry, folder), entry.id)
    return asdict(g)


def _grader_error(entry: Entry, folder: Path, settings: dict, why: str) -> dict:
    return asdict(unusable(settings["name"], entry.student, _file(entry, folder),
                           "grader-error", f"The grader could not finish this notebook "
                           f"({why}); it was not graded. Tell your instructor.", entry.id))


def warm(name: str) -> None:
    """Import here what grading a notebook of homework ``name`` imports on first use (IPython's
    input transformer, the registered problems a question checks a file against), so each
    notebook's forked process inherits it instead of importing it again: about 0.4 CPU s a
    notebook (``python benchmarks/grading.py --profile``).  Nothing of a student's runs here."""
    questions_of(name)
    nbm.transform("%time x = 1\n!true")
    from gpsaccel import registry
    from gpsaccel.check.batch import warm as warm_check

    registry.problems()
    # what the questions' references import on first use, since `import gpsaccel` imports
    # nothing: scipy.stats and filterpy (the check's warm-up), scipy.integrate (CoopModel's truth)
    warm_check(registry.assignment(name).problem or "calibration")
    import scipy.integrate  # noqa: F401


def _graded_item(item: tuple[Entry, Path, dict]) -> dict:
    return _task(*item)


#: What a notebook without a grade was, by :attr:`gpsaccel.sandbox.Lost.reason`.
_LOST = {"too-long": "it took too long", "died": "its process died, {detail}",
         "not-a-report": "its process returned no grade"}


def _pooled(entries: list[Entry], folder: Path, settings: dict, jobs: int,
            done: Callable[[int, dict], None], executor: object = None) -> None:
    """Every notebook through the sandbox's one pool (:func:`gpsaccel.sandbox.run_items`): a
    forked process each, or a Dask worker each, within the same deadline; results as they
    come."""
    from gpsaccel import sandbox as sb

    limit = settings["timeout"] * 2 + 60 + SLACK  # the notebook's box, the file's box, the rest

    def finished(i: int, out: object) -> None:
        if not isinstance(out, dict):
            lost = out if isinstance(out, sb.Lost) else sb.Lost("not-a-report")
            why = lost.detail if lost.reason == "error" else \
                _LOST.get(lost.reason, "{detail}").format(detail=lost.detail)
            out = _grader_error(entries[i], folder, settings, why)
        done(i, out)

    sb.run_items(_graded_item, [(e, folder, settings) for e in entries], jobs, limit, finished,
                 executor)


def _forked(entries: list[Entry], folder: Path, settings: dict, jobs: int,
            done: Callable[[int, dict], None]) -> None:
    """Each notebook in a forked process (module docstring); results as they come."""
    warm(settings["name"])
    _pooled(entries, folder, settings, jobs, done)


def _dask(entries: list[Entry], folder: Path, settings: dict, spec: str, jobs: int,
          done: Callable[[int, dict], None]) -> None:
    """Each notebook on a Dask worker, with the forked processes' deadline."""
    _pooled(entries, folder, settings, jobs, done, spec)


# ---------------------------------------------------------------------------------- output
def _cell(value: str) -> str:
    """A CSV text cell a spreadsheet will not evaluate (=, +, -, @ lead a formula)."""
    return "'" + value if value[:1] in ("=", "+", "-", "@", "\t", "\r") else value


def _safe_name(name: str) -> str:
    """A file name that cannot leave the folder, unique to ``name``
    (:func:`gpsaccel._untrusted.student_id`)."""
    return _untrusted.student_id(name)


HEADER = ("student", "id", "file")


def write_csv(grades: list[Grade], possible: dict[str, float], path: Path) -> None:
    """``grades.csv``: a header, a row of the points possible, one row per student."""
    buf = io.StringIO()
    w = csv.writer(buf)
    qs = list(possible)
    w.writerow([*HEADER, *qs, "total", "possible", "status", "seconds"])
    w.writerow(["Points Possible", "", "", *(f"{possible[q]:g}" for q in qs),
                f"{sum(possible.values()):g}", f"{sum(possible.values()):g}", "", ""])
    for g in grades:
        w.writerow([_cell(g.student), _cell(g.id), _cell(_untrusted.shown(g.file, 1000)),
                    *(f"{g.scores.get(q, 0):g}" for q in qs),
                    f"{g.total:g}", f"{g.max_total:g}", g.status, f"{g.seconds:.1f}"])
    write_text(path, buf.getvalue())


def summary(grades: list[Grade], possible: dict[str, float]) -> list[dict]:
    """Per question: mean score, its possible, and how many students got each mistake code."""
    out = []
    for q, pts in possible.items():
        scored = [g.scores.get(q, 0.0) for g in grades]
        codes = Counter(c for g in grades for c in dict.fromkeys(g.codes.get(q, [])))
        out.append({"question": q, "possible": pts, "mean": float(np.mean(scored)) if scored
                    else math.nan, "full": sum(s >= pts for s in scored), "students":
                    len(scored), "codes": dict(codes.most_common())})
    return out


def write_summary(rows: list[dict], grades: list[Grade], out: Path) -> None:
    """``summary.csv`` (question, code, students) and ``summary.png`` (the same as bars)."""
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(["question", "possible", "mean", "full marks", "students", "code", "count"])
    for r in rows:
        base = [r["question"], f"{r['possible']:g}", f"{r['mean']:.3f}", r["full"],
                r["students"]]
        if not r["codes"]:
            w.writerow([*base, "", ""])
        for code, n in r["codes"].items():
            w.writerow([*base, code, n])
    statuses = Counter(g.status for g in grades)
    w.writerow([])
    for s, n in statuses.most_common():
        w.writerow(["status", "", "", "", "", s, n])
    write_text(out / "summary.csv", buf.getvalue())
    _figure(rows, out / "summary.png")


def _figure(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from gpsaccel._atomic import savefig

    codes = [(f"{r['question']}: {c}", n) for r in rows for c, n in r["codes"].items()]
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, max(3.0, 0.3 * len(codes) + 1.5)))
    names = [r["question"] for r in rows]
    a.bar(names, [r["mean"] / r["possible"] if r["possible"] else 0 for r in rows])
    a.set_ylim(0, 1)
    a.set_ylabel("mean score / points possible")
    a.set_title(f"{rows[0]['students'] if rows else 0} students")
    if codes:
        b.barh([c for c, _ in codes][::-1], [n for _, n in codes][::-1])
        b.set_xlabel("students")
        b.set_title("mistake codes")
    else:
        b.axis("off")
    fig.tight_layout()
    savefig(fig, path, dpi=100)
    plt.close(fig)


def default_out(submissions: Path) -> Path:
    """``<submissions>-grades`` beside the submissions folder (never inside it)."""
    s = submissions.resolve()
    return s.parent / f"{s.name}-grades"


def read_secret(secret_file: str | os.PathLike | None) -> bytes | None:
    """The instructor's secret: the file's bytes, else ``$GPSACCEL_GRADING_SECRET``, else None."""
    if secret_file is not None:
        data = Path(secret_file).read_bytes().strip()
        if len(data) < 16:
            raise ValueError(f"secret_file: {secret_file} must hold at least 16 bytes (e.g. "
                             f"`python -c 'import secrets; print(secrets.token_hex(32))'`)")
        return data
    env = os.environ.get(SECRET_ENV, "").encode()
    return env or None


# ------------------------------------------------------------------------------ the command
def grade(submissions: str | os.PathLike, name: str, out: str | os.PathLike | None = None,
          jobs: int | None = None, timeout: float = TIMEOUT, seed: int | None = None,
          secret: bytes | None = None, student: str | None = None, dask: str | None = None,
          sandbox: str = "auto", progress: bool = False) -> list[Grade]:
    """Grade every student of ``submissions`` for homework ``name`` (module docstring).

    jobs : notebooks at once (default: CPUs, at most 4); timeout : wall-clock seconds of one
    notebook's box; seed : the fresh data's seed (default: random, or the recorded one when
    regrading one ``student``); secret : the instructor's secret for per-student variants (None:
    every student gets the public notebook's numbers); dask : a Dask address or "dask-local";
    progress : a tqdm bar on stderr when it is a terminal (the last student graded, the ETA).
    """
    from gpsaccel import sandbox as sb

    folder = Path(submissions)
    out, jobs = _checked(folder, out, timeout, jobs)
    possible = _possible(questions_of(name))
    out.mkdir(parents=True, exist_ok=True)
    log = _Log(out, possible, student, progress)
    entries, notes = find_submissions(folder, name)
    if student is not None:  # by the name as found, its id or as it is shown
        entries = [e for e in entries if student in (e.student, e.id, e.shown)]
        if not entries:
            raise ValueError(f"student: no submission of {student!r} in {folder}")
        seed = log.previous.get("seed") if seed is None else seed
    if seed is None:
        seed = secrets.randbits(63)
    if not isinstance(seed, int) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    backend = sb.resolve_backend(sandbox)
    sb.refuse_unsafe_basic(backend)  # a class is not graded where basic cannot isolate it
    settings = {"name": name, "seed": int(seed), "secret": secret, "sandbox": backend,
                "timeout": float(timeout)}
    log.start(entries, {
        "assignment": name, "seed": int(seed), "sandbox": backend, "timeout": timeout,
        "variants": "per student (HMAC of the id under the instructor's secret)" if secret
        else "none (no secret given: every student has the public notebook's numbers)",
        "questions": possible, "started": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "student": student, "skipped": notes})
    try:
        if dask:
            _dask(entries, folder, settings, dask, jobs, log.done)
        else:
            _forked(entries, folder, settings, jobs, log.done)
    except BaseException:  # Ctrl-C, a lost cluster: what is done stays, the rest not-graded
        log.finish(interrupted=True)
        raise
    log.finish(interrupted=False)
    return [g for g in log.grades if g is not None]


def _checked(folder: Path, out: str | os.PathLike | None, timeout: float, jobs: int | None
             ) -> tuple[Path, int]:
    """The output folder and the jobs of :func:`grade`, its arguments checked."""
    if not folder.is_dir():
        raise ValueError(f"submissions must be a folder (a student's folder or notebook per "
                         f"student), got {folder}")
    if not (isinstance(timeout, (int, float)) and 0 < timeout < math.inf):
        raise ValueError(f"timeout must be a positive number of seconds, got {timeout!r}")
    jobs = min(4, os.cpu_count() or 1) if jobs is None else int(jobs)
    if jobs < 1:
        raise ValueError(f"jobs must be >= 1, got {jobs}")
    out = Path(out) if out is not None else default_out(folder)
    if out.resolve().is_relative_to(folder.resolve()):
        raise ValueError(f"out: {out} is inside the submissions folder; write the grades "
                         f"elsewhere (a student's files must not share a folder with them)")
    return out, jobs


class _Log:
    """What a run writes, each file whole (:mod:`gpsaccel._atomic`), after every notebook.

    ``grades.csv`` (and ``grades.json``, the same rows with their codes) always hold a row for
    every student: a full run starts them ``not-graded``; a regrade (``student``) keeps the
    student's old row until the new one is written.  ``grading.json`` holds the class record;
    a regrade appends itself to its ``regrades``."""

    def __init__(self, out: Path, possible: dict[str, float], student: str | None,
                 progress: bool = False) -> None:
        self.out, self.possible, self.student, self.progress = out, possible, student, progress
        self.record = out / "grading.json"
        self.kept_path = out / "grades.json"
        self.feedback = out / "feedback"
        self.previous = self._json(self.record, {})
        self.old = [Grade(**d) for d in self._json(self.kept_path, [])] if student else []
        for g in self.old:  # a row of an earlier version, without its id
            g.id = g.id or _untrusted.student_id(g.student)
        self.entries: list[Entry] = []
        self.grades: list[Grade | None] = []
        self.t0 = time.perf_counter()

    @staticmethod
    def _json(path: Path, default):  # noqa: ANN001, ANN205 - a dict or a list
        return json.loads(path.read_text(encoding="utf-8")) if path.is_file() else default

    def start(self, entries: list[Entry], info: dict) -> None:
        from tqdm.auto import tqdm

        self.bar = tqdm(total=len(entries), desc=info["assignment"], unit="notebook",
                        leave=False, disable=None if self.progress else True)
        self.entries, self.grades = entries, [None] * len(entries)
        self.feedback.mkdir(exist_ok=True)
        if self.student is None or not isinstance(self.previous, dict) or not self.previous:
            self.info = {**info, "regrades": []}
        else:  # the class record stays; the regrade is appended to it
            self.info = self.previous
            self.info.setdefault("regrades", []).append(
                {k: info[k] for k in ("student", "seed", "started")})
        write_text(self.record, json.dumps(self.info, indent=2))
        if self.student is None:  # a full run: the feedback of students no longer there is stale
            keep = {f"{e.id}.txt" for e in entries}
            for f in self.feedback.glob("*.txt"):
                if f.name not in keep:
                    f.unlink()
        self.flush()

    def rows(self) -> list[Grade]:
        now = [g for g in self.grades if g is not None]
        if self.student is None:
            missing = [Grade(e.shown, "", {q: 0.0 for q in self.possible}, self.possible,
                             "not-graded", id=e.id)
                       for e, g in zip(self.entries, self.grades, strict=True) if g is None]
            return sorted(now + missing, key=lambda g: (g.student.lower(), g.id))
        new = {g.id for g in now}
        kept = [g for g in self.old if g.id not in new]
        return sorted(kept + now, key=lambda g: (g.student.lower(), g.id))

    def flush(self) -> None:
        current = self.rows()
        write_csv(current, self.possible, self.out / "grades.csv")
        write_text(self.kept_path, json.dumps([{**asdict(x), "feedback": ""} for x in current]))

    def done(self, i: int, data: dict) -> None:
        g = Grade(**data)
        g.student = _untrusted.clean(g.student)
        g.feedback = _untrusted.clean(g.feedback, newlines=True)
        self.bar.set_postfix_str(f"{g.student[:40]}: {g.status}")
        self.bar.update()
        write_text(self.feedback / f"{self.entries[i].id}.txt", g.feedback)
        self.grades[i] = g
        self.flush()

    def finish(self, interrupted: bool) -> None:
        self.bar.close()
        self.flush()
        final = self.rows()
        if not interrupted:
            write_summary(summary(final, self.possible), final, self.out)
        entry = self.info["regrades"][-1] if self.student is not None and \
            self.info.get("regrades") else self.info
        entry["seconds"] = round(time.perf_counter() - self.t0, 1)
        entry["graded"] = sum(g is not None for g in self.grades)
        entry["interrupted"] = interrupted
        write_text(self.record, json.dumps(self.info, indent=2))
