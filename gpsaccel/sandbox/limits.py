"""The limits of one box beyond its arguments: rlimits set before exec, the box's cgroup, and (as
root) a uid of its own (:mod:`._cgroup`, :mod:`._boxuser`)."""

from __future__ import annotations

import functools
import os
import resource
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import psutil

from gpsaccel.sandbox import _boxuser, _cgroup, _enter
from gpsaccel.sandbox.fence import Fence
from gpsaccel.sandbox.procs import _libc
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

    def kill_at_once(self) -> bool:
        """SIGKILL every process of the box's cgroup in one step, where it has ``cgroup.kill``
        (:meth:`._cgroup.BoxCgroup.kill_at_once`)."""
        return self.cgroup is not None and self.cgroup.kill_at_once()


def _confine(limits: Limits, backend: str, needed: list[str], extra: int) -> _Confinement:
    """A cgroup and (as root) a uid of its own for a new box; whatever an earlier box of the same
    uid left running is killed first.  ``extra``: the box's own processes beside the runner
    (bwrap's two, a basic warm box's keeper)."""
    c = _Confinement()
    if sys.platform.startswith("linux"):
        c.cgroup = _cgroup.create(limits.memory, limits.processes + 1 + extra)
        got = _boxuser.acquire()
        if got is not None:
            c.uid, c.lock = got
    if c.uid is not None:
        _boxuser.kill_uid(c.uid)
        c.reveal = _boxuser.reveal(needed)
    return c


def _entry_plan(limits: Limits, nproc: int, drop_caps: bool, cap_last: int,
                c: _Confinement, own_proc: bool = False) -> dict:
    """What the box's first process does before the student's code (:mod:`._enter`'s plan):
    join the box's cgroup, limits, no core files; as root also the mounts revealing the
    interpreter, an empty capability bounding set, the box's uid, no new privileges; last the
    fence of a basic box's hidden folders.  ``own_proc``: a ``/proc`` that shows the box only its
    own uid's processes (a basic box as root, where the kernel lets it mount one)."""
    cpu = int(limits.time) + 2
    fence = c.fence
    return {
        "cgroup": c.cgroup.procs_files if c.cgroup is not None else [],
        "cgroup_kill": c.cgroup.kill_procs_files if c.cgroup is not None else [],
        "reveal": [[top, list(paths)] for top, paths in c.reveal],
        "fence": fence.kind if fence is not None else None,
        "hidden": list(fence.hidden) if fence is not None else [],
        "empty": fence.empty if fence is not None else None,
        "rlimits": [[resource.RLIMIT_AS, limits.memory], [resource.RLIMIT_CPU, cpu],
                    [resource.RLIMIT_FSIZE, limits.file_size], [resource.RLIMIT_NPROC, nproc],
                    [resource.RLIMIT_NOFILE, limits.open_files], [resource.RLIMIT_CORE, 0]],
        "proc": own_proc, "drop_caps": drop_caps, "cap_last": cap_last, "uid": c.uid}


def _preexec(plan: dict, confinement: _Confinement) -> Callable[[], None]:
    """The ``preexec_fn`` of a cold box: :func:`._enter.enter` with this plan (it runs after
    fork; everything it calls is looked up before)."""
    fence = confinement.fence
    ruleset = fence.ruleset if fence is not None else None
    return functools.partial(_enter.enter, _libc(), plan, ruleset)
