"""Warm boxes: each box started from a process that has already imported what every box imports.

A box's runner is a fresh Python that imports numpy, then the student's file; a notebook that
answers imports scipy.stats, whose import is most of a graded notebook's CPU.  A class run starts
one *zygote* (:func:`warm_boxes`): a clean Python, started by exec with the box's interpreter flags,
``sys.path`` and environment, that imports the public modules its boxes import (the course's
:data:`COURSE_IMPORTS`, or what a homework declares) and waits.  Each box of the run is then
forked from it (:mod:`._zygote`) instead of exec'd, and is confined exactly as a cold box: the same
cgroup, uid, rlimits, fence, capabilities and, under bwrap, the namespaces and mounts bwrap makes
for it (``docs/sandbox.md``, "Warm boxes", argues it point by point).

What the zygote may hold: only public code.  It is exec'd (not forked from the grader, which
holds answers, the secret and the seed), it inherits none of the grader's descriptors, its
folder is root's alone, and it never reads a request: the child it forks for a box (the box's
keeper) does.  It imports nothing from a folder a box may not read (checked when it starts and
for every box), and a zygote that may not import gpsaccel has none of it in ``sys.modules``.

Served warm (:func:`serving`), else the box starts cold as it always did: as root (the box has a
uid of its own), under ``basic`` or ``bwrap``, for a box that imports what the zygote's ``sys.path``
gives (``allow_gpsaccel`` the same), whose hidden folders hold none of the zygote's modules, and
whose memory limit is at least :data:`MEMORY_SHARE` times the zygote's address space (a warm box
starts with it).  A zygote that has died (killed, out of memory) serves no more boxes: they start
cold.

    with sb.warm_boxes(sb.Warm(("numpy", "scipy.stats"))):
        sb.run(sub, calls, limits)          # forked from the zygote, confined as before

One box's start from a zygote, as its supervisor sees it, is :mod:`gpsaccel.sandbox.warmbox`.
"""

from __future__ import annotations

import contextlib
import json
import os
import resource
import select
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from gpsaccel.sandbox import _boxuser
from gpsaccel.sandbox._removal import remove_tree
from gpsaccel.sandbox.confinement import (
    PACKAGE_DIR,
    RUNNER,
    ZYGOTE_PREFIX,
    _environment,
    _python,
    _site_dirs,
    check_hide,
    hidden_dirs,
)
from gpsaccel.sandbox.procs import PR_SET_PDEATHSIG, _prctl

#: What a box of this course imports besides the runner's numpy: a filled notebook's answer
#: imports scipy.stats, a student's filter filterpy (which imports scipy.stats).
COURSE_IMPORTS = ("numpy", "scipy.stats", "filterpy.kalman")

#: A box is served warm only when its memory limit is at least this many times the zygote's
#: address space (RLIMIT_AS counts what the box starts with).
MEMORY_SHARE = 3

#: The files the zygote runs, copied into its folder.
FILES = (Path(__file__).with_name("_zygote.py"), RUNNER, Path(__file__).with_name("_enter.py"))

#: Seconds a zygote may take to import its modules before it is given up (a loaded machine).
START_WAIT = 600.0

@dataclass
class Zygote:
    """A running zygote: its pid, folder and socket, what it serves (``allow_gpsaccel``,
    ``sys_path``), what it imported (``imports``, and the files of every module it holds) and its
    address space (bytes): ``extra`` of it past what a cold runner holds when the student's code
    starts (its imports past numpy), which a warm box's address-space limit adds
    (:func:`with_room`)."""

    pid: int
    folder: str
    allow_gpsaccel: bool
    sys_path: tuple[str, ...]
    imports: tuple[str, ...]
    modules: tuple[str, ...]
    vmsize: int
    proc: subprocess.Popen | None = field(default=None, repr=False)
    extra: int = 0

    def alive(self) -> bool:
        try:
            os.kill(self.pid, 0)
        except ProcessLookupError:
            return False
        return True

    def holds_any_of(self, dirs: Sequence[str]) -> list[str]:
        """The zygote's module files under one of ``dirs`` (none, or it serves no such box)."""
        heads = tuple(d.rstrip("/") + "/" for d in dirs)
        return [m for m in self.modules if m.startswith(heads)]


