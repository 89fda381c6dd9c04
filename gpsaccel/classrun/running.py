"""One run of a task over a class's entries, for ``gpsaccel check`` and ``gpsaccel grade`` alike.

What a class run decides once, before any student's code runs: the seed of the data (drawn
with :func:`gpsaccel._untrusted.secret_seed` unless given, so no student can precompute an
answer; recorded by the caller so a verdict can be reproduced), the jobs, the sandbox's backend
(and the refusal of the basic one where it cannot isolate a student:
:func:`gpsaccel.sandbox.refuse_unsafe_basic`), and the imports every item needs (the task's
:meth:`Task.warm`, before the pool forks, so each item inherits them).

:func:`run` then sends each entry through the sandbox's one pool
(:func:`gpsaccel.sandbox.run_items`): a process forked per item (the default, ``"processes"``),
this process one after the other (``None``), or a Dask cluster or any executor, each item within
the task's deadline.  An entry without a submission (its :attr:`~gpsaccel.classrun.entries.Entry
.problem`) is never run: the task says its result here.  An item that gives no result is worded
from the sandbox's own table (``lost.<reason>`` of :data:`gpsaccel.sandbox.outcomes.OUTCOMES`)
and becomes that entry's result through :meth:`Task.lost`: one student's loss, never the class's.
Ctrl-C, SIGTERM or SIGHUP kills every item and what their boxes left (the pool's), and raises
:class:`Interrupted` (a :class:`gpsaccel._interrupt.Stopped`, so a KeyboardInterrupt naming the
signal) holding what finished.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from gpsaccel import _untrusted
from gpsaccel import _validation as _v
from gpsaccel import sandbox as sb
from gpsaccel._interrupt import Stopped
from gpsaccel.classrun.entries import Entry
from gpsaccel.sandbox import zygote
from gpsaccel.sandbox.outcomes import OUTCOMES


class Interrupted(Stopped):
    """A class run was stopped (Ctrl-C, SIGTERM, SIGHUP: :mod:`gpsaccel._interrupt`); the
    signal and what the pool kept as ``stopped`` said them, and ``results`` holds, per entry,
    its result or None where it did not finish."""

    def __init__(self, results: list, stopped: BaseException | None = None) -> None:
        if isinstance(stopped, Stopped):
            super().__init__(stopped.signum, stopped.kept)
        else:
            super().__init__()
        self.results = results


def seed_of(seed: int | None) -> tuple[int, bool]:
    """(the run's seed, whether it was drawn): ``seed`` checked, or a secret one."""
    if seed is None:
        return _untrusted.secret_seed(), True
    return _v.integer("seed", seed, minimum=0), False


def jobs_of(jobs: int | None, default: int, name: str = "jobs") -> int:
    """Items at once: ``jobs`` checked (an integer >= 1), or ``default``."""
    return default if jobs is None else _v.integer(name, jobs, minimum=1)


def cpus() -> int:
    return os.cpu_count() or 1


def backend_of(sandbox: str, allow_unsafe_basic: bool = False) -> str:
    """The sandbox's backend, resolved once for the class (a clear error before anything runs),
    and the basic one refused where it cannot isolate a student."""
    backend = sb.resolve_backend(sandbox)
    sb.refuse_unsafe_basic(backend, allow_unsafe_basic)
    return backend


def hidden_from_boxes(backend: str, folders: Mapping[str, str | os.PathLike | None],
                      optional: Sequence[str] = ("secret_file",)
                      ) -> contextlib.AbstractContextManager:
    """The class's own folders (argument name -> folder) hidden from every box the run starts,
    under ``basic`` (:func:`gpsaccel.sandbox.hiding`: a basic box reads what other users may,
    and an LMS export is world-readable); a ``bwrap`` box sees none of them anyway.
    ``optional``: those left visible where they hold what every box reads (the interpreter)."""
    return (sb.hiding(folders, optional=optional) if backend == "basic"
            else contextlib.nullcontext())


def open_to_others(path: str | os.PathLike) -> bool:
    """Whether a user with no claim on ``path`` (neither its owner nor in its group, as a basic
    box's uid) can read it: the file readable by others and every folder above it enterable."""
    import stat
    from pathlib import Path

    p = Path(path).resolve()
    if not p.stat().st_mode & stat.S_IROTH:
        return False
    return all(d.stat().st_mode & stat.S_IXOTH for d in p.parents)


def secret_of(secret: bytes | None, secret_file: str | os.PathLike | None, backend: str
              ) -> bytes | None:
    """The instructor's secret: ``secret``, or ``secret_file``'s
    (:func:`gpsaccel.assignments.grading.read_secret`).  A file a
    basic box could read is refused: the box runs as another user, and a notebook that read it
    would carry it back in its feedback (a redteam box did, from the wheel)."""
    from gpsaccel.assignments.grading import read_secret

    if secret_file is None:
        return secret
    if secret is not None:
        raise ValueError("secret_file: give the secret or its file, not both")
    if backend == "basic" and open_to_others(secret_file):
        raise ValueError(f"secret_file (--secret-file): {secret_file} can be read by other "
                         f"users, and a basic box runs as another user: `chmod 600 {secret_file}` "
                         f"(or keep it in a folder others cannot enter), or grade with sandbox 'bwrap'")
    return read_secret(secret_file)


class Task:
    """What a class run does with each entry: the hooks a kind of run overrides.

    ``timeout`` is the student's own time limit, ``deadline`` what one item may take in all
    (boxes, references, feedback) before it is lost.  :meth:`item` runs in the item's process
    (a module-level class, so Dask can send it); the others run here."""

    timeout: float = 60.0
    deadline: float = 180.0
    #: Who runs an item and what it does, as a lost item's wording says them (the
    #: ``lost.<reason>`` templates' ``doer`` and ``doing``): a check and a grade say their own.
    doer: str = "run"
    doing: str = "running this item"

    def warm(self) -> None:
        """Import what every item imports on first use, before the pool forks (only modules:
        no answer exists before a box is empty)."""

    def boxes(self) -> tuple[sb.Warm, ...]:
        """The kinds of box the items start, for a run whose boxes start warm (``warm_boxes``:
        a zygote per kind, :func:`gpsaccel.sandbox.warm_boxes`); none: every box starts cold."""
        return ()

    def item(self, entry: Entry) -> dict:
        """The entry's result, computed in the item's process (its box runs from there)."""
        raise NotImplementedError

    def refused(self, entry: Entry) -> dict:
        """The result of an entry that has no submission to run (``entry.problem``)."""
        raise NotImplementedError

    def lost(self, entry: Entry, why: str) -> dict:
        """The result of an item that gave none; ``why`` is the sandbox's wording."""
        raise NotImplementedError


def lost_text(lost: sb.Lost, task: Task) -> str:
    """Why an item has no result, in the words of :data:`gpsaccel.sandbox.outcomes.OUTCOMES`
    (``lost.<reason>``; fields ``detail``, ``limit`` the task's deadline, ``slack`` its part
    beyond the time limit, ``doer`` and ``doing`` the task's)."""
    known = OUTCOMES.get(f"lost.{lost.reason}")
    return (known.finding if known else "{detail}").format(
        detail=lost.detail, limit=task.deadline, slack=task.deadline - task.timeout,
        doer=task.doer, doing=task.doing)


#: The executors of this machine: a forked process per item, or this process.
LOCAL = ("processes", "local", None, "inprocess")


#: The fewest items a run starts warm by default: a run pays its zygotes' imports once (about
#: 1.4 CPU s for a class run's two), a warm box saves from 0.2 (a student's filter) to 0.7 CPU s
#: (a filled calibration notebook): docs/benchmarks/per_file.txt.
WARM_FROM = 8


def warm_of(warm_boxes: bool | None, executor: object, items: int | None = None) -> bool:
    """Whether the run's boxes start warm.  Warm boxes need this machine's items (they inherit
    the zygotes) and root on Linux (each box a uid of its own): None (the default) starts them
    warm where they can and the run has at least :data:`WARM_FROM` ``items`` to run (unknown:
    enough), True asks for them (a ValueError says why where they cannot start), False starts
    every box cold."""
    if warm_boxes is None:
        return (executor in LOCAL and zygote.usable()
                and (items is None or items >= WARM_FROM))
    if not isinstance(warm_boxes, bool):
        raise ValueError(f"warm_boxes must be True, False or None (warm where boxes can "
                         f"start warm), got {warm_boxes!r}")
    if warm_boxes and executor not in LOCAL:
        raise ValueError(f"warm_boxes (--boxes warm): boxes start warm only from this "
                         f"machine's items (executor 'processes' or None, no --dask), not from "
                         f"{executor!r}")
    if warm_boxes and not zygote.usable():
        raise ValueError("warm_boxes (--boxes warm): boxes start warm only as root on Linux "
                         "(each box runs under a uid of its own); run without it")
    return warm_boxes


def run(task: Task, entries: Sequence[Entry], jobs: int, executor: object = "processes",
        on_result: Callable[[int, dict], None] | None = None,
        warm_boxes: bool | None = None) -> list[dict | None]:
    """Every entry's result, in order (module docstring); ``on_result(i, result)`` as each ends.

    ``executor``: ``"processes"`` (a process forked per item), None (here, one after the other)
    or anything :func:`gpsaccel.executors.resolve_executor` accepts (``"dask-local"``,
    ``"tcp://..."``, an Executor).  ``warm_boxes``: the items' boxes start from a zygote per
    kind of box (:meth:`Task.boxes`), started before the items and killed when they end; a box
    a zygote cannot serve starts cold (:mod:`gpsaccel.sandbox.zygote`); None: warm where they
    can, True: a ValueError where they cannot (:func:`warm_of`).  Raises :class:`Interrupted`
    on Ctrl-C, SIGTERM or SIGHUP."""
    results: list[dict | None] = [None] * len(entries)

    def done(i: int, out: Any) -> None:
        results[i] = out
        if on_result is not None:
            on_result(i, out)

    runnable = [i for i, e in enumerate(entries) if e.problem is None and e.path is not None]
    warm = warm_of(warm_boxes, executor, len(runnable))
    try:
        for i in sorted(set(range(len(entries))) - set(runnable)):
            done(i, task.refused(entries[i]))
        if executor in LOCAL:
            task.warm()  # before the pool forks: every item inherits the imports

        def finished(k: int, out: Any) -> None:
            i = runnable[k]
            if not isinstance(out, dict):
                lost = out if isinstance(out, sb.Lost) else sb.Lost("not-a-report")
                out = task.lost(entries[i], lost_text(lost, task))
            done(i, out)

        spec = None if executor in ("processes", "local") else \
            "inprocess" if executor is None else executor
        kinds = task.boxes() if warm and runnable else ()
        with sb.warm_boxes(*kinds) if kinds else contextlib.nullcontext():
            sb.run_items(task.item, [entries[i] for i in runnable], jobs, task.deadline,
                         finished, spec)
    except KeyboardInterrupt as exc:
        raise Interrupted(results, exc) from exc
    return results
