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

This module runs the class; grading one notebook is :mod:`gpsaccel.assignments.scoring`
(:func:`grade_notebook`, :class:`Grade`, the feedback) and writing what the run leaves is
:mod:`gpsaccel.assignments.results`.  Their public names stay reachable here.
"""

from __future__ import annotations

import math
import os
import secrets
import time
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path

from gpsaccel.assignments import notebook as nbm

# the names the CLI, the kit, benchmarks/ and the tests read as ``grading.NAME``
from gpsaccel.assignments.results import HEADER as HEADER
from gpsaccel.assignments.results import _Log
from gpsaccel.assignments.results import summary as summary
from gpsaccel.assignments.results import write_csv as write_csv
from gpsaccel.assignments.results import write_summary as write_summary
from gpsaccel.assignments.scoring import BOX_MEMORY as BOX_MEMORY
from gpsaccel.assignments.scoring import BOX_PROCESSES as BOX_PROCESSES
from gpsaccel.assignments.scoring import SKIP_MARK as SKIP_MARK
from gpsaccel.assignments.scoring import (
    SLACK,
    TIMEOUT,
    Grade,
    _possible,
    grade_notebook,
    questions_of,
    unusable,
)
from gpsaccel.assignments.scoring import VARIANT_MARK as VARIANT_MARK
from gpsaccel.assignments.scoring import _calls as _calls
from gpsaccel.assignments.scoring import _feedback_text as _feedback_text
from gpsaccel.assignments.scoring import assignment_module as assignment_module
from gpsaccel.assignments.scoring import is_otter_cell as is_otter_cell
from gpsaccel.assignments.scoring import student_variant as student_variant
from gpsaccel.assignments.submissions import Entry, find_submissions

#: Environment variable holding the instructor's secret (or use ``secret_file``).
SECRET_ENV = "GPSACCEL_GRADING_SECRET"


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
    notebook (``python benchmarks/grading.py --profile``), and what the homework's ``warm``
    makes (modules, inputs of its reads: never a reference answer, which exists only once a
    notebook's box is empty).  Nothing of a student's runs here."""
    questions_of(name)
    nbm.transform("%time x = 1\n!true")
    from gpsaccel import registry
    from gpsaccel.check.batch import warm as warm_check

    registry.problems()
    # what the questions' references import on first use, since `import gpsaccel` imports
    # nothing: scipy.stats and filterpy (the check's warm-up), scipy.integrate (CoopModel's truth)
    warm_check(registry.assignment(name).problem or "calibration")
    import scipy.integrate  # noqa: F401

    # the homework's own (graded.py's optional ``warm``): the modules its references import
    # (filterpy, scipy.stats: 1-2 CPU s a notebook) and the inputs its reads share
    homework_warm = getattr(assignment_module(name), "warm", None)
    if callable(homework_warm):
        homework_warm()


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

    jobs : notebooks at once (default: CPUs, at most 4); timeout : seconds of one notebook's
    box, on its fair clock (:mod:`gpsaccel.sandbox.clock`); seed : the fresh data's seed (default: random, or the recorded one when
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