def usable() -> bool:
    """Whether boxes can start warm here: Linux, as root (each box has a uid of its own)."""
    return sys.platform.startswith("linux") and _boxuser.box_uid() is not None


@dataclass(frozen=True)
class Warm:
    """A kind of box a class run starts warm: boxes that may import gpsaccel or not (those of a
    notebook, those of a student's filter), the folders of the package they may not read
    (``hide``, as :func:`gpsaccel.sandbox.run` takes it), and the public modules their zygote
    imports ahead (what every such box imports: a homework's ``BOX_IMPORTS``)."""

    imports: tuple[str, ...] = COURSE_IMPORTS
    allow_gpsaccel: bool = False
    hide: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "imports", tuple(self.imports))
        object.__setattr__(self, "hide", check_hide(self.hide, self.allow_gpsaccel))
        hidden = [PACKAGE_DIR.name] if not self.allow_gpsaccel else \
            [f"{PACKAGE_DIR.name}.{rel.replace('/', '.')}" for rel in self.hide]
        for name in self.imports:
            if not isinstance(name, str) or not all(p.isidentifier() for p in name.split(".")):
                raise ValueError(f"imports: each must be a module name, got {name!r}")
            if any(name == h or name.startswith(h + ".") for h in hidden):
                raise ValueError(f"imports: {name} is a module its boxes may not read; import "
                                 f"only public libraries ahead of a box")


def start(kind: Warm = Warm()) -> Zygote:
    """A new zygote for boxes of ``kind``; ValueError when one of its modules comes from a
    folder such a box may not read, OSError when it does not start."""
    return _ready(kind, *_launch(kind))


def _launch(kind: Warm) -> tuple[subprocess.Popen, str, list[str]]:
    """The zygote started by exec (it imports meanwhile): (its process, folder, sys.path)."""
    folder = tempfile.mkdtemp(prefix=f"{ZYGOTE_PREFIX}{os.getpid()}-")  # 0700: root's alone
    sys_path = _site_dirs()
    if kind.allow_gpsaccel:
        sys_path.insert(0, str(PACKAGE_DIR.parent))
    try:
        for f in FILES:
            shutil.copy2(f, os.path.join(folder, f.name))
        config = {"sys_path": sys_path, "imports": list(kind.imports), "parent": os.getpid()}
        proc = subprocess.Popen(
            [_python(), "-I", "-S", "-B", os.path.join(folder, "_zygote.py"), folder,
             json.dumps(config)],
            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd="/",
            env=_environment(folder), close_fds=True, start_new_session=True,
            preexec_fn=_dies_with_us)
    except BaseException:
        remove_tree(folder)
        raise
    return proc, folder, sys_path


def _ready(kind: Warm, proc: subprocess.Popen, folder: str, sys_path: list[str]) -> Zygote:
    """The zygote once it said it is ready (its modules, its address space), checked to hold no
    module its boxes may not read."""
    try:
        info = _ready_line(proc)
    except BaseException:
        remove_tree(folder)
        raise
    z = Zygote(proc.pid, folder, kind.allow_gpsaccel, tuple(sys_path), kind.imports,
               tuple(info["modules"]), int(info["vmsize"]) * 1024, proc,
               max(0, int(info["vmsize"]) - int(info["base_vmsize"])) * 1024)
    bad = z.holds_any_of(hidden_dirs(kind.allow_gpsaccel, kind.hide))
    if bad:
        stop(z)
        raise ValueError(f"imports: the zygote would hold {bad[0]}, a file its boxes may not "
                         f"read; import only public libraries ahead of a box")
    return z


