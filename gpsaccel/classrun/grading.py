r"""A class's grade (``gpsaccel grade DIR --assignment NAME``, :func:`grade`): every notebook only
inside the checker's sandbox, every score computed outside, every file written by this function.

* submissions as an LMS exports them (:func:`gpsaccel.classrun.entries.walk` with
  :func:`~gpsaccel.classrun.entries.notebooks`): a folder per student or one notebook per
  student at the top; every name (any bytes, NFC or NFD, any punctuation or length) gets once a
  unique printable id that names the student's files; every entry is either graded or reported
  with why not (``no-notebook``, ``ambiguous``, ``unreadable``, ``file-limit``,
  ``id-collision``), never skipped silently;
* each notebook is graded as an item of the one class run
  (:func:`gpsaccel.classrun.running.run`; the item is
  :func:`gpsaccel.assignments.grading.grade_item`): in a forked process of its own (a student
  who kills it loses only their own grade: ``grader-error``), forked from a parent that has
  imported what grading a notebook needs; the run is a child subreaper and sweeps what a dead
  process left; ``grades.csv`` is rewritten (atomically) after every notebook with a row for
  every student, so a run killed half-way leaves the grades it had; one interrupted (Ctrl-C)
  leaves ``not-graded`` rows for the rest, records ``interrupted`` and raises
  :class:`~gpsaccel.classrun.running.Interrupted` (a KeyboardInterrupt: the command exits 130);
* output (default: ``<submissions>-grades`` next to the submissions folder, never inside it):
  ``grades.csv`` (student name as shown, id, file, one column per question, total, possible,
  status, seconds, and a first row of the points possible), ``grades.json`` (the same rows with
  their codes), ``feedback/<id>.txt`` (stale files of an earlier run removed),
  ``summary.csv`` and ``summary.png`` (per question: mean score, how many students got each
  mistake code), ``grading.json`` — the instructor's record: the seed, the sandbox, which
  questions, when.  It holds no answer; keep it from students all the same (with the secret it
  reproduces their data).  Then, once every notebook is graded, the class-wide files
  (:mod:`gpsaccel.classrun.classwide`): with a roster the LMS gradebooks, and the similarity
  report;
* a file the file system refuses (a full disk) costs that file only
  (:class:`~gpsaccel.classrun.writing.Outputs`): the grades and every other file are kept, and
  ``grading.json``'s ``missing`` names what is not written; :func:`rewrite_class` writes the
  class-wide files again from ``grades.json`` once there is room, without grading;
* a rerun into the same output without ``seed`` keeps the recorded seed and the recorded grade
  of every notebook whose SHA-256 is unchanged (same homework, secret, sandbox, time limit and
  gpsaccel; ``regrade=True`` grades every one again); ``student=ID`` (or several ids) regrades
  those students with the recorded seed: each old row stays until its new one is written, and
  the regrade is appended to ``grading.json``'s ``regrades`` (its ``student``: a list of ids);
  a run that starts a new record keeps the earlier ones in its ``earlier``, but for a run that
  graded nothing on the same seed (:func:`_idle`);
* ``dask=...`` sends each notebook to a Dask cluster (same function, same seed: same grades)
  with the same deadline.
"""

from __future__ import annotations

import json
import math
import os
import time
from collections import Counter
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gpsaccel import _untrusted
from gpsaccel.assignments import grading as item
from gpsaccel.assignments.roster import Student, read_roster
from gpsaccel.assignments.scoring import TIMEOUT, Grade
from gpsaccel.classrun import classwide, running, statuses, writing
from gpsaccel.classrun.classwide import UNMAPPED
from gpsaccel.classrun.entries import Entry, Naming, Superseded, notebooks, walk
from gpsaccel.classrun.exports import Export


