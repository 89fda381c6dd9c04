"""Run one student's submission in a box: isolated, limited, and emptied before anything is trusted.

The interface is generic (any checker of this package uses it)::

    from gpsaccel.check import sandbox
    sub = sandbox.load_submission("alice/", function="kalman_filter")   # a .py file or a folder
    calls = [sandbox.Call("kalman_filter", (z[r],),
                          (sandbox.Output("x_hat", (151, 3)), sandbox.Output("P", (151, 3, 3))))
             for r in range(n_runs)]
    box = sandbox.run(sub, calls, sandbox.Limits(time=60), backend="auto")
    box.results[r]["x_hat"]        # float64 (151, 3), exactly the declared shape, or box.failure

Each call names a function of the submission, its positional numpy arguments and the arrays it must
return (one :class:`Output` = the function returns that array; several = a tuple of them, in
order).  The student's code runs in a separate Python (``_runner.py``); whatever it returns comes
back over a pipe as frames the parent reads against the shapes and dtypes *it* declared
(:class:`FrameReader`): a result of another shape, a larger one, or bytes that are not a frame
are refused (``result-refused``), never loaded.  Nothing the student wrote to a file is read.

Backends
--------
``bwrap`` (bubblewrap; ``apt-get install bubblewrap``)
    New user, PID, network, IPC, UTS and cgroup namespaces; inside, uid 65534 with no
    capabilities.  The file system is the interpreter's folders (``/usr``, the Python prefix, the
    site-packages) read-only, the checker's own package hidden under an empty tmpfs, ``/proc`` of
    the box's PID namespace only (the checker's memory and environment are not in it), and two
    small writable tmpfs: the working directory ``/box`` (holding a copy of the submission's own
    files, nothing else) and ``/tmp``, each of at most ``Limits.file_size`` bytes.  No network.
    ``--die-with-parent``: when the checker goes, the box goes; when the box's first process is
    killed, the kernel kills every process of its PID namespace.
``basic`` (any Linux; the isolation that needs no tool)
    A fresh session; resource limits set before exec (address space, CPU time, file size,
    processes, open files, no core files); an environment of ``PATH``, ``HOME`` (the box) and
    ``LANG`` only; a private temporary working directory holding a copy of the submission only;
    the checker made non-dumpable while the student runs (so ``/proc/<checker>/mem``,
    ``environ``, ``maps`` are closed to a process without ``CAP_SYS_PTRACE``).  Run as root it
    also empties the child's capability bounding set before exec, so the student's root has no
    capability (no ``CAP_SYS_PTRACE`` to read the checker's memory, no ``CAP_SYS_RESOURCE`` to
    lift its limits, no ``CAP_KILL`` on other users).  It cannot hide files: the student reads
    what the checker's user can read, and (as root, or as the same user) can write what that
    user can write; a student can kill the checker process (a batch survives that, see
    :mod:`gpsaccel.check.batch`).  Root's processes are not counted by ``RLIMIT_NPROC``; the
    process limit is then enforced by counting the box's processes every 250 ms (under both
    backends: a bwrap box started by root runs as root outside its user namespace).
``auto`` is ``bwrap`` when a trial box starts on this machine, else ``basic``.

Every run ends with a checked kill: the checker is a child subreaper while the box runs (a
``setsid`` daemon is re-parented to it, not to init), every process of the box (the descendants of
its first process and the orphans adopted meanwhile) is killed with SIGKILL until a scan of
``/proc`` finds none alive, and they are reaped.  Only then does :func:`run` return, so a caller
that computes the reference answer afterwards never holds it while a student process lives.

Limits (:class:`Limits`) and what exceeding them gives (:attr:`BoxResult.failure`): ``timeout``
(wall-clock), ``memory-limit`` (address space; a ``MemoryError`` or a process that died of it),
``output-limit`` (printed bytes; the box is stopped at the limit), ``file-limit`` (one file, or a
box tmpfs, full), ``process-limit``, ``uses-checker`` (an import of gpsaccel was attempted),
``result-refused``, ``crashed`` (the process ended without saying ``done``), and the runner's
own: ``import-error``, ``no-function``, ``exception``, ``return-value``, ``not-numeric``,
``wrong-shape``.
"""

