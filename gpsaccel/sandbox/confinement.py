"""Confinement: the backends (bwrap and basic), what a box sees (its control folder, the
interpreter's folders, the package hidden or its answers hidden), and the box folders."""

from __future__ import annotations

import ast
import functools
import json
import os
import shutil
import site
import stat
import subprocess
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from gpsaccel.sandbox import _boxuser, _cgroup
from gpsaccel.sandbox._removal import remove_tree
from gpsaccel.sandbox.spec import Call, Limits
from gpsaccel.sandbox.submission import Submission, _open_checked

#: The script that runs the student's code in the box.
RUNNER = Path(__file__).with_name("_runner.py")
#: The pid 1 of a warm box under bwrap (:mod:`gpsaccel.sandbox._reaper`).
REAPER = Path(__file__).with_name("_reaper.py")

#: The package a submission may not import (unless allowed): the checker's own.
PACKAGE_DIR = Path(__file__).resolve().parent.parent
BLOCKED = (PACKAGE_DIR.name,)

BACKENDS = ("auto", "bwrap", "basic")

#: uid/gid of the student inside a bwrap box.
BOX_UID = 65534


@functools.lru_cache(maxsize=1)
def bwrap_path() -> str | None:
    """``bwrap`` when it is installed and a trial box (the namespaces used here) starts."""
    exe = shutil.which("bwrap")
    if exe is None:
        return None
    try:
        r = subprocess.run([exe, *_bwrap_namespaces(), "--ro-bind", "/", "/", "--proc", "/proc",
                            "--", "/bin/sh", "-c", "exit 0"], capture_output=True, timeout=20,
                           stdin=subprocess.DEVNULL)
    except (OSError, subprocess.TimeoutExpired):
        return None
    return exe if r.returncode == 0 else None


def resolve_backend(backend: str = "auto") -> str:
    """``"bwrap"`` or ``"basic"``; ValueError when ``bwrap`` is asked for and does not work."""
    if backend not in BACKENDS:
        raise ValueError(f"sandbox must be one of {', '.join(BACKENDS)}, got {backend!r}")
    if backend == "auto":
        return "bwrap" if bwrap_path() else "basic"
    if backend == "bwrap" and not bwrap_path():
        raise ValueError("sandbox 'bwrap' was asked for, but bubblewrap is not installed or "
                         "cannot create namespaces here (apt-get install bubblewrap); use "
                         "--sandbox basic or auto")
    return backend


def basic_is_safe() -> bool:
    """Whether the basic backend isolates a student here: only as root, where each box runs as a
    uid of its own (:mod:`gpsaccel.sandbox._boxuser`).  As any other user the student's code runs
    as that user: it can write what the user can (the environment's site-packages: a ``.pth``
    that forges the next check), signal the user's processes (kill or stop the batch) and leave
    processes the box cannot name (docs/sandbox.md)."""
    return _boxuser.box_uid() is not None


def refuse_unsafe_basic(backend: str, allow: bool = False) -> None:
    """ValueError when ``backend`` is ``"basic"``, it is not safe here (:func:`basic_is_safe`)
    and ``allow`` (``--allow-unsafe-basic``) was not given: for grading a class."""
    if backend == "basic" and not allow and not basic_is_safe():
        raise ValueError("sandbox: 'basic' is not safe for grading here: not run as root, a "
                         "student's code runs as your user, so it can write into your Python "
                         "environment (forging later checks), kill or stop the batch and leave "
                         "processes behind (docs/sandbox.md). Install bubblewrap (apt-get install "
                         "bubblewrap) for --sandbox bwrap, or run the check as root, or pass "
                         "--allow-unsafe-basic (allow_unsafe_basic=True) if you accept that")


def _bwrap_namespaces() -> list[str]:
    return ["--unshare-user", "--unshare-pid", "--unshare-net", "--unshare-ipc",
            "--unshare-uts", "--unshare-cgroup-try", "--uid", str(BOX_UID),
            "--gid", str(BOX_UID), "--die-with-parent", "--new-session"]


def _site_dirs() -> list[str]:
    """The folders the box's Python imports third-party packages from (numpy, scipy, ...)."""
    dirs = list(site.getsitepackages())
    if site.ENABLE_USER_SITE and site.getusersitepackages():
        dirs.append(site.getusersitepackages())
    return [d for d in dict.fromkeys(dirs) if os.path.isdir(d)]


def _environment(home: str) -> dict[str, str]:
    return {"PATH": "/usr/local/bin:/usr/bin:/bin", "HOME": home, "LANG": "C.UTF-8"}