class _Grade(running.Task):
    """One notebook's grade as a class's item (:mod:`gpsaccel.assignments.grading`)."""

    doer, doing = "grader", "grading this notebook"

    def __init__(self, folder: Path, settings: dict) -> None:
        self.folder, self.settings, self.name = folder, settings, settings["name"]
        self.timeout = settings["timeout"]
        self.deadline = item.deadline(self.timeout)

    def _file(self, entry: Entry) -> str:
        """The notebook's path relative to the submissions (as found: the similarity report
        opens it again; ``grades.csv`` shows it printable)."""
        return os.path.relpath(entry.path, self.folder) if entry.path else ""

    def warm(self) -> None:
        item.warm(self.name)

    def boxes(self) -> tuple:
        """A notebook's box (it may import the course's models, not the grader's folders) and
        a file question's (a student's filter: no gpsaccel)."""
        from gpsaccel import sandbox as sb
        from gpsaccel.assignments.notebook import BOX_HIDES

        return (sb.Warm(allow_gpsaccel=True, hide=BOX_HIDES), sb.Warm())

    def item(self, entry: Entry) -> dict:
        assert entry.path is not None  # the run sends only entries with a notebook
        return item.grade_item(entry.path, entry.student, self._file(entry), entry.id,
                               self.settings)

    def refused(self, entry: Entry) -> dict:
        assert entry.problem is not None  # an entry without a notebook says why
        return item.not_run(self.name, entry.student, entry.id, *entry.problem)

    def lost(self, entry: Entry, why: str) -> dict:
        return item.grader_error(self.name, entry.student, self._file(entry), entry.id, why)


def summary(grades: Sequence[Grade], possible: dict[str, float]) -> list[dict]:
    """Per question: mean score, its possible, and how many students got each mistake code."""
    out = []
    for q, pts in possible.items():
        scored = [g.scores.get(q, 0.0) for g in grades]
        codes = Counter(c for g in grades for c in dict.fromkeys(g.codes.get(q, [])))
        out.append({"question": q, "possible": pts, "mean": float(np.mean(scored)) if scored
                    else math.nan, "full": sum(s >= pts for s in scored), "students":
                    len(scored), "codes": dict(codes.most_common())})
    return out


#: The summary's files (:func:`gpsaccel.classrun.writing.write_summary`).
SUMMARY = ("summary.csv", "summary.png")


