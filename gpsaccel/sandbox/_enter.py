"""What a box's first process does before the student's code runs, as plain data and system calls.

Used by :mod:`gpsaccel.sandbox` in two places, so it is written once: in the child of
``subprocess.Popen`` before exec (a cold box: :func:`enter` is its ``preexec_fn``), and in a child
of the zygote (a warm box, :mod:`gpsaccel.sandbox.zygote`), which loads this file by path.  It
imports only the standard library: the zygote that loads it may not import gpsaccel (a box for a
check must find no module of the package in ``sys.modules``).

A *plan* (a dict of JSON types, made by :func:`gpsaccel.sandbox.limits._entry_plan`) says what to
do, in this order (:func:`enter`):

``cgroup``   the box's cgroup files to join (``cgroup.procs``), and ``cgroup_kill`` (optional)
             those whose join may fail (a cgroup made only for ``cgroup.kill``);
``reveal``   the interpreter's folders made reachable to the box's uid (a private mount namespace:
             :func:`gpsaccel.sandbox._boxuser.reveal`);
``fence``    ``"mount"``: ``hidden`` folders covered by the empty folder ``empty``;
             ``"landlock"``: the ruleset (a descriptor passed beside the plan) restricts the
             process last, once it cannot gain privileges (:mod:`gpsaccel.sandbox.fence`);
``proc``     (basic, root) a ``/proc`` of the box's own that shows it no other uid's process
             (``hidepid=2``): the box shares the machine's PID namespace, and every process's
             command line (a grader's ``--seed``) was readable to it;
``rlimits``  [resource, value] pairs, set as soft and hard limit;
``drop_caps`` an empty capability bounding set (root: after exec the permitted set is the
             bounding set);
``uid``      the box's own uid (root), as real, effective and saved uid and gid, no groups;
then the death signal (after the uid: a change of uid clears it) and no new privileges.

A warm box under bwrap also joins the namespaces bwrap made for it (:func:`join_namespaces`) and
drops every capability they gave it (:func:`drop_all_caps`).
"""

from __future__ import annotations

import ctypes
import os
import resource
import signal
import struct
from collections.abc import Sequence

PR_SET_PDEATHSIG, PR_SET_DUMPABLE, PR_CAPBSET_DROP = 1, 4, 24
PR_SET_CHILD_SUBREAPER, PR_SET_NO_NEW_PRIVS = 36, 38
PR_CAP_AMBIENT, PR_CAP_AMBIENT_CLEAR_ALL = 47, 4

CLONE_NEWNS = 0x00020000
MS_RDONLY, MS_NOSUID, MS_NODEV, MS_NOEXEC, MS_REMOUNT, MS_BIND = 1, 2, 4, 8, 32, 4096
MS_REC, MS_PRIVATE = 16384, 1 << 18

#: landlock_add_rule and landlock_restrict_self: one number on every Linux architecture; a
#: rule beneath a folder, and the access right to read a file
_LANDLOCK_ADD_RULE, _LANDLOCK_RESTRICT_SELF = 445, 446
RULE_PATH_BENEATH = 1
READ_FILE = 1 << 2
#: capset's header version 3: two 32-bit words per set
_CAPS_V3 = 0x20080522


def check(libc: ctypes.CDLL, rc: int, what: str) -> int:
    """``rc`` of a libc call, or OSError with errno and ``what``."""
    if rc < 0:
        err = ctypes.get_errno()
        raise OSError(err, f"{what}: {os.strerror(err)}")
    return rc


def prctl(libc: ctypes.CDLL, option: int, arg: int = 0) -> int:
    return libc.prctl(ctypes.c_int(option), ctypes.c_ulong(arg), ctypes.c_ulong(0),
                      ctypes.c_ulong(0), ctypes.c_ulong(0))


def join_cgroup(procs_files: Sequence[str], optional: Sequence[str] = ()) -> None:
    """Move this process into the box's cgroup (its children follow); into each of ``optional``
    too where it can."""
    for f in [*procs_files, *optional]:
        try:
            fd = os.open(f, os.O_WRONLY)
            try:
                os.write(fd, b"0")
            finally:
                os.close(fd)
        except OSError:
            if f not in optional:
                raise