from __future__ import annotations

import ast
import ctypes
import functools
import json
import os
import resource
import selectors
import shutil
import signal
import site
import struct
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

#: The script that runs the student's code in the box.
RUNNER = Path(__file__).with_name("_runner.py")

#: The package a submission may not import (unless allowed): the checker's own.
PACKAGE_DIR = Path(__file__).resolve().parent.parent
BLOCKED = (PACKAGE_DIR.name,)

BACKENDS = ("auto", "bwrap", "basic")

#: Largest submission copied into a box: files and bytes (a folder of data files may be large).
MAX_FILES = 200
MAX_BYTES = 32 << 20

#: Longest frame header (JSON) the parent accepts from the runner.
MAX_HEADER = 1 << 16

#: uid/gid of the student inside a bwrap box.
BOX_UID = 65534

_POLL = 0.05  # s between looks at the pipes and the process
#: s between counts of the box's processes, done only where RLIMIT_NPROC does not bind (root): a
#: count scans all of /proc (about 10 ms for 100 processes)
COUNT_EVERY = 0.25


# ------------------------------------------------------------------------------ what to run
@dataclass(frozen=True)
class Limits:
    """What one box may use.

    memory : address space per process, bytes (RLIMIT_AS; default 1 GiB).
    time : wall-clock limit of the whole box (import and every call), s.
    file_size : largest file the student may write, bytes (RLIMIT_FSIZE); under bwrap also the
        size of each writable tmpfs (``/box``, ``/tmp``).
    processes : processes of the box at once (the runner included).
    open_files : open file descriptors per process (RLIMIT_NOFILE).
    output : bytes the student may print (stdout and stderr together); the box is stopped there
        (default 16 MiB: a correct filter that prints every GPS time prints 6.3 MB in a 200-run
        check; the checker keeps only the last 64 KiB, so the limit bounds wasted time, not
        memory).
    """

    memory: int = 1 << 30
    time: float = 60.0
    file_size: int = 64 << 20
    processes: int = 64
    open_files: int = 256
    output: int = 16 << 20

    def __post_init__(self) -> None:
        for name in ("memory", "file_size", "processes", "open_files", "output"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"limits.{name} must be a positive integer, got {value!r}")
        if not (isinstance(self.time, (int, float)) and 0 < self.time < float("inf")):
            raise ValueError(f"limits.time must be a finite number of seconds > 0, "
                             f"got {self.time!r}")
        if self.memory < 256 << 20:
            raise ValueError(f"limits.memory must be at least 256 MiB (Python with numpy needs "
                             f"about 260 MB of address space), got {self.memory}")
        if self.open_files < 16:
            raise ValueError(f"limits.open_files must be at least 16, got {self.open_files}")


@dataclass(frozen=True)
class Output:
    """One array a call must return: its name (for messages), shape and dtype."""

    name: str
    shape: tuple[int, ...]
    dtype: str = "float64"

    def __post_init__(self) -> None:
        if not all(isinstance(n, (int, np.integer)) and n >= 0 for n in self.shape):
            raise ValueError(f"output {self.name!r}: shape must be a tuple of sizes >= 0, "
                             f"got {self.shape!r}")
        dt = np.dtype(self.dtype)
        if dt.hasobject or dt.kind not in "biuf":
            raise ValueError(f"output {self.name!r}: dtype must be a numeric dtype, "
                             f"got {self.dtype!r}")

    @property
    def nbytes(self) -> int:
        return int(np.prod(self.shape, dtype=np.int64)) * np.dtype(self.dtype).itemsize


@dataclass(frozen=True)
class Call:
    """Call ``function(*args)`` of the submission; it must return ``outputs``."""

    function: str
    args: tuple[np.ndarray, ...]
    outputs: tuple[Output, ...]

    def __post_init__(self) -> None:
        if not self.function.isidentifier():
            raise ValueError(f"call: function must be a Python name, got {self.function!r}")
        if not self.outputs:
            raise ValueError(f"call {self.function}: declare at least one output")


