"""Check a whole class at once (``gpsaccel check DIR ...``), in a batch nothing can take down.

What a submission is: each top-level entry of a folder given on the command line is one
submission, a ``.py`` file or a folder (one student's: the file that defines ``kalman_filter`` and
its helpers and data; see :func:`gpsaccel.sandbox.load_submission`).  A file given on the
command line is one submission.  A helper module inside a student's folder is part of that
submission, never a failing submission of its own.

How the batch runs (:func:`check_many` with the default ``executor="processes"``), through the
sandbox's one pool (:func:`gpsaccel.sandbox.run_items`, which grading uses too): each check
runs in a process of its own, forked for that one file (``--workers 1`` too), which runs the
student's box, then computes the optimal answer, then hands back a plain dictionary over a pipe and
exits.  So:

- a check whose process dies (a student who killed its parent, a crash of the checker) is
  recorded as ``checker-error`` for that file only, and the batch goes on: there is no pool to
  break, the next file gets a fresh process;
- the batch's own process is a child subreaper while it runs: whatever a dead check leaves behind
  (a box whose parent was killed) is re-parented to it and killed; at the end, every process it
  started is confirmed gone before :func:`check_many` returns;
- Ctrl-C kills every check and every process of the students', and raises :class:`Interrupted`
  holding the results finished so far.

``executor=None`` checks the files one after the other in this process (each still in its box);
a Dask specification (``"dask-local"``, ``"tcp://..."``) or an ``Executor`` sends each check to
that executor (its workers run the boxes; a worker killed by a student is then Dask's to handle),
with the same deadline per check (:data:`CHECK_SLACK` beyond the time limit).
"""

from __future__ import annotations

import json
import os
import secrets
import unicodedata
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

from gpsaccel import _validation as _v
from gpsaccel import registry
from gpsaccel import sandbox as sb
from gpsaccel._atomic import write_text
from gpsaccel.check.problems import submission
from gpsaccel.check.report import Report, no_verdict
from gpsaccel.sandbox.outcomes import OUTCOMES

#: Seconds a check's process may take beyond the student's time limit (simulating the data,
#: comparing, diagnosing) before it is killed as a checker error.
CHECK_SLACK = 120.0


class Interrupted(Exception):
    """The batch was interrupted (Ctrl-C); ``results`` holds the checks that finished, in order
    (None where a check did not finish)."""

    def __init__(self, results: list[dict | None]) -> None:
        super().__init__("interrupted")
        self.results = results


def find_submissions(paths: Iterable[str | os.PathLike]) -> tuple[list[Path], list[str]]:
    """The submissions named by ``paths``: a file is one; a folder holds one per top-level entry
    (a ``.py`` file, or a sub-folder for one student).  Returns (submissions, notes on what was
    skipped).

    Left out of a folder: hidden entries, ``__pycache__``, ``__init__.py`` and files that are not
    ``.py``.  A misnamed filter stays in (it must show up as ``no-kalman-filter``, not vanish),
    and so does a symbolic link, whatever it points to (its check refuses it: ``link-refused``;
    ``mallory.py -> alice.py`` is not a second passing submission).
    """
    found: list[Path] = []
    notes: list[str] = []
    for p in map(Path, paths):
        if not p.is_dir():
            found.append(p)  # a missing file becomes a "not-found" finding, not an error here
            continue
        entries = sorted(p.iterdir())
        n = len(found)
        for e in entries:
            if e.name.startswith(".") or e.name == "__pycache__":
                continue
            if e.is_symlink():  # never followed: the check refuses it with a finding
                found.append(e)
            elif e.is_dir():
                found.append(e)
            elif e.name == "__init__.py":
                notes.append(f"{e}: skipped (a package's __init__.py)")
            elif e.suffix == ".py":
                found.append(e)
            else:
                notes.append(f"{e}: skipped (not a .py file or a folder)")
        if len(found) == n:
            notes.append(f"{p}: no .py file or folder in it")
    return list(dict.fromkeys(found)), notes


def _check_one(path: str, n_runs: int | None, seed: int, timeout: float,
               **options: Any) -> dict:
    return student_result(submission(path, n_runs=n_runs, seed=seed, timeout=timeout,
                                     **options))


def student_result(report: Report) -> dict:
    """What ``gpsaccel check`` prints and writes of one report: the student's projection
    (:meth:`~gpsaccel.check.report.Report.for_student`), its JSON and its table's text."""
    student = report.for_student()
    out = student.to_dict()
    out["text"] = str(student)
    return out


