"""The confinement's own details (gpsaccel.sandbox.confinement): the order of bwrap's mounts, and
the removal of a box that leaves the folder holding it as it was."""

from __future__ import annotations

import os
import sys

from gpsaccel import sandbox as sb
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


def test_removing_a_box_never_changes_the_mode_of_the_folder_that_holds_it(tmp_path):
    """A box lives in /tmp; removing it once chmod-ed its parent (/tmp) to 0700 when the box's own
    folder could not be removed, which locked every other user (and every later box) out."""
    from gpsaccel.sandbox import confinement

    parent = tmp_path / "shared"
    parent.mkdir()
    parent.chmod(0o1777)
    confinement._remove_tree(str(parent / "gone-already"))  # rmtree fails on the root itself
    box = parent / "box"
    (box / "locked" / "deep").mkdir(parents=True)
    (box / "locked" / "deep" / "f").write_text("x")
    (box / "locked").chmod(0)  # what a student can do to a folder of theirs
    confinement._remove_tree(str(box))
    assert not box.exists()
    assert parent.stat().st_mode & 0o7777 == 0o1777
