"""A class's grading record (:func:`gpsaccel.classrun.grading.grade_class`): what a run writes
after every notebook, and what a rerun into the same output keeps.

* :class:`Record` rewrites ``grades.csv`` and ``grades.json`` (each whole,
  :mod:`gpsaccel._atomic`) after every notebook with a row for every student, writes each
  student's feedback, ``grading.json`` (the class record, a regrade appended to its
  ``regrades``) and at the end the summary (:func:`summary`); a file the file system refuses is
  named in ``grading.json``'s ``missing`` (:class:`~gpsaccel.classrun.writing.Outputs`);
* :func:`resumed` says what a run grades and on which seed: the students asked for with the
  recorded seed, else every notebook whose SHA-256 changed since the recorded run
  (:meth:`Record.reusable`) when the homework, secret, sandbox, time limit and gpsaccel are
  those of the record (:func:`fingerprint`), else all.
"""

from __future__ import annotations

import functools
import json
import math
import time
from collections import Counter
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from gpsaccel import _untrusted
from gpsaccel.assignments import grading as item
from gpsaccel.assignments.scoring import Grade
from gpsaccel.classrun import running, statuses, writing
from gpsaccel.classrun.entries import Entry


def read_json(path: Path, default: Any) -> Any:
    """The JSON a run wrote at ``path``, or ``default`` where there is no file."""
    return json.loads(path.read_text(encoding="utf-8")) if path.is_file() else default


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


class Record:
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
        self.previous = read_json(self.record, {})
        if not isinstance(self.previous, dict):
            self.previous = {}
        # a regrade keeps what the folder still misses (another student's feedback)
        kept = self.previous.get("missing") if student and isinstance(self.previous, dict) \
            else None
        self.outputs = writing.Outputs(out, kept if isinstance(kept, dict) else None)
        try:
            self.old = [Grade(**d) for d in read_json(self.kept_path, [])]
        except TypeError:  # grades.json of another version: nothing is reused from it
            self.old = []
        for g in self.old:  # a row of an earlier version, without its id
            g.id = g.id or _untrusted.student_id(g.student)
        self.notebooks: dict[str, str] = {}
        self.reused: dict[int, Grade] = {}
        self.entries: Sequence[Entry] = []
        self.grades: list[Grade | None] = []
        self.t0 = time.perf_counter()

    def reusable(self, entries: Sequence[Entry], settings: dict) -> str:
        """Fill :attr:`reused` with the recorded grade of every entry whose notebook is
        unchanged (its SHA-256) under the recorded seed and settings; "" or why nothing is."""
        self.notebooks = {e.id: _digest(e.path) for e in entries if e.path is not None}
        before = self.previous.get("reuse")
        if not self.previous.get("seed") or before != fingerprint(settings):
            return ("no earlier run in this folder" if not self.previous else
                    _changed(self.previous, settings))
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
        if self.student is not None:  # a regrade records the ids, however they were named
            info["student"] = [e.student for e in entries]
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
        writing.dump_json(self.record, self.info, indent=2, mode=writing.PRIVATE)  # the seed
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
                           indent=2, mode=writing.PRIVATE)


def resumed(record: Record, entries: list[Entry], wanted: Sequence[str] | None,
             folder: Path, settings: dict, regrade: bool) -> tuple[list[Entry], str]:
    """What this run grades and on which seed (``settings["seed"]`` set): the students
    ``wanted`` with the recorded seed; else, without a seed or ``regrade``, every notebook that
    changed since the recorded run (:meth:`Record.reusable`), the others' grades kept; else
    all.  Returns the entries and the line that says what was kept ("" when nothing could
    be)."""
    seed, reuse = settings["seed"], ""
    if wanted is not None:  # by the name as found, its id or as it is shown
        entries = _chosen(entries, wanted, folder)
        seed = record.previous.get("seed") if seed is None else seed
        if record.previous.get("reuse") not in (None, fingerprint(settings)):  # said, not refused
            reuse = "regraded under other settings than the class: " + \
                _changed(record.previous, settings)
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


def _chosen(entries: Sequence[Entry], wanted: Sequence[str], folder: Path) -> list[Entry]:
    """The entries of the students ``wanted`` (each by the name as found, its id or as shown,
    or the export's own name for it: Canvas's file, Moodle's folder); ValueError naming any that
    has no submission."""
    def names(e: Entry) -> tuple[str, ...]:
        return e.student, e.id, e.shown, e.found

    missing = [w for w in wanted if not any(w in names(e) for e in entries)]
    if missing:
        raise ValueError(f"student: no submission of {', '.join(map(repr, missing))} in "
                         f"{folder}")
    return [e for e in entries if any(w in names(e) for w in wanted)]


def _idle(record: dict, seed: int) -> bool:
    """A recorded run that graded nothing on ``seed`` (every grade kept, no regrade since, not
    interrupted): the run it kept them from is in ``earlier`` already, so a rerun replaces it
    rather than keeping it there once more."""
    return (record.get("graded") == 0 and record.get("seed") == seed
            and not record.get("regrades") and not record.get("interrupted"))


def _changed(previous: dict, settings: dict) -> str:
    """Why a recorded run's grades cannot be kept: the settings it records that differ now (the
    flag that brings them back), else what it records only as a hash (the secret, the homework's
    files, gpsaccel)."""
    said = {"assignment": ("homework", "--assignment {}"), "sandbox": ("sandbox", "--sandbox {}"),
            "timeout": ("time limit", "--timeout {:g}")}
    now = {"assignment": settings["name"], "sandbox": settings["sandbox"],
           "timeout": settings["timeout"]}
    differ = [(what, flag.format(previous[k]), previous[k], now[k])
              for k, (what, flag) in said.items() if k in previous and previous[k] != now[k]]

    def shown(v: object) -> str:
        return f"{v:g} s" if isinstance(v, (int, float)) else str(v)

    if differ:
        return "the earlier run's " + ", ".join(
            f"{what} was {shown(was)}, now {shown(new)} (give {flag} to match it)"
            for what, flag, was, new in differ)
    return "the earlier run's secret, homework files or gpsaccel (its version or its files) differ"


def _digest(path: Path) -> str:
    """The SHA-256 of a notebook (what a rerun compares): read in blocks, never parsed."""
    import hashlib

    with open(path, "rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()


def fingerprint(settings: dict) -> str:
    """What a recorded grade depends on besides the notebook and the seed: the homework (its
    questions), the secret, the sandbox, the time limit, gpsaccel (its version and
    :func:`package_digest`); hashed (the record holds no secret)."""
    import hashlib

    from gpsaccel._version import __version__

    text = json.dumps([settings["name"], (settings["secret"] or b"").hex(), settings["sandbox"],
                       settings["timeout"], __version__, package_digest(),
                       possible_names(settings["name"])])
    return hashlib.sha256(text.encode()).hexdigest()


@functools.lru_cache(maxsize=1)
def package_digest() -> str:
    """The SHA-256 of the grader itself: every file of the installed package (its code, and the
    homework and checks it grades with), ``__pycache__`` aside.  A wheel rebuilt under the same
    version string with other code grades otherwise, so a rerun under it grades again rather
    than keep the old code's grades (the version alone let it keep them)."""
    import hashlib

    import gpsaccel

    root = Path(gpsaccel.__file__).parent
    h = hashlib.sha256()
    for path in sorted(root.rglob("*")):
        if path.is_file() and "__pycache__" not in path.parts:
            h.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes())
    return h.hexdigest()


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