def checker_error(path: Path | str, message: str) -> dict:
    """The result of a check that did not complete (its process died, or the checker failed)."""
    path = Path(path)
    return {"subject": path.name, "passed": False, "codes": ["checker-error"],
            "findings": [{"code": "checker-error", "severity": "error", "message": message}],
            "details": {"path": str(path)}, "seconds": 0.0,
            "text": f"{path.name}: FAILED (checker-error)\n  - {message}"}


def secret_seed() -> int:
    """A seed no student can predict (63 bits from :mod:`secrets`): the default of a class's
    check, so answers precomputed at home for a public seed pass nothing.  It is recorded in the
    results (``settings.seed``, ``details.seed``), so any verdict can be reproduced."""
    return secrets.randbits(63)


def check_many(paths: Sequence[str | os.PathLike], n_runs: int | None = None,
               seed: int | None = None,
               timeout: float = 60, executor: object = "processes",
               max_workers: int | None = None, sandbox: str = "auto",
               limits: sb.Limits | None = None, allow_gpsaccel: bool = False,
               on_result: Callable[[dict], None] | None = None,
               problem: str = "calibration", allow_unsafe_basic: bool = False) -> list[dict]:
    """Check every submission of ``paths`` (see :func:`find_submissions`); one dict per
    submission, in order.

    ``executor``: ``"processes"`` (default; a process per check, see the module docstring),
    ``None`` (in this process, one after the other) or anything
    :func:`gpsaccel.executors.resolve_executor` accepts.  ``on_result(result)`` is called as each
    check finishes (e.g. to append it to a log).  Every submission sees the same realizations
    (``seed``), so their results are comparable.  ``problem`` is a name of
    :func:`gpsaccel.registry.problems` ("calibration", "coop", "ship", "tracker", ...); ``n_runs``
    None is the problem's default.  ``n_runs``,
    ``seed`` and ``timeout`` are checked here, before any submission runs (a bad one would
    otherwise fail every check alike).  ``seed`` None (the default) is :func:`secret_seed`: a
    class is graded on data no student could know in advance; pass a seed to reproduce a run.
    The basic sandbox is refused unless it is safe here (:func:`gpsaccel.sandbox.
    refuse_unsafe_basic`: the checker runs as root) or ``allow_unsafe_basic``.  Raises
    :class:`Interrupted` on Ctrl-C.
    """
    n_runs = None if n_runs is None else _v.integer("n_runs", n_runs, minimum=2)
    problem = _v.choice("problem", problem, registry.problems())
    seed = secret_seed() if seed is None else _v.integer("seed", seed, minimum=0)
    timeout = _v.positive_float("timeout", timeout)
    files, _ = find_submissions(paths)
    backend = sb.resolve_backend(sandbox)  # once, and a clear error before anything runs
    sb.refuse_unsafe_basic(backend, allow_unsafe_basic)
    options: dict[str, Any] = {"sandbox": backend, "limits": limits, "allow_gpsaccel": allow_gpsaccel,
               "problem": problem}
    args = (n_runs, seed, timeout)
    if executor in ("processes", "local"):
        executor = None  # the sandbox's pool: a process forked per check
    elif executor is None:
        executor = "inprocess"
    warm(problem)  # before the pool forks: every check inherits the imports
    return _isolated(files, args, options, max_workers or os.cpu_count() or 1, timeout,
                     on_result, executor)


def warm(problem: str) -> None:
    """Import here what checking a file of ``problem`` imports on first use (scipy.special for
    the χ² bounds, the system's catalogue of mistakes), so each check's forked process inherits it
    instead of importing it again (``python benchmarks/per_file.py``).  No check imports
    filterpy or scipy.stats (1.5 CPU s), so neither is imported here.  Only modules: nothing is
    computed, so no answer exists here before a file's box is empty."""
    import importlib
    import importlib.util

    registry.problem(problem)
    system = registry.entry(problem).system
    names = ["scipy.special"]
    if system and system.isidentifier() and importlib.util.find_spec(f"gpsaccel.{system}") \
            and importlib.util.find_spec(f"gpsaccel.{system}.mistakes"):
        names.append(f"gpsaccel.{system}.mistakes")
    for name in names:
        importlib.import_module(name)


# ------------------------------------------------------------------ a process per check
def _check_item(item: tuple[str, tuple, dict]) -> dict:
    """One check in its item's process (:mod:`gpsaccel.sandbox.pool`); the checker's own error is
    that file's result."""
    path, args, options = item
    try:
        return _check_one(path, *args, **options)
    except Exception as exc:  # noqa: BLE001 - a bug of the checker: one file's error
        return checker_error(path, f"the checker failed: {type(exc).__name__}: {exc}")


