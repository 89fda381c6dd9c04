"""The checked kill that empties a box (gpsaccel.sandbox.procs._kill_box): every process of the
box dies, however it moves."""

from __future__ import annotations

import contextlib
import functools
import os
import signal
import subprocess
import sys

import pytest

from gpsaccel.sandbox import _cgroup, _enter, procs
from gpsaccel.sandbox.limits import _Confinement


def _cgroup_kill_here() -> bool:
    """Whether a box's cgroup can have ``cgroup.kill`` here: a box cgroup at all, a cgroup v2
    hierarchy mounted (the boxes' own, or the unified one beside cgroup1's), Linux 5.14 or
    later."""
    release = os.uname().release.split("-")[0].split(".")
    try:
        version = (int(release[0]), int(release[1]))
    except (IndexError, ValueError):
        return False
    return _cgroup.available() is not None and version >= (5, 14) and \
        any(kind == "cgroup2" for _, kind, _ in _cgroup._mounts())


@pytest.mark.skipif(not _cgroup_kill_here(), reason="no cgroup v2 with cgroup.kill here "
                                                     "(Linux 5.14, a cgroup2 mount, root)")
def test_a_box_no_kill_by_pid_reaches_is_emptied_at_once(monkeypatch):
    """The checked kill scans /proc and the box's cgroup, then SIGKILLs each pid it found: a
    chain of processes that each fork and exit is gone from its pid before the kill lands, and
    a box's processes are its cgroup's whatever their pids.  Where the box's cgroup has
    ``cgroup.kill`` (a cgroup v2, or under cgroup1 a cgroup of the box's own in the unified
    hierarchy mounted beside), the kernel kills every process of it in one step, forks in
    flight included, and the scan only confirms.  Here every kill by pid misses (``os.kill``
    does nothing), as against a chain too fast for any scan: before, the kill gave up after 200
    rounds (RuntimeError, 10 s); now the box is empty after one."""
    cg = _cgroup.create(256 << 20, 8)
    assert cg is not None
    before = procs._my_children()
    sleeper = subprocess.Popen([sys.executable, "-I", "-S", "-c", "import time; time.sleep(60)"],
                               preexec_fn=functools.partial(_enter.join_cgroup, cg.procs_files),
                               start_new_session=True)
    misses: list[int] = []
    try:
        assert sleeper.pid in cg.pids()
        monkeypatch.setattr(os, "kill", lambda pid, sig: misses.append(pid))
        found = procs._kill_box(sleeper, before, _Confinement(cgroup=cg))
        monkeypatch.undo()
        assert misses  # the kill by pid was tried, and missed
        assert found == 1
        assert sleeper.returncode == -signal.SIGKILL
        assert not cg.pids()
    finally:
        monkeypatch.undo()
        with contextlib.suppress(OSError):
            os.kill(sleeper.pid, signal.SIGKILL)
        sleeper.wait()
        assert cg.remove()
    assert not [d for d in cg.dirs.values() if d.exists()]  # the box's cgroups, each removed
