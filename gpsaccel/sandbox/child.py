"""Host-side work on untrusted input, under limits: :func:`in_child`.

Parsing a student's notebook is our code running on the student's bytes, not the student's code,
so it needs no box; it needs limits.  IPython's input transformer is quadratic on some input (a
cell of 600 ``%env`` lines raises ``RuntimeError: Input transformation still changing after 500
iterations`` after seconds of CPU), and ``json`` recurses on nested lists.  :func:`in_child` runs
one such job in a forked child: CPU time and added address space limited by rlimits, a wall-clock
guard in the parent, the result back over a pipe as JSON (plain data: no pickle, nothing that runs
code when read), and every way the child can end an :class:`ChildResult` outcome, never an exception
that escapes::

    out = sb.in_child(parse, path, cpu=5, memory=256 << 20, wall=120)
    if out.failure is None:
        cells = out.value          # what parse returned, as JSON gives it back (lists, dicts, ...)
    else:
        out.failure, out.detail    # "raised", "RuntimeError: Input transformation ..."

Fork, not spawn: the child starts with what the parent has imported (IPython's transformer, the
questions of a homework), so the job's arguments are never pickled and a short job costs a
fork (about a millisecond), not an interpreter.  The child ignores SIGINT (Ctrl-C is the
parent's), dies with its parent (``PR_SET_PDEATHSIG``) and leaves through ``os._exit`` (no
at-exit handler or buffer of the parent's runs twice).  A parent interrupted while it waits
kills the child before the interruption goes on.
"""

from __future__ import annotations

import faulthandler
import json
import os
import resource
import select
import signal
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from gpsaccel.sandbox.procs import PR_SET_PDEATHSIG, _prctl

#: The ways a child's job can end besides a value (:attr:`ChildResult.failure`).
FAILURES = ("raised", "cpu-limit", "memory-limit", "wall-limit", "too-large", "not-plain-data",
            "crashed", "not-started")

_DETAIL = 300  # characters of an exception's text kept


@dataclass(frozen=True)
class ChildResult:
    """How a job run by :func:`in_child` ended.

    value : what the job returned, through JSON (a tuple comes back a list), when
        ``failure`` is None.
    failure : None, or one of :data:`FAILURES`: ``raised`` (the job raised: ``detail`` is
        ``Type: message``, anything from ``RuntimeError`` to ``SystemExit``), ``cpu-limit``,
        ``memory-limit`` (a ``MemoryError`` at the address-space limit), ``wall-limit`` (killed
        after ``wall`` seconds), ``too-large`` (a reply longer than ``max_bytes``),
        ``not-plain-data`` (a value JSON cannot carry), ``crashed`` (the child died otherwise:
        ``detail`` says how), ``not-started`` (no child could be forked: the machine's, not the
        input's).
    cpu : CPU seconds (user + system) the child used.
    """

    value: Any = None
    failure: str | None = None
    detail: str = ""
    cpu: float = 0.0

    @property
    def ok(self) -> bool:
        return self.failure is None