def _dies_with_us() -> None:
    _prctl(PR_SET_PDEATHSIG, signal.SIGKILL)


def _ready_line(proc: subprocess.Popen) -> dict:
    """The zygote's line saying it is ready, or OSError with what it wrote to stderr."""
    assert proc.stdout is not None and proc.stderr is not None
    line = b""
    give_up = time.monotonic() + START_WAIT
    while not line.endswith(b"\n") and time.monotonic() < give_up:
        ready, _, _ = select.select([proc.stdout], [], [], 1.0)
        if ready:
            chunk = os.read(proc.stdout.fileno(), 1 << 20)
            if not chunk:
                break
            line += chunk
    try:
        info = json.loads(line) if line.endswith(b"\n") else None
    except ValueError:
        info = None
    if info is None or info.get("threads") != 1:
        proc.kill()
        err = proc.stderr.read().decode(errors="replace")[-2000:]
        proc.wait()
        why = f"it runs {info['threads']} threads, not one" if info else (err or "no reply")
        raise OSError(f"the zygote of warm boxes did not start: {why}")
    proc.stdout.close()
    proc.stderr.close()
    return info


def stop(z: Zygote) -> None:
    """Kill the zygote by its pid and remove its folder (a keeper lives until its box's
    connection closes: its supervisor emptied the box, or died)."""
    try:
        os.kill(z.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    if z.proc is not None:
        z.proc.wait()
    remove_tree(z.folder)


#: The zygotes this process's boxes may start from (a forked item inherits them).
_ACTIVE: list[Zygote] = []


@contextlib.contextmanager
def warm_boxes(*kinds: Warm) -> Iterator[list[Zygote]]:
    """Within the block, boxes of this process (and of the processes it forks) of these kinds
    (default: one :class:`Warm`) start warm, each from a zygote of its kind started here (all at
    once) and killed at the end of the block, by pid, with its folder (module docstring).  It
    yields the zygotes: none where boxes cannot start warm here (:func:`usable`), and then they
    start cold, as without the block."""
    kinds = kinds or (Warm(),)
    if not usable():
        yield []
        return
    started: list[Zygote] = []
    launched = []
    try:
        for kind in kinds:
            launched.append((kind, *_launch(kind)))
        while launched:
            started.append(_ready(*launched.pop(0)))
        with serve(*started):
            yield started
    finally:
        for _, proc, folder, _ in launched:
            proc.kill()
            proc.wait()
            remove_tree(folder)
        for z in started:
            stop(z)


@contextlib.contextmanager
def serve(*zygotes: Zygote) -> Iterator[None]:
    """Within the block, boxes of this process may start from these running zygotes."""
    _ACTIVE.extend(zygotes)
    try:
        yield
    finally:
        for z in zygotes:
            _ACTIVE.remove(z)


def with_room(plan: dict, z: Zygote) -> dict:
    """The plan of a box forked from ``z``: its address-space limit raised by what ``z`` holds
    past a cold runner's numpy (RLIMIT_AS counts the address space a box starts with), so that a
    student whose code imports numpy alone has the room a cold box gives; one who imports what
    the zygote holds has that much more address space than cold, where that import counted, and
    its memory is still bounded by the box's cgroup where it has one."""
    rlimits = [[r, v + z.extra if r == resource.RLIMIT_AS else v] for r, v in plan["rlimits"]]
    return dict(plan, rlimits=rlimits)


def serving(backend: str, allow_gpsaccel: bool, sys_path: Sequence[str], memory: int,
            hidden: Sequence[str]) -> Zygote | None:
    """The active zygote that serves this box, or None (it starts cold)."""
    if backend not in ("basic", "bwrap") or not usable():
        return None
    for z in _ACTIVE:
        if z.allow_gpsaccel == allow_gpsaccel and list(z.sys_path) == list(sys_path) \
                and memory >= MEMORY_SHARE * z.vmsize and not z.holds_any_of(hidden) \
                and z.alive():
            return z
    return None
