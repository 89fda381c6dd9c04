"""A class's check (``gpsaccel check DIR ...``): every submission of one problem, in a run nothing
can take down.

What a submission is: each top-level entry of a folder given is one, a ``.py`` file or a folder
(one student's: the file that defines the contract's functions, its helpers and data); a file
given is one (:data:`gpsaccel.classrun.entries.PYTHON`).  A helper module inside a student's
folder is part of that submission, never a failing submission of its own.

:func:`plan_check` settles everything once, before any submission runs: the numbers (``n_runs``,
``seed``, ``timeout``: :func:`gpsaccel.check.problem.arguments`), the problem, the walk of the
paths, the sandbox's backend (the basic one refused where it is unsafe) and the seed (secret
unless given).  :meth:`CheckPlan.run` then checks each file as an item of the one class run
(:func:`gpsaccel.classrun.running.run`): by default in a process forked for it alone, which runs
the student's box, then computes the optimal answer, hands back a plain dictionary and exits.  So

- a check whose process dies (a student who killed its parent, a crash of the checker) is
  recorded as ``checker-error`` for that file only, and the class goes on: the next file gets a
  fresh process;
- the run's own process is a child subreaper meanwhile: whatever a dead check leaves behind is
  re-parented to it and killed; every process it started is gone before the run returns;
- Ctrl-C kills every check and every process of the students', and raises
  :class:`~gpsaccel.classrun.running.Interrupted` holding the results finished so far.

``executor=None`` checks the files one after the other in this process (each still in its box);
a Dask specification (``"dask-local"``, ``"tcp://..."``) or an ``Executor`` sends each check to
that executor, with the same deadline per check (:data:`gpsaccel.check.batch.CHECK_SLACK` beyond
the time limit).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from gpsaccel import _validation as _v
from gpsaccel import registry
from gpsaccel import sandbox as sb
from gpsaccel._untrusted import json_safe
from gpsaccel.check import batch
from gpsaccel.check.problem import BOX_HIDES, arguments
from gpsaccel.classrun import running
from gpsaccel.classrun.entries import PYTHON, Entry, Naming, walk


class _Check(running.Task):
    """One file's check as a class's item (:mod:`gpsaccel.check.batch`); each result JSON-safe
    (:func:`gpsaccel._untrusted.json_safe`: a name that was not UTF-8 written ``\\xNN``), as the
    results file, the log and the table take it."""

    doer, doing = "checker", "checking this file"

    def __init__(self, plan: CheckPlan) -> None:
        self.problem, self.timeout = plan.problem, plan.timeout
        self.deadline = plan.timeout + batch.CHECK_SLACK
        self.n_runs, self.seed = plan.n_runs, plan.seed
        self.options: dict[str, object] = {"sandbox": plan.backend, "limits": plan.limits,
                        "allow_gpsaccel": plan.allow_gpsaccel, "problem": plan.problem}

    def warm(self) -> None:
        batch.warm(self.problem)

    def boxes(self) -> tuple[sb.Warm, ...]:
        """The file's box: it may import gpsaccel (not the checker's folders) or not at all."""
        allow = bool(self.options["allow_gpsaccel"])
        return (sb.Warm(allow_gpsaccel=allow, hide=BOX_HIDES if allow else ()),)

    def item(self, entry: Entry) -> dict:
        assert entry.path is not None  # the run sends only entries with a path
        return json_safe(batch.check_file(entry.path, self.n_runs, self.seed, self.timeout,
                                          **self.options))

    def refused(self, entry: Entry) -> dict:
        assert entry.problem is not None  # an entry without a path says why
        return json_safe(batch.unchecked(entry.path or entry.found, *entry.problem))

    def lost(self, entry: Entry, why: str) -> dict:
        return json_safe(batch.checker_error(entry.path or entry.found, why))


@dataclass(frozen=True)
class CheckPlan:
    """A class's check, settled (:func:`plan_check`): what is checked, on what, how."""

    entries: tuple[Entry, ...]
    notes: tuple[str, ...]
    problem: str
    n_runs: int | None
    seed: int
    seed_drawn: bool
    timeout: float
    backend: str
    limits: sb.Limits | None = None
    allow_gpsaccel: bool = False
    paths: tuple[str, ...] = ()

    @property
    def settings(self) -> dict:
        """What the results file records of the run (``settings``), so a verdict can be
        reproduced."""
        return {"problem": self.problem, "runs": self.n_runs, "seed": self.seed,
                "seed_drawn": self.seed_drawn, "timeout": self.timeout, "sandbox": self.backend,
                "allow_gpsaccel": self.allow_gpsaccel,
                "limits": None if self.limits is None else dict(vars(self.limits))}

    def hidden(self) -> tuple[dict[str, str | os.PathLike | None], list[str]]:
        """The folders no box may read under basic (every classmate's files): each folder of
        ``paths``, and the folder of each file given (left visible where it holds the
        interpreter, as a file given from the working folder of a repository)."""
        folders: dict[str, str | os.PathLike | None] = {}
        optional: list[str] = []
        for k, p in enumerate(self.paths):
            name = f"paths[{k}]"
            if os.path.isdir(p):
                folders[name] = p
            else:
                folders[name] = os.path.dirname(os.path.abspath(p))
                optional.append(name)
        return folders, optional

    def run(self, executor: object = "processes", max_workers: int | None = None,
            on_result: Callable[[dict], None] | None = None,
            warm_boxes: bool | None = None) -> list[dict]:
        """Check every entry (module docstring); one dict per entry, in order.  ``on_result``
        is called with each as it finishes (e.g. to append it to a log); ``warm_boxes``: each
        box starts from a zygote (:func:`gpsaccel.classrun.running.run`; None: where boxes can
        start warm)."""
        jobs = running.jobs_of(max_workers, running.cpus(), "max_workers")
        with running.hidden_from_boxes(self.backend, *self.hidden()):
            results = running.run(_Check(self), self.entries, jobs, executor,
                                  None if on_result is None else lambda i, r: on_result(r),
                                  warm_boxes)
        return [r for r in results if r is not None]


