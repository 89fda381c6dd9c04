"""Removing a folder a student's processes may still change: a box's folder (its copy of the
submission, where a basic box's code writes) and what a box's uid left in the shared temporary
folders.  Used by :mod:`gpsaccel.sandbox`; not an interface of its own.  One walk for both: by
descriptors, never by a path below the folder (:func:`remove_tree`)."""

from __future__ import annotations

import os
import stat


def remove_tree(path: str) -> None:
    """Remove the folder ``path`` and everything in it, also what a student made unreadable
    (chmod 000 folders), without ever acting on a path below it.

    The folder may still change as it is removed: the sweep takes a stale box while the box's
    processes may run on (they are killed when a later box takes their uid).  So every step is
    made through the descriptor of a folder opened without following a link, relative to its
    parent's (``dir_fd``): a folder swapped for a symbolic link between a look and an action is
    then either the folder opened, or fails to open; no chmod nor unlink ever reaches what a
    link points to (a check of ``os.path.islink`` before a chmod by path once let a swap in
    between make the grader's site-packages 0700).  Modes are changed only of folders inside
    ``path``, never of the folder that holds it (``/tmp``, which a failed removal once made
    0700); ``path`` itself not a folder (a link) is left as it is."""
    root = os.path.abspath(path)
    try:
        holder = os.open(os.path.dirname(root), os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
    except OSError:
        return
    try:
        top = os.stat(os.path.basename(root), dir_fd=holder, follow_symlinks=False)
    except OSError:
        os.close(holder)
        return
    if not stat.S_ISDIR(top.st_mode):
        os.close(holder)
        return
    _Removal(holder, os.path.basename(root)).run()


class _Removal:
    """One removal of :func:`remove_tree`: a walk without recursion (a student's folders may be
    thousands deep), holding one descriptor per level.  A folder whose removal fails (a process
    wrote into it meanwhile, or swapped it for a link) is looked at again, :attr:`AGAIN` times in
    all; then what is left stays (the removal is a best effort, as rmtree's ``ignore_errors``)."""

    AGAIN = 64

    def __init__(self, holder: int, name: str) -> None:
        # each level: an open folder, the names in it still to remove, its own name in the level
        # above (the first level is the holder, whose name is not needed)
        self.stack: list[tuple[int, list[str], str]] = [(holder, [name], "")]
        self.again = self.AGAIN

    def run(self) -> None:
        try:
            while self.stack:
                fd, names, _ = self.stack[-1]
                if names:
                    self._remove(fd, names.pop())
                else:
                    self._leave()
        finally:
            for fd, _, _ in self.stack:
                os.close(fd)

    def _remove(self, dir_fd: int, name: str) -> None:
        """Unlink ``name`` of the folder ``dir_fd``, or enter it when it is a folder."""
        try:
            st = os.stat(name, dir_fd=dir_fd, follow_symlinks=False)
        except OSError:
            return  # gone already
        if stat.S_ISDIR(st.st_mode):
            fd = _enter(dir_fd, name)
            if fd is not None:
                try:
                    self.stack.append((fd, os.listdir(fd), name))
                    return
                except OSError:
                    os.close(fd)
        else:
            try:
                os.unlink(name, dir_fd=dir_fd)
                return
            except FileNotFoundError:
                return
            except OSError:
                pass
        self._look_again(dir_fd, name)

    def _leave(self) -> None:
        """The folder on top is empty (as far as its listing went): remove it from its parent."""
        fd, _, name = self.stack.pop()
        os.close(fd)
        if not self.stack:
            return  # that was the holder
        parent = self.stack[-1][0]
        try:
            os.rmdir(name, dir_fd=parent)
        except FileNotFoundError:
            pass
        except OSError:  # written into meanwhile, or no longer a folder
            self._look_again(parent, name)

    def _look_again(self, dir_fd: int, name: str) -> None:
        if self.again > 0:
            self.again -= 1
            for fd, names, _ in self.stack:
                if fd == dir_fd:
                    names.append(name)


def _enter(dir_fd: int, name: str) -> int | None:
    """The folder ``name`` of the folder ``dir_fd``, opened to list and remove what it holds
    (None when it cannot be: a link now, or not ours): opened without following a link, its
    mode made ``rwx`` for its owner through the descriptor when it is not (a folder the student
    made unreadable is opened as a path first, changed through ``/proc/self/fd``, then opened
    again from there: the same folder, not whatever ``name`` is by then)."""
    flags = os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC
    fd: int | None
    try:
        fd = os.open(name, flags | os.O_NOFOLLOW, dir_fd=dir_fd)
    except PermissionError:
        fd = _reopen_writable(dir_fd, name, flags)
    except OSError:
        return None
    if fd is not None and stat.S_IMODE(os.fstat(fd).st_mode) & 0o700 != 0o700:
        try:
            os.fchmod(fd, 0o700)
        except OSError:
            pass
    return fd


def _reopen_writable(dir_fd: int, name: str, flags: int) -> int | None:
    """A folder this user may not read (mode 000): opened as a path (O_PATH needs no right on
    the folder), made 0700 through the magic link of that descriptor, reopened from it."""
    o_path = getattr(os, "O_PATH", None)
    if o_path is None or not os.path.isdir("/proc/self/fd"):
        return None
    try:
        path_fd = os.open(name, o_path | os.O_DIRECTORY | os.O_NOFOLLOW | os.O_CLOEXEC,
                          dir_fd=dir_fd)
    except OSError:
        return None
    try:
        os.chmod(f"/proc/self/fd/{path_fd}", 0o700)
        return os.open(f"/proc/self/fd/{path_fd}", flags)
    except OSError:
        return None
    finally:
        os.close(path_fd)