@dataclass(frozen=True)
class Submission:
    """A student's files: ``root`` (a folder), the ``entry`` file defining the function, and
    ``files`` (paths relative to ``root``) copied into the box."""

    root: Path
    entry: str
    files: tuple[str, ...]


class SubmissionError(ValueError):
    """What is handed in is not a submission; ``code`` is the finding to report."""

    def __init__(self, code: str, message: str) -> None:
        super().__init__(message)
        self.code = code


def defines(path: str | os.PathLike, function: str) -> bool:
    """Whether the file defines ``function`` at top level (read with ast, never executed)."""
    try:
        tree = ast.parse(Path(path).read_bytes(), filename=str(path))
    except (SyntaxError, ValueError, OSError):
        return False
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name == function:
            return True
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == function
                                                for t in node.targets):
            return True
        if isinstance(node, (ast.Import, ast.ImportFrom)) and any(
                (a.asname or a.name) == function for a in node.names):
            return True
    return False


def load_submission(path: str | os.PathLike, function: str) -> Submission:
    """The submission at ``path``: a ``.py`` file alone, or a folder (one student's) holding
    one ``.py`` file that defines ``function`` plus its helper modules and data files.

    Hidden entries and ``__pycache__`` are left out; symbolic links are not followed out of the
    folder.  Raises :class:`SubmissionError` (``not-found``, ``no-function``, ``ambiguous-entry``,
    ``file-limit``) with a message for the student.
    """
    path = Path(path)
    if path.is_file():
        if path.suffix != ".py":
            raise SubmissionError("not-found", f"{path.name} is not a Python file (.py).")
        if path.stat().st_size > MAX_BYTES:
            raise SubmissionError("file-limit", f"{path.name} is larger than "
                                  f"{MAX_BYTES >> 20} MB.")
        return Submission(path.resolve().parent, path.name, (path.name,))
    if not path.is_dir():
        raise SubmissionError("not-found", f"{path} is neither a file nor a folder.")
    root = path.resolve()
    files: list[str] = []
    size = 0
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames[:] = sorted(d for d in dirnames if not d.startswith(".") and d != "__pycache__"
                             and not os.path.islink(os.path.join(dirpath, d)))
        for f in sorted(filenames):
            full = Path(dirpath, f)
            if f.startswith(".") or full.is_symlink() or not full.is_file():
                continue
            files.append(full.relative_to(root).as_posix())
            size += full.stat().st_size
            if len(files) > MAX_FILES or size > MAX_BYTES:
                raise SubmissionError("file-limit", f"The folder {path.name} holds more than "
                                      f"{MAX_FILES} files or {MAX_BYTES >> 20} MB: hand in your "
                                      f"code and the data it reads, nothing else.")
    py = [f for f in files if f.endswith(".py") and "/" not in f]
    entries = [f for f in py if defines(root / f, function)]
    if not entries:
        raise SubmissionError("no-function", f"No Python file at the top of the folder "
                              f"{path.name} defines {function}(...) (files: "
                              f"{', '.join(py) or 'none'}). Define it in one of them.")
    if len(entries) > 1:
        raise SubmissionError("ambiguous-entry", f"Several files of the folder {path.name} "
                              f"define {function}: {', '.join(entries)}. Keep it in one file and "
                              f"import it from there.")
    return Submission(root, entries[0], tuple(files))


# ------------------------------------------------------------------------------ the result
@dataclass
class BoxResult:
    """What came back from one box.

    backend : ``"bwrap"`` or ``"basic"``.
    results : one dict per completed call (output name -> array of the declared shape/dtype), in
        order; fewer than the calls when it stopped early.
    failure : None when every call returned, else a code (see the module docstring).
    problem : the runner's report of the first problem (kind, traceback, shapes, ...), or None.
    detail : a short text on what the sandbox saw (which limit, what was refused).
    uses_checker : the submission tried to import a blocked package (even if it caught the error).
    returned : what the first call returned (type and shape of each output), for notes.
    output : the tail of what the student printed; output_bytes : its full length.
    returncode : exit status of the box's first process (negative: killed by that signal).
    seconds : wall-clock time of the box; import_seconds, run_seconds as the runner measured.
    killed : processes the student's code had started and left alive (besides the runner),
        killed at the end.
    """

    backend: str
    results: list[dict[str, np.ndarray]] = field(default_factory=list)
    failure: str | None = None
    problem: dict | None = None
    detail: str = ""
    uses_checker: bool = False
    returned: dict | None = None
    output: str = ""
    output_bytes: int = 0
    returncode: int | None = None
    seconds: float = 0.0
    import_seconds: float | None = None
    run_seconds: float | None = None
    killed: int = 0


