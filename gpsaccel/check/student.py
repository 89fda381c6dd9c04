"""Call named functions of a student's file on numpy inputs; get validated arrays back.

The one place the problem checkers (:mod:`gpsaccel.check.problems`) reach the student's code::

    calls = [Call("ekf", (y, Q, R), (Output("x_hat", (1001, 6)), Output("P", (1001, 6, 6))))]
    got = call_functions("alice.py", calls, timeout=60)
    got.results[0]["x_hat"]       # float64 (1001, 6), or got.failure / got.problem

``Call`` and ``Output`` are the sandbox's (:mod:`gpsaccel.check.sandbox`); the calls run in a
box of their own, and the box's result comes back in this module's terms (:class:`StudentCalls`).

Which functions a file defines is read with :mod:`ast` before anything runs (:func:`defines`),
so a problem whose contract accepts either of two functions (coop: ``ekf`` and/or ``lkf``) calls
only those the file has.
"""

from __future__ import annotations

import os
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gpsaccel.check import sandbox as sb
from gpsaccel.check.sandbox import Call, Output, defines

__all__ = ["Call", "Output", "StudentCalls", "call_functions", "defines"]


#: Characters of the student's printed output kept.
OUTPUT_KEEP = 1500


@dataclass
class StudentCalls:
    """What came back.

    results : one dict per completed call (output name -> float64 array of the declared shape).
    failure : None when every call returned; else ``timeout``, ``crashed``, or the runner's kind
        (``import-error``, ``no-function``, ``exception``, ``return-value``, ``not-numeric``,
        ``wrong-shape``).
    problem : the runner's account of the first problem (call index, traceback, shapes).
    returned : type and shape of each output the first call of each function returned.
    output : the tail of what the student printed; output_chars : its full length.
    seconds : wall-clock time; backend : the sandbox backend that ran (``"bwrap"``, ``"basic"``).
    detail : the sandbox's short account of a limit hit or a refused result.
    """

    results: list[dict[str, np.ndarray]] = field(default_factory=list)
    failure: str | None = None
    problem: dict | None = None
    returned: dict = field(default_factory=dict)
    output: str = ""
    output_chars: int = 0
    seconds: float = 0.0
    backend: str = "sandbox"
    detail: str = ""


def call_functions(path: str | os.PathLike, calls: Sequence[Call], timeout: float,
                   sandbox: str = "auto", limits: object = None,
                   allow_gpsaccel: bool = False) -> StudentCalls:
    """Make ``calls`` on the student's file ``path`` in a sandbox; see the module docstring.

    ``sandbox`` (backend), ``limits`` (a ``sandbox.Limits``; its time is set to ``timeout``) and
    ``allow_gpsaccel`` are the sandbox's.  Never raises for anything the student's code does.
    """
    return _in_sandbox(Path(path).resolve(), list(calls), timeout, sandbox, limits,
                       allow_gpsaccel)


def _in_sandbox(path: Path, calls: list[Call], timeout: float, backend: str = "auto",
                limits: object = None, allow_gpsaccel: bool = False) -> StudentCalls:
    """The calls in the sandbox; its result in this module's terms."""
    t0 = time.perf_counter()
    try:
        sub = sb.load_submission(path, function=calls[0].function)
    except sb.SubmissionError as exc:
        return StudentCalls(failure=exc.code, problem={"kind": exc.code}, detail=str(exc),
                            seconds=time.perf_counter() - t0, backend="sandbox")
    box = sb.run(sub, calls,
                 sb.Limits(**{**vars(limits or sb.Limits()), "time": timeout}),
                 backend=backend, allow_gpsaccel=allow_gpsaccel)
    problem = dict(box.problem or {}) if box.failure else None
    if problem is not None:
        problem.setdefault("kind", box.failure)
        if box.failure == "wrong-shape" and "call" in problem:
            outs = {o.name: o.shape for o in calls[problem["call"]].outputs}
            problem["shape"] = problem.get("got")
            problem["expected"] = list(outs.get(problem.get("name"), ()))
        if box.failure == "timeout":
            problem["calls_done"] = len(box.results)
    return StudentCalls(results=list(box.results), failure=box.failure, problem=problem,
                        returned={calls[0].function: box.returned or {}}, output=box.output,
                        output_chars=box.output_bytes, seconds=box.seconds,
                        backend=box.backend, detail=box.detail)
