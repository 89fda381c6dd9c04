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
  graded nothing on the same seed (:mod:`gpsaccel.classrun.record`);
* ``dask=...`` sends each notebook to a Dask cluster (same function, same seed: same grades)
  with the same deadline;
* a class handed per-student variants is never graded without the secret: with no secret, a
  run is refused before any box starts when the earlier run in the same output graded variants
  (the instructor's own record) or when at least :data:`DECLARING` notebooks, and more than half
  of them, declare numbers of their own (:func:`gpsaccel.assignments.grading.declares_variant`);
  the notebooks are the students', so one student can neither stop a class graded on the public
  numbers by adding a variant nor, by deleting theirs, gain anything in a class handed variants
  (graded with the secret, every student's numbers come from it).  ``no_variants=True``
  (``--no-variants``) grades on the public numbers all the same.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from gpsaccel import _untrusted
from gpsaccel.assignments import grading as item
from gpsaccel.assignments.roster import Student, read_roster
from gpsaccel.assignments.scoring import TIMEOUT, Grade
from gpsaccel.classrun import classwide, running, writing
from gpsaccel.classrun.classwide import UNMAPPED
from gpsaccel.classrun.entries import Collision, Entry, Naming, Superseded, notebooks, walk
from gpsaccel.classrun.exports import Export
from gpsaccel.classrun.record import (  # noqa: F401 - possible_names: re-exported
    SUMMARY,
    Record,
    fingerprint,
    possible_names,
    read_json,
    resumed,
    summary,
)


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
                secret_file: str | os.PathLike | None = None,
                no_variants: bool = False) -> Graded:
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
    no_variants : grade every notebook on the public notebook's numbers although they declare
    variants of their own (without it, and without a secret, such a class is refused: module
    docstring); an error with a secret.
    """
    folder = Path(submissions)
    out, jobs = _checked(folder, out, timeout, jobs)
    backend = running.backend_of(sandbox)  # a class is not graded where basic cannot isolate it
    secret = _secret(secret, secret_file, backend, no_variants)
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
    declared = _check_variants(entries, name, out, bool(secret) or no_variants)
    out.mkdir(parents=True, exist_ok=True)
    wanted = _wanted(student)
    record = Record(out, possible, wanted, progress)
    settings: dict[str, Any] = {"name": name, "seed": seed, "secret": secret,
                                "sandbox": backend, "timeout": float(timeout)}
    entries, reuse = resumed(record, entries, wanted, folder, settings, regrade)
    seed = settings["seed"]  # drawn by running.seed_of where none was given or recorded
    todo = [i for i in range(len(entries)) if i not in record.reused]
    warm = running.warm_of(warm_boxes, dask or "processes",
                           sum(entries[i].path is not None for i in todo))
    record.start(entries, {
        "assignment": name, "seed": seed, "sandbox": backend, "timeout": timeout,
        "variants": _variants(secret, no_variants), "boxes": "warm" if warm else "cold",
        "questions": possible,
        "started": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "student": wanted,
        "export": layout.found, "skipped": notes, "reuse": fingerprint(settings)})
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
    lines += declared + _closing(students, layout, reuse, notes)
    record.save()
    return Graded([g for i, g in enumerate(record.grades) if g is not None
                   and i not in record.reused], rows, out, lines, dict(record.outputs.missing))


#: grading.json's ``variants`` of a run graded with the secret: what a later run reads back
#: (:func:`_recorded_variants`), one string for both
PER_STUDENT = "per student (HMAC of the id under the instructor's secret)"


def _variants(secret: bytes | None, no_variants: bool = False) -> str:
    return (PER_STUDENT if secret
            else "none (--no-variants: every student graded on the public notebook's numbers)"
            if no_variants else
            "none (no secret given: every student has the public notebook's numbers)")


#: Fewest notebooks declaring a variant of their own that tell a class handed variants (with
#: more than half of the class's notebooks): a single student never stops a class.
DECLARING = 2


def _secret(secret: bytes | None, secret_file: str | os.PathLike | None, backend: str,
            no_variants: bool) -> bytes | None:
    """The instructor's secret (:func:`gpsaccel.classrun.running.secret_of`); an error beside
    ``no_variants``, which grades without one."""
    secret = running.secret_of(secret, secret_file, backend)
    if no_variants and secret:
        raise ValueError("no_variants (--no-variants) grades on the public notebook's numbers: "
                         "leave out the secret (secret_file, --secret-file, "
                         "$GPSACCEL_GRADING_SECRET)")
    return secret


def _check_variants(entries: Sequence[Entry], name: str, out: Path, told: bool) -> list[str]:
    """Refuse to grade without the secret a class handed per-student variants (module
    docstring), before any box starts; else the line that says how many notebooks declare a
    variant all the same (none: nothing to say).  Nothing read where the instructor ``told``
    (a secret, or ``no_variants``) or the homework has no variants."""
    if told or not item.assignment_module(name).DEFAULT_VARIANT:
        return []
    papers = [e.path for e in entries if e.path is not None]
    declared = sum(item.declares_variant(p, name) is True for p in papers)
    recorded = _recorded_variants(out, name)
    if recorded or (declared >= DECLARING and 2 * declared > len(papers)):
        why = (f"the earlier run in {out} graded per-student variants (its grading.json)"
               + (f", and {declared} of the {len(papers)} notebooks declare one of their own"
                  if declared else "") if recorded else
               f"{declared} of the {len(papers)} notebooks declare a variant of their own "
               f"(handed out by `gpsaccel assignment --roster --secret-file`)")
        raise ValueError(f"secret_file (--secret-file): {why}, and no secret was given: every "
                         f"notebook would be graded on the public notebook's numbers. Give the "
                         f"secret they were handed out with (--secret-file FILE or "
                         f"$GPSACCEL_GRADING_SECRET), or no_variants=True (--no-variants) to "
                         f"grade on the public numbers all the same")
    return [f"variants: {declared} of the {len(papers)} notebooks declare numbers of their "
            f"own, too few to tell a class handed variants (at least {DECLARING} and more than "
            f"half); all graded on the public notebook's numbers (handed out with variants? "
            f"grade again with --secret-file)"] if declared else []


def _recorded_variants(out: Path, name: str) -> bool:
    """Whether the run recorded in ``out`` (the instructor's folder) graded ``name`` with
    per-student variants."""
    try:
        info = read_json(out / "grading.json", None)
    except (OSError, ValueError):  # unreadable: the record's own reading says so
        return False
    return (isinstance(info, dict) and info.get("assignment") == name
            and info.get("variants") == PER_STUDENT)


def _closing(students: Sequence[Student] | None, layout: Export, reuse: str,
             notes: Sequence[object]) -> list[str]:
    """The run's last lines: roster rows no submission matched, what a rerun reused, the
    superseded submissions left out, the submissions that show one name under different
    numbers of the export."""
    return (_unmapped(students, layout) + ([f"rerun: {reuse}"] if reuse else [])
            + [f"not graded: {n} (grading.json's skipped)" for n in notes
               if isinstance(n, Superseded)]
            + [f"id-collision: {n}" for n in notes if isinstance(n, Collision)])


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
    info = read_json(out / "grading.json", None)
    if not isinstance(info, dict):
        raise ValueError(f"out: no grading.json in {out}: grade the class first (without "
                         f"--from-grades)")
    if info.get("assignment") != name:
        raise ValueError(f"assignment: {out} holds the grades of {info.get('assignment')!r}, "
                         f"not {name!r}")
    before = info.get("missing")
    before = before if isinstance(before, dict) else {}
    kept = read_json(out / "grades.json", None)
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
    outputs.write(["grading.json"], writing.dump_json, out / "grading.json", info, indent=2,
                  mode=writing.PRIVATE)
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
          secret_file: str | os.PathLike | None = None, no_variants: bool = False
          ) -> list[Grade]:
    """Grade a class (:func:`grade_class`: the same files as ``gpsaccel grade`` writes); this
    run's grades, one per student graded, in the class's order.  OSError when a file could not
    be written (every other one is; ``grading.json`` names them, :func:`rewrite_class` writes
    the class-wide ones once there is room)."""
    graded = grade_class(submissions, name, out, jobs, timeout, seed, secret, student, dask,
                         sandbox, progress, roster, similarity, naming, export, regrade,
                         warm_boxes=warm_boxes, secret_file=secret_file,
                         no_variants=no_variants)
    if graded.missing:
        raise OSError(f"not written in {graded.out}: " + ", ".join(
            f"{f} ({why})" for f, why in graded.missing.items()))
    return graded.grades


def _wanted(student: str | Sequence[str] | None) -> list[str] | None:
    """The students a regrade is for (None: the class)."""
    return None if student is None else [student] if isinstance(student, str) else list(student)


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
        unzip = (f": unzip the LMS's download first (unzip -d {folder.with_suffix('')} {folder})"
                 if folder.suffix.lower() == ".zip" else "")
        raise ValueError(f"submissions must be a folder (a student's folder or notebook per "
                         f"student), got {folder}{unzip}")
    if not (isinstance(timeout, (int, float)) and 0 < timeout < math.inf):
        raise ValueError(f"timeout must be a positive number of seconds, got {timeout!r}")
    jobs = running.jobs_of(jobs, min(4, running.cpus()))
    out = Path(out) if out is not None else default_out(folder)
    if out.resolve().is_relative_to(folder.resolve()):
        raise ValueError(f"out: {out} is inside the submissions folder; write the grades "
                         f"elsewhere (a student's files must not share a folder with them)")
    return out, jobs