# --------------------------------------------------------------------------- preparing a box
def _write_control(control: Path, sub: Submission, calls: Sequence[Call], sys_path: list[str],
                   allow: bool, reaper: bool = False) -> None:
    """The box's control folder: the runner, its plan and inputs (and, for a warm box under
    bwrap, the box's pid 1: :data:`REAPER`)."""
    control.mkdir()
    shutil.copy2(RUNNER, control / "_runner.py")
    if reaper:
        shutil.copy2(REAPER, control / "_reaper.py")
    arrays = {f"c{i}_{j}": np.asarray(a) for i, c in enumerate(calls) for j, a in
              enumerate(c.args)}
    for k, a in arrays.items():
        if a.dtype.hasobject:
            raise ValueError(f"call arguments must be numeric arrays; {k} is {a.dtype}")
    np.savez(control / "inputs.npz", **arrays)  # type: ignore[arg-type]  # numpy's stub
    plan = {"entry": sub.entry, "sys_path": sys_path, "block": [] if allow else list(BLOCKED),
            "block_dirs": [] if allow else _blocked_dirs(),
            "calls": [{"function": c.function, "n_args": len(c.args),
                       "outputs": [{"name": o.name, "shape": list(o.shape), "dtype": o.dtype,
                                    "column": o.column} for o in c.outputs]} for c in calls]}
    (control / "plan.json").write_text(json.dumps(plan), encoding="utf-8")
    for p in control.iterdir():
        p.chmod(0o444)
    control.chmod(0o555)


def _blocked_dirs() -> list[str]:
    """Folders of the checker's package: this one, and where an installed copy (editable or not)
    lives, as the interpreter would find it without this checkout on its path."""
    dirs = {str(PACKAGE_DIR)}
    for d in _site_dirs():
        if os.path.isdir(os.path.join(d, PACKAGE_DIR.name)):
            dirs.add(os.path.join(d, PACKAGE_DIR.name))
        for f in Path(d).glob(f"__editable__*{PACKAGE_DIR.name}*finder.py"):
            try:  # setuptools' editable finder maps the package to its source folder
                text = f.read_text(encoding="utf-8")
            except OSError:
                continue
            for line in text.splitlines():
                if line.startswith("MAPPING") and "{" in line:
                    try:
                        mapping = ast.literal_eval(line.split("=", 1)[1].strip())
                    except (ValueError, SyntaxError):
                        continue
                    dirs.update(str(v) for v in mapping.values())
    return sorted(dirs)


def _python() -> str:
    return sys.executable


def _bwrap_command(exe: str, tmp: Path, sub: Submission, limits: Limits, allow: bool,
                   result_fd: int, go_fd: int | None = None, hide: Sequence[str] = (),
                   warm: bool = False) -> tuple[list[str], list[int]]:
    """The bwrap command line, and the file descriptors it must inherit (one per copied file).
    The box runs the runner; a warm box runs :data:`REAPER` as its pid 1 instead (the runner is
    forked into the box's namespaces from the zygote: :mod:`gpsaccel.sandbox.zygote`)."""
    # /tmp first: the interpreter's folders may live below it (a venv in /tmp), and a bind made
    # before the tmpfs would be hidden by it
    cmd = [exe, *_bwrap_namespaces(), "--disable-userns", "--cap-drop", "ALL",
           "--size", str(limits.file_size), "--tmpfs", "/tmp"]
    bound: list[str] = []

    def ro(path: str) -> None:
        real = os.path.realpath(path)
        if not os.path.exists(real) or any(real == b or real.startswith(b + "/") for b in bound):
            return
        bound.append(real)
        cmd.extend(["--ro-bind", real, real])

    for d in ("/bin", "/sbin", "/lib", "/lib32", "/lib64", "/libx32"):
        if os.path.islink(d):
            cmd.extend(["--symlink", os.readlink(d), d])
        elif os.path.isdir(d):
            ro(d)
    ro("/usr")
    for f in ("/etc/ld.so.cache", "/etc/ld.so.conf", "/etc/ld.so.conf.d", "/etc/localtime",
              "/etc/alternatives", "/etc/fonts"):
        if os.path.exists(f):
            cmd.extend(["--ro-bind", f, f])
    for d in (sys.base_prefix, sys.prefix, sys.exec_prefix, *_site_dirs()):
        ro(d)
    exe_py = _python()
    if os.path.dirname(exe_py) not in bound:  # the venv's bin/python symlink
        cmd.extend(["--ro-bind", os.path.dirname(exe_py), os.path.dirname(exe_py)])
    pkg = str(PACKAGE_DIR)
    if allow:
        ro(pkg)
        cmd.extend(_hide_answers(tmp, bound, hide))
    elif any(pkg == b or pkg.startswith(b + "/") for b in bound):
        cmd.extend(["--tmpfs", pkg])  # an editable or installed gpsaccel: hidden
    # every writable mount has a size: /box, /tmp, /dev/shm; the root, /dev and the folders
    # made for the binds (/root, /etc, ...) are remounted read-only at the end
    cmd.extend(["--proc", "/proc", "--dev", "/dev",
                "--size", str(limits.file_size), "--tmpfs", "/dev/shm",
                "--size", str(limits.file_size), "--perms", "0755", "--tmpfs", "/box",
                "--ro-bind", str(tmp / "control"), "/control"])
    fds = []
    made = set()
    for rel in sub.files:
        parts = rel.split("/")
        for k in range(1, len(parts)):
            d = "/box/" + "/".join(parts[:k])
            if d not in made:
                made.add(d)
                cmd.extend(["--dir", d])
        fd = _open_checked(sub, rel)
        fds.append(fd)
        cmd.extend(["--perms", "0644", "--file", str(fd), "/box/" + rel])
    cmd.extend(["--remount-ro", "/dev", "--remount-ro", "/"])
    cmd.extend(["--chdir", "/box"])
    if warm:
        return cmd + ["--as-pid-1", "--", exe_py, "-I", "-S", "-B", "/control/_reaper.py"], fds
    cmd.extend(["--", exe_py, "-I", "-S", "-B", "/control/_runner.py", "/control", "/box",
                str(result_fd)] + ([] if go_fd is None else [str(go_fd)]))
    return cmd, fds


