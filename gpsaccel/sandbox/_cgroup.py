"""A control group per box: memory, processes and CPU of the whole box, not of each process.

Used by :mod:`gpsaccel.sandbox`; not an interface of its own.  One box is one cgroup named
``gpsaccel-box-<pid>-<random>`` (``pid``: the supervising process) below the cgroup this process
is in, so a box never escapes the limits its checker runs under.  Where it is made, in order:

``cgroup2``  a unified hierarchy whose cgroup of this process delegates ``memory`` and ``pids``
             (``cgroup.subtree_control``): ``memory.max`` (and ``memory.swap.max`` = 0),
             ``memory.oom.group`` = 1 (an out-of-memory kill takes the whole box), ``pids.max``,
             ``cpu.max`` (one CPU);
``cgroup1``  the v1 ``memory`` and ``pids`` hierarchies, writable here: ``memory.limit_in_bytes``
             and ``memory.memsw.limit_in_bytes`` when swap is accounted, ``pids.max``; the v1
             ``cpu`` hierarchy when there is one (``cpu.cfs_quota_us``: one CPU);
``None``     neither (not root, no delegation): the sandbox falls back on per-process rlimits.

A box's cgroup v2 (Linux 5.14 or later) has ``cgroup.kill``: one write SIGKILLs every process of
the cgroup at once, forks in flight included, which no chain of processes that fork and exit can
outrun (a kill by pid can miss each link).  Under cgroup1 the box also has a cgroup of its own,
with no controller, in the unified hierarchy when it is mounted beside the v1 ones (systemd's
hybrid layout, ``/sys/fs/cgroup/unified``), for that write alone: :meth:`BoxCgroup.kill_at_once`.

Memory in a cgroup is every page the box's processes are charged for: anonymous memory of every
process, page cache, tmpfs files (bwrap's ``/box``, ``/tmp``) and memfds.  A box whose cgroup
outlives its checker (a killed worker) is emptied and removed by the next box made below the same
cgroup (:func:`sweep_stale`).
"""

from __future__ import annotations

import os
import secrets
import signal
import time
from dataclasses import dataclass, field
from pathlib import Path

PREFIX = "gpsaccel-box-"
#: CPU time per period a box may use (µs of 100 000): one CPU of a shared machine.
CPU_QUOTA = 100_000
CPU_PERIOD = 100_000


def _mounts() -> list[tuple[str, str, set[str]]]:
    """(mount point, type, options) of every cgroup file system mounted here."""
    out = []
    try:
        with open("/proc/self/mounts", encoding="utf-8") as f:
            for line in f:
                parts = line.split()
                if len(parts) >= 4 and parts[2] in ("cgroup", "cgroup2"):
                    out.append((parts[1], parts[2], set(parts[3].split(","))))
    except OSError:
        pass
    return out


def _own_paths() -> dict[str, str]:
    """controller (``""`` for the unified hierarchy) -> this process's cgroup path."""
    out = {}
    try:
        with open("/proc/self/cgroup", encoding="utf-8") as f:
            for line in f:
                _, controllers, path = line.rstrip("\n").split(":", 2)
                for c in controllers.split(",") if controllers else [""]:
                    out[c] = path
    except (OSError, ValueError):
        pass
    return out


def _write(path: Path, value: str) -> None:
    with open(path, "w", encoding="ascii") as f:
        f.write(value)


def _read(path: Path) -> str:
    try:
        return path.read_text(encoding="ascii")
    except OSError:
        return ""


def _count(text: str, key: str) -> int:
    """The number after ``key`` in a flat-keyed cgroup file (``oom_kill 2``, ``max 5``)."""
    for line in text.splitlines():
        parts = line.split()
        if len(parts) == 2 and parts[0] == key:
            try:
                return int(parts[1])
            except ValueError:
                return 0
    return 0


def _v2_base() -> Path | None:
    own = _own_paths().get("")
    for mount, kind, _ in _mounts():
        if kind != "cgroup2" or own is None:
            continue
        base = Path(mount + own.rstrip("/")) if own != "/" else Path(mount)
        available = _read(base / "cgroup.controllers").split()
        if not {"memory", "pids"} <= set(available) or not os.access(base, os.W_OK):
            continue
        enabled = set(_read(base / "cgroup.subtree_control").split())
        want = [c for c in ("memory", "pids", "cpu") if c in available and c not in enabled]
        try:
            if want:
                _write(base / "cgroup.subtree_control", " ".join("+" + c for c in want))
        except OSError:  # a cgroup holding processes cannot delegate (the no-internal rule)
            if not {"memory", "pids"} <= enabled:
                continue
        return base
    return None