class Refused(Exception):
    """The runner's channel carried something other than the declared frames."""


class FrameReader:
    """Parse the runner's frames against the declared outputs; raise :class:`Refused` otherwise.

    The parent holds at most one frame header (≤ :data:`MAX_HEADER` bytes) plus one declared
    result in memory; sizes come from ``calls``, never from the bytes read.
    """

    def __init__(self, calls: Sequence[Call]) -> None:
        self.calls = calls
        self.buf = bytearray()
        self.results: list[dict[str, np.ndarray]] = []
        self.events: list[dict] = []
        self.done = False
        self.problem: dict | None = None

    def feed(self, data: bytes) -> None:
        if self.done or self.problem is not None:
            if data:
                raise Refused("bytes after the last frame")
        self.buf += data
        while len(self.buf) >= 4:
            (n,) = struct.unpack(">I", self.buf[:4])
            if n > MAX_HEADER:
                raise Refused(f"a frame header of {n} bytes (at most {MAX_HEADER})")
            if len(self.buf) < 4 + n:
                return
            try:
                header = json.loads(bytes(self.buf[4:4 + n]))
            except (UnicodeDecodeError, ValueError) as exc:
                raise Refused(f"a frame header that is not JSON ({exc})") from None
            if not isinstance(header, dict):
                raise Refused("a frame header that is not a JSON object")
            kind = header.get("t")
            size = 0
            if kind == "result":
                i = len(self.results)
                if header.get("call") != i or i >= len(self.calls):
                    raise Refused(f"a result for call {header.get('call')!r} where call {i} "
                                  f"was expected ({len(self.calls)} declared)")
                size = sum(o.nbytes for o in self.calls[i].outputs)
            elif kind not in ("uses-checker", "imported", "problem", "done"):
                raise Refused(f"a frame of unknown kind {kind!r}")
            if len(self.buf) < 4 + n + size:
                return
            payload = bytes(self.buf[4 + n:4 + n + size])
            del self.buf[:4 + n + size]
            self.events.append(header)
            if kind == "result":
                out, at = {}, 0
                for o in self.calls[len(self.results)].outputs:
                    out[o.name] = np.frombuffer(payload, dtype=o.dtype, count=o.nbytes
                                                // np.dtype(o.dtype).itemsize,
                                                offset=at).reshape(o.shape).copy()
                    at += o.nbytes
                self.results.append(out)
            elif kind == "problem":
                self.problem = header
            elif kind == "done":
                if len(self.results) != len(self.calls):
                    raise Refused(f"'done' after {len(self.results)} of {len(self.calls)} "
                                  f"results")
                self.done = True
            if (self.done or self.problem is not None) and self.buf:
                raise Refused("bytes after the last frame")


# ------------------------------------------------------------------------- the machinery
@functools.lru_cache(maxsize=1)
def _libc() -> ctypes.CDLL | None:
    if not sys.platform.startswith("linux"):
        return None
    try:
        return ctypes.CDLL(None, use_errno=True)
    except OSError:
        return None


PR_SET_PDEATHSIG, PR_GET_DUMPABLE, PR_SET_DUMPABLE = 1, 3, 4
PR_CAPBSET_DROP, PR_SET_NO_NEW_PRIVS = 24, 38
PR_SET_CHILD_SUBREAPER, PR_GET_CHILD_SUBREAPER = 36, 37


def _prctl(option: int, arg: int = 0) -> int:
    libc = _libc()
    if libc is None:
        return -1
    return libc.prctl(ctypes.c_int(option), ctypes.c_ulong(arg), ctypes.c_ulong(0),
                      ctypes.c_ulong(0), ctypes.c_ulong(0))


