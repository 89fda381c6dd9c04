"""The box's own user: as root, a student runs as a uid that owns nothing and that nothing else runs as.

Used by :mod:`gpsaccel.sandbox` (both backends, when the checker runs as root); not an
interface of its own.

* :func:`acquire`: a uid with no passwd entry, ``UID_BASE + SLOTS * pid + k`` for the
  supervising process's pid and the first slot ``k`` no other box of that process holds (a lock
  file).  The pid is unique among live processes and the slot among its boxes, so two boxes
  running at once never share a uid; whatever still runs as the uid when a box starts is what an
  earlier box of a dead supervisor with the same pid left, and is killed.  The uid owns no file
  of the package, the environment or the instructor's, so the student cannot write a ``.pth``
  into site-packages, edit the package or a results file, nor signal (kill, SIGSTOP) any process
  but its own.
* :func:`kill_uid`: everything the uid runs, wherever it is in the process tree (a daemon, a
  process a terminal multiplexer server started), is killed until a scan of ``/proc`` finds
  none; :func:`remove_files` removes what the uid left in the shared writable folders.
* :func:`reveal`: the interpreter may live where that uid cannot reach it (``/root/.pyenv``, a
  venv in a 0700 home).  In the box's first process, before it drops root, a private mount
  namespace replaces each unreachable ancestor by a small read-only tmpfs holding read-only bind
  mounts of exactly the folders the box needs (the rest of ``/root`` is then not in reach
  either): :func:`gpsaccel.sandbox._enter.reveal` does it from this plan.
"""

from __future__ import annotations

import fcntl
import os
import pwd
import signal
import stat
import tempfile
import time
from pathlib import Path

from gpsaccel.sandbox._removal import remove_tree
from gpsaccel.sandbox.procs import proc_files

#: First uid of the boxes' range (2^31 - 2^27: above every distribution's allocation ranges,
#: below the 32-bit overflow uids): SLOTS uids for each pid (threads of one process may run
#: boxes at once), for pids below 2^22 (the largest ``pid_max``); the range ends below 2^32 - 1.
UID_BASE = 2_013_265_920
UID_SPAN = 1 << 22
SLOTS = 512

#: Shared writable folders where a box user could leave files (cleaned after each box): every
#: folder of a Debian or Ubuntu machine any user may write, ``/run/lock`` (``/var/lock``) too.
SHARED_TMP = ("/tmp", "/var/tmp", "/dev/shm", "/run/lock", "/var/lock")


def box_uid() -> int | None:
    """The first uid of this process's slots, or None (not root, no /proc, or an account in the
    range): then a box runs as the checker's own user."""
    if os.geteuid() != 0 or not os.path.isdir("/proc/self"):
        return None
    uid = UID_BASE + (os.getpid() % UID_SPAN) * SLOTS
    for u in (uid, uid + SLOTS - 1):
        try:
            pwd.getpwuid(u)
        except KeyError:
            continue
        return None  # pragma: no cover - an account in the boxes' range
    return uid


def acquire() -> tuple[int, int] | None:
    """(uid, lock) for a new box: the first of this process's slots no other box holds, locked
    (``flock`` on a file of a root-only folder) until :func:`release`; None when there is no box
    uid here."""
    base = box_uid()
    if base is None:
        return None
    folder = os.path.join(tempfile.gettempdir(), "gpsaccel-uids")
    try:
        os.mkdir(folder, 0o700)
    except FileExistsError:
        pass
    st = os.lstat(folder)
    if not stat.S_ISDIR(st.st_mode) or st.st_uid != 0 or st.st_mode & 0o077:
        return None  # not a folder only root controls: no lock to trust
    for k in range(SLOTS):
        fd = os.open(os.path.join(folder, str(base + k)),
                     os.O_CREAT | os.O_RDWR | os.O_NOFOLLOW | os.O_CLOEXEC, 0o600)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            continue
        return base + k, fd
    return None  # pragma: no cover - 512 boxes at once in one process


def release(lock: int) -> None:
    os.close(lock)


def uid_pids(uid: int) -> set[int]:
    """Live processes any of whose uids (real, effective, saved, file system) is ``uid``.  Read
    from /proc by hand: psutil's ``uids()`` has no file-system uid, which a box process may keep
    (``setfsuid``) while its other uids change."""
    out = set()
    want = str(uid).encode()
    for pid, status in proc_files("status"):
        uids, state = _field(status, b"Uid:"), _field(status, b"State:")[:1]
        if uids and want in uids and state not in ([b"Z"], [b"X"]):
            out.add(pid)
    return out


def _field(status: bytes, name: bytes) -> list[bytes]:
    """The words after ``name`` on its line of a /proc/<pid>/status text ([] if none): found
    directly rather than by splitting every line (a box reads every process's status a few
    times); never the first line, which is ``Name:``."""
    i = status.find(b"\n" + name)
    if i < 0:
        return []
    end = status.find(b"\n", i + 1)
    return status[i + 1 + len(name):end if end >= 0 else len(status)].split()


def kill_uid(uid: int, rounds: int = 200) -> int:
    """SIGKILL every process of ``uid`` until none is left; how many there were at first."""
    first = None
    for _ in range(rounds):
        pids = uid_pids(uid)
        if first is None:
            first = len(pids)
        if not pids:
            return first
        for pid in pids:
            try:
                os.kill(pid, signal.SIGKILL)
            except (ProcessLookupError, PermissionError):
                pass
        time.sleep(0.005)
    raise RuntimeError(f"the sandbox could not kill the processes of uid {uid}")  # pragma: no cover


def remove_files(uid: int) -> list[str]:
    """Remove the entries of the shared temporary folders owned by ``uid``; their paths."""
    gone = []
    for d in SHARED_TMP:
        try:
            entries = list(os.scandir(d))
        except OSError:
            continue
        for e in entries:
            try:
                st = e.stat(follow_symlinks=False)
            except OSError:
                continue
            if st.st_uid != uid:
                continue
            try:
                if stat.S_ISDIR(st.st_mode):  # any depth (rmtree's recursion stops at 1000)
                    remove_tree(e.path)
                else:
                    os.unlink(e.path)
                gone.append(e.path)
            except OSError:
                pass
    return gone


def _others_can_enter(path: str) -> bool:
    try:
        st = os.stat(path)
    except OSError:
        return True  # not there: nothing to reveal
    return bool(st.st_mode & stat.S_IXOTH)


def reveal(paths: list[str]) -> list[tuple[str, list[str]]]:
    """For the folders ``paths`` the box needs: (unreachable ancestor, the needed folders below
    it) for every ancestor another user cannot enter; empty when all are reachable."""
    plan: dict[str, list[str]] = {}
    real = sorted({os.path.realpath(p) for p in paths if os.path.isdir(p)})
    for p in real:
        parts = Path(p).parts
        for k in range(2, len(parts) + 1):
            a = str(Path(*parts[:k - 1]))
            if not _others_can_enter(a):
                top = next((t for t in plan if a == t or a.startswith(t + "/")), a)
                plan.setdefault(top, [])
                if not any(p == q or p.startswith(q + "/") for q in plan[top]):
                    plan[top] = [q for q in plan[top] if not q.startswith(p + "/")] + [p]
                break
    return sorted(plan.items())