def _v1_bases() -> dict[str, Path] | None:
    own = _own_paths()
    found: dict[str, Path] = {}
    for mount, kind, options in _mounts():
        if kind != "cgroup":
            continue
        for c in ("memory", "pids", "cpu"):
            if c in options and c in own and c not in found:
                base = Path(mount + own[c].rstrip("/")) if own[c] != "/" else Path(mount)
                if base.is_dir() and os.access(base, os.W_OK):
                    found[c] = base
    return found if {"memory", "pids"} <= set(found) else None


def _v2_kill_base() -> Path | None:
    """This process's cgroup in a cgroup v2 hierarchy, writable: where a box's cgroup made only
    for ``cgroup.kill`` goes (under cgroup1, beside its v1 ones)."""
    own = _own_paths().get("")
    if own is None:
        return None
    for mount, kind, _ in _mounts():
        base = Path(mount + own.rstrip("/")) if own != "/" else Path(mount)
        if kind == "cgroup2" and base.is_dir() and os.access(base, os.W_OK):
            return base
    return None


def _kill_only(base: Path, name: str) -> Path | None:
    """A new cgroup ``name`` below ``base`` (cgroup v2), with no controller, for its
    ``cgroup.kill``; None when it cannot be made or the kernel has no ``cgroup.kill``."""
    sweep_stale(base)
    d = base / name
    try:
        d.mkdir()
    except OSError:
        return None
    if (d / "cgroup.kill").exists():
        return d
    d.rmdir()
    return None


def available() -> str | None:
    """``"cgroup2"``, ``"cgroup1"`` or None: which kind of box cgroup can be made here."""
    if _v2_base() is not None:
        return "cgroup2"
    if _v1_bases() is not None:
        return "cgroup1"
    return None


@dataclass
class BoxCgroup:
    """The cgroup(s) of one box: ``kind`` and one folder per hierarchy (one under cgroup2), by
    controller, and ``"kill"``: the cgroup v2 whose ``cgroup.kill`` kills the box at once (the
    box's own under cgroup2; under cgroup1 one in the unified hierarchy), where there is one."""

    kind: str
    dirs: dict[str, Path] = field(default_factory=dict)

    @property
    def procs_files(self) -> list[str]:
        """Where a process writes ``0`` to join the box (done in the child before exec): the
        cgroups of its limits."""
        limits = [d for c, d in self.dirs.items() if c != "kill"]
        return [str(d / "cgroup.procs") for d in dict.fromkeys(limits)]

    @property
    def kill_procs_files(self) -> list[str]:
        """Where a process writes ``0`` to join the box's cgroup made for ``cgroup.kill`` alone
        (under cgroup1), if any: a join that fails there costs the box only the kill at once
        (the kill by pid remains), so it never stops a box from starting."""
        kill = self.dirs.get("kill")
        if kill is None or kill in [d for c, d in self.dirs.items() if c != "kill"]:
            return []
        return [str(kill / "cgroup.procs")]

    def pids(self) -> set[int]:
        """Every process of the box (in this PID namespace's numbers)."""
        out: set[int] = set()
        for d in dict.fromkeys(self.dirs.values()):
            for tok in _read(d / "cgroup.procs").split():
                if tok.isdigit():
                    out.add(int(tok))
        return out

    def memory_killed(self) -> int:
        """Processes the kernel killed at the box's memory limit."""
        d = self.dirs["memory"]
        name = "memory.events" if self.kind == "cgroup2" else "memory.oom_control"
        return _count(_read(d / name), "oom_kill")

    def memory_peak(self) -> int | None:
        d = self.dirs["memory"]
        name = "memory.peak" if self.kind == "cgroup2" else "memory.max_usage_in_bytes"
        text = _read(d / name).strip()
        return int(text) if text.isdigit() else None

    def fork_refused(self) -> int:
        """fork()s the kernel refused at the box's process limit."""
        return _count(_read(self.dirs["pids"] / "pids.events"), "max")

    def set_processes(self, processes: int) -> None:
        """A new ``pids.max`` (a box that starts otherwise than planned: its own processes
        differ)."""
        _write(self.dirs["pids"] / "pids.max", str(processes))

    def kill_at_once(self) -> bool:
        """SIGKILL every process of the box in one step (``cgroup.kill``: the kernel's, forks in
        flight included); False where the box has no cgroup with it."""
        d = self.dirs.get("kill")
        if d is None:
            return False
        try:
            _write(d / "cgroup.kill", "1")
        except OSError:
            return False
        return True

    def kill(self) -> int:
        """SIGKILL every process of the box: at once where it can, then each that is left; how
        many were signalled by pid."""
        self.kill_at_once()
        pids = self.pids()
        for pid in pids:
            try:
                os.kill(pid, signal.SIGKILL)
            except (ProcessLookupError, PermissionError):
                pass
        return len(pids)

    def remove(self, wait: float = 2.0) -> bool:
        """Kill what is left and remove the folders; True when they are gone."""
        deadline = time.monotonic() + wait
        for d in dict.fromkeys(self.dirs.values()):
            while True:
                self.kill()
                try:
                    d.rmdir()
                    break
                except FileNotFoundError:
                    break
                except OSError:  # a process still exiting: its cgroup is busy a moment
                    if time.monotonic() > deadline:
                        return False
                    time.sleep(0.01)
        return True


