"""Folders outside the package that no box may read: a class's own (its submissions, its grades,
the instructor's homework and secret), hidden from every box its caller starts meanwhile.

A ``bwrap`` box sees none of them (only the interpreter's folders and its own).  A ``basic``
box sees whatever other users may read, and an unzipped LMS export is world-readable (0755,
0644): a student's code could read a classmate's notebook, the grades or the solutions.  Inside
:func:`hiding`, every box started by this process or a worker it forks or spawns on this machine
(the folders travel in an environment variable, which the box's own environment never holds)
fences them as it fences the package's masters (:mod:`gpsaccel.sandbox.fence`: Landlock, else a
mount namespace, else folders closed to other users, else no box).  For the last, a folder the
grader owns is closed here (``chmod go-rwx``); another user's is refused, with what to do.
"""

from __future__ import annotations

import contextlib
import json
import os
import stat
import sys
import tempfile
from collections.abc import Collection, Iterator, Mapping

from gpsaccel.sandbox import confinement, fence

#: The environment variable holding the hidden folders (a JSON list of real paths).
ENV = confinement.HIDDEN_ENV


def _inside(path: str, folder: str) -> bool:
    return path == folder or path.startswith(folder.rstrip("/") + "/")


def _needed() -> list[str]:
    """What every box reads: the interpreter's folders, the package and the box folders' home."""
    return [os.path.realpath(p) for p in (sys.base_prefix, sys.prefix, sys.exec_prefix,
                                          *confinement._site_dirs(), str(confinement.PACKAGE_DIR),
                                          tempfile.gettempdir(), os.path.dirname(sys.executable))]


def checked(folders: Mapping[str, str | os.PathLike | None], optional: Collection[str] = ()
            ) -> list[str]:
    """The real paths of the folders that exist; ValueError naming the argument whose folder
    holds what every box must read (the interpreter, the package, the temporary folder), but
    an ``optional`` one, which is left out."""
    dirs: list[str] = []
    for name, folder in folders.items():
        if folder is None or not os.path.isdir(folder):
            continue
        real = os.path.realpath(folder)
        clash = [n for n in _needed() if _inside(n, real)]
        if clash and name in optional:
            continue
        if clash:
            raise ValueError(f"{name}: {folder} holds {clash[0]}, which every box must read, "
                             f"so it cannot be hidden from the boxes; move it elsewhere")
        dirs.append(real)
    return list(dict.fromkeys(dirs))


def close_to_others(folders: Mapping[str, str]) -> None:
    """Where only permissions can fence a basic box (root, no Landlock, no mount namespace): each
    folder open to other users is closed (``chmod go-rwx``) when this user owns it; ValueError
    naming the argument otherwise."""
    for name, real in folders.items():
        st = os.stat(real)
        if not st.st_mode & (stat.S_IRWXO | stat.S_IRWXG):
            continue
        if st.st_uid != os.geteuid():
            raise ValueError(
                f"{name}: {real} is open to other users and not yours, so a basic box (another "
                f"user) could read it: close it (`chmod go-rwx {real}` by its owner), or grade "
                f"with --sandbox bwrap")
        os.chmod(real, stat.S_IMODE(st.st_mode) & ~(stat.S_IRWXO | stat.S_IRWXG))


@contextlib.contextmanager
def hiding(folders: Mapping[str, str | os.PathLike | None], optional: Collection[str] = ()
           ) -> Iterator[list[str]]:
    """Hide ``folders`` (argument name -> folder; None or a missing folder is skipped) from every
    box started meanwhile, under both backends (module docstring); the real paths hidden.
    ``optional``: names of folders left visible where they hold what a box needs (e.g. a
    secret's folder holding the interpreter; its file is closed to others all the same).
    Nested: the outer folders stay hidden."""
    dirs = checked(folders, optional)
    if os.geteuid() == 0 and fence.supported() == "permissions":
        names = {os.path.realpath(str(f)): n for n, f in folders.items() if f is not None}
        close_to_others({names[d]: d for d in dirs})
    before = os.environ.get(ENV)
    outer = json.loads(before) if before else []
    os.environ[ENV] = json.dumps(list(dict.fromkeys([*outer, *dirs])))
    try:
        yield dirs
    finally:
        if before is None:
            os.environ.pop(ENV, None)
        else:
            os.environ[ENV] = before


__all__ = ["ENV", "checked", "close_to_others", "hiding"]
