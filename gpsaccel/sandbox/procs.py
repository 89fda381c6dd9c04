"""Processes: prctl (subreaper, dumpable, death signal), the process table (/proc, psutil), a box's
processes, the time a process waited for a CPU and the CPU its processes used (the box's fair
clock), and the checked kill that empties a box."""

from __future__ import annotations

import ctypes
import functools
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterable, Iterator, Sequence
from collections.abc import Set as AbstractSet
from typing import Protocol

import psutil


class _NamesPids(Protocol):
    """What a kill asks of a box's confinement (limits._Confinement, which imports this module):
    every process it can name, by cgroup or uid, and a kill of its cgroup at once."""

    def pids(self) -> set[int]: ...

    def kill_at_once(self) -> bool: ...


# psutil.process_iter keeps its Process objects between calls, each with a lock: a thread of the
# parent (a watcher, a second pool) may hold one at the moment of a fork, and the forked item
# would wait on it for ever.  The forked child starts with an empty cache instead.
if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=psutil.process_iter.cache_clear)


@functools.lru_cache(maxsize=1)
def _libc() -> ctypes.CDLL | None:
    if not sys.platform.startswith("linux"):
        return None
    try:
        return ctypes.CDLL(None, use_errno=True)
    except OSError:
        return None


PR_SET_PDEATHSIG, PR_GET_DUMPABLE, PR_SET_DUMPABLE = 1, 3, 4
PR_CAPBSET_DROP, PR_SET_NO_NEW_PRIVS = 24, 38
PR_SET_CHILD_SUBREAPER, PR_GET_CHILD_SUBREAPER = 36, 37


def _prctl(option: int, arg: int = 0) -> int:
    libc = _libc()
    if libc is None:
        return -1
    return libc.prctl(ctypes.c_int(option), ctypes.c_ulong(arg), ctypes.c_ulong(0),
                      ctypes.c_ulong(0), ctypes.c_ulong(0))


def _get_subreaper() -> int:
    libc = _libc()
    if libc is None:
        return 0
    value = ctypes.c_int(0)
    libc.prctl(ctypes.c_int(PR_GET_CHILD_SUBREAPER), ctypes.byref(value), ctypes.c_ulong(0),
               ctypes.c_ulong(0), ctypes.c_ulong(0))
    return value.value


def set_subreaper(on: bool) -> bool:
    """Make this process a child subreaper (orphans of its descendants become its children)."""
    return _prctl(PR_SET_CHILD_SUBREAPER, int(on)) == 0


def _proc_table() -> dict[int, tuple[int, str, str]]:
    """pid -> (ppid, state, name) of every process this one can see; state is ``"Z"`` for a
    zombie, ``"X"`` for a dead one.  On Linux read from /proc/<pid>/stat directly: the checked
    kill scans the table several times per box, and psutil's generic objects cost three times
    the CPU for it (benchmarks/sandbox.py); elsewhere psutil (macOS, the BSDs)."""
    if not os.path.isdir("/proc/self"):
        return _psutil_table()
    table: dict[int, tuple[int, str, str]] = {}
    for pid, raw in proc_files("stat"):
        close = raw.rfind(b")")
        rest = raw[close + 2:].split()
        if close < 0 or len(rest) < 2:
            continue  # the process went away while it was read
        comm = raw[raw.find(b"(") + 1:close].decode(errors="replace")
        table[pid] = (int(rest[1]), rest[0].decode(), comm)
    return table


def proc_files(name: str) -> Iterator[tuple[int, bytes]]:
    """(pid, the bytes of /proc/<pid>/``name``) for every process that is still there when read.

    Read unbuffered (``os.open``/``os.read`` until the end): a box scans every process's file
    about a dozen times, and Python's buffered file objects cost a third more CPU per scan."""
    for entry in os.scandir("/proc"):
        if not entry.name.isdigit():
            continue
        try:
            fd = os.open(f"/proc/{entry.name}/{name}", os.O_RDONLY)
        except OSError:
            continue
        try:
            chunks = [os.read(fd, 1 << 16)]
            while chunks[-1]:
                chunks.append(os.read(fd, 1 << 16))
        except OSError:
            continue
        finally:
            os.close(fd)
        yield int(entry.name), b"".join(chunks)