def reveal(libc: ctypes.CDLL, plan: list) -> None:
    """As root, before the uid drop: a private mount namespace where each unreachable ancestor
    ``top`` of :func:`gpsaccel.sandbox._boxuser.reveal`'s plan is a small read-only tmpfs holding
    read-only bind mounts of exactly the folders below it the box needs."""
    check(libc, libc.unshare(CLONE_NEWNS), "unshare(CLONE_NEWNS)")
    check(libc, libc.mount(None, b"/", None, MS_REC | MS_PRIVATE, None), "mount --make-rprivate /")
    for top, needed in plan:
        fds = [os.open(p, os.O_PATH | os.O_DIRECTORY) for p in needed]
        check(libc, libc.mount(b"tmpfs", top.encode(), b"tmpfs", MS_NOSUID | MS_NODEV,
                               b"mode=0755,size=1m"), f"tmpfs on {top}")
        for p, fd in zip(needed, fds, strict=True):
            os.makedirs(p, mode=0o755, exist_ok=True)
            check(libc, libc.mount(f"/proc/self/fd/{fd}".encode(), p.encode(), None,
                                   MS_BIND | MS_REC, None), f"bind {p}")
            check(libc, libc.mount(None, p.encode(), None, MS_REMOUNT | MS_BIND | MS_RDONLY,
                                   None), f"read-only {p}")
            os.close(fd)
        check(libc, libc.mount(None, top.encode(), None,
                               MS_REMOUNT | MS_RDONLY | MS_NOSUID | MS_NODEV, None),
              f"read-only {top}")


def mount_fence(libc: ctypes.CDLL, hidden: list[str], empty: str) -> None:
    """As root: a private mount namespace with the empty folder bound read-only over each hidden
    folder (bwrap's way, ``ENOENT`` in the box)."""
    check(libc, libc.unshare(CLONE_NEWNS), "unshare(CLONE_NEWNS)")
    check(libc, libc.mount(None, b"/", None, MS_REC | MS_PRIVATE, None), "mount --make-rprivate /")
    for h in hidden:
        check(libc, libc.mount(empty.encode(), h.encode(), None, MS_BIND, None), f"bind over {h}")
        check(libc, libc.mount(None, h.encode(), None,
                               MS_REMOUNT | MS_BIND | MS_RDONLY | MS_NOSUID | MS_NODEV, None),
              f"read-only {h}")


def private_proc(libc: ctypes.CDLL, ruleset: int | None = None) -> None:
    """As root: a private mount namespace whose ``/proc`` is a procfs of its own mounted with
    ``hidepid=2``, so that the box's uid sees its own processes only (a basic box has no PID
    namespace: the machine's ``/proc`` gave it every process's command line).  ``ruleset``: the
    box's Landlock ruleset, not yet in force, which gets the rule of the new ``/proc`` (Landlock
    skips the rule of a covered mount: the machine's ``/proc`` rule no longer applies)."""
    check(libc, libc.unshare(CLONE_NEWNS), "unshare(CLONE_NEWNS)")
    check(libc, libc.mount(None, b"/", None, MS_REC | MS_PRIVATE, None), "mount --make-rprivate /")
    check(libc, libc.mount(b"proc", b"/proc", b"proc", MS_NOSUID | MS_NODEV | MS_NOEXEC,
                           b"hidepid=2"), "mount /proc hidepid=2")
    if ruleset is not None:
        fd = os.open("/proc", os.O_PATH | os.O_CLOEXEC)
        try:
            check(libc, add_rule(libc, ruleset, fd, READ_FILE), "landlock_add_rule /proc")
        finally:
            os.close(fd)


def add_rule(libc: ctypes.CDLL, ruleset: int, fd: int, access: int) -> int:
    """landlock_add_rule: ``access`` beneath the folder (or of the file) open as ``fd`` (an
    ``O_PATH`` descriptor); the call's return value."""
    rule = ctypes.create_string_buffer(struct.pack("=Qi", access, fd))
    return libc.syscall(ctypes.c_long(_LANDLOCK_ADD_RULE), ctypes.c_int(ruleset),
                        ctypes.c_int(RULE_PATH_BENEATH), rule, ctypes.c_uint32(0))


def landlock(libc: ctypes.CDLL, ruleset: int) -> None:
    """Restrict this process (and everything it starts) by the Landlock ruleset ``ruleset``."""
    check(libc, libc.syscall(ctypes.c_long(_LANDLOCK_RESTRICT_SELF), ctypes.c_int(ruleset),
                             ctypes.c_uint32(0)), "landlock_restrict_self")


def mounts(libc: ctypes.CDLL | None, plan: dict, ruleset: int | None) -> None:
    """The plan's mounts, as root and in this order: ``reveal``, the ``mount`` fence over the
    revealed folders, the box's own ``/proc``.  Before the rlimits: the parent's descriptors may
    still be open here (Popen closes them after preexec_fn), so with RLIMIT_NOFILE set first a
    grader holding more than open_files descriptors could not open the folders to reveal."""
    steps = [("reveal", bool(plan["reveal"])), ("fence", plan["fence"] == "mount"),
             ("own /proc", bool(plan.get("proc")))]
    for what, wanted in steps:
        if wanted and libc is None:
            raise OSError(f"the box's {what} needs Linux's libc")
    if libc is None:
        return
    if plan["reveal"]:
        reveal(libc, plan["reveal"])
    if plan["fence"] == "mount":
        mount_fence(libc, plan["hidden"], plan["empty"])
    if plan.get("proc"):
        private_proc(libc, ruleset if plan["fence"] == "landlock" else None)