class _Record:
    """What a run writes, each file whole (:mod:`gpsaccel._atomic`), after every notebook.

    ``grades.csv`` (and ``grades.json``, the same rows with their codes) always hold a row for
    every student: a full run starts them ``not-graded``; a regrade (``student``) keeps the
    student's old row until the new one is written.  ``grading.json`` holds the class record;
    a regrade appends itself to its ``regrades``."""

    def __init__(self, out: Path, possible: dict[str, float], student: Sequence[str] | None,
                 progress: bool = False) -> None:
        self.out, self.possible, self.student, self.progress = out, possible, student, progress
        self.record = out / "grading.json"
        self.kept_path = out / "grades.json"
        self.feedback = out / "feedback"
        self.previous = self._json(self.record, {})
        if not isinstance(self.previous, dict):
            self.previous = {}
        # a regrade keeps what the folder still misses (another student's feedback)
        kept = self.previous.get("missing") if student and isinstance(self.previous, dict) \
            else None
        self.outputs = writing.Outputs(out, kept if isinstance(kept, dict) else None)
        try:
            self.old = [Grade(**d) for d in self._json(self.kept_path, [])]
        except TypeError:  # grades.json of another version: nothing is reused from it
            self.old = []
        for g in self.old:  # a row of an earlier version, without its id
            g.id = g.id or _untrusted.student_id(g.student)
        self.notebooks: dict[str, str] = {}
        self.reused: dict[int, Grade] = {}
        self.entries: Sequence[Entry] = []
        self.grades: list[Grade | None] = []
        self.t0 = time.perf_counter()

    @staticmethod
    def _json(path: Path, default):  # noqa: ANN001, ANN205 - a dict or a list
        return json.loads(path.read_text(encoding="utf-8")) if path.is_file() else default

    def reusable(self, entries: Sequence[Entry], settings: dict) -> str:
        """Fill :attr:`reused` with the recorded grade of every entry whose notebook is
        unchanged (its SHA-256) under the recorded seed and settings; "" or why nothing is."""
        self.notebooks = {e.id: _digest(e.path) for e in entries if e.path is not None}
        before = self.previous.get("reuse")
        if not self.previous.get("seed") or before != _fingerprint(settings):
            return ("no earlier run in this folder" if not self.previous else
                    "the earlier run's homework, secret, sandbox, time limit or gpsaccel "
                    "differ")
        old = {g.id: g for g in self.old}
        recorded = self.previous.get("notebooks") or {}
        for i, e in enumerate(entries):
            g = old.get(e.id)
            if g is None:
                continue
            refused = e.path is None and e.problem is not None and g.status == e.problem[0]
            if refused or (statuses.scored(g.status) and e.id in self.notebooks
                           and recorded.get(e.id) == self.notebooks[e.id]):
                self.reused[i] = g  # the same refusal, or the same notebook's own grade
        return ""

    def start(self, entries: Sequence[Entry], info: dict) -> None:
        from tqdm.auto import tqdm

        self.bar = tqdm(total=len(entries) - len(self.reused), desc=info["assignment"],
                        unit="notebook", leave=False, disable=None if self.progress else True)
        self.entries, self.grades = entries, [None] * len(entries)
        for i, g in self.reused.items():
            g.late = entries[i].late
            self.grades[i] = g
        self.feedback.mkdir(exist_ok=True)
        if self.student is None or not self.previous:
            earlier = self.previous.get("earlier", []) + (
                [{k: v for k, v in self.previous.items() if k not in ("earlier", "notebooks")}]
                if self.previous and not _idle(self.previous, info["seed"]) else [])
            self.info = {**info, "regrades": [], "earlier": earlier}
        else:  # the class record stays; the regrade is appended to it
            self.info = self.previous
            self.info.setdefault("regrades", []).append(
                {k: info[k] for k in ("student", "seed", "started")})
        self.info.setdefault("notebooks", {}).update(self.notebooks)
        writing.dump_json(self.record, self.info, indent=2)
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
        kept = [g for g in self.old if g.id not in new]  # a regrade keeps the other rows
        return sorted(kept + now, key=lambda g: (g.student.lower(), g.id))

    def flush(self) -> None:
        """``grades.csv`` and ``grades.json`` now; one the file system refuses is missing
        until a later flush writes it (:class:`~gpsaccel.classrun.writing.Outputs`)."""
        current = self.rows()
        self.outputs.write(["grades.csv"], writing.write_grades, current, self.possible,
                           self.out / "grades.csv")
        self.outputs.write(["grades.json"], writing.dump_json, self.kept_path,
                           [{**asdict(x), "feedback": ""} for x in current])

    def done(self, i: int, data: dict) -> None:
        g = Grade(**data)
        g.late = self.entries[i].late
        self.bar.set_postfix_str(f"{g.student[:40]}: {g.status}")
        self.bar.update()
        sid = self.entries[i].id
        self.outputs.write([f"feedback/{sid}.txt"], writing.write_feedback, self.feedback, sid,
                           g.feedback)
        self.grades[i] = g
        self.flush()

    def finish(self, interrupted: bool, pending: Sequence[str] = ()) -> list[Grade]:
        """The last flush, the record, then the summary; ``pending``: the class-wide files
        still to be written.  The record names the summary and them missing before they are
        written (a disk that fills up on them may leave no room to update it), and
        :meth:`save` after them names what is still missing."""
        self.bar.close()
        self.flush()
        final = self.rows()
        entry = self.info["regrades"][-1] if self.student is not None and \
            self.info.get("regrades") else self.info
        entry["seconds"] = round(time.perf_counter() - self.t0, 1)
        entry["graded"] = sum(g is not None for g in self.grades) - len(self.reused)
        entry["reused"] = len(self.reused)
        entry["interrupted"] = interrupted
        if not interrupted:
            self.outputs.pending([*SUMMARY, *pending])
        self.save()
        if not interrupted:
            self.outputs.write(SUMMARY, writing.write_summary, summary(final, self.possible),
                               final, self.out)
        return final

    def save(self) -> None:
        """``grading.json``, with the files the output folder misses (``missing``: file ->
        why; empty when every file is written)."""
        self.info["missing"] = dict(self.outputs.missing)
        self.outputs.write(["grading.json"], writing.dump_json, self.record, self.info,
                           indent=2)


@dataclass
class Graded:
    """What :func:`grade_class` did: this run's grades (one per student graded now, in the
    class's order), every row the output now holds (a regrade keeps the others'), the output
    folder, and what the class-wide step says (lines for the instructor)."""

    grades: list[Grade]
    rows: list[Grade]
    out: Path
    classwide: list[str] = field(default_factory=list)
    #: The files not written (relative to ``out``) and why (the file system's words).
    missing: dict[str, str] = field(default_factory=dict)


