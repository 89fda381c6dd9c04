"""The confinement's own details (gpsaccel.sandbox.confinement): the order of bwrap's mounts, and
the sweep of stale box folders (their removal: tests/sandbox/test_removal.py)."""

from __future__ import annotations

import os
import stat
import sys

from gpsaccel import sandbox as sb
from gpsaccel.sandbox import confinement
from gpsaccel.sandbox.confinement import _bwrap_command


def test_bwrap_mounts_tmp_before_the_interpreters_folders(tmp_path, monkeypatch):
    """A venv below /tmp (CI's fresh clone) must stay visible: bwrap applies its mounts in order,
    so the /tmp tmpfs has to come before every bind, or it hides them."""
    entry = tmp_path / "f.py"
    entry.write_text("def kalman_filter(z):\n    return z\n")
    sub = sb.load_submission(entry, "kalman_filter")
    monkeypatch.setattr(sys, "prefix", "/tmp/some-venv")
    (tmp_path / "control").mkdir()
    cmd, fds = _bwrap_command("bwrap", tmp_path, sub, sb.Limits(), False, 9)
    for fd in fds:
        os.close(fd)
    first_tmpfs = next(i for i in range(len(cmd) - 1) if cmd[i:i + 2] == ["--tmpfs", "/tmp"])
    first_bind = cmd.index("--ro-bind")
    assert first_tmpfs < first_bind
    assert cmd.count("/tmp") == 1  # mounted once


#: No process has this pid (Linux's PID_MAX_LIMIT is 2**22): a box folder named with it is stale.
DEAD = (1 << 22) + 1


def test_the_sweep_never_follows_nor_removes_what_a_student_planted(tmp_path):
    """Under basic a box's /tmp is the machine's, where box and zygote folders are made, and the
    sweep runs as root at every box's start (a classmate's box starts while this one runs).  A
    student planted a stale box's name (a dead pid) as a symbolic link to any folder or file:
    rmtree refused the link, and its error handler changed the link's target to mode 0700 (the
    grader's site-packages, the interpreter's folder: every later box of the class fails).  The
    sweep takes only real folders of its own user: a link and a folder of another user are
    left as they are (the box's uid's files are removed with the box), a stale box folder of
    ours is removed as before."""
    parent = tmp_path / "tmp"
    parent.mkdir()
    target = tmp_path / "site-packages"
    target.mkdir()
    target.chmod(0o755)
    answers = tmp_path / "answers.txt"
    answers.write_text("secret")
    answers.chmod(0o644)
    (parent / f"{sb.BOX_PREFIX}{DEAD}-link").symlink_to(target)
    (parent / f"{confinement.ZYGOTE_PREFIX}{DEAD}-link").symlink_to(answers)
    stale = parent / f"{sb.BOX_PREFIX}{DEAD}-stale"
    (stale / "box").mkdir(parents=True)
    (stale / "box" / "x").write_text("")
    theirs = parent / f"{confinement.ZYGOTE_PREFIX}{DEAD}-theirs"
    theirs.mkdir()
    if os.geteuid() == 0:  # a folder the student's uid made
        os.chown(theirs, 2013265920 + DEAD, 2013265920 + DEAD)
    swept = sb.sweep_stale_boxes(str(parent))
    assert stat.S_IMODE(target.stat().st_mode) == 0o755
    assert stat.S_IMODE(answers.stat().st_mode) == 0o644
    assert swept == (1 if os.geteuid() == 0 else 2)
    assert answers.read_text() == "secret"
    assert not stale.exists()
    assert theirs.exists() == (os.geteuid() == 0)
