"""One process pool for every class-wide job (``gpsaccel check DIR``, ``gpsaccel grade``): each item
in a process forked for it alone, with a deadline, under a subreaper that sweeps what a dead item
left, and Ctrl-C, SIGTERM or SIGHUP that leave nothing running; or the same items on a Dask cluster
(or any :class:`concurrent.futures.Executor`) with the same deadlines.

    from gpsaccel.sandbox import pool
    pool.run_items(task, items, jobs=2, deadline=180, done=lambda i, out: ...)

``task(item)`` runs in the item's process and returns a picklable result; ``done(i, out)`` is called
in this process as each item ends, in the order they end, with that result or a :class:`Lost` saying
why there is none (the task raised, the process died, the deadline passed).  One item's failure is
that item's only: there is no pool to break, the next item gets a fresh process.

Why fork per item: the item's process runs a student's box and then computes the answers; a
student who kills it (the box's code reaching its parent) loses only their own item, and the
answers of one item never live in a process that later runs another student's code.  The forked
process ignores SIGINT, SIGTERM and SIGHUP (stopping is the pool's), dies with the pool
(``PR_SET_PDEATHSIG``) and is not dumpable for its whole life (it holds answers while other boxes
run).

Stopping: SIGINT (Ctrl-C), SIGTERM (``timeout``, ``systemctl stop``, ``docker stop``, a batch
scheduler) and SIGHUP (the terminal closed) are latched (:func:`gpsaccel._interrupt.latched_stop`)
and read by the loop between polls: it SIGKILLs every running item, whose boxes end with it (bwrap's
``--die-with-parent``, the runner's death signal), sweeps what they left (re-parented to the pool,
the subreaper) and raises :class:`gpsaccel._interrupt.Stopped`, a KeyboardInterrupt naming the
signal and what finished, which the callers handle as Ctrl-C: they keep what finished.

Under Dask the items run in the workers (each box still a box of its own); the pool submits at most
``jobs`` at once, so an item's clock starts when it is submitted, and an item past its deadline is
reported :class:`Lost` ("too-long") and cancelled (Dask cannot stop a running task: the box's own
time limit ends it).
"""

from __future__ import annotations

import concurrent.futures as cf
import multiprocessing as mp
import multiprocessing.connection as mpc
import os
import signal
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from gpsaccel._interrupt import Latch, latched, latched_stop
from gpsaccel.sandbox.confinement import sweep_stale_boxes
from gpsaccel.sandbox.procs import (
    PR_SET_PDEATHSIG,
    _get_subreaper,
    _my_children,
    _prctl,
    set_dumpable,
    set_subreaper,
    sweep,
)


@dataclass(frozen=True)
class Lost:
    """Why an item has no result.

    reason : ``"error"`` (the task raised: ``detail`` is ``Type: message``), ``"not-a-report"``
        (it returned something that could not be sent back), ``"too-long"`` (past its deadline,
        killed), ``"died"`` (its process ended without a result: ``detail`` says how, e.g.
        ``signal SIGKILL``, ``exit status 1``).
    """

    reason: str
    detail: str = ""


Done = Callable[[int, Any], None]


def run_items(task: Callable[[Any], Any], items: Sequence[Any], jobs: int, deadline: float,
              done: Done, executor: object = None) -> None:
    """Run ``task(item)`` for every item, ``jobs`` at once, each within ``deadline`` seconds;
    ``done(i, result or Lost)`` as each ends.  ``executor`` None forks a process per item (Linux
    and macOS); anything else is an executor or a specification
    :func:`gpsaccel.executors.resolve_executor` accepts (``"dask-local"``, ``"tcp://..."``).
    Ctrl-C, SIGTERM or SIGHUP kills every running item and whatever their boxes left, then
    raises :class:`gpsaccel._interrupt.Stopped` (a KeyboardInterrupt)."""
    if jobs < 1:
        raise ValueError(f"jobs must be >= 1, got {jobs}")
    if not deadline > 0:
        raise ValueError(f"deadline must be a positive number of seconds, got {deadline!r}")
    if executor is None:
        with latched_stop(raise_now=False) as interrupted:  # read by the loop, never lost
            _Forked(task, items, jobs, deadline, done, interrupted).run()
    else:  # SIGTERM, SIGHUP raise where they land, as Ctrl-C does (the executor's own
        # machinery handles it)
        with latched((signal.SIGTERM, signal.SIGHUP), raise_now=True):
            _on_executor(task, items, jobs, deadline, done, executor)


# ------------------------------------------------------------------------- a process per item
def _child(conn: mpc.Connection, task: Callable[[Any], Any], item: Any, pool: int) -> None:
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):  # stopping is the pool's
        signal.signal(sig, signal.SIG_IGN)
    _prctl(PR_SET_PDEATHSIG, signal.SIGKILL)  # a pool killed outright takes its items along
    if os.getppid() != pool:  # the pool died before the death signal was set
        os._exit(1)
    set_dumpable(False)  # for its whole life: after its box it holds answers
    try:
        out: Any = task(item)
    except Exception as exc:  # noqa: BLE001 - a bug of the caller's task: one item's error
        out = Lost("error", f"{type(exc).__name__}: {exc}")
    try:
        conn.send(out)
    except Exception as exc:  # noqa: BLE001 - not picklable
        conn.send(Lost("not-a-report", f"{type(exc).__name__}: {exc}"))
    conn.close()


