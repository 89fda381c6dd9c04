"""One submission's check as an item of a class's run (``gpsaccel check DIR``).

The class run itself (the walk of the folder, the seed, the pool, the results files and the
table) is :mod:`gpsaccel.classrun`; this module is what it asks of the checker for one file: the
check (:func:`check_file`, in the item's own process, which runs the student's box and then
computes the answers), what the instructor's table and JSON keep of its report
(:func:`student_result`), the result of a check that did not complete (:func:`unchecked`), and
the imports and the data-free part every check needs (:func:`warm`), made once before the pool
forks.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from gpsaccel import registry
from gpsaccel.check.problems import get, submission
from gpsaccel.check.report import Report

#: Seconds a check's process may take beyond the student's time limit (simulating the data,
#: comparing, diagnosing) before it is killed as a checker error.
CHECK_SLACK = 120.0


def check_file(path: str | os.PathLike, n_runs: int | None, seed: int, timeout: float,
               **options: Any) -> dict:
    """The check of one submission (:func:`gpsaccel.check.submission`; ``options`` are its own:
    problem, sandbox, limits, allow_gpsaccel) as :func:`student_result`."""
    return student_result(submission(path, n_runs=n_runs, seed=seed, timeout=timeout,
                                     **options))


def student_result(report: Report) -> dict:
    """What ``gpsaccel check`` prints and writes of one report: the student's projection
    (:meth:`~gpsaccel.check.report.Report.for_student`), its JSON and its table's text."""
    student = report.for_student()
    out = student.to_dict()
    out["text"] = str(student)
    return out


def unchecked(path: Path | str, code: str, message: str) -> dict:
    """The result of a submission that was not checked to the end: ``code`` and why."""
    path = Path(path)
    return {"subject": path.name, "passed": False, "codes": [code],
            "findings": [{"code": code, "severity": "error", "message": message}],
            "details": {"path": str(path)}, "seconds": 0.0,
            "text": f"{path.name}: FAILED ({code})\n  - {message}"}


def checker_error(path: Path | str, message: str) -> dict:
    """The result of a check that did not complete (its process died, or the checker failed)."""
    return unchecked(path, "checker-error", message)


def warm(problem: str) -> None:
    """Import here what checking a file of ``problem`` imports on first use (scipy.special for
    the χ² bounds, the system's catalogue of mistakes), so each check's forked process inherits it
    instead of importing it again (``python benchmarks/per_file.py``), and build what every
    file's check shares (:meth:`~gpsaccel.check.problem.Problem.prepare`: a linear problem's
    catalogue and candidate filters, built and never run; ``python benchmarks/check_class.py
    --shared``).  No check imports filterpy or scipy.stats (their price:
    ``benchmarks/imports.py``), so neither is imported here.  Nothing is run on data, so no
    answer exists here before a file's box is empty (docs/sandbox.md)."""
    import importlib
    import importlib.util

    get(problem).prepare()
    system = registry.entry(problem).system
    names = ["scipy.special"]
    if system and system.isidentifier() and importlib.util.find_spec(f"gpsaccel.{system}") \
            and importlib.util.find_spec(f"gpsaccel.{system}.mistakes"):
        names.append(f"gpsaccel.{system}.mistakes")
    for name in names:
        importlib.import_module(name)