def plan_check(paths: Sequence[str | os.PathLike], problem: str = "calibration",
               n_runs: int | None = None, seed: int | None = None, timeout: float = 60,
               sandbox: str = "auto", limits: sb.Limits | None = None,
               allow_gpsaccel: bool = False, allow_unsafe_basic: bool = False,
               naming: Naming | None = None) -> CheckPlan:
    """The check of every submission of ``paths`` (module docstring), settled before any of them
    runs: a bad number, problem or backend is a ValueError naming it.  ``seed`` None draws a
    secret one (:func:`gpsaccel._untrusted.secret_seed`): a class is checked on data no student
    could know in advance; pass the recorded seed to reproduce a run.  ``naming``: who each
    entry is (:data:`~gpsaccel.classrun.entries.Naming`; default its name)."""
    seed, drawn = running.seed_of(seed)
    n_runs, seed, timeout = arguments(n_runs, seed, timeout)
    problem = _v.choice("problem", problem, registry.problems())
    if limits is not None and not isinstance(limits, sb.Limits):
        raise ValueError(f"limits must be a gpsaccel.sandbox.Limits, got {limits!r}")
    entries, notes = walk(paths, PYTHON, naming)
    backend = running.backend_of(sandbox, allow_unsafe_basic)
    return CheckPlan(tuple(entries), tuple(notes), problem, n_runs, seed, drawn, timeout,
                     backend, limits, allow_gpsaccel, tuple(os.fspath(p) for p in paths))


def check_many(paths: Sequence[str | os.PathLike], n_runs: int | None = None,
               seed: int | None = None, timeout: float = 60, executor: object = "processes",
               max_workers: int | None = None, sandbox: str = "auto",
               limits: sb.Limits | None = None, allow_gpsaccel: bool = False,
               on_result: Callable[[dict], None] | None = None,
               problem: str = "calibration", allow_unsafe_basic: bool = False,
               warm_boxes: bool | None = None) -> list[dict]:
    """Check every submission of ``paths``: :func:`plan_check`, then :meth:`CheckPlan.run`.

    ``problem`` is a name of :func:`gpsaccel.registry.problems` ("calibration", "coop", "ship",
    "tracker", ...); ``n_runs`` None is its default.  Every submission sees the same
    realizations (``seed``), so their results are comparable.  ``executor``: ``"processes"``
    (a process per check), None (in this process) or anything
    :func:`gpsaccel.executors.resolve_executor` accepts.  The basic sandbox is refused where it
    is unsafe (:func:`gpsaccel.sandbox.refuse_unsafe_basic`) unless ``allow_unsafe_basic``.
    ``warm_boxes``: each box starts from a zygote that has imported numpy, scipy.stats and
    filterpy (:mod:`gpsaccel.sandbox.zygote`; as root on Linux, with this machine's executor);
    None (the default) where boxes can start warm, False every box cold.
    Raises :class:`~gpsaccel.classrun.running.Interrupted` on Ctrl-C."""
    plan = plan_check(paths, problem, n_runs, seed, timeout, sandbox, limits, allow_gpsaccel,
                      allow_unsafe_basic)
    return plan.run(executor, max_workers, on_result, warm_boxes)