def in_child(fn: Callable[..., Any], *args: Any, cpu: float, memory: int, wall: float,
             max_bytes: int | None = None) -> ChildResult:
    """``fn(*args)`` in a forked child limited to ``cpu`` CPU seconds, ``memory`` bytes of
    address space beyond what it starts with (a forked child starts with the parent's), and
    ``wall`` seconds of wall-clock time (a guard for a machine that starves it: generous); its
    reply at most ``max_bytes`` of JSON (default ``memory``).  Never raises for what ``fn``
    does (ValueError for bad limits); see :class:`ChildResult`.  Linux and macOS (fork)."""
    for name, value in (("cpu", cpu), ("wall", wall)):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
            raise ValueError(f"in_child: {name} must be a positive number of seconds, "
                             f"got {value!r}")
    limit = memory if max_bytes is None else max_bytes
    for name, value in (("memory", memory), ("max_bytes", limit)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ValueError(f"in_child: {name} must be a positive number of bytes, "
                             f"got {value!r}")
    try:
        rfd, wfd = os.pipe()
    except OSError as exc:
        return ChildResult(failure="not-started", detail=f"pipe: {exc.strerror}")
    parent = os.getpid()
    try:
        pid = os.fork()
    except OSError as exc:
        os.close(rfd)
        os.close(wfd)
        return ChildResult(failure="not-started", detail=f"fork: {exc.strerror}")
    if pid == 0:  # pragma: no cover - the child (coverage does not follow a fork)
        os.close(rfd)
        _child(wfd, parent, fn, args, cpu, memory)
    os.close(wfd)
    return _Parent(pid, rfd, cpu, wall, limit).wait()


# ------------------------------------------------------------------------------- the child
def _child(wfd: int, parent: int, fn: Callable[..., Any], args: tuple,  # pragma: no cover
           cpu: float, memory: int) -> None:
    """Run the job and send ``{"value": ...}`` or ``{"failure": ..., "detail": ...}``; exit
    without cleanup, whatever happens."""
    code = 0
    try:
        _detach(parent)
        _limit(cpu, memory)
        try:
            reply: dict[str, Any] = {"value": fn(*args)}
        except MemoryError:
            reply = {"failure": "memory-limit", "detail": "MemoryError"}
        except BaseException as exc:  # noqa: BLE001 - the job's every error is an outcome
            reply = {"failure": "raised", "detail": _described(exc)}
        try:
            data = json.dumps(reply, allow_nan=True).encode()
        except MemoryError:
            data = b'{"failure": "memory-limit", "detail": "MemoryError"}'
        except (TypeError, ValueError, RecursionError) as exc:
            data = json.dumps({"failure": "not-plain-data", "detail": _described(exc)}).encode()
        view = memoryview(data)
        while view:
            view = view[os.write(wfd, view):]
    except BaseException:  # noqa: BLE001 - the parent reports the exit status
        code = 3
    finally:
        os._exit(code)


def _detach(parent: int) -> None:  # pragma: no cover - runs in the child
    """Signals as a worker's: Ctrl-C is the parent's; SIGTERM and SIGHUP kill (not a handler of
    the parent's, copied by the fork); the child dies with the parent; a crash is the outcome's
    to report, not a traceback on the parent's terminal (faulthandler off)."""
    faulthandler.disable()
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    for sig in (signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, signal.SIG_DFL)
    _prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
    if os.getppid() != parent:  # the parent died before the death signal was set
        os._exit(4)


def _limit(cpu: float, memory: int) -> None:  # pragma: no cover - runs in the child
    """CPU seconds (SIGXCPU at the limit, SIGKILL a second later) and address space added to
    what the child has now (a forked child's address space is its parent's)."""
    soft = max(1, int(cpu + 0.999))
    resource.setrlimit(resource.RLIMIT_CPU, (soft, soft + 1))
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
    now = _address_space()
    if now is not None:
        resource.setrlimit(resource.RLIMIT_AS, (now + memory, now + memory))


def _address_space() -> int | None:
    """This process's address space (bytes), None where /proc does not say (then no memory
    limit: the CPU limit still bounds the job)."""
    try:
        with open("/proc/self/statm", "rb") as f:
            return int(f.read().split()[0]) * resource.getpagesize()
    except (OSError, ValueError, IndexError):
        return None


def _described(exc: BaseException) -> str:
    try:
        text = f"{type(exc).__name__}: {exc}"
    except BaseException:  # noqa: BLE001 - an exception whose str() raises
        text = type(exc).__name__
    return text if len(text) <= _DETAIL else text[:_DETAIL - 1] + "…"


# ------------------------------------------------------------------------------ the parent
class _Parent:
    """Read the child's reply within the wall-clock guard and the size limit, reap the child,
    and name how it ended."""

    def __init__(self, pid: int, rfd: int, cpu: float, wall: float, max_bytes: int) -> None:
        self.pid, self.rfd, self.cpu_limit, self.max_bytes = pid, rfd, cpu, max_bytes
        self.deadline = time.monotonic() + wall
        self.wall = wall
        self.chunks: list[bytes] = []
        self.size = 0
        self.status: int | None = None
        self.cpu = 0.0

    def wait(self) -> ChildResult:
        stopped: str | None = None
        try:
            stopped = self._read()
        finally:  # an interrupted parent (Ctrl-C, SIGTERM) leaves no child behind
            if self.status is None:
                self._kill()
            os.close(self.rfd)
        return self._outcome(stopped)

    def _read(self) -> str | None:
        """Until the reply's end (EOF, or the child gone and the pipe drained: a child forked
        meanwhile by another thread may hold the write end), the deadline or the size limit."""
        while True:
            left = self.deadline - time.monotonic()
            if left <= 0:
                return "wall-limit"
            ready = select.select([self.rfd], [], [], min(left, 0.25))[0]
            if ready:
                chunk = os.read(self.rfd, 1 << 20)
                if not chunk:
                    return None
                self.chunks.append(chunk)
                self.size += len(chunk)
                if self.size > self.max_bytes:
                    return "too-large"
            elif self._reaped(os.WNOHANG):
                os.set_blocking(self.rfd, False)
                try:
                    while chunk := os.read(self.rfd, 1 << 20):
                        self.chunks.append(chunk)
                        self.size += len(chunk)
                except BlockingIOError:
                    pass
                return "too-large" if self.size > self.max_bytes else None

    def _reaped(self, flags: int) -> bool:
        pid, status, usage = os.wait4(self.pid, flags)
        if pid == 0:
            return False
        self.status = status
        self.cpu = usage.ru_utime + usage.ru_stime
        return True

    def _kill(self) -> None:
        try:
            os.kill(self.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        while True:
            try:
                self._reaped(0)
                return
            except InterruptedError:  # pragma: no cover - retried by Python since 3.5
                continue
            except ChildProcessError:  # pragma: no cover - reaped elsewhere
                return

    def _outcome(self, stopped: str | None) -> ChildResult:
        if stopped is None and self.status is None:
            self._reaped(0)  # EOF came first: the child is exiting
        assert self.status is not None
        code = os.waitstatus_to_exitcode(self.status)
        if stopped == "wall-limit":
            return ChildResult(failure=stopped, detail=f"still running after {self.wall:g} s",
                               cpu=self.cpu)
        if stopped == "too-large":
            return ChildResult(failure=stopped, detail=f"a reply of more than {self.max_bytes} "
                               f"bytes", cpu=self.cpu)
        # SIGXCPU at the soft limit; SIGKILL a second later at the hard one, where the job
        # ignored SIGXCPU
        if code == -signal.SIGXCPU or (code == -signal.SIGKILL and self.cpu >= self.cpu_limit):
            return ChildResult(failure="cpu-limit",
                               detail=f"more than {self.cpu_limit:g} CPU s", cpu=self.cpu)
        if code != 0:
            return ChildResult(failure="crashed", detail=_how(code), cpu=self.cpu)
        try:
            reply = json.loads(b"".join(self.chunks))
        except (ValueError, RecursionError, MemoryError):
            return ChildResult(failure="crashed", detail="no complete reply", cpu=self.cpu)
        if not isinstance(reply, dict) or not ("value" in reply or "failure" in reply):
            return ChildResult(failure="crashed", detail="no complete reply", cpu=self.cpu)
        if "value" in reply:
            return ChildResult(value=reply["value"], cpu=self.cpu)
        failure = reply.get("failure")
        return ChildResult(failure=failure if failure in FAILURES else "crashed",
                           detail=str(reply.get("detail", ""))[:_DETAIL], cpu=self.cpu)


def _how(code: int) -> str:
    if code >= 0:
        return f"exit status {code}"
    try:
        return f"signal {signal.Signals(-code).name}"
    except ValueError:
        return f"signal {-code}"