def check_hide(hide: Sequence[str], allow: bool) -> tuple[str, ...]:
    """``hide`` as given, checked: folders relative to the package, for a box that may import
    it (without ``allow`` the whole package is out of the box's reach)."""
    if isinstance(hide, str):
        raise ValueError(f"hide must be a sequence of folders, got the string {hide!r}")
    hide = tuple(hide)
    if hide and not allow:
        raise ValueError("hide names folders of gpsaccel a box that may import it does not see; "
                         "without allow_gpsaccel the box sees none of the package")
    for rel in hide:
        if not isinstance(rel, str) or not rel or os.path.isabs(rel) or ".." in rel.split("/"):
            raise ValueError(f"hide: each folder must be a path relative to the gpsaccel "
                             f"package, got {rel!r}")
    return hide


#: The folders outside the package hidden from every box (:func:`gpsaccel.sandbox.hiding`).
HIDDEN_ENV = "GPSACCEL_SANDBOX_HIDDEN"


def class_dirs() -> list[str]:
    """The folders :func:`gpsaccel.sandbox.hiding` hides now, those that exist (real paths)."""
    try:
        dirs = json.loads(os.environ.get(HIDDEN_ENV) or "[]")
    except ValueError:
        dirs = []
    return [os.path.realpath(d) for d in dirs if isinstance(d, str) and os.path.isdir(d)]


def hidden_dirs(allow: bool, hide: Sequence[str]) -> list[str]:
    """The folders no process of a box may read: every copy of the package (this one, an
    installed or editable one the interpreter would find) when the box may not import it, else
    the folders ``hide`` of each copy that exist; and the class's own folders
    (:func:`class_dirs`); real paths."""
    copies = list(dict.fromkeys([str(PACKAGE_DIR), *_blocked_dirs()]))
    dirs = copies if not allow else [os.path.join(pkg, rel) for pkg in copies for rel in hide]
    dirs = dirs + class_dirs()
    return list(dict.fromkeys(os.path.realpath(d) for d in dirs if os.path.isdir(d)))


def _hide_answers(tmp: Path, bound: list[str], hide: Sequence[str]) -> list[str]:
    """bwrap arguments binding an empty read-only folder over the folders ``hide`` of every
    copy of the package the box can see (this one, an installed one in site-packages)."""
    empty = tmp / "empty"
    args: list[str] = []
    for real in hidden_dirs(True, hide):
        # only what the box sees (a lessons link to a folder outside the binds is not there)
        if any(real.startswith(b + "/") for b in bound) and real not in args:
            args.extend(["--ro-bind", str(empty), real])
    if args:
        empty.mkdir(mode=0o555, exist_ok=True)
    return args


#: Where box folders are made: a ``gpsaccel-box-<pid>-*`` folder whose process is dead (a worker
#: killed mid-check) is removed by the next box or by :func:`sweep_stale_boxes`; so is a zygote's
#: ``gpsaccel-zygote-<pid>-*`` folder (:mod:`gpsaccel.sandbox.zygote`) whose starter is dead.
BOX_PREFIX = "gpsaccel-box-"
ZYGOTE_PREFIX = "gpsaccel-zygote-"


def sweep_stale_boxes(parent: str | None = None) -> int:
    """Remove the box and zygote folders whose supervising (starting) process is dead; how
    many.  Only real folders of this process's user: under basic a box's ``/tmp`` is the
    machine's, and a name planted there by a student (a symbolic link to any path, a folder of
    the box's uid) is not ours to follow or remove (removing a link's target as root once
    changed it to mode 0700)."""
    parent = parent or tempfile.gettempdir()
    n = 0
    try:
        entries = list(os.scandir(parent))
    except OSError:
        return 0
    for e in entries:
        prefix = next((p for p in (BOX_PREFIX, ZYGOTE_PREFIX) if e.name.startswith(p)), None)
        if prefix is None or not _ours(e):
            continue
        owner = e.name[len(prefix):].split("-", 1)[0]
        if owner.isdigit() and not _cgroup._alive(int(owner)):
            remove_tree(e.path)
            n += 1
    return n


def _ours(entry: os.DirEntry) -> bool:
    """Whether ``entry`` is a folder (not a link to one) of this process's user."""
    try:
        st = entry.stat(follow_symlinks=False)
    except OSError:
        return False
    return stat.S_ISDIR(st.st_mode) and st.st_uid == os.geteuid()