def create(memory: int, processes: int) -> BoxCgroup | None:
    """A new box cgroup with these limits (bytes of the whole box; processes and threads at
    once), or None when none can be made here (the caller falls back on rlimits)."""
    name = f"{PREFIX}{os.getpid()}-{secrets.token_hex(4)}"
    base = _v2_base()
    if base is not None:
        sweep_stale(base)
        d = base / name
        try:
            d.mkdir()
            _write(d / "memory.max", str(memory))
            for opt, value in (("memory.swap.max", "0"), ("memory.oom.group", "1"),
                               ("cpu.max", f"{CPU_QUOTA} {CPU_PERIOD}")):
                if (d / opt).exists():
                    _write(d / opt, value)
            _write(d / "pids.max", str(processes))
        except OSError:
            BoxCgroup("cgroup2", {"memory": d}).remove()
            return None
        box = BoxCgroup("cgroup2", {"memory": d, "pids": d, "cpu": d})
        if (d / "cgroup.kill").exists():
            box.dirs["kill"] = d
        return box
    bases = _v1_bases()
    if bases is None:
        return None
    box = BoxCgroup("cgroup1")
    try:
        for c, b in bases.items():
            sweep_stale(b)
            d = b / name
            d.mkdir()
            box.dirs[c] = d
        m = box.dirs["memory"]
        _write(m / "memory.limit_in_bytes", str(memory))
        if (m / "memory.memsw.limit_in_bytes").exists():  # swap accounted: no way around
            _write(m / "memory.memsw.limit_in_bytes", str(memory))
        if (m / "memory.swappiness").exists():
            try:
                _write(m / "memory.swappiness", "0")
            except OSError:
                pass
        _write(box.dirs["pids"] / "pids.max", str(processes))
        if "cpu" in box.dirs:
            _write(box.dirs["cpu"] / "cpu.cfs_period_us", str(CPU_PERIOD))
            _write(box.dirs["cpu"] / "cpu.cfs_quota_us", str(CPU_QUOTA))
        unified = _v2_kill_base()
        killer = _kill_only(unified, name) if unified is not None else None
        if killer is not None:
            box.dirs["kill"] = killer
    except OSError:
        box.remove()
        return None
    return box


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def sweep_stale(base: Path) -> int:
    """Empty and remove the box cgroups below ``base`` whose supervising process is dead (a
    worker killed mid-check); returns how many."""
    n = 0
    try:
        entries = list(base.iterdir())
    except OSError:
        return 0
    for d in entries:
        if not d.name.startswith(PREFIX):
            continue
        owner = d.name[len(PREFIX):].split("-", 1)[0]
        if owner.isdigit() and not _alive(int(owner)):
            dirs = {"memory": d, **({"kill": d} if (d / "cgroup.kill").exists() else {})}
            n += BoxCgroup("cgroup1", dirs).remove(wait=0.5)
    return n