def _lost(path: Path, lost: sb.Lost, timeout: float) -> dict:
    # the sandbox's table of outcomes words each reason (lost.<reason>)
    known = OUTCOMES.get(f"lost.{lost.reason}")
    why = (known.finding if known else "{detail}").format(
        detail=lost.detail, limit=timeout + CHECK_SLACK, slack=CHECK_SLACK)
    return checker_error(path, why)


def _isolated(files: list[Path], args: tuple, options: dict, workers: int, timeout: float,
              on_result: Callable[[dict], None] | None, executor: object = None) -> list[dict]:
    """Every check through the sandbox's one pool: a process per file (``executor`` None) or
    the executor's workers, each within the time limit plus :data:`CHECK_SLACK`."""
    results: list[dict | None] = [None] * len(files)

    def done(i: int, out: object) -> None:
        result = out if isinstance(out, dict) else _lost(files[i], out, timeout) \
            if isinstance(out, sb.Lost) else _lost(files[i], sb.Lost("not-a-report"), timeout)
        results[i] = result
        if on_result is not None:
            on_result(result)

    items = [(str(f), args, options) for f in files]
    try:
        sb.run_items(_check_item, items, workers, timeout + CHECK_SLACK, done, executor)
    except KeyboardInterrupt:
        raise Interrupted(results) from None
    return [r for r in results if r is not None]


# ------------------------------------------------------------------------------- output
#: Longest submission name shown in the table (the JSON keeps it whole).
NAME_WIDTH = 80


def printable(text: str, keep_newlines: bool = False) -> str:
    """``text`` as it may reach a terminal: every control, format or separator character
    (C0/C1 controls, ESC and so every escape sequence, bidirectional overrides, U+2028/U+2029,
    unassigned code points) shown as ``\\x..``/``\\u....``; newlines kept only when asked."""
    out = []
    for c in text:
        if keep_newlines and c == "\n":
            out.append(c)
        elif unicodedata.category(c)[0] == "C" or unicodedata.category(c) in ("Zl", "Zp"):
            out.append(f"\\x{ord(c):02x}" if ord(c) < 256 else f"\\u{ord(c):04x}"
                       if ord(c) < 0x10000 else f"\\U{ord(c):08x}")
        else:
            out.append(c)
    return "".join(out)


def _shown_name(r: dict) -> str:
    name = printable(str(r["details"].get("path", r["subject"])))
    return name if len(name) <= NAME_WIDTH else name[:NAME_WIDTH - 1] + "…"


def table(results: Sequence[dict]) -> str:
    """The instructor's table: submission, passed, codes, seconds (names made printable:
    :func:`printable`).  "again" where the check gave no verdict (:func:`~gpsaccel.check.report
    .no_verdict`): not the student's fail."""
    names = [_shown_name(r) for r in results]
    name_w = max([len(n) for n in names] + [10])
    head = f"{'submission':<{name_w}}  {'passed':<6}  {'seconds':>7}  codes"
    lines = [head, "-" * max(len(head), 40)]
    again = [r["passed"] is not True and no_verdict(False, list(r["codes"])) for r in results]
    for name, r, a in zip(names, results, again, strict=True):
        lines.append(f"{name:<{name_w}}  "
                     f"{'yes' if r['passed'] is True else 'again' if a else 'NO':<6}  "
                     f"{r['seconds']:7.1f}  {printable(', '.join(r['codes'])) or '-'}")
    n_pass = sum(r["passed"] is True for r in results)
    summary = f"{n_pass} of {len(results)} passed"
    if any(again):
        summary += (f"; {sum(again)} without a verdict (the machine or the checker, not the "
                    f"student's code: check them again)")
    lines.append(summary)
    return "\n".join(lines)


def write_json(results: Sequence[dict], path: str | os.PathLike, **settings: object) -> Path:
    """Write ``{"settings": ..., "results": [...]}`` to ``path`` (UTF-8, indented), atomically
    (:mod:`gpsaccel._atomic`: a temporary file in the same folder, renamed once complete)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_text(path, json.dumps({"settings": settings, "results": list(results)}, indent=2,
                                ensure_ascii=False))  # whole or not at all
    return path


def log_path(json_path: str | os.PathLike) -> Path:
    """Where results are appended as each check finishes: ``results.json`` -> ``results.jsonl``."""
    p = Path(json_path)
    return p.with_name(p.stem + ".jsonl")


def appender(path: str | os.PathLike) -> Callable[[dict], None]:
    """``on_result`` that appends each result as one JSON line to ``path`` (started empty)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("", encoding="utf-8")

    def append(result: dict) -> None:
        with open(path, "a", encoding="utf-8") as f:
            # ASCII: no raw U+2028/U+2029, U+0085 or other separator a line reader splits on
            f.write(json.dumps(result, ensure_ascii=True) + "\n")
            f.flush()
            os.fsync(f.fileno())

    return append
