"""What a ``basic`` box may not read: folders kept out of its reach by the kernel, not by an audit hook.

bwrap hides a folder by binding an empty one over it in the box's mount namespace.  A ``basic``
box has no namespace of its own, so its first process, before it executes Python, fences the
hidden folders (:func:`choose`, then :meth:`Fence.apply` in the child) with the first of these
that works here:

``landlock`` (Linux 5.13 or later with Landlock enabled at boot; any user; Docker's default
seccomp profile allows it since moby#43199, 2022)
    The process restricts itself and everything it will start: reading a file
    (``LANDLOCK_ACCESS_FS_READ_FILE``) is granted beneath every entry of each hidden folder's
    ancestors except those ancestors and the hidden folders themselves, so no call opens a file
    of a hidden folder (``open`` and ``openat`` through ctypes, ``/proc/self/root/...``, a
    symbolic link made in ``/tmp``: ``EACCES``), and a file cannot be linked or renamed out of
    one (``LANDLOCK_ACCESS_FS_REFER``: ``EXDEV``).  Names stay listable: listing is not
    restricted, and a package's file names are public (its wheel's ``RECORD`` lists them).
    A file put later straight into an ancestor folder (not into a sub-folder) is not readable
    in the box, which never needs one.  Fails on older kernels, kernels booted without it
    (``lsm=``), and under a seccomp profile older than it.
``mount`` (root with ``CAP_SYS_ADMIN``: a machine, not a default Docker container)
    A private mount namespace with an empty read-only folder bound over each hidden folder, as
    bwrap does (``ENOENT``).  Fails without ``CAP_SYS_ADMIN`` (a default Docker container:
    ``unshare`` is refused).
``permissions`` (root)
    The box runs as a uid of its own (:mod:`._boxuser`), so a folder that other users cannot
    enter (``chmod o-rwx``) is already out of its reach; nothing is done, it is only checked.

Where none applies, a box that must hide folders does not start as root (:class:`NoFence`);
run as another user, ``basic`` is not safe anyway (the student's code reads whatever the user
reads: :func:`gpsaccel.sandbox.refuse_unsafe_basic`), and the box runs without a fence.
"""

from __future__ import annotations

import ctypes
import functools
import os
import stat
import struct
import sys
from collections.abc import Iterable
from dataclasses import dataclass, field

from gpsaccel.sandbox import _enter
from gpsaccel.sandbox.procs import _libc

# Landlock's system calls: one number on every Linux architecture (added after the tables were
# unified), and its constants (include/uapi/linux/landlock.h)
_CREATE_RULESET = 444
_CREATE_RULESET_VERSION = 1
READ_FILE, REFER = _enter.READ_FILE, 1 << 13


KINDS = ("landlock", "mount", "permissions")


class NoFence(OSError):
    """A basic box run as root must hide folders, and nothing here can fence them."""


@functools.lru_cache(maxsize=1)
def landlock_abi() -> int:
    """The Landlock ABI version of this kernel, 0 where there is none (not Linux, an older
    kernel, not enabled at boot, refused by a seccomp filter)."""
    libc = _libc()
    if libc is None:
        return 0
    rc = libc.syscall(ctypes.c_long(_CREATE_RULESET), None, ctypes.c_size_t(0),
                      ctypes.c_uint32(_CREATE_RULESET_VERSION))
    return max(int(rc), 0)


@functools.lru_cache(maxsize=1)
def mounts_allowed() -> bool:
    """Whether this process may make a private mount namespace (root with ``CAP_SYS_ADMIN``):
    tried once, in a child."""
    libc = _libc()
    if libc is None or os.geteuid() != 0:
        return False
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        os._exit(0 if libc.unshare(_enter.CLONE_NEWNS) == 0 else 1)
    _, status = os.waitpid(pid, 0)
    return os.waitstatus_to_exitcode(status) == 0


@functools.lru_cache(maxsize=1)
def private_proc_allowed() -> bool:
    """Whether a box's first process may mount a ``/proc`` of its own that hides other uids'
    processes (:func:`gpsaccel.sandbox._enter.private_proc`: root with ``CAP_SYS_ADMIN``, a
    kernel that lets a mount namespace mount procfs): tried once, in a child."""
    libc = _libc()
    if libc is None or os.geteuid() != 0:
        return False
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        try:
            _enter.private_proc(libc)
        except BaseException:  # noqa: BLE001 - the child's answer is its exit status
            os._exit(1)
        os._exit(0)
    _, status = os.waitpid(pid, 0)
    return os.waitstatus_to_exitcode(status) == 0


def _closed_to_others(path: str) -> bool:
    """Whether another user (the box's own uid) cannot enter ``path``."""
    try:
        return not os.stat(path).st_mode & stat.S_IXOTH
    except OSError:
        return True