def runqueue_wait(pid: int) -> float | None:
    """Seconds task ``pid`` (a process's main thread) has waited on a run queue, runnable but
    not running, since it started: the second field of Linux's /proc/<pid>/schedstat (ns on a
    CPU, ns waiting, timeslices).  None where it cannot be read (not Linux, or the task is
    gone)."""
    try:
        with open(f"/proc/{pid}/schedstat", "rb") as f:
            return int(f.read().split()[1]) * 1e-9
    except (OSError, ValueError, IndexError):
        return None


def lowered_priority(pid: int) -> bool:
    """Whether task ``pid`` runs at a lower priority than this process (a larger nice value, or
    SCHED_IDLE): its waits for a CPU are then of its own making.  It cannot raise it back
    (RLIMIT_NICE 0, no CAP_SYS_NICE), so a look at the end tells."""
    try:
        if os.getpriority(os.PRIO_PROCESS, pid) > os.getpriority(os.PRIO_PROCESS, 0):
            return True
        idle = getattr(os, "SCHED_IDLE", None)
        return idle is not None and os.sched_getscheduler(pid) == idle
    except (OSError, AttributeError):
        return False


def cpu_seconds(pids: Iterable[int]) -> float:
    """CPU time (user + system, s) used by processes ``pids``, every thread and every child they
    waited for included (/proc/<pid>/stat); 0 for a process gone or not readable."""
    tick = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100
    total = 0
    for pid in pids:
        try:
            with open(f"/proc/{pid}/stat", "rb") as f:
                raw = f.read()
            fields = raw[raw.rfind(b")") + 2:].split()
            total += sum(int(x) for x in fields[11:15])  # utime stime cutime cstime
        except (OSError, ValueError):
            continue
    return total / tick


def _psutil_table() -> dict[int, tuple[int, str, str]]:
    table: dict[int, tuple[int, str, str]] = {}
    for p in psutil.process_iter(["ppid", "status", "name"]):
        info = p.info
        if info["ppid"] is None:
            continue  # gone while it was read
        status = info["status"]
        state = "Z" if status == psutil.STATUS_ZOMBIE else "X" if status == psutil.STATUS_DEAD \
            else "R"
        table[p.pid] = (int(info["ppid"]), state, info["name"] or "")
    return table


def start_time(pid: int) -> float | None:
    """When process ``pid`` started (s since the epoch), None when it is gone."""
    try:
        return psutil.Process(pid).create_time()
    except psutil.Error:
        return None


def box_processes(first: int | Sequence[int], adopted_from: set[int] | None) -> list[int]:
    """Live processes of a box: descendants of ``first`` (itself included; or of each of several
    first processes: a warm box's keeper and bwrap) and, when ``adopted_from`` is given, every
    new child of this process (orphans it adopted as a subreaper) with its descendants.  Zombies
    are not counted."""
    firsts = [first] if isinstance(first, int) else list(first)
    table = _proc_table()
    children: dict[int, list[int]] = {}
    for pid, (ppid, _, _) in table.items():
        children.setdefault(ppid, []).append(pid)
    roots = [p for p in firsts if p in table]
    if adopted_from is not None:
        me = os.getpid()
        roots += [p for p in children.get(me, []) if p not in firsts and p not in adopted_from]
    out, stack = [], list(roots)
    while stack:
        pid = stack.pop()
        if pid in out:
            continue
        out.append(pid)
        stack.extend(children.get(pid, []))
    return [p for p in out if table.get(p, (0, "Z", ""))[1] not in ("Z", "X")]


def bwrap_own(first: int, table: dict[int, tuple[int, str, str]]) -> set[int]:
    """bwrap's own processes in a box whose first process ``first`` is bwrap: itself and its
    child, the box's pid 1 (bwrap's init, or a warm box's reaper).  Known by pid, not by name:
    a student's process may call itself ``bwrap`` (prctl PR_SET_NAME), but none can be a child
    of ``first``: an orphan in the box goes to the box's pid 1, and a pid namespace's init may
    not give its children away (CLONE_PARENT)."""
    return {first} | {pid for pid, (ppid, _, _) in table.items() if ppid == first}


class _FirstProcess(Protocol):
    """What a kill asks of a box's first process (a ``subprocess.Popen``, or a warm box's
    keeper: :class:`gpsaccel.sandbox.warmbox.WarmBox`)."""

    pid: int

    def poll(self) -> int | None: ...

    def wait(self, timeout: float | None = None) -> int: ...


