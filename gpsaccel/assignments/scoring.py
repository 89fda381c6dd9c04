r"""Grading one homework notebook: its cells run in the sandbox, every score computed outside it.

:func:`grade_notebook` turns the student's code cells into one module
(:mod:`gpsaccel.assignments.notebook`), runs it in a box (:func:`gpsaccel.sandbox.run`) that calls
the cells in order and the *reads* every question declares (which cells and how the reads are
called: :mod:`gpsaccel.assignments.boxcalls`), after the last cell and after each
question's answer cell (:mod:`gpsaccel.assignments.snapshots`: a notebook that stops is graded
from the last group of reads it reached), and only once the box is empty draws the reference
answers and scores each question; a question graded from a file the notebook writes is checked
by :func:`gpsaccel.check.submission` in a box of its own.  The feedback a student gets
(:func:`_feedback_text`, at most :data:`MAX_FEEDBACK` bytes) is the student's projection of each
finding.  A class's run grades each notebook through :mod:`gpsaccel.assignments.grading`.
"""

from __future__ import annotations

import os
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from gpsaccel import _untrusted
from gpsaccel.assignments import notebook as nbm
from gpsaccel.assignments import snapshots
from gpsaccel.assignments.boxcalls import SKIP_MARK as SKIP_MARK
from gpsaccel.assignments.boxcalls import VARIANT_MARK as VARIANT_MARK
from gpsaccel.assignments.boxcalls import box_calls, checked_question, per_call, prepare
from gpsaccel.assignments.boxcalls import calls as _calls  # noqa: F401 - the tests' name for it
from gpsaccel.assignments.boxcalls import is_otter_cell as is_otter_cell
from gpsaccel.assignments.questions import (
    Answer,
    Draw,
    Question,
    answer_from,
    question_seed,
    variant_number,
)
from gpsaccel.check.report import Report, first_line, see
from gpsaccel.sandbox.outcomes import OUTCOMES, ours

#: Time limit (s) of one notebook's box (every cell and every read; its own time, not its waits
#: on a busy machine: gpsaccel.sandbox.clock), default.
TIMEOUT = 120.0

#: Seconds a notebook's process may take beyond its boxes' limits (reference answers, feedback)
#: before it is killed as a grader error.
SLACK = 120.0

#: Memory (address space) of a notebook's box: numpy, scipy and matplotlib need about 1 GB.
BOX_MEMORY = 2 << 30

#: Processes a notebook's box may hold at once.
BOX_PROCESSES = 32




