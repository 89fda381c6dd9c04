"""A student's file as a filter callable, run in a process of its own, for side-by-side comparison.

:func:`gpsaccel.calibration.compare.compare` takes filters as callables ``kalman_filter(z) ->
(x_hat, P)``; this module makes one of a student's ``.py`` file without importing it here::

    from gpsaccel import check
    from gpsaccel.calibration.compare import compare
    print(compare("joseph", "square-root", filters={"alice": check.student_filter("alice.py")}))

Each call runs the file in a sandbox (:mod:`gpsaccel.sandbox`, as
:meth:`gpsaccel.check.problem.Problem.check` does for a check: a box of its own with limits,
nothing of the student's imported into this process) on ``repeat`` copies of ``z`` and hands back
the first run's (x_hat, P).  The time per run is measured in the child around the student's calls
only, and set as the callable's ``seconds`` (``compare`` reports it instead of the box's start-up).

Whatever goes wrong in the student's code (it raises, loops, returns the wrong shapes, kills its
process, breaks a limit) raises :class:`StudentFilterError` here with the checker's message for
it, which ``compare`` prints in the filter's row.  The results that come back are untrusted: read
against the declared shapes (anything else is refused); NaN and inf are passed on (``compare``
counts them as infinitely wrong).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel import sandbox as sb
from gpsaccel.check.findings import box_findings
from gpsaccel.check.problems.calibration import FUNCTION, calls
from gpsaccel.check.report import Report


class StudentFilterError(RuntimeError):
    """The student's file did not give back (x_hat, P); the message says why."""


class StudentFilter:
    """``kalman_filter(z) -> (x_hat, P)`` of the file ``path``, run in a child process.

    Parameters
    ----------
    path : the student's ``.py`` file, defining ``kalman_filter(z)`` for report 000's problem.
    timeout : time limit (s) of one call (import and ``repeat`` runs), counted by the box's
        fair clock (:mod:`gpsaccel.sandbox.clock`: a busy machine's run-queue wait not counted).
    repeat : runs per call, for the time per run (the mean of the runs, measured in the child).
    sandbox : ``"auto"``, ``"bwrap"`` or ``"basic"`` (:mod:`gpsaccel.sandbox`).

    After a call, ``seconds`` is the time of one run (s).
    """

    def __init__(self, path: str | os.PathLike, timeout: float = 60.0, repeat: int = 3,
                 sandbox: str = "auto") -> None:
        self.path = Path(path)
        if not self.path.is_file():
            raise ValueError(f"path: {self.path} is not a file")
        self.timeout = _v.positive_float("timeout", timeout)
        self.repeat = _v.integer("repeat", repeat, minimum=1)
        self.sandbox = sb.resolve_backend(sandbox)
        self.seconds: float | None = None
        self.description = f"student file {self.path.name} (own process)"
        self.__name__ = self.path.stem

    def __call__(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        z = _v.finite_array("z", z, (None, 2), allow_nan=True)
        self.seconds = None
        try:
            sub = sb.load_submission(self.path, FUNCTION)
        except sb.SubmissionError as exc:
            raise StudentFilterError(str(exc)) from None
        limits = sb.Limits(time=self.timeout)
        many = calls(np.repeat(z[None], self.repeat, axis=0))
        box = sb.run(sub, many, limits, self.sandbox)
        report = Report(self.path.name)
        if not box_findings(report, box, many, limits, labels=[f"run {r}" for r in
                                                                  range(self.repeat)]):
            raise StudentFilterError("\n".join(f.message for f in report.findings
                                                if f.severity == "error") or "no result")
        x, P = box.results[0]["x_hat"], box.results[0]["P"]  # the declared shapes
        # the child's own clock, not trusted beyond the wall clock of the whole box (start-up
        # and import included); a hostile file can still under-report it, so it is indicative
        done = self.repeat  # no problem reported: every run came back
        wall = box.seconds / done
        reported = box.run_seconds
        per_run = float(reported) / done if isinstance(reported, (int, float)) else np.nan
        self.seconds = per_run if np.isfinite(per_run) and 0 < per_run <= wall else wall
        return x, P


def student_filter(path: str | os.PathLike, timeout: float = 60.0, repeat: int = 3,
                   sandbox: str = "auto") -> StudentFilter:
    """The student's file ``path`` as a ``kalman_filter(z)`` callable (see :class:`StudentFilter`)."""
    return StudentFilter(path, timeout=timeout, repeat=repeat, sandbox=sandbox)