def _get_subreaper() -> int:
    libc = _libc()
    if libc is None:
        return 0
    value = ctypes.c_int(0)
    libc.prctl(ctypes.c_int(PR_GET_CHILD_SUBREAPER), ctypes.byref(value), ctypes.c_ulong(0),
               ctypes.c_ulong(0), ctypes.c_ulong(0))
    return value.value


def set_subreaper(on: bool) -> bool:
    """Make this process a child subreaper (orphans of its descendants become its children)."""
    return _prctl(PR_SET_CHILD_SUBREAPER, int(on)) == 0


def _cap_last() -> int:
    try:
        return int(Path("/proc/sys/kernel/cap_last_cap").read_text())
    except (OSError, ValueError):
        return 40


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


def _user_tasks() -> int:
    """Processes and threads of this real uid (what RLIMIT_NPROC counts), from /proc."""
    uid, n = os.getuid(), 0
    for entry in os.scandir("/proc"):
        if entry.name.isdigit():
            try:
                with open(f"/proc/{entry.name}/status", "rb") as f:
                    status = f.read()
            except OSError:
                continue
            fields = dict(line.split(b":", 1) for line in status.splitlines() if b":" in line)
            try:
                if int(fields.get(b"Uid", b"-1 0").split()[0]) == uid:
                    n += int(fields.get(b"Threads", b"1"))
            except (ValueError, IndexError):
                continue
    return n


def _nproc(limits: Limits) -> int:
    """RLIMIT_NPROC for the box.  It counts every process and thread of the real uid, not of the
    box, so for a user other than root it is set to what the user runs now plus the box's
    allowance; root's processes are not counted at all (the parent's scan enforces it then)."""
    if os.getuid() == 0 or not os.path.isdir("/proc"):
        return limits.processes
    return _user_tasks() + limits.processes


def _preexec(limits: Limits, nproc: int, drop_caps: bool, cap_last: int) -> None:
    """In the child, before exec: limits, no core files, no new privileges (runs after fork;
    everything it calls was looked up before the fork)."""
    cpu = int(limits.time) + 2
    for res, value in ((resource.RLIMIT_AS, limits.memory), (resource.RLIMIT_CPU, cpu),
                       (resource.RLIMIT_FSIZE, limits.file_size),
                       (resource.RLIMIT_NPROC, nproc),
                       (resource.RLIMIT_NOFILE, limits.open_files),
                       (resource.RLIMIT_CORE, 0)):
        resource.setrlimit(res, (value, value))
    _prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
    if drop_caps:  # root: after exec the permitted set is the bounding set, so empty it
        for cap in range(cap_last + 1):
            _prctl(PR_CAPBSET_DROP, cap)
        _prctl(PR_SET_NO_NEW_PRIVS, 1)


def _proc_table() -> dict[int, tuple[int, str, str]]:
    """pid -> (ppid, state, comm) of every process visible in /proc (``ps`` where there is no
    /proc)."""
    table = {}
    if not os.path.isdir("/proc/self"):
        ps = subprocess.run(["ps", "-A", "-o", "pid=,ppid=,stat=,comm="], capture_output=True,
                            text=True, check=True).stdout
        for line in ps.splitlines():
            pid, ppid, stat, *comm = line.split()
            table[int(pid)] = (int(ppid), stat[0], " ".join(comm))
        return table
    for entry in os.scandir("/proc"):
        if not entry.name.isdigit():
            continue
        try:
            with open(f"/proc/{entry.name}/stat", "rb") as f:
                stat = f.read()
        except OSError:
            continue
        close = stat.rfind(b")")
        rest = stat[close + 2:].split()
        if close < 0 or len(rest) < 2:
            continue  # the process went away while it was read
        comm = stat[stat.find(b"(") + 1:close].decode(errors="replace")
        table[int(entry.name)] = (int(rest[1]), rest[0].decode(), comm)
    return table