@dataclass
class Fence:
    """How one basic box is kept out of ``hidden`` (real paths of folders): ``kind`` is one of
    :data:`KINDS`; ``ruleset`` the Landlock ruleset's descriptor (made here, applied in the
    child, closed by :meth:`close`); ``empty`` the empty folder bound over each hidden one."""

    kind: str
    hidden: list[str]
    ruleset: int | None = None
    empty: str | None = None
    granted: list[str] = field(default_factory=list)

    def apply(self, libc: ctypes.CDLL) -> None:
        """In the box's first process (``mount``: while still root; ``landlock``: last, once it
        cannot gain privileges): :func:`gpsaccel.sandbox._enter.enter` does it from the box's
        plan; this is the same for a test.  Raises OSError when a step fails."""
        if self.kind == "mount":
            assert self.empty is not None
            _enter.mount_fence(libc, self.hidden, self.empty)
        elif self.kind == "landlock":
            assert self.ruleset is not None
            _enter.landlock(libc, self.ruleset)

    def close(self) -> None:
        if self.ruleset is not None:
            os.close(self.ruleset)
            self.ruleset = None


def choose(hidden: Iterable[str], root: bool, empty: str, revealed: Iterable[str] = ()
           ) -> Fence | None:
    """The fence of a basic box that may not read the folders ``hidden`` (those that exist);
    None when there is nothing to hide, or not as root where nothing works (module docstring).
    ``root``: the box runs as a uid of its own; ``empty``: a folder to make empty for
    ``mount``; ``revealed``: the folders the box's reveal will bind-mount
    (:func:`gpsaccel.sandbox._boxuser.reveal`).  NoFence as root where nothing works."""
    dirs = sorted({os.path.realpath(h) for h in hidden if os.path.isdir(h)})
    if not dirs:
        return None
    abi = landlock_abi()
    if abi > 0:
        return _landlock(dirs, abi, list(revealed))
    if root and mounts_allowed():
        os.mkdir(empty, 0o555)
        return Fence("mount", dirs, empty=empty)
    if root and all(_closed_to_others(d) for d in dirs):
        return Fence("permissions", dirs)
    if not root:
        return None
    raise NoFence(
        "sandbox 'basic' cannot keep the box out of " + ", ".join(dirs) + " here: this kernel "
        "has no Landlock (Linux 5.13+, enabled at boot, allowed by the container's seccomp "
        "profile), this process may not make a mount namespace (it needs CAP_SYS_ADMIN) and the "
        "folders are open to other users. Use --sandbox bwrap where it works, or close those "
        "folders to other users (chmod -R o-rwx FOLDER: root, which grades, still reads them)")


def _landlock(hidden: list[str], abi: int, revealed: list[str]) -> Fence:
    """A ruleset granting READ_FILE (and REFER, from ABI 2) beneath every entry of the hidden
    folders' ancestors but those ancestors and the hidden folders (module docstring), and
    beneath each folder the box's reveal binds that holds no hidden one: a folder mounted over
    one of those entries later (the reveal's tmpfs over ``/root``) hides the entry's rule
    from Landlock, which skips covered mount points, but not the rule of the bound folder's own
    root."""
    libc = _libc()
    assert libc is not None
    handled = READ_FILE | (REFER if abi >= 2 else 0)
    attr = ctypes.create_string_buffer(struct.pack("=Q", handled))
    fd = _enter.check(libc, libc.syscall(ctypes.c_long(_CREATE_RULESET), attr, ctypes.c_size_t(8),
                             ctypes.c_uint32(0)), "landlock_create_ruleset")
    os.set_inheritable(fd, False)
    fence = Fence("landlock", hidden, ruleset=fd)
    try:
        for path, is_dir, pfd in _grants(hidden, revealed):
            try:
                if _enter.add_rule(libc, fd, pfd, handled if is_dir else READ_FILE) == 0:
                    fence.granted.append(path)
            finally:
                os.close(pfd)
    except BaseException:
        fence.close()
        raise
    return fence


def _grants(hidden: list[str], revealed: list[str]) -> Iterable[tuple[str, bool, int]]:
    """(path, is a folder, an ``O_PATH`` descriptor) of every entry of the hidden folders'
    ancestors to grant (not an ancestor, not hidden, and not a link to either) and of the
    revealed folders that hold no hidden one."""
    ancestors: set[str] = set()
    for h in hidden:
        p = os.path.dirname(h)
        while True:
            ancestors.add(p)
            if p == "/":
                break
            p = os.path.dirname(p)

    def reaches(real: str) -> bool:  # an ancestor of, or inside, a hidden folder
        return any(h == real or h.startswith(real.rstrip("/") + "/") or real.startswith(h + "/")
                   for h in hidden)

    paths = [os.path.join(a, e.name) for a in sorted(ancestors) for e in _entries(a)]
    for path in dict.fromkeys(paths + sorted(revealed)):
        if path in ancestors or reaches(os.path.realpath(path)):
            continue
        try:
            pfd = os.open(path, os.O_PATH | os.O_CLOEXEC)
        except OSError:
            continue
        yield path, stat.S_ISDIR(os.fstat(pfd).st_mode), pfd


def _entries(folder: str) -> list[os.DirEntry]:
    try:
        return sorted(os.scandir(folder), key=lambda e: e.name)
    except OSError:
        return []


def supported() -> str:
    """The fence a basic box would use here as this user (``none`` without one), for the
    docs and the report."""
    if sys.platform.startswith("linux") and landlock_abi() > 0:
        return f"landlock (ABI {landlock_abi()})"
    if mounts_allowed():
        return "mount"
    return "permissions" if os.geteuid() == 0 else "none"