def default_out(submissions: str | os.PathLike) -> Path:
    """``<submissions>-grades`` beside the submissions folder (never inside it)."""
    s = Path(submissions).resolve()
    return s.parent / f"{s.name}-grades"


def _earlier(compare_with: str | os.PathLike | None, similarity: bool) -> Path | None:
    """The folder of earlier submissions the similarity report compares with (None: none)."""
    if compare_with is None:
        return None
    if not (similarity and Path(compare_with).is_dir()):
        raise ValueError(f"compare_with: {compare_with} must be a folder of earlier submissions, "
                         f"and the similarity report asked for (it makes the comparison)")
    return Path(compare_with)


def grade_class(submissions: str | os.PathLike, name: str, out: str | os.PathLike | None = None,
                jobs: int | None = None, timeout: float = TIMEOUT, seed: int | None = None,
                secret: bytes | None = None, student: str | Sequence[str] | None = None,
                dask: str | None = None, sandbox: str = "auto", progress: bool = False,
                roster: Sequence[Student] | str | os.PathLike | None = None,
                similarity: bool = True, naming: Naming | None = None,
                export: str = "auto", regrade: bool = False,
                compare_with: str | os.PathLike | None = None,
                canvas_column: str | None = None,
                warm_boxes: bool | None = None,
                secret_file: str | os.PathLike | None = None) -> Graded:
    """Grade every student of ``submissions`` for homework ``name`` and write every file
    (module docstring); :func:`grade` is this with the grades alone.

    jobs : notebooks at once (default: CPUs, at most 4); timeout : seconds of one notebook's
    box, on its fair clock (:mod:`gpsaccel.sandbox.clock`); seed : the fresh data's seed
    (default: secret, or the recorded one when regrading one ``student``); secret : the
    instructor's secret for per-student variants (None: every student gets the public notebook's
    numbers); dask : a Dask address or "dask-local"; progress : a tqdm bar on stderr when it is
    a terminal; roster : the class roster (students, or its file: :func:`~gpsaccel.assignments
    .roster.read_roster`), for the LMS gradebooks; similarity : write the similarity report;
    export : how the submissions were downloaded (:data:`gpsaccel.classrun.exports.LAYOUTS`;
    "auto": told from their names), each mapped to the roster through the ids its name carries;
    naming : who each entry is, instead (:data:`~gpsaccel.classrun.entries.Naming`);
    student : regrade these students only (an id, or several), with the recorded seed;
    regrade : grade every notebook again; without it (and without ``seed``) a rerun in the same
    ``out`` reuses the recorded seed and the recorded grade of every notebook that is unchanged
    (its SHA-256) under the same homework, secret, sandbox, time limit and gpsaccel.
    compare_with : a folder of earlier submissions (an export as graded) the similarity report
    compares every answer with too.  canvas_column : the name of ``canvas.csv``'s grade column
    (:mod:`gpsaccel.classrun.classwide`; default the homework's title).
    warm_boxes : start each box from a zygote that has imported numpy, scipy.stats and filterpy
    (:mod:`gpsaccel.sandbox.zygote`; as root on Linux, without ``dask``), confined as a cold box
    (the same grades: a rerun reuses them either way); None (the default) where boxes can start
    warm, False every box cold, True an error where they cannot.
    """
    folder = Path(submissions)
    out, jobs = _checked(folder, out, timeout, jobs)
    backend = running.backend_of(sandbox)  # a class is not graded where basic cannot isolate it
    secret = running.secret_of(secret, secret_file, backend)
    running.warm_of(warm_boxes, dask or "processes")  # asked where it cannot be: refused here
    earlier = _earlier(compare_with, similarity)
    students = read_roster(roster) if isinstance(roster, (str, os.PathLike)) else roster
    possible = item.possible_of(name)
    layout = Export(notebooks(name), export, students)
    entries, notes = walk(folder, notebooks(name), naming,
                          known={s.id for s in students} if students else (),
                          layout=None if naming is not None else layout)
    if not entries:
        raise ValueError(f"submissions: no student's folder or notebook in {folder}")
    _check_mapped(entries, students, layout)
    out.mkdir(parents=True, exist_ok=True)
    wanted = _wanted(student)
    record = _Record(out, possible, wanted, progress)
    settings: dict[str, Any] = {"name": name, "seed": seed, "secret": secret,
                                "sandbox": backend, "timeout": float(timeout)}
    entries, reuse = _resumed(record, entries, wanted, folder, settings, regrade)
    seed = settings["seed"]  # drawn by running.seed_of where none was given or recorded
    todo = [i for i in range(len(entries)) if i not in record.reused]
    warm = running.warm_of(warm_boxes, dask or "processes",
                           sum(entries[i].path is not None for i in todo))
    record.start(entries, {
        "assignment": name, "seed": seed, "sandbox": backend, "timeout": timeout,
        "variants": _variants(secret), "boxes": "warm" if warm else "cold", "questions": possible,
        "started": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "student": wanted,
        "export": layout.found, "skipped": notes, "reuse": _fingerprint(settings)})
    try:
        if todo:
            with running.hidden_from_boxes(backend, _class_folders(
                    folder, out, earlier, name, secret_file)):
                running.run(_Grade(folder, settings), [entries[i] for i in todo], jobs,
                            dask or "processes", lambda k, data: record.done(todo[k], data),
                            warm)
    except BaseException:  # Ctrl-C, a lost cluster: what is done stays, the rest not-graded
        record.finish(interrupted=True)
        raise
    rows = record.finish(False, classwide.files(students is not None, similarity))
    lines = classwide.write(folder, out, name, rows, possible, students, similarity,
                            record.outputs, earlier, canvas_column)
    lines += _closing(students, layout, reuse, notes)
    record.save()
    return Graded([g for i, g in enumerate(record.grades) if g is not None
                   and i not in record.reused], rows, out, lines, dict(record.outputs.missing))