def box_processes(first: int, adopted_from: set[int] | None) -> list[int]:
    """Live processes of a box: descendants of ``first`` (itself included) and, when
    ``adopted_from`` is given, every new child of this process (orphans it adopted as a subreaper)
    with its descendants.  Zombies are not counted."""
    table = _proc_table()
    children: dict[int, list[int]] = {}
    for pid, (ppid, _, _) in table.items():
        children.setdefault(ppid, []).append(pid)
    roots = [first] if first in table else []
    if adopted_from is not None:
        me = os.getpid()
        roots += [p for p in children.get(me, []) if p != first and p not in adopted_from]
    out, stack = [], list(roots)
    while stack:
        pid = stack.pop()
        if pid in out:
            continue
        out.append(pid)
        stack.extend(children.get(pid, []))
    return [p for p in out if table.get(p, (0, "Z", ""))[1] not in ("Z", "X")]


def _kill_box(proc: subprocess.Popen, before: set[int]) -> int:
    """SIGKILL every process of the box until none is alive; reap them.  Returns how many
    processes (bwrap's own not counted) were alive when the kill began."""
    found: int | None = None
    for _ in range(200):
        alive = box_processes(proc.pid, before)
        if found is None:
            table = _proc_table()
            found = sum(table.get(p, (0, "", ""))[2] != "bwrap" for p in alive)
        if not alive:
            break
        for pid in alive:
            try:
                os.kill(pid, signal.SIGKILL)
            except (ProcessLookupError, PermissionError):
                pass
        if proc.poll() is None:
            try:
                proc.wait(timeout=0.05)
            except subprocess.TimeoutExpired:
                pass
        _reap_adopted(before, proc.pid)
    else:  # pragma: no cover - a box that outlives 200 rounds of SIGKILL
        raise RuntimeError(f"the sandbox could not kill processes {alive}")
    proc.wait()
    _reap_adopted(before, proc.pid)
    return found or 0


def _reap_adopted(before: set[int], first: int) -> None:
    """waitpid every exited child of this process that the box left (orphans adopted)."""
    for pid, (ppid, state, _) in _proc_table().items():
        if ppid == os.getpid() and pid not in before and pid != first and state in ("Z", "X"):
            try:
                os.waitpid(pid, os.WNOHANG)
            except ChildProcessError:
                pass


def _my_children() -> set[int]:
    me = os.getpid()
    return {pid for pid, (ppid, _, _) in _proc_table().items() if ppid == me}