def assignment_module(name: str):
    """The homework's graded questions: ``graded.py`` beside its master (the packaged
    ``gpsaccel/assignments/masters/NAME/``, or the instructor's own folder; ValueError for an
    unknown name)."""
    import importlib.util
    import sys

    from gpsaccel import registry
    from gpsaccel.assignments.homework import homework_dir

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
    mistake codes; feedback : the text for the student; late : handed in after the deadline, as
    the export marks it (Canvas's ``_LATE_``); similarity : the notebook's record for
    the class's similarity report, made from this grading's parse of it
    (:func:`gpsaccel.assignments.answercode.record`; never shown to the student).
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
    late: bool = False
    similarity: dict = field(default_factory=dict)

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


#: failure -> what the notebook's stop says (the sandbox's one table of outcomes)
_STOPS = {code: o.stop for code, o in OUTCOMES.items() if o.stop}


def _stop_message(failure: str, where: str, limits, graded: Sequence[str] = (),
                  state: str = "") -> str:
    """Where the notebook stopped and why, and which answers count: ``graded``, as the notebook
    stood ``state`` (:mod:`.snapshots`)."""
    why = _STOPS.get(failure, failure).format(limit=limits.time, memory=limits.memory >> 30)
    kept = (f" Answers complete before that count: {', '.join(graded)}, graded as your notebook "
            f"stood {state}." if graded else " No answer was complete before that.")
    return f"The notebook stopped {where}: {why}.{kept}"


def _after(cells: Sequence, i: int) -> str:
    """The state after cell index ``i`` of the cells run, in the student's numbering."""
    if i == len(cells) - 1:
        return "after its last cell"
    return f"after cell {cells[i].number}" if cells[i].number else "before its first cell"


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


def _where_stopped(p: snapshots.Plan, stopped: int | None, cells: Sequence,
                   reads: Sequence[nbm.Read]) -> str:
    """Where the box stopped: in a cell, in a read of a question, or after its last call."""
    if stopped is None:
        return "after its last answer"
    group, i = p.calls[stopped]
    if group == -1:
        number = cells[i].number
        return f"in cell {number}" if number else "before the first cell"
    q = next(q for q, (a, b) in p.spans.items() if a <= i < b)
    text = f"while {'reading' if reads[i].value else 'calling'} {reads[i].name} ({q})"
    after = p.groups[group].after
    return text if after == len(cells) - 1 else f"{text}, {_after(cells, after)}"


def _not_graded(q: Question, code: str, text: str) -> Report:
    rep = Report(q.name)
    rep.add(code, text=text)
    return rep


def _question_report(q: Question, nb: nbm.Notebook, draw: Draw, answers: list[Answer] | None,
                     timeout: float, stop: str | None) -> Report:
    """One question's report: graded from a file, from its answers, or not graded: its cells
    had not run (``answers`` None: ``not-run``), or its read did not come back (``stop``, the
    box's failure, where the box stopped in it; else ``not-read``)."""
    if q.file is not None:
        return _grade_file(q, nb, draw, timeout)
    if answers is None:
        return _not_graded(q, "not-run", "Not graded: the notebook stopped before this "
                           "question's cells had run (see above).")
    if stop is not None:
        return _not_graded(q, stop, "Not graded: the notebook stopped while reading this "
                           "answer (see above).")
    if any(x.status == "not-run" for x in answers):
        return _not_graded(q, "not-read", "Not graded: the notebook stopped while reading "
                           "another answer, before this one (see above).")
    return _safe_grade(q, draw, answers)


def _plan(run: nbm.Notebook, nb: nbm.Notebook, qs: Sequence[Question],
          draws: dict[str, Draw]) -> tuple[list[nbm.Read], snapshots.Plan]:
    """Every question's reads, in order, and when the box makes them (:mod:`.snapshots`)."""
    reads: list[nbm.Read] = []
    spans: dict[str, tuple[int, int]] = {}
    for q in qs:
        r = list(q.reads(draws[q.name]))
        if r:
            spans[q.name] = (len(reads), len(reads) + len(r))
            reads += r
    reading = {q: sorted({r.name for r in reads[a:b]}) for q, (a, b) in spans.items()}
    checks = {c.number: asked for c in nb.cells
              if (asked := checked_question(c.source)) is not None}
    return reads, snapshots.plan(len(run.cells), spans,
                                 snapshots.answer_cells(run.cells, checks, reading))


def _returned(p: snapshots.Plan, box, covers: list[range], cells: Sequence,
              reads: list[nbm.Read], limits
              ) -> tuple[dict[str, list[Answer]], dict[str, str], list[str], list[str]]:
    """What the box returned (its calls made ``covers`` of the plan's, :func:`~.boxcalls.box_calls`),
    read as the one group that grades (:func:`.snapshots.kept`): the answers of each question
    in it, the failure of the question whose read stopped, the notes on where the notebook
    stopped and what counts and on where it forked its process, the notes on its cells."""
    results = per_call(p, box.results, covers)
    received = len(results)
    results += [None] * (len(p.calls) - received)
    kept = snapshots.kept(p, received)
    answers = {q: [answer_from(results[c], len(reads[k].shapes))
                   for c, k in zip(at, range(*p.spans[q]), strict=True)]
               for q, at in kept.questions.items()}
    stops = {q: box.failure for q, at in kept.questions.items() if kept.stopped in at}
    notes = []
    if box.failure is not None:
        graded = [q for q, a in answers.items() if q not in stops
                  and all(x.status != "not-run" for x in a)]
        state = "" if kept.group is None else _after(cells, p.groups[kept.group].after)
        notes.append(_stop_message(box.failure, _where_stopped(p, kept.stopped, cells, reads),
                                   limits, graded, state))
    if box.forked is not None:
        notes.append(_fork_note(p, box.forked, covers, cells, reads))
    return answers, stops, notes, _cell_notes(cells, [results[i] for i in p.cell_calls])


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
    run = prepare(nb, variant)
    reads, p = _plan(run, nb, qs, draws)
    compared = _similarity_record(name, qs, run, reads, p.spans)
    limits = sb.Limits(memory=BOX_MEMORY, time=float(timeout), processes=BOX_PROCESSES)
    with _scratch("nb") as tmp:
        folder = Path(tmp) / "submission"
        folder.mkdir()
        (folder / "notebook.py").write_text(nbm.module_source(run, reads), encoding="utf-8")
        sub = sb.load_submission(folder / "notebook.py", "_gpsaccel_cell")
        calls, covers = box_calls(p, reads)
        box = sb.run(sub, calls, limits, backend=sandbox, allow_gpsaccel=True, hide=nbm.BOX_HIDES)
    # ---- the box is empty from here on: nothing of the student's runs while answers exist
    answers, stops, notes, cell_notes = _returned(p, box, covers, run.cells, reads, limits)
    status = box.failure or "graded"
    reports = {q.name: _question_report(q, nb, draws[q.name], answers.get(q.name), timeout,
                                        stops.get(q.name)) for q in qs}
    scores = {q.name: q.score(reports[q.name]) for q in qs}
    codes = {k: r.codes for k, r in reports.items()}
    if ours(status) or any(ours(c) for cs in codes.values() for c in cs):
        status = "grader-error"  # the machine's or the checker's, not a grade: graded again
    g = Grade(_untrusted.shown(student), file, scores, possible, status, "", codes,
              time.perf_counter() - t0, sid or _untrusted.student_id(student),
              similarity=compared)
    g.feedback = _feedback_text(g, notes, reports, variant, cell_notes)
    return g


def _scratch(kind: str) -> tempfile.TemporaryDirectory:
    """A temporary folder for the files a box is loaded from, named as the sandbox names its box
    folders (``gpsaccel-box-<pid>-``): removed on exit, and, when this process is killed inside it
    (a notebook past its deadline, Ctrl-C), by the pool's sweep of the folders whose process is
    dead (:func:`gpsaccel.sandbox.sweep_stale_boxes`) instead of staying in ``/tmp``."""
    from gpsaccel import sandbox as sb

    return tempfile.TemporaryDirectory(prefix=f"{sb.BOX_PREFIX}{os.getpid()}-{kind}-")


def _similarity_record(name: str, qs: Sequence[Question], run: nbm.Notebook,
                       reads: list[nbm.Read], spans: dict[str, tuple[int, int]]) -> dict:
    """The notebook's record for the similarity report, from the cells this grading parsed and
    runs (never raises: a failure is the record's ``why``)."""
    from gpsaccel.assignments import answercode

    try:
        asked = answercode.asked(name, qs, {q: reads[a:b] for q, (a, b) in spans.items()})
    except Exception as exc:  # noqa: BLE001 - the report's, never the grade's
        return {"why": f"the grader could not list what its questions read ({type(exc).__name__})"}
    return answercode.from_notebook(run, asked)


def _grader_error(q: Question, exc: Exception) -> Report:
    """The question's report when the grader itself raised: that question only, and the student
    sees the exception's type, never its text (which may hold the expected value)."""
    rep = Report(q.name)
    rep.add("grader-error", f"{type(exc).__name__}: {exc}", text="The grader failed on "
            "this question ({type}); tell your instructor.", observed={"type": type(exc).__name__})
    return rep


def _safe_grade(q: Question, draw: Draw, answers: list[Answer]) -> Report:
    assert q.grade is not None  # a question read from the box has its grade
    try:
        return q.grade(draw, answers)
    except Exception as exc:  # noqa: BLE001 - a bug of the grader: this question only
        return _grader_error(q, exc)


def _grade_file(q: Question, nb: nbm.Notebook, draw: Draw, timeout: float) -> Report:
    assert q.file is not None and q.grade_file is not None  # a file question has both
    found = nb.writefile(q.file)
    if found is None:
        rep = Report(q.name)
        rep.add("no-file", text="The notebook has no cell `%%writefile {file}`: the question "
                "asks for the function in that file (keep the cell's first line as it is).",
                observed={"file": q.file})
        return rep
    with _scratch("file") as tmp:
        path = Path(tmp) / q.file
        path.write_text(found[1], encoding="utf-8", errors="replace")  # a lone surrogate too
        try:
            return q.grade_file(path, draw, timeout)
        except Exception as exc:  # noqa: BLE001 - a bug of the grader: this question only
            return _grader_error(q, exc)


# --------------------------------------------------------------------------------- feedback
#: The most a student's feedback holds (bytes of UTF-8), in its file and in Gradescope's output:
#: the score, the notes on the run and every question's findings come first; the notes on the
#: student's own cells (which raised, which lines were not run) fill what is left, and what is
#: left out is counted in the text.  An honest notebook's feedback is under 2 KB.
MAX_FEEDBACK = 16 << 10

#: The longest line of feedback (characters): a finding or a note quoting the student's text.
MAX_LINE = 1000


#: The note on a notebook that forked its process (``{where}``: where, :func:`_where_stopped`'s
#: words) and the lesson section under it.
FORK_NOTE = ("Your notebook forked its process {where} (os.fork(), or multiprocessing, which calls "
             "it). Only the notebook's own process is graded: the copy a fork makes was stopped "
             "where it would have handed back an answer, so nothing it computed counts, for or "
             "against you. A notebook computes in one process: remove os.fork() from it.\n{see}")


def _fork_note(p: snapshots.Plan, forked: int, covers: Sequence[range], cells: Sequence,
               reads: Sequence[nbm.Read]) -> str:
    """The note on a fork during the box's call ``forked`` (:attr:`gpsaccel.sandbox.BoxResult
    .forked`; -1, the module's import, runs none of the student's code but is named all the
    same)."""
    where = (_where_stopped(p, covers[forked].start, cells, reads) if 0 <= forked < len(covers)
             else "before its first cell")
    return FORK_NOTE.format(where=where, see=see("forked"))


#: What replaces a run of findings (1) or of notes on cells (2) left out of the feedback.
_LEFT_OUT = {1: "    - ... {n} more finding(s) of this question left out: the feedback holds at "
                "most {kb} KB",
             2: "... {n} more note(s) on your cells left out: the feedback holds at most {kb} KB"}


def _feedback_text(g: Grade, notes: list[str], reports: dict[str, Report],
                   variant: dict, cells: Sequence[str] = ()) -> str:
    """The student's feedback: the notes about their notebook (where it stopped), per question
    the student's projection of each finding (:meth:`gpsaccel.check.report.Finding.for_student`:
    no expected value reaches this text), each error and warning (and a note it shows) with the
    lesson section that teaches its fix under it, then the notes on its cells (``cells``); at most
    :data:`MAX_FEEDBACK` bytes, the notes on cells cut first
    (:func:`gpsaccel._untrusted.bounded`: a finding and its section are kept or left out
    together)."""
    lines: list[tuple[int, str]] = [
        (0, f"{g.student}: {g.total:g} / {g.max_total:g} points ({g.status})")]
    if variant:
        lines.append((0, "Your variant: " + ", ".join(f"{k} = {v}" for k, v in variant.items())))
    lines.append((0, ""))
    for n in dict.fromkeys(notes):
        lines.append((0, n))
    if notes:
        lines.append((0, ""))
    for q, points in g.possible.items():
        lines.append((0, f"{q}: {g.scores.get(q, 0):g} / {points:g}"))
        rep = reports.get(q)
        seen = set()
        for f in rep.for_student().findings if rep else []:
            if f.severity == "note" and f.code not in ("uses-own-jacobian",):
                continue
            text = f"{f.code}: {first_line(f.message)}"  # "ends with: SyntaxError."
            if text in seen:
                continue  # each failure once
            seen.add(text)
            lines.append((1, "    - " + text + ("\n      " + f.see() if f.see() else "")))
        lines.append((0, ""))
    lines += [(2, n) for n in dict.fromkeys(cells)]
    return _untrusted.bounded(lines, MAX_FEEDBACK, _LEFT_OUT, MAX_LINE)