def enter(libc: ctypes.CDLL | None, plan: dict, ruleset: int | None = None,
          cgroup: bool = True) -> None:
    """The steps of the module docstring, in its order.  ``ruleset``: the Landlock ruleset's
    descriptor when ``plan["fence"]`` is ``"landlock"``; ``cgroup`` False when the process is in
    the box's cgroup already (a warm box's first process joined it).  Raises OSError when a step
    fails (the box then does not start)."""
    if cgroup:
        join_cgroup(plan["cgroup"], plan.get("cgroup_kill", []))
    mounts(libc, plan, ruleset)
    for res, value in plan["rlimits"]:
        resource.setrlimit(res, (value, value))
    if plan["drop_caps"] and libc is not None:
        for cap in range(plan["cap_last"] + 1):
            prctl(libc, PR_CAPBSET_DROP, cap)
    uid = plan["uid"]
    if uid is not None:
        os.setgroups([])
        os.setresgid(uid, uid, uid)
        os.setresuid(uid, uid, uid)
    if libc is not None:
        prctl(libc, PR_SET_PDEATHSIG, signal.SIGKILL)  # after the uid: a change of uid clears it
    landlocked = plan["fence"] == "landlock" and ruleset is not None
    if (plan["drop_caps"] or landlocked) and libc is not None:
        # Landlock restricts only a process that cannot gain privileges
        prctl(libc, PR_SET_NO_NEW_PRIVS, 1)
    if landlocked:
        assert libc is not None and ruleset is not None
        landlock(libc, ruleset)


#: The namespaces a warm bwrap box joins, in order, after the user namespace that owns them: a
#: process has capabilities over them only there, and not once it is in bwrap's nested user
#: namespace (``--disable-userns``), which is joined last.
NAMESPACES = ("ipc", "uts", "net", "pid", "cgroup", "mnt")


def join_namespaces(libc: ctypes.CDLL, owner: int, fds: list[int], user: int) -> None:
    """Join the namespaces of a bwrap box: ``owner`` (the user namespace owning them), ``fds``
    (one per :data:`NAMESPACES`), then ``user`` (the box's own user namespace).  The PID
    namespace is the one this process's next child is born into."""
    check(libc, libc.setns(owner, 0), "setns(user namespace of the box's namespaces)")
    for name, fd in zip(NAMESPACES, fds, strict=True):
        check(libc, libc.setns(fd, 0), f"setns({name})")
    check(libc, libc.setns(user, 0), "setns(the box's user namespace)")


class _CapHeader(ctypes.Structure):
    _fields_ = [("version", ctypes.c_uint32), ("pid", ctypes.c_int)]


class _CapData(ctypes.Structure):
    _fields_ = [("effective", ctypes.c_uint32), ("permitted", ctypes.c_uint32),
                ("inheritable", ctypes.c_uint32)]


def drop_all_caps(libc: ctypes.CDLL, cap_last: int) -> None:
    """No capability left, as bwrap's ``--cap-drop ALL`` leaves its command: the bounding set,
    the ambient set, and the effective, permitted and inheritable sets emptied."""
    for cap in range(cap_last + 1):
        prctl(libc, PR_CAPBSET_DROP, cap)
    check(libc, prctl(libc, PR_CAP_AMBIENT, PR_CAP_AMBIENT_CLEAR_ALL), "clear ambient caps")
    header = _CapHeader(_CAPS_V3, 0)
    data = (_CapData * 2)()
    check(libc, libc.capset(ctypes.byref(header), data), "capset")


def status_fields(pid: int | str = "self") -> dict[str, str]:
    """The credential lines of /proc/<pid>/status (uids, gids, groups, capabilities, no new
    privileges, seccomp): what a test compares between a warm box and bwrap's own command."""
    keep = ("Uid", "Gid", "Groups", "CapInh", "CapPrm", "CapEff", "CapBnd", "CapAmb",
            "NoNewPrivs", "Seccomp")
    with open(f"/proc/{pid}/status", encoding="ascii", errors="replace") as f:
        pairs = (line.split(":", 1) for line in f if ":" in line)
        return {k: " ".join(v.split()) for k, v in pairs if k in keep}