# --------------------------------------------------------------------------- preparing a box
def _write_control(control: Path, sub: Submission, calls: Sequence[Call], sys_path: list[str],
                   allow: bool) -> None:
    control.mkdir()
    shutil.copy2(RUNNER, control / "_runner.py")
    arrays = {f"c{i}_{j}": np.asarray(a) for i, c in enumerate(calls) for j, a in
              enumerate(c.args)}
    for k, a in arrays.items():
        if a.dtype.hasobject:
            raise ValueError(f"call arguments must be numeric arrays; {k} is {a.dtype}")
    np.savez(control / "inputs.npz", **arrays)
    plan = {"entry": sub.entry, "sys_path": sys_path, "block": [] if allow else list(BLOCKED),
            "block_dirs": [] if allow else _blocked_dirs(),
            "calls": [{"function": c.function, "n_args": len(c.args),
                       "outputs": [{"name": o.name, "shape": list(o.shape), "dtype": o.dtype}
                                   for o in c.outputs]} for c in calls]}
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
                   result_fd: int) -> tuple[list[str], list[int]]:
    """The bwrap command line, and the file descriptors it must inherit (one per copied file)."""
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
    elif any(pkg == b or pkg.startswith(b + "/") for b in bound):
        cmd.extend(["--tmpfs", pkg])  # an editable or installed gpsaccel: hidden
    cmd.extend(["--proc", "/proc", "--dev", "/dev",
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
        fd = os.open(sub.root / rel, os.O_RDONLY)
        fds.append(fd)
        cmd.extend(["--perms", "0644", "--file", str(fd), "/box/" + rel])
    cmd.extend(["--chdir", "/box", "--", exe_py, "-I", "-S", "-B", "/control/_runner.py",
                "/control", "/box", str(result_fd)])
    return cmd, fds


def _copy_submission(sub: Submission, box: Path) -> None:
    for rel in sub.files:
        dest = box / rel
        dest.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(sub.root / rel, dest)


# ----------------------------------------------------------------------------------- run
def run(sub: Submission, calls: Sequence[Call], limits: Limits = Limits(),
        backend: str = "auto", allow_gpsaccel: bool = False) -> BoxResult:
    """Run ``calls`` on the submission in a new box; return only once every process it started
    is dead.  Never raises for anything the submission does (ValueError for bad arguments)."""
    backend = resolve_backend(backend)
    calls = list(calls)
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="gpsaccel-box-") as tmp_name:
        tmp = Path(tmp_name)
        sys_path = _site_dirs()
        if allow_gpsaccel:
            sys_path.insert(0, str(PACKAGE_DIR.parent))
        _write_control(tmp / "control", sub, calls, sys_path, allow_gpsaccel)
        res_r, res_w = os.pipe()
        out_r, out_w = os.pipe()
        owned = [res_r, res_w, out_r, out_w]  # closed once, here or when handed to the child
        fds: list[int] = []
        try:
            if backend == "bwrap":
                cmd, fds = _bwrap_command(bwrap_path(), tmp, sub, limits, allow_gpsaccel, res_w)
                owned += fds
                cwd, env, drop = str(tmp), _environment("/box"), False
            else:
                box = tmp / "box"
                box.mkdir()
                _copy_submission(sub, box)
                cmd = [_python(), "-I", "-S", "-B", str(tmp / "control" / "_runner.py"),
                       str(tmp / "control"), str(box), str(res_w)]
                cwd, env, drop = str(box), _environment(str(box)), os.geteuid() == 0
            return _supervise(backend, cmd, cwd, env, drop, limits, calls, res_r, out_r,
                              [res_w, out_w, *fds], owned, t0)
        finally:
            for fd in owned:
                try:
                    os.close(fd)
                except OSError:
                    pass


def _supervise(backend: str, cmd: list[str], cwd: str, env: dict, drop_caps: bool,
               limits: Limits, calls: list[Call], res_r: int, out_r: int,
               child_fds: list[int], owned: list[int], t0: float) -> BoxResult:
    result = BoxResult(backend)
    reader = FrameReader(calls)
    tail = bytearray()
    keep = 1 << 16
    was_dumpable = _prctl(PR_GET_DUMPABLE)
    was_subreaper = _get_subreaper()
    set_subreaper(True)
    _prctl(PR_SET_DUMPABLE, 0)  # /proc/<checker>/mem, environ: closed to the student
    before = _my_children()
    hit: str | None = None
    refused: str | None = None
    proc = None
    sel = None
    emptied = False
    try:
        res_w, out_w = child_fds[:2]
        proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=out_w, stderr=out_w,
                                cwd=cwd, env=env, pass_fds=(res_w, *child_fds[2:]), close_fds=True,
                                start_new_session=True,
                                preexec_fn=functools.partial(_preexec, limits, _nproc(limits),
                                                             drop_caps, _cap_last()))
        for fd in child_fds:  # the parent keeps only the reading ends
            os.close(fd)
            owned.remove(fd)
        deadline = time.monotonic() + limits.time
        sel = selectors.DefaultSelector()
        sel.register(res_r, selectors.EVENT_READ, "res")
        sel.register(out_r, selectors.EVENT_READ, "out")
        open_pipes = 2
        exited_at = None
        count = os.getuid() == 0 or not sys.platform.startswith("linux")
        next_count = time.monotonic() + COUNT_EVERY
        while True:
            now = time.monotonic()
            if now >= deadline:
                hit = "timeout"
                break
            for key, _ in sel.select(timeout=min(_POLL, deadline - now)):
                data = os.read(key.fd, 1 << 16)
                if not data:
                    sel.unregister(key.fd)
                    open_pipes -= 1
                    continue
                if key.data == "out":
                    result.output_bytes += len(data)
                    tail += data
                    del tail[:-keep]
                    if result.output_bytes > limits.output:
                        hit = "output-limit"
                else:
                    try:
                        reader.feed(data)
                    except Refused as exc:
                        refused = str(exc)
                        hit = "result-refused"
            if hit:
                break
            now = time.monotonic()
            if proc.poll() is not None:
                # the runner is gone: its pipes close unless a child of the student's holds them
                exited_at = exited_at or now
                if open_pipes == 0 or now - exited_at > 0.2:
                    break
            if count and now >= next_count:
                next_count = now + COUNT_EVERY
                n = len(box_processes(proc.pid, before))
                # under bwrap two bwrap processes stand above the student's
                if n - (2 if backend == "bwrap" else 0) > limits.processes:
                    hit = "process-limit"
                    break
        # the runner is still alive when the box's first process is (basic) or when anything
        # is (bwrap: the PID namespace ends with the runner); what else lived, the student left
        runner_alive = proc.poll() is None
        found = _kill_box(proc, before)
        emptied = True
        result.killed = max(0, found - (1 if (runner_alive if backend == "basic" else found)
                                        else 0))
        # every writer is dead: what is left in the pipes is all there will be
        for fd, what in ((res_r, "res"), (out_r, "out")):
            os.set_blocking(fd, False)
            while True:
                try:
                    data = os.read(fd, 1 << 16)
                except BlockingIOError:
                    break
                if not data:
                    break
                if what == "out":
                    result.output_bytes += len(data)
                    tail += data
                    del tail[:-keep]
                elif not refused:
                    try:
                        reader.feed(data)
                    except Refused as exc:
                        refused = str(exc)
                        hit = hit or "result-refused"
        result.returncode = proc.returncode
    finally:
        if proc is not None and not emptied:  # Ctrl-C or an error of ours: the box goes too
            _kill_box(proc, before)
        if sel is not None:
            sel.close()
        set_subreaper(bool(was_subreaper))
        if was_dumpable > 0:
            _prctl(PR_SET_DUMPABLE, was_dumpable)
    result.output = tail.decode("utf-8", errors="replace")
    result.results = reader.results
    result.problem = reader.problem
    result.seconds = time.perf_counter() - t0
    for ev in reader.events:
        if ev.get("t") == "uses-checker":
            result.uses_checker = True
        elif ev.get("t") == "done":
            result.import_seconds = ev.get("import_seconds")
            result.run_seconds = ev.get("run_seconds")
        elif ev.get("t") == "result" and result.returned is None:
            result.returned = ev.get("returned")
    result.failure, result.detail = _failure(result, hit, refused, reader, limits)
    return result