def _variants(secret: bytes | None) -> str:
    return ("per student (HMAC of the id under the instructor's secret)" if secret
            else "none (no secret given: every student has the public notebook's numbers)")


def _closing(students: Sequence[Student] | None, layout: Export, reuse: str,
             notes: Sequence[object]) -> list[str]:
    """The run's last lines: roster rows no submission matched, what a rerun reused, the
    superseded submissions left out."""
    return (_unmapped(students, layout) + ([f"rerun: {reuse}"] if reuse else [])
            + [f"not graded: {n} (grading.json's skipped)" for n in notes
               if isinstance(n, Superseded)])


def rewrite_class(submissions: str | os.PathLike, name: str, out: str | os.PathLike | None = None,
                  roster: Sequence[Student] | str | os.PathLike | None = None,
                  similarity: bool = True, canvas_column: str | None = None) -> Graded:
    """The class-wide step again from the grades a run recorded, without grading a notebook
    (``gpsaccel grade --from-grades``): ``grades.csv`` and the summary from ``grades.json``,
    then the gradebooks (with a roster) and the similarity report, each as :func:`grade_class`
    writes them; ``grading.json``'s ``missing`` then names only what is still not written (a
    student's feedback needs that student graded again: ``grades.json`` keeps no feedback).
    For a run that could not write everything (a full disk), once there is room."""
    folder = Path(submissions)
    if not folder.is_dir():
        raise ValueError(f"submissions must be the folder that was graded, got {folder}")
    out = Path(out) if out is not None else default_out(folder)
    info = _Record._json(out / "grading.json", None)
    if not isinstance(info, dict):
        raise ValueError(f"out: no grading.json in {out}: grade the class first (without "
                         f"--from-grades)")
    if info.get("assignment") != name:
        raise ValueError(f"assignment: {out} holds the grades of {info.get('assignment')!r}, "
                         f"not {name!r}")
    before = info.get("missing")
    before = before if isinstance(before, dict) else {}
    kept = _Record._json(out / "grades.json", None)
    if not isinstance(kept, list) or "grades.json" in before:  # none, or an earlier run's
        raise ValueError(f"out: {out} holds no grades.json of the last run (it could not be "
                         f"written): grade the class again")
    rows = [Grade(**d) for d in kept]
    for g in rows:  # a row of an earlier version, without its id
        g.id = g.id or _untrusted.student_id(g.student)
    recorded = info.get("questions")
    possible = recorded if isinstance(recorded, dict) else item.possible_of(name)
    students = read_roster(roster) if isinstance(roster, (str, os.PathLike)) else roster
    outputs = writing.Outputs(out, before)
    outputs.write(["grades.csv"], writing.write_grades, rows, possible, out / "grades.csv")
    outputs.write(SUMMARY, writing.write_summary, summary(rows, possible), rows, out)
    outputs.pending(classwide.files(students is not None, similarity))  # one it declines
    lines = classwide.write(folder, out, name, rows, possible, students, similarity, outputs,
                            canvas_column=canvas_column)
    info.setdefault("rewrites", []).append({
        "started": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "roster": students is not None, "similarity": similarity})
    info["missing"] = dict(outputs.missing)
    outputs.write(["grading.json"], writing.dump_json, out / "grading.json", info, indent=2)
    return Graded([], rows, out, lines, dict(outputs.missing))


