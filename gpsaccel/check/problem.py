r"""What a homework problem is, and the one check every problem runs.

A :class:`Problem` says

* the **contract**: which functions the student's file defines, their inputs and outputs with
  shapes and units (:attr:`Problem.functions`; ``required="any"`` when one of them is enough);
* how the checker **simulates** the data it calls them on (:meth:`Problem.cases`, from a seed);
* the **reference** answer on that data and the **tolerance** that separates every honest way of
  computing it from every catalogued mistake (:meth:`Problem.evaluate`, :attr:`Problem.tolerance`);
* the **catalogue** of known mistakes, from the system's package (:meth:`Problem.codes`).

:meth:`Problem.check` is the same for every problem: load the submission (a file or one
student's folder, :func:`gpsaccel.sandbox.load_submission`), read which functions it defines
(without running it), simulate, call the student's functions in the sandbox
(:func:`gpsaccel.sandbox.run`), turn whatever went wrong into findings with the one
:func:`gpsaccel.check.findings.box_findings` (each problem's wording as data), then compare with
the reference and diagnose.  The result is the one :class:`~gpsaccel.check.report.
Report` type of the package.

The problems themselves, one per file, and the registry's front door (:func:`~gpsaccel.check.
problems.submission`) are in :mod:`gpsaccel.check.problems`; the pipeline every linear problem
shares is :mod:`gpsaccel.check.linear`.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import ClassVar

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel import sandbox as sb
from gpsaccel.check.findings import MESSAGES, box_findings
from gpsaccel.check.report import Report
from gpsaccel.sandbox import Call, Output, defines

#: The folders of gpsaccel (relative to it) that a student's box may not read when it may import
#: the package (``allow_gpsaccel``: the course's models for data): the checks, the homework's
#: graded questions and reference answers, the lessons' self-check answers, the lessons'
#: masters and solutions, and the example homework (its master and graded.py, which an
#: instructor may grade as shipped).  The sandbox keeps them out of reach on every backend
#: (:func:`gpsaccel.sandbox.run`'s ``hide``); a graded notebook's box hides the same
#: (:mod:`gpsaccel.assignments.notebook`).
BOX_HIDES = ("check", "assignments", "exercises", "_lessons/masters", "_lessons/solutions",
             "homework/example")


def _hides(allow_gpsaccel: bool) -> tuple[str, ...]:
    """What the box hides: nothing more when it may not import gpsaccel at all."""
    return BOX_HIDES if allow_gpsaccel else ()


@dataclass(frozen=True)
class Argument:
    """One input of a contract function: name, shape (None for a size given in the text), meaning."""

    name: str
    shape: tuple[int, ...]
    meaning: str


@dataclass(frozen=True)
class Function:
    """One function of a contract: its name, inputs and outputs (the sandbox's ``Output``)."""

    name: str
    args: tuple[Argument, ...]
    outputs: tuple[Output, ...]
    meaning: str

    @property
    def signature(self) -> str:
        return (f"{self.name}({', '.join(a.name for a in self.args)}) -> "
                f"({', '.join(o.name for o in self.outputs)})")


class Problem:
    """A homework problem (module docstring); subclasses fill in the parts.

    The hooks: :meth:`cases` (the data, from a seed), :meth:`calls` (the sandbox calls of one
    contract function on them), :meth:`evaluate` (compare, diagnose, add statistics),
    :meth:`prepare` (build what every file shares, once, before the boxes),
    :meth:`forget` (drop every cached answer before the student runs), :meth:`labels` (a name per
    call, for messages); the wording: :attr:`messages` (code -> template, over
    :data:`gpsaccel.check.findings.MESSAGES`), :attr:`renames` (a box failure reported under
    another code) and :meth:`message_fields`.
    """

    name: str = ""
    title: str = ""
    functions: tuple[Function, ...] = ()
    required: str = "all"
    #: What the tolerance is and why (shown in reports and the README).
    tolerance: str = ""
    default_runs: int = 4
    #: code -> message template overriding :data:`gpsaccel.check.findings.MESSAGES`.
    messages: dict[str, str] = {}
    #: a box failure -> the code this problem reports it under.
    renames: dict[str, str] = {}
    #: code -> the student's template of a catalogue finding, over
    #: :data:`gpsaccel.check.wording.STUDENT` (a problem's own words: report 000's physics).
    student: dict[str, str] = {}

    #: ``Problem.linear(name, Phi=..., Gamma=..., W=..., H=..., V=..., M0=..., x0=..., every=...,
    #: n_epochs=...)``: a problem for any linear model, checked against the generic catalogue of
    #: linear-filter mistakes (:func:`gpsaccel.check.linear.linear`, which says the arguments).
    #: Set by :mod:`gpsaccel.check.problems`, the package every public path to this class goes
    #: through: the linear problems are subclasses of this class, so defining it here would make
    #: this module and :mod:`gpsaccel.check.linear` import each other.
    linear: ClassVar[Callable[..., Problem]]

    # ---------------------------------------------------------------- the contract
    def describe(self) -> str:
        """The contract as text, for students."""
        lines = [f"{self.title}", "Your file defines " + (
            "one or more of:" if self.required == "any" else "all of:")]
        for f in self.functions:
            lines.append(f"  {f.signature}: {f.meaning}")
            for a in f.args:
                lines.append(f"      {a.name} {a.shape}: {a.meaning}")
            for o in f.outputs:
                lines.append(f"      returns {o.name} {o.shape}")
        return "\n".join(lines)

    def codes(self) -> tuple[str, ...]:
        """The codes of this problem's catalogue of mistakes."""
        raise NotImplementedError

    def prepare(self) -> None:
        """Build what checking every file shares and no data decides, once (a class's check
        calls it before its boxes start: :func:`gpsaccel.check.batch.warm`): the model's
        matrices, the catalogue's mistakes, candidate filters built and not run.  Never a result
        on data, nor a covariance a filter computes: those are answers (:meth:`forget`)."""

    def forget(self) -> None:
        """Drop every cached reference answer (called before a student's code runs)."""

    # ---------------------------------------------------------------- to fill in
    def cases(self, n_runs: int, seed: int):
        """The data the functions are called on (cached by the subclass)."""
        raise NotImplementedError

    def calls(self, cases, function: Function) -> list[Call]:
        raise NotImplementedError

    def labels(self, cases) -> list[str]:
        """A name for each case ("run 0", "the course log"), in the order of :meth:`calls`."""
        return list(getattr(cases, "labels", ()))

    def message_fields(self, cases) -> dict[str, object]:
        """Fields of this problem's message templates (e.g. ``work``, ``rows``, ``every``)."""
        return {}

    def evaluate(self, report: Report, cases, function: Function,
                 results: list[dict[str, np.ndarray]], returned: dict) -> None:
        """Compare with the reference, diagnose, add the informational statistics.
        ``returned`` describes what the first call returned (type, dtype, shape per output)."""
        raise NotImplementedError

    # ---------------------------------------------------------------- the check
    def check(self, path: str | os.PathLike, n_runs: int | None = None, seed: int = 0,
              timeout: float = 60, sandbox: str = "auto", limits: sb.Limits | None = None,
              allow_gpsaccel: bool = False) -> Report:
        """Check the student's submission ``path`` (a ``.py`` file or one student's folder);
        never raises for what the file does.

        ``sandbox``, ``limits`` and ``allow_gpsaccel`` go to the sandbox
        (:mod:`gpsaccel.sandbox`); the reference answers are computed only after the
        student's box is gone (and no answer of an earlier check is kept meanwhile).
        """
        t0 = time.perf_counter()
        n_runs, seed, timeout = arguments(n_runs, seed, timeout)
        n_runs = self.default_runs if n_runs is None else n_runs
        if limits is not None and not isinstance(limits, sb.Limits):
            raise ValueError(f"limits must be a gpsaccel.sandbox.Limits, got {limits!r}")
        limits = sb.Limits(**{**vars(limits or sb.Limits()), "time": timeout})
        backend = sb.resolve_backend(sandbox)
        path = Path(path)
        report = Report(path.name)
        report.details.update({"path": str(path), "problem": self.name, "n_runs": n_runs,
                               "seed": seed, "timeout": timeout, "sandbox": backend})
        try:
            sub = self._submission(path)
        except sb.SubmissionError as exc:
            report.add(self.renames.get(exc.code, exc.code), text="{error}",
                       observed={"error": str(exc)})  # about the student's own files
            report.seconds = time.perf_counter() - t0
            return report
        if sub.files != (sub.entry,):
            report.details["files"] = list(sub.files)
            report.details["entry"] = sub.entry
        entry = sub.root / sub.entry
        present = [f for f in self.functions if defines(entry, f.name)]
        missing = [f for f in self.functions if f not in present]
        if not present:  # the runner says what the file does define (read by importing it)
            present = [self.functions[0]]
        elif self.required == "all" and missing:
            names = " and ".join(f.signature for f in missing)
            report.add("no-function", text="Your file does not define {names} at top level "
                       "(read without running it). {contract}", observed={
                           "names": names, "contract": self.describe().split("\n", 1)[1]})
            report.seconds = time.perf_counter() - t0
            return report
        cases = self.cases(n_runs, seed)
        calls: list[Call] = []
        spans: list[tuple[Function, int, int]] = []
        for f in present:
            mine = _columns_accepted(self.calls(cases, f))
            spans.append((f, len(calls), len(calls) + len(mine)))
            calls += mine
        labels = self.labels(cases) * len(present)
        self.forget()  # no reference answer exists while the student's code runs
        box = sb.run(sub, calls, limits, backend, allow_gpsaccel, _hides(allow_gpsaccel))
        _note_columns(report, box, calls)
        report.details["student_seconds"] = round(box.seconds, 3)
        fields = {"signature": " or ".join(f.signature for f in self.functions),
                  **self.message_fields(cases)}
        if box_findings(report, box, calls, limits, self.messages, labels, self.renames,
                        **fields):
            for f, a, b in spans:
                self.evaluate(report, cases, f, box.results[a:b], box.returned or {})
        report.sort()
        report.seconds = time.perf_counter() - t0
        return report

    def _submission(self, path: Path) -> sb.Submission:
        """The submission at ``path``: its entry is the file defining the contract's functions
        (the first of them found; :func:`gpsaccel.sandbox.load_submission`)."""
        error: sb.SubmissionError | None = None
        for f in self.functions:
            try:
                return sb.load_submission(path, f.name)
            except sb.SubmissionError as exc:
                if exc.code != "no-function":
                    raise
                error = error or exc
        if path.is_file():  # a file defining none: the runner names what it does define
            return sb.Submission(path.resolve().parent, path.name, (path.name,))
        assert error is not None
        raise error


def arguments(n_runs: int | None, seed: int, timeout: float) -> tuple[int | None, int, float]:
    """A check's ``n_runs`` (None: the problem's default), ``seed`` and ``timeout``, checked
    (a ValueError naming each): by :meth:`Problem.check`, and by a class's check once, before
    any submission runs."""
    n_runs = None if n_runs is None else _v.integer("n_runs", n_runs, minimum=2)
    return n_runs, _v.integer("seed", seed, minimum=0), _v.positive_float("timeout", timeout)


def _columns_accepted(calls: list[Call]) -> list[Call]:
    """The calls with every output declared ``column``: a filterpy filter keeps x as a column,
    so an output of shape ``declared + (1,)`` is filterpy's own and is accepted, its axis dropped
    in the box (:class:`gpsaccel.sandbox.Output`); one box, whatever the student stored."""
    return [Call(c.function, c.args, tuple(replace(o, column=True) for o in c.outputs))
            for c in calls]


def _note_columns(report: Report, box: sb.BoxResult, calls: list[Call]) -> None:
    """A note for each output the box's first call returned as a column (its reported shape is
    the declared one plus a trailing 1; the arrays that came back have the declared shape)."""
    if not calls or not box.results:
        return
    returned = box.returned or {}
    for o in calls[0].outputs:
        shape = (returned.get(o.name) or {}).get("shape")
        if isinstance(shape, list) and tuple(shape) == tuple(o.shape) + (1,):
            report.add("filterpy-column", severity="note", text=MESSAGES["filterpy-column"],
                       where=o.name, observed={"name": o.name, "shape": tuple(shape),
                                               "wanted": tuple(o.shape)})