def _failure(result: BoxResult, hit: str | None, refused: str | None, reader: FrameReader,
             limits: Limits) -> tuple[str | None, str]:
    """The failure code of a box, most telling first."""
    if hit == "result-refused":
        return hit, f"the result channel carried {refused}"
    if hit == "output-limit":
        return hit, f"more than {limits.output} bytes printed"
    if hit == "process-limit":
        return hit, f"more than {limits.processes} processes at once"
    if result.uses_checker and not reader.done:
        return "uses-checker", "an import of the checker's package was attempted"
    problem = reader.problem
    if problem is not None:
        limit = problem.get("limit")
        if limit in ("memory", "file", "process"):
            return f"{limit}-limit", f"{problem.get('exception')} in the student's code"
        return problem["kind"], ""
    if hit == "timeout":
        return "timeout", f"still running after {limits.time:g} s"
    if reader.done:
        return ("uses-checker", "") if result.uses_checker else (None, "")
    # the runner ended without a last frame: which limit, if any, killed it
    rc = result.returncode
    text = result.output[-4000:]
    if rc == -signal.SIGXFSZ:
        return "file-limit", "killed by SIGXFSZ (file size limit)"
    if rc == -signal.SIGXCPU:
        return "timeout", "killed at the CPU-time limit"
    if "MemoryError" in text or "Cannot allocate memory" in text or "std::bad_alloc" in text \
            or "failed to allocate" in text.lower():
        return "memory-limit", "the process ran out of its address space"
    if "Resource temporarily unavailable" in text:
        return "process-limit", "fork() refused"
    return "crashed", f"exit status {rc}"