def _context() -> Any:  # a fork or spawn context (typeshed's BaseContext has no Process)
    methods = mp.get_all_start_methods()
    return mp.get_context("fork" if "fork" in methods else "spawn")


@dataclass
class _Running:
    proc: Any  # multiprocessing.Process of the context
    conn: mpc.Connection
    deadline: float


class _Forked:
    """The fork-per-item loop (module docstring)."""

    def __init__(self, task: Callable[[Any], Any], items: Sequence[Any], jobs: int,
                 deadline: float, done: Done, interrupted: Latch) -> None:
        self.task, self.items, self.jobs, self.deadline = task, items, jobs, deadline
        self.done, self.interrupted = done, interrupted
        self.ctx = _context()
        self.pending = deque(range(len(items)))
        self.running: dict[int, _Running] = {}
        self.before: set[int] = set()

    def run(self) -> None:
        was_subreaper = _get_subreaper()
        set_subreaper(True)
        self.before = _my_children()  # not the pool's: never swept
        try:
            while self.pending or self.running:
                self.interrupted.check(self._kept())
                self._fill()
                mpc.wait([r.conn for r in self.running.values()]
                         + [r.proc.sentinel for r in self.running.values()], timeout=0.1)
                self._collect()
        finally:  # Ctrl-C or an exception of ours: leave nothing behind
            for r in self.running.values():
                r.proc.kill()
            for r in self.running.values():
                r.proc.join()
                r.conn.close()
            self.running.clear()
            sweep(self.before)
            sweep_stale_boxes()
            set_subreaper(bool(was_subreaper))

    def _kept(self) -> str:
        """What a stop keeps: the items that finished."""
        finished = len(self.items) - len(self.pending) - len(self.running)
        return (f"{finished} of {len(self.items)} finished and kept, {len(self.running)} "
                f"stopped, {len(self.pending)} not started")

    def _fill(self) -> None:
        while self.pending and len(self.running) < self.jobs:
            i = self.pending.popleft()
            recv, send = self.ctx.Pipe(duplex=False)
            proc = self.ctx.Process(target=_child, args=(send, self.task, self.items[i],
                                                         os.getpid()),
                                    daemon=True, name=f"gpsaccel-item-{i}")
            proc.start()
            send.close()
            self.running[i] = _Running(proc, recv, time.monotonic() + self.deadline)

    def _collect(self) -> None:
        now = time.monotonic()
        for i in list(self.running):
            r = self.running[i]
            out = _outcome(r, now, self.deadline)
            if out is None:
                continue  # still running
            r.proc.join(timeout=5)
            if r.proc.exitcode is None:
                r.proc.kill()
                r.proc.join()
            r.conn.close()
            del self.running[i]
            sweep(self.before | {x.proc.pid for x in self.running.values()})
            sweep_stale_boxes()  # the box folder of an item that was killed
            self.done(i, out)


def _outcome(r: _Running, now: float, deadline: float) -> Any:
    """An item's result, a :class:`Lost` (one past its deadline is killed), or None while it is
    still running."""
    if r.conn.poll():
        try:
            return r.conn.recv()
        except (EOFError, OSError):
            pass
        except Exception as exc:  # noqa: BLE001 - what came back cannot be unpickled
            return Lost("not-a-report", f"{type(exc).__name__}: {exc}")
    code = r.proc.exitcode
    if code is None and now < r.deadline:
        return None
    if code is None:
        r.proc.kill()
        return Lost("too-long", f"{deadline:g} s")
    how = f"signal {signal.Signals(-code).name}" if code < 0 else f"exit status {code}"
    return Lost("died", how)


# --------------------------------------------------------------------- an executor (Dask, ...)
def _guarded(task: Callable[[Any], Any], item: Any) -> Any:
    """The task in an executor's worker: its exception is the item's, not the pool's."""
    try:
        return task(item)
    except Exception as exc:  # noqa: BLE001
        return Lost("error", f"{type(exc).__name__}: {exc}")


def _on_executor(task: Callable[[Any], Any], items: Sequence[Any], jobs: int, deadline: float,
                 done: Done, executor: object) -> None:
    from gpsaccel.executors import resolve_executor

    with resolve_executor(executor, max_workers=jobs) as ex:
        pending = deque(range(len(items)))
        running: dict[cf.Future, tuple[int, float]] = {}
        try:
            while pending or running:
                while pending and len(running) < jobs:
                    i = pending.popleft()
                    running[ex.submit(_guarded, task, items[i])] = (i, time.monotonic() + deadline)
                finished, _ = cf.wait(list(running), timeout=0.1,
                                      return_when=cf.FIRST_COMPLETED)
                _collect_futures(running, finished, deadline, done)
        finally:
            for fut in running:
                fut.cancel()


def _collect_futures(running: dict[cf.Future, tuple[int, float]], finished: set[cf.Future],
                     deadline: float, done: Done) -> None:
    now = time.monotonic()
    for fut in list(running):
        i, until = running[fut]
        if fut in finished:
            try:
                out = fut.result()
            except Exception as exc:  # noqa: BLE001 - a worker lost: that item only
                out = Lost("died", f"{type(exc).__name__}: {exc}")
        elif now >= until:
            fut.cancel()
            out = Lost("too-long", f"{deadline:g} s")
        else:
            continue
        del running[fut]
        done(i, out)