def _kill_box(proc: _FirstProcess, before: set[int], confinement: _NamesPids | None = None,
              roots: Sequence[int] = (), own: AbstractSet[int] = frozenset(),
              bwrap: bool = False) -> int:
    """SIGKILL every process of the box (the process trees of ``roots``, or of ``proc``, its
    cgroup, its uid) until none is alive; reap them.  Returns how many processes were alive
    when the kill began, besides the box's ``own`` (a basic warm box's keeper) and, when
    ``proc`` is bwrap (``bwrap``), bwrap's own (:func:`bwrap_own`).

    Once they are counted, the box's cgroup is killed at once where it can be (``cgroup.kill``:
    no chain of processes that fork and exit outruns it); the scan and the kill by pid go on
    as before, for what is outside the cgroup (a basic warm box's keeper) and where there is no
    ``cgroup.kill``."""
    roots = list(roots) or [proc.pid]
    found: int | None = None
    for _ in range(200):
        alive = set(box_processes(roots, before))
        if confinement is not None:
            alive |= confinement.pids()
        if found is None:
            boxes = (own | bwrap_own(proc.pid, _proc_table())) if bwrap else own
            found = len(alive - boxes)
            if confinement is not None:
                confinement.kill_at_once()
        if not alive:
            break
        for pid in alive:
            try:
                os.kill(pid, signal.SIGKILL)
            except (ProcessLookupError, PermissionError):
                pass
        if proc.poll() is None:
            try:
                proc.wait(timeout=0.05)
            except subprocess.TimeoutExpired:
                pass
        _reap_adopted(before, proc.pid)
    else:  # pragma: no cover - a box that outlives 200 rounds of SIGKILL
        raise RuntimeError(f"the sandbox could not kill processes {alive}")
    proc.wait()
    _reap_adopted(before, proc.pid)
    return found or 0


def _reap_adopted(before: set[int], first: int) -> None:
    """waitpid every exited child of this process that the box left (orphans adopted)."""
    for pid, (ppid, state, _) in _proc_table().items():
        if ppid == os.getpid() and pid not in before and pid != first and state in ("Z", "X"):
            try:
                os.waitpid(pid, os.WNOHANG)
            except ChildProcessError:
                pass


def _my_children() -> set[int]:
    me = os.getpid()
    return {pid for pid, (ppid, _, _) in _proc_table().items() if ppid == me}


def orphans(keep: AbstractSet[int]) -> list[int]:
    """Live processes under this one, except ``keep`` (the running items, and the children this
    process had before) and theirs: what a dead item's box left behind (re-parented here, the
    subreaper), with their descendants."""
    table = _proc_table()
    children: dict[int, list[int]] = {}
    for pid, (ppid, _, _) in table.items():
        children.setdefault(ppid, []).append(pid)
    stack = [p for p in children.get(os.getpid(), []) if p not in keep]
    out: list[int] = []
    while stack:
        pid = stack.pop()
        if pid not in out:
            out.append(pid)
            stack.extend(children.get(pid, []))
    return [p for p in out if table[p][1] not in ("Z", "X")]


def _reap_zombies(keep: AbstractSet[int]) -> None:
    me = os.getpid()
    for pid, (ppid, state, _) in _proc_table().items():
        if ppid == me and pid not in keep and state in ("Z", "X"):
            try:
                os.waitpid(pid, os.WNOHANG)
            except ChildProcessError:
                pass


def sweep(keep: AbstractSet[int] = frozenset()) -> int:
    """Kill (SIGKILL, until a scan finds none) every process under this one except ``keep`` and
    theirs; returns how many were killed."""
    killed: set[int] = set()
    for _ in range(200):
        alive = orphans(keep)
        if not alive:
            break
        for pid in alive:
            try:
                os.kill(pid, signal.SIGKILL)
                killed.add(pid)
            except (ProcessLookupError, PermissionError):
                pass
        time.sleep(0.01)
        _reap_zombies(keep)
    _reap_zombies(keep)
    return len(killed)


def set_dumpable(on: bool) -> None:
    """Open or close /proc/<this>/mem, environ, ... to processes of the same user (a process that
    holds answers while a student's code runs elsewhere closes them)."""
    _prctl(PR_SET_DUMPABLE, int(on))
