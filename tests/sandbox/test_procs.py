"""The checked kill that empties a box (gpsaccel.sandbox.procs._kill_box): every process of the
box dies, however it moves; the box's cgroup killed at once where it can be, never at the cost of
a box that does not start."""

from __future__ import annotations

import contextlib
import functools
import os
import signal
import subprocess
import sys

import numpy as np
import pytest

from gpsaccel import sandbox as sb
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
                               preexec_fn=functools.partial(_enter.join_cgroup, cg.procs_files,
                                                            cg.kill_procs_files),
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


@pytest.mark.skipif(_cgroup.available() != "cgroup1" or _cgroup._v2_kill_base() is None,
                    reason="a box cgroup made for cgroup.kill alone is made only under cgroup1, "
                           "beside a mounted unified hierarchy")
def test_a_box_starts_though_its_cgroup_for_the_kill_cannot_be_joined(backend, monkeypatch,
                                                                      tmp_path):
    """Under cgroup1 the box's cgroup made for ``cgroup.kill`` alone (in the unified hierarchy)
    is a help, not a limit: where its process cannot join it (here it is not there at all), the
    box starts, runs and is emptied as before, by pid."""
    monkeypatch.setattr(_cgroup, "_kill_only", lambda base, name: tmp_path / "no-such-cgroup")
    (tmp_path / "s.py").write_text("def f(z):\n    return z + 1.0\n")
    box = sb.run(sb.load_submission(tmp_path / "s.py", "f"),
                 [sb.Call("f", (np.zeros(2),), (sb.Output("a", (2,)),))],
                 sb.Limits(memory=512 << 20, time=20), backend)
    assert box.failure is None, (box.failure, box.detail)
    np.testing.assert_array_equal(box.results[0]["a"], np.ones(2))
