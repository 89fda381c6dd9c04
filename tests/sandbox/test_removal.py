"""Removing a box's folder (gpsaccel.sandbox._removal): only what is inside it, whatever its
student does to it meanwhile, at any depth, and never the folder that holds it."""

from __future__ import annotations

import os
import stat
import subprocess
import tempfile

import pytest

from gpsaccel import sandbox as sb
from gpsaccel.sandbox import _boxuser
from gpsaccel.sandbox._removal import remove_tree

#: No process has this pid (Linux's PID_MAX_LIMIT is 2**22): a box folder named with it is stale.
DEAD = (1 << 22) + 1


def test_removing_a_box_never_changes_the_mode_of_the_folder_that_holds_it(tmp_path):
    """A box lives in /tmp; removing it once chmod-ed its parent (/tmp) to 0700 when the box's own
    folder could not be removed, which locked every other user (and every later box) out."""
    parent = tmp_path / "shared"
    parent.mkdir()
    parent.chmod(0o1777)
    remove_tree(str(parent / "gone-already"))  # rmtree fails on the root itself
    box = parent / "box"
    (box / "locked" / "deep").mkdir(parents=True)
    (box / "locked" / "deep" / "f").write_text("x")
    (box / "locked").chmod(0)  # what a student can do to a folder of theirs
    remove_tree(str(box))
    assert not box.exists()
    assert parent.stat().st_mode & 0o7777 == 0o1777


def test_removing_a_link_never_changes_its_target(tmp_path):
    """remove_tree given a symbolic link leaves it and its target alone: the rmtree it used
    refused the link, and its error handler chmod-ed the path, which follows the link."""
    target = tmp_path / "public"
    target.mkdir()
    target.chmod(0o755)
    link = tmp_path / "link"
    link.symlink_to(target)
    remove_tree(str(link))
    assert stat.S_IMODE(target.stat().st_mode) == 0o755
    assert link.is_symlink()


def _names(path: object, folder: str) -> bool:
    """Whether ``path`` (a path, or a name relative to a ``dir_fd``) names ``folder``."""
    if isinstance(path, int):
        return False
    path = os.fsdecode(os.fspath(path))  # type: ignore[arg-type]
    return path == folder or path.endswith(os.sep + folder)


def test_removing_a_tree_its_student_still_changes_never_reaches_outside_it(tmp_path,
                                                                            monkeypatch):
    """The sweep removes a stale box (its supervisor died) while the box's processes may still
    run: they are killed only when a later box takes their uid, after its sweep.  One writes into
    a folder as it is removed (the folder's removal fails: not empty), then swaps the folder for
    a symbolic link to a folder outside (the grader's site-packages).  The retry checked
    ``os.path.islink`` and then chmod-ed the path: swapped between the two, root's chmod followed
    the link and made site-packages 0700 (every later box of the class fails).  Here the swap
    comes at exactly that moment: right after the first look at the folder that follows the
    failed removal, whatever the look is (a check of the path, an open relative to its parent)."""
    victim = tmp_path / "site-packages"
    victim.mkdir()
    (victim / "numpy.pth").write_text("keep")
    victim.chmod(0o755)
    box = tmp_path / "tmp" / f"{sb.BOX_PREFIX}{DEAD}-stale"
    locked = box / "work" / "locked"
    locked.mkdir(parents=True)
    (locked / "f").write_text("x")
    state = {"written": False, "swapped": False}

    def swap() -> None:
        state["swapped"] = True
        os.rename(locked, box / "work" / "moved")  # the student's own folder, still in the box
        os.symlink(victim, locked)

    real_rmdir = os.rmdir

    def rmdir(path, *args, **kwargs):  # noqa: ANN001, ANN002, ANN003, ANN202 - os.rmdir's own
        if _names(path, "locked") and not state["written"]:
            state["written"] = True
            (locked / "late").write_text("x")  # the student's process writes meanwhile
        return real_rmdir(path, *args, **kwargs)

    def after(real):  # noqa: ANN001, ANN202
        def look(path, *args, **kwargs):  # noqa: ANN001, ANN002, ANN003, ANN202
            out = real(path, *args, **kwargs)
            if state["written"] and not state["swapped"] and _names(path, "locked"):
                swap()
            return out
        return look

    monkeypatch.setattr(os, "rmdir", rmdir)
    for name in ("lstat", "stat", "open", "chmod", "scandir", "listdir"):
        monkeypatch.setattr(os, name, after(getattr(os, name)))
    monkeypatch.setattr(os.path, "islink", after(os.path.islink))
    remove_tree(str(box))
    monkeypatch.undo()
    assert state["swapped"]  # the attack happened
    assert stat.S_IMODE(victim.stat().st_mode) == 0o755
    assert (victim / "numpy.pth").read_text() == "keep"
    assert not box.exists() and not os.path.lexists(box)  # its own folders went all the same


def _nest(top: str, depth: int) -> None:
    """``depth`` folders ``d`` one in the other below ``top`` (each made relative to the last,
    as a student's code can: no path is longer than a name), the deepest unreadable."""
    fd = os.open(top, os.O_RDONLY)
    try:
        for _ in range(depth):
            os.mkdir("d", dir_fd=fd)
            below = os.open("d", os.O_RDONLY, dir_fd=fd)
            os.close(fd)
            fd = below
        os.fchmod(fd, 0)
    finally:
        os.close(fd)


def test_a_student_s_folders_thousands_deep_are_removed(tmp_path):
    """A basic box's folder is on the grader's disk, and a student's code can nest folders as
    deep as it likes (each made relative to the last).  rmtree's walk recurses once per level:
    past Python's recursion limit (1000 frames) it raised RecursionError out of ``sandbox.run``
    (which never raises for what a submission does) and left the box folder, a copy of the
    submission, behind.  The deepest folder is also made unreadable, as a student can."""
    box = tmp_path / "box"
    box.mkdir()
    _nest(str(box), 1500)
    open_before = len(os.listdir("/proc/self/fd"))
    try:
        remove_tree(str(box))
        assert not box.exists()
        assert len(os.listdir("/proc/self/fd")) == open_before  # one per level, all closed
    finally:  # what a failed removal left must not fail pytest's own clean-up of tmp_path later
        subprocess.run(["rm", "-rf", "--", str(box)], check=False)


@pytest.mark.skipif(os.geteuid() != 0, reason="a box user needs root")
def test_what_a_box_user_left_thousands_deep_in_tmp_is_removed():
    """A basic box's user may write the machine's /tmp; what it left there is removed after the
    box (before its cgroup and its uid's lock are let go).  A folder nested 1500 deep raised
    RecursionError out of that removal: ``sandbox.run`` raised, and the box's folder, cgroup and
    uid lock were left."""
    uid = _boxuser.UID_BASE - 1  # below the boxes' range: no box, no account (no passwd entry)
    top = tempfile.mkdtemp(prefix=f"gpsaccel-test-removal-{os.getpid()}-")
    try:
        _nest(top, 1500)
        os.chown(top, uid, uid)
        assert top in _boxuser.remove_files(uid)
        assert not os.path.lexists(top)
    finally:
        subprocess.run(["rm", "-rf", "--", top], check=False)