def _class_folders(folder: Path, out: Path, earlier: Path | None, name: str,
                   secret_file: str | os.PathLike | None) -> dict:
    """What no box may read, by argument: every classmate's notebook, the grades and feedback,
    the earlier submissions, the instructor's homework (its solutions), the secret's folder."""
    from gpsaccel.assignments.homework import own_folder

    return {"submissions": folder, "out": out, "compare_with": earlier,
            "the homework's folder": own_folder(name),
            "secret_file": None if secret_file is None else Path(secret_file).resolve().parent}


def grade(submissions: str | os.PathLike, name: str, out: str | os.PathLike | None = None,
          jobs: int | None = None, timeout: float = TIMEOUT, seed: int | None = None,
          secret: bytes | None = None, student: str | Sequence[str] | None = None,
          dask: str | None = None, sandbox: str = "auto", progress: bool = False,
          roster: Sequence[Student] | str | os.PathLike | None = None,
          similarity: bool = True, naming: Naming | None = None, export: str = "auto",
          regrade: bool = False, warm_boxes: bool | None = None,
          secret_file: str | os.PathLike | None = None) -> list[Grade]:
    """Grade a class (:func:`grade_class`: the same files as ``gpsaccel grade`` writes); this
    run's grades, one per student graded, in the class's order.  OSError when a file could not
    be written (every other one is; ``grading.json`` names them, :func:`rewrite_class` writes
    the class-wide ones once there is room)."""
    graded = grade_class(submissions, name, out, jobs, timeout, seed, secret, student, dask,
                         sandbox, progress, roster, similarity, naming, export, regrade,
                         warm_boxes=warm_boxes, secret_file=secret_file)
    if graded.missing:
        raise OSError(f"not written in {graded.out}: " + ", ".join(
            f"{f} ({why})" for f, why in graded.missing.items()))
    return graded.grades


def _wanted(student: str | Sequence[str] | None) -> list[str] | None:
    """The students a regrade is for (None: the class)."""
    return None if student is None else [student] if isinstance(student, str) else list(student)


def _resumed(record: _Record, entries: list[Entry], wanted: Sequence[str] | None,
             folder: Path, settings: dict, regrade: bool) -> tuple[list[Entry], str]:
    """What this run grades and on which seed (``settings["seed"]`` set): the students
    ``wanted`` with the recorded seed; else, without a seed or ``regrade``, every notebook that
    changed since the recorded run (:meth:`_Record.reusable`), the others' grades kept; else
    all.  Returns the entries and the line that says what was kept ("" when nothing could
    be)."""
    seed, reuse = settings["seed"], ""
    if wanted is not None:  # by the name as found, its id or as it is shown
        entries = _chosen(entries, wanted, folder)
        seed = record.previous.get("seed") if seed is None else seed
    elif seed is None and not regrade:
        why = record.reusable(entries, settings)
        seed = record.previous.get("seed") if not why else None
        reuse = "" if not record.previous else f"nothing kept: {why}" if why else \
            f"{len(record.reused)} unchanged notebook(s) not graded again (their recorded " \
            f"grades kept; --regrade grades every one)"
    if not record.notebooks:
        record.notebooks = {e.id: _digest(e.path) for e in entries if e.path is not None}
    settings["seed"], _ = running.seed_of(seed)
    return entries, reuse


