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
* ``student=ID`` regrades one student with the recorded seed: the old row stays until the new
  one is written, and the regrade is appended to ``grading.json``'s ``regrades`` (the class
  record is kept);
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

import numpy as np

from gpsaccel import _untrusted
from gpsaccel.assignments import grading as item
from gpsaccel.assignments.roster import Student, read_roster
from gpsaccel.assignments.scoring import TIMEOUT, Grade
from gpsaccel.classrun import classwide, running, writing
from gpsaccel.classrun.entries import Entry, Naming, notebooks, walk


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

    def __init__(self, out: Path, possible: dict[str, float], student: str | None,
                 progress: bool = False) -> None:
        self.out, self.possible, self.student, self.progress = out, possible, student, progress
        self.record = out / "grading.json"
        self.kept_path = out / "grades.json"
        self.feedback = out / "feedback"
        self.previous = self._json(self.record, {})
        # a regrade keeps what the folder still misses (another student's feedback)
        kept = self.previous.get("missing") if student and isinstance(self.previous, dict) \
            else None
        self.outputs = writing.Outputs(out, kept if isinstance(kept, dict) else None)
        self.old = [Grade(**d) for d in self._json(self.kept_path, [])] if student else []
        for g in self.old:  # a row of an earlier version, without its id
            g.id = g.id or _untrusted.student_id(g.student)
        self.entries: Sequence[Entry] = []
        self.grades: list[Grade | None] = []
        self.t0 = time.perf_counter()

    @staticmethod
    def _json(path: Path, default):  # noqa: ANN001, ANN205 - a dict or a list
        return json.loads(path.read_text(encoding="utf-8")) if path.is_file() else default

    def start(self, entries: Sequence[Entry], info: dict) -> None:
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
        kept = [g for g in self.old if g.id not in new]
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
        entry["graded"] = sum(g is not None for g in self.grades)
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


def grade_class(submissions: str | os.PathLike, name: str, out: str | os.PathLike | None = None,
                jobs: int | None = None, timeout: float = TIMEOUT, seed: int | None = None,
                secret: bytes | None = None, student: str | None = None, dask: str | None = None,
                sandbox: str = "auto", progress: bool = False,
                roster: Sequence[Student] | str | os.PathLike | None = None,
                similarity: bool = True, naming: Naming | None = None) -> Graded:
    """Grade every student of ``submissions`` for homework ``name`` and write every file
    (module docstring); :func:`grade` is this with the grades alone.

    jobs : notebooks at once (default: CPUs, at most 4); timeout : seconds of one notebook's
    box, on its fair clock (:mod:`gpsaccel.sandbox.clock`); seed : the fresh data's seed
    (default: secret, or the recorded one when regrading one ``student``); secret : the
    instructor's secret for per-student variants (None: every student gets the public notebook's
    numbers); dask : a Dask address or "dask-local"; progress : a tqdm bar on stderr when it is
    a terminal; roster : the class roster (students, or its file: :func:`~gpsaccel.assignments
    .roster.read_roster`), for the LMS gradebooks; similarity : write the similarity report;
    naming : who each entry of the export is (:data:`~gpsaccel.classrun.entries.Naming`;
    default: the folder's or the notebook's name).
    """
    folder = Path(submissions)
    out, jobs = _checked(folder, out, timeout, jobs)
    students = read_roster(roster) if isinstance(roster, (str, os.PathLike)) else roster
    possible = item.possible_of(name)
    entries, notes = walk(folder, notebooks(name), naming,
                          known={s.id for s in students} if students else ())
    if not entries:
        raise ValueError(f"submissions: no student's folder or notebook in {folder}")
    out.mkdir(parents=True, exist_ok=True)
    record = _Record(out, possible, student, progress)
    if student is not None:  # by the name as found, its id or as it is shown
        entries = [e for e in entries if student in (e.student, e.id, e.shown)]
        if not entries:
            raise ValueError(f"student: no submission of {student!r} in {folder}")
        seed = record.previous.get("seed") if seed is None else seed
    seed, _ = running.seed_of(seed)
    backend = running.backend_of(sandbox)  # a class is not graded where basic cannot isolate it
    settings = {"name": name, "seed": seed, "secret": secret, "sandbox": backend,
                "timeout": float(timeout)}
    record.start(entries, {
        "assignment": name, "seed": seed, "sandbox": backend, "timeout": timeout,
        "variants": "per student (HMAC of the id under the instructor's secret)" if secret
        else "none (no secret given: every student has the public notebook's numbers)",
        "questions": possible, "started": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "student": student, "skipped": notes})
    try:
        running.run(_Grade(folder, settings), entries, jobs, dask or "processes", record.done)
    except BaseException:  # Ctrl-C, a lost cluster: what is done stays, the rest not-graded
        record.finish(interrupted=True)
        raise
    rows = record.finish(False, classwide.files(students is not None, similarity))
    lines = classwide.write(folder, out, name, rows, possible, students, similarity,
                            record.outputs)
    record.save()
    return Graded([g for g in record.grades if g is not None], rows, out, lines,
                  dict(record.outputs.missing))


def rewrite_class(submissions: str | os.PathLike, name: str, out: str | os.PathLike | None = None,
                  roster: Sequence[Student] | str | os.PathLike | None = None,
                  similarity: bool = True) -> Graded:
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
    lines = classwide.write(folder, out, name, rows, possible, students, similarity, outputs)
    info.setdefault("rewrites", []).append({
        "started": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "roster": students is not None, "similarity": similarity})
    info["missing"] = dict(outputs.missing)
    outputs.write(["grading.json"], writing.dump_json, out / "grading.json", info, indent=2)
    return Graded([], rows, out, lines, dict(outputs.missing))


def grade(submissions: str | os.PathLike, name: str, out: str | os.PathLike | None = None,
          jobs: int | None = None, timeout: float = TIMEOUT, seed: int | None = None,
          secret: bytes | None = None, student: str | None = None, dask: str | None = None,
          sandbox: str = "auto", progress: bool = False,
          roster: Sequence[Student] | str | os.PathLike | None = None,
          similarity: bool = True, naming: Naming | None = None) -> list[Grade]:
    """Grade a class (:func:`grade_class`: the same files as ``gpsaccel grade`` writes); this
    run's grades, one per student graded, in the class's order.  OSError when a file could not
    be written (every other one is; ``grading.json`` names them, :func:`rewrite_class` writes
    the class-wide ones once there is room)."""
    graded = grade_class(submissions, name, out, jobs, timeout, seed, secret, student, dask,
                         sandbox, progress, roster, similarity, naming)
    if graded.missing:
        raise OSError(f"not written in {graded.out}: " + ", ".join(
            f"{f} ({why})" for f, why in graded.missing.items()))
    return graded.grades


def _checked(folder: Path, out: str | os.PathLike | None, timeout: float, jobs: int | None
             ) -> tuple[Path, int]:
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
