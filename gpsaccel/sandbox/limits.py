"""The limits of one box beyond its arguments: rlimits set before exec, the box's cgroup, and (as
root) a uid of its own (:mod:`._cgroup`, :mod:`._boxuser`)."""

from __future__ import annotations

import os
import resource
import signal
import sys
from dataclasses import dataclass, field
from pathlib import Path

import psutil

from gpsaccel.sandbox import _boxuser, _cgroup
from gpsaccel.sandbox.fence import Fence
from gpsaccel.sandbox.procs import PR_CAPBSET_DROP, PR_SET_NO_NEW_PRIVS, PR_SET_PDEATHSIG, _libc, _prctl
from gpsaccel.sandbox.spec import Limits


def _cap_last() -> int:
    try:
        return int(Path("/proc/sys/kernel/cap_last_cap").read_text())
    except (OSError, ValueError):
        return 40


def _user_tasks() -> int:
    """Processes and threads of this real uid (what RLIMIT_NPROC counts; psutil)."""
    uid, n = os.getuid(), 0
    for p in psutil.process_iter(["uids", "num_threads"]):
        uids, threads = p.info["uids"], p.info["num_threads"]
        if uids is not None and uids.real == uid:
            n += threads or 1
    return n


def _nproc(limits: Limits) -> int:
    """RLIMIT_NPROC for the box.  It counts every process and thread of the real uid, not of the
    box, so for a user other than root it is set to what the user runs now plus the box's
    allowance; root's processes are not counted at all (the parent's scan enforces it then)."""
    if os.getuid() == 0 or not os.path.isdir("/proc"):
        return limits.processes
    return _user_tasks() + limits.processes


@dataclass
class _Confinement:
    """What confines one box beyond its rlimits: the uid it runs as (root only), its cgroup, the
    mounts that reveal the interpreter to that uid, the fence of a basic box's hidden folders."""

    uid: int | None = None
    cgroup: _cgroup.BoxCgroup | None = None
    reveal: list[tuple[str, list[str]]] = field(default_factory=list)
    lock: int | None = None  # held while the uid is this box's
    fence: Fence | None = None

    @property
    def limit_backend(self) -> str:
        return self.cgroup.kind if self.cgroup is not None else "rlimit"

    def pids(self) -> set[int]:
        """Every process of the box this confinement can name (its cgroup, its uid)."""
        out = self.cgroup.pids() if self.cgroup is not None else set()
        if self.uid is not None:
            out |= _boxuser.uid_pids(self.uid)
        return out


def _confine(limits: Limits, backend: str, needed: list[str]) -> _Confinement:
    """A cgroup and (as root) a uid of its own for a new box; whatever an earlier box of the same
    uid left running is killed first."""
    c = _Confinement()
    extra = 2 if backend == "bwrap" else 0  # bwrap's own two processes
    if sys.platform.startswith("linux"):
        c.cgroup = _cgroup.create(limits.memory, limits.processes + 1 + extra)
        got = _boxuser.acquire()
        if got is not None:
            c.uid, c.lock = got
    if c.uid is not None:
        _boxuser.kill_uid(c.uid)
        c.reveal = _boxuser.reveal(needed)
    return c


def _preexec(limits: Limits, nproc: int, drop_caps: bool, cap_last: int,
             confinement: _Confinement | None = None) -> None:
    """In the child, before exec: join the box's cgroup, limits, no core files; as root also the
    mounts revealing the interpreter, an empty capability bounding set, the box's uid, no new
    privileges; last the fence of a basic box's hidden folders (runs after fork; everything it
    calls was looked up before the fork)."""
    c = confinement or _Confinement()
    libc = _libc()
    if c.cgroup is not None:
        for f in c.cgroup.procs_files:
            fd = os.open(f, os.O_WRONLY)
            try:
                os.write(fd, b"0")
            finally:
                os.close(fd)
    if c.reveal:  # before the rlimits: the parent's descriptors are still open here (close_fds
        # comes after preexec_fn), so with RLIMIT_NOFILE set first, a grader holding more than
        # open_files descriptors could not open the folders to reveal and no box would start
        if libc is None:
            raise OSError("the box's reveal needs Linux's libc")
        _boxuser.apply_reveal(libc, c.reveal)
    landlock = c.fence is not None and c.fence.kind == "landlock"
    if c.fence is not None and c.fence.kind == "mount":  # as root, over the revealed folders
        if libc is None:
            raise OSError("the box's fence needs Linux's libc")
        c.fence.apply(libc)
    cpu = int(limits.time) + 2
    for res, value in ((resource.RLIMIT_AS, limits.memory), (resource.RLIMIT_CPU, cpu),
                       (resource.RLIMIT_FSIZE, limits.file_size),
                       (resource.RLIMIT_NPROC, nproc),
                       (resource.RLIMIT_NOFILE, limits.open_files),
                       (resource.RLIMIT_CORE, 0)):
        resource.setrlimit(res, (value, value))
    if drop_caps:  # root: after exec the permitted set is the bounding set, so empty it
        for cap in range(cap_last + 1):
            _prctl(PR_CAPBSET_DROP, cap)
    if c.uid is not None:
        os.setgroups([])
        os.setresgid(c.uid, c.uid, c.uid)
        os.setresuid(c.uid, c.uid, c.uid)
    _prctl(PR_SET_PDEATHSIG, signal.SIGKILL)  # after the uid: a change of uid clears it
    if drop_caps or landlock:  # Landlock restricts only a process that cannot gain privileges
        _prctl(PR_SET_NO_NEW_PRIVS, 1)
    if landlock:
        assert c.fence is not None and libc is not None
        c.fence.apply(libc)