def _idle(record: dict, seed: int) -> bool:
    """A recorded run that graded nothing on ``seed`` (every grade kept, no regrade since, not
    interrupted): the run it kept them from is in ``earlier`` already, so a rerun replaces it
    rather than keeping it there once more."""
    return (record.get("graded") == 0 and record.get("seed") == seed
            and not record.get("regrades") and not record.get("interrupted"))


def _digest(path: Path) -> str:
    """The SHA-256 of a notebook (what a rerun compares): read in blocks, never parsed."""
    import hashlib

    with open(path, "rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()


def _fingerprint(settings: dict) -> str:
    """What a recorded grade depends on besides the notebook and the seed: the homework (its
    questions), the secret, the sandbox, the time limit, gpsaccel's version; hashed (the record
    holds no secret)."""
    import hashlib

    from gpsaccel._version import __version__

    text = json.dumps([settings["name"], (settings["secret"] or b"").hex(), settings["sandbox"],
                       settings["timeout"], __version__, possible_names(settings["name"])])
    return hashlib.sha256(text.encode()).hexdigest()


def possible_names(name: str) -> list[str]:
    """The homework's questions and points, and for a folder of the instructor's own the
    SHA-256 of its every file (a changed ``graded.py`` grades differently)."""
    import hashlib

    from gpsaccel.assignments.homework import own_folder

    out = [f"{q}={p}" for q, p in item.possible_of(name).items()]
    folder = own_folder(name)
    if folder is not None:
        out += [f"{f.relative_to(folder)}={hashlib.sha256(f.read_bytes()).hexdigest()}"
                for f in sorted(Path(folder).rglob("*.py")) + sorted(Path(folder).rglob("*.ipynb"))
                if "__pycache__" not in f.parts]
    return out


def _chosen(entries: Sequence[Entry], wanted: Sequence[str], folder: Path) -> list[Entry]:
    """The entries of the students ``wanted`` (each by the name as found, its id or as shown);
    ValueError naming any that has no submission."""
    missing = [w for w in wanted if not any(w in (e.student, e.id, e.shown) for e in entries)]
    if missing:
        raise ValueError(f"student: no submission of {', '.join(map(repr, missing))} in "
                         f"{folder}")
    return [e for e in entries if any(w in (e.student, e.id, e.shown) for w in wanted)]


def _check_mapped(entries: Sequence[Entry], students: Sequence[Student] | None,
                  layout: Export) -> None:
    """A roster that names none of the submissions is the wrong roster (or export): refused
    before any notebook runs."""
    if students and all(e.problem is not None and e.problem[0] in UNMAPPED for e in entries):
        raise ValueError(f"roster: none of the {len(entries)} submissions names a student of "
                         f"the roster (read as {'; '.join(layout.found) or 'given'}); give the "
                         f"roster the submissions were handed out from, or --export")


def _unmapped(students: Sequence[Student] | None, layout: Export) -> list[str]:
    """Lines for the instructor: how the export was read (the submissions it mapped to no one
    are named with the other empty cells: :func:`gpsaccel.classrun.statuses.unscored_lines`),
    and the roster's ids that no file or folder can be named (under a plain layout: they can
    never match)."""
    from gpsaccel.assignments.roster import unmatchable

    lines = [f"export read as {how}" for how in layout.found]
    never = unmatchable(students or [])
    if never and any(how.startswith("plain") for how in layout.found):
        lines.append("roster: no file or folder can be named as these ids, so no submission "
                     "can match them: " + ", ".join(repr(_untrusted.shown(x, 80))
                                                    for x in never))
    return lines


def _checked(folder: Path, out: str | os.PathLike | None, timeout: float,
             jobs: int | None) -> tuple[Path, int]:
    """The output folder and the jobs of :func:`grade_class`, its arguments checked."""
    if not folder.is_dir():
        raise ValueError(f"submissions must be a folder (a student's folder or notebook per "
                         f"student), got {folder}")
    if not (isinstance(timeout, (int, float)) and 0 < timeout < math.inf):
        raise ValueError(f"timeout must be a positive number of seconds, got {timeout!r}")
    jobs = running.jobs_of(jobs, min(4, running.cpus()))
    out = Path(out) if out is not None else default_out(folder)
    if out.resolve().is_relative_to(folder.resolve()):
        raise ValueError(f"out: {out} is inside the submissions folder; write the grades "
                         f"elsewhere (a student's files must not share a folder with them)")
    return out, jobs
