"""Run one student's submission in a box: isolated, limited, and emptied before anything is trusted.

The interface is generic (any checker of this package uses it)::

    from gpsaccel import sandbox
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

Backends (the threat model, what each isolates and what not: ``docs/sandbox.md``)
--------
``bwrap`` (bubblewrap; ``apt-get install bubblewrap``)
    New user, PID, network, IPC, UTS and cgroup namespaces; inside, uid 65534 with no
    capabilities.  The file system is the interpreter's folders (``/usr``, the Python prefix, the
    site-packages) read-only, the checker's own package hidden under an empty tmpfs (or, for a
    box that may import gpsaccel, its answers and checks under empty folders:
    :data:`HIDDEN_WITH_GPSACCEL`), ``/proc`` of the box's PID namespace only (the checker's
    memory and environment are not in it), and three small writable tmpfs: the working
    directory ``/box`` (holding a copy of the submission's own files, nothing else), ``/tmp`` and
    ``/dev/shm``, each of at most ``Limits.file_size`` bytes; the root, ``/dev`` and the folders
    made for the binds are remounted read-only.  No network.
    ``--die-with-parent``: when the checker goes, the box goes; when the box's first process is
    killed, the kernel kills every process of its PID namespace.
``basic`` (any Linux; the isolation that needs no tool)
    A fresh session; resource limits set before exec (address space, CPU time, file size,
    processes, open files, no core files); an environment of ``PATH``, ``HOME`` (the box) and
    ``LANG`` only; a private temporary working directory holding a copy of the submission only;
    the checker made non-dumpable while the student runs.  It cannot hide files: the student
    reads what other users may read.  Not run as root it is not safe for grading (the student is
    the checker's user: :func:`refuse_unsafe_basic`).
``auto`` is ``bwrap`` when a trial box starts on this machine, else ``basic``.

As root, under both backends, the student runs as a uid of its own that owns nothing and that
nothing else runs as, with no capability and no new privileges (:mod:`gpsaccel.sandbox._boxuser`;
bwrap itself runs as that uid): it cannot write into the package or the environment (a ``.pth``),
nor signal the checker, and everything the uid runs is killed at the end, wherever it is in the
process tree.  Where the machine allows it, a cgroup per box (:mod:`gpsaccel.sandbox._cgroup`:
cgroup v2, else v1) limits the memory (processes, tmpfs files and memfds together), the processes
and the CPU of the whole box; else the per-process rlimits are the limits
(:attr:`BoxResult.limit_backend` says which).

Every run ends with a checked kill: the checker is a child subreaper while the box runs (a
``setsid`` daemon is re-parented to it, not to init), every process of the box (the descendants of
its first process, the orphans adopted meanwhile, its cgroup's and its uid's) is killed with
SIGKILL until a scan finds none alive, and they are reaped; what the student left running is
counted first, while the runner waits after its last frame (:attr:`BoxResult.killed`).  Then the
cgroup and the box folder are removed (a folder or cgroup left by a killed checker is removed by
the next box: :func:`sweep_stale_boxes`).  Only then does :func:`run` return, so a caller that
computes the reference answer afterwards never holds it while a student process lives.

Limits (:class:`Limits`) and what exceeding them gives (:attr:`BoxResult.failure`): ``timeout``
(wall-clock), ``memory-limit`` (address space, or the box's cgroup; a ``MemoryError`` or a process
killed at it), ``output-limit`` (printed bytes; the box is stopped at the limit), ``file-limit``
(one file, or a box tmpfs, full), ``process-limit``, ``uses-checker`` (an import of gpsaccel was
attempted), ``result-refused`` (see :class:`FrameReader`), ``link-refused`` (see
:func:`load_submission`), ``crashed`` (the process ended without saying ``done``), and the
runner's own: ``import-error``, ``no-function``, ``exception``, ``return-value``,
``not-numeric``, ``wrong-shape``.
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
import stat
import struct
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TypeGuard

import numpy as np

from gpsaccel.sandbox import _boxuser, _cgroup

#: The script that runs the student's code in the box.
RUNNER = Path(__file__).with_name("_runner.py")

#: The package a submission may not import (unless allowed): the checker's own.
PACKAGE_DIR = Path(__file__).resolve().parent.parent
BLOCKED = (PACKAGE_DIR.name,)

BACKENDS = ("auto", "bwrap", "basic")

#: Folders of the package (relative to it) that are not in a bwrap box even when the box may
#: import gpsaccel (``allow_gpsaccel``: a notebook using the course's models for data): the
#: checks, the homework's graded questions and reference answers, the lessons' self-check answers
#: and the lessons' masters and solutions.  An empty read-only folder is bound over each, so no
#: call (an ``open`` through ctypes included) finds their files; the audit hook of the notebook's
#: module (:mod:`gpsaccel.assignments.notebook`) is the only fence under ``basic``.
HIDDEN_WITH_GPSACCEL = ("check", "assignments", "exercises", "_lessons/masters",
                        "_lessons/solutions")

#: Largest submission copied into a box: files and bytes (a folder of data files may be large).
MAX_FILES = 200
MAX_BYTES = 32 << 20
#: Entries (files and folders, hidden ones too) a submission's folder may hold, and its depth.
MAX_ENTRIES = 2000
MAX_DEPTH = 16

#: Longest frame header (JSON) the parent accepts from the runner, and longest text field in it
#: (the runner keeps a traceback's last lines, each cut to a line's worth).
MAX_HEADER = 1 << 16
MAX_TEXT = 8000
#: Bytes of the result channel beyond the declared outputs: per call (a result header), and for
#: the other frames (imported, uses-checker, problem, done: each at most MAX_HEADER).
HEADER_ALLOWANCE = 1024
CHANNEL_ALLOWANCE = 4 * MAX_HEADER
#: Largest finite magnitude a float result may hold: a filter's estimates and covariances are
#: far below it, and the checker squares and sums them (1e100² · 10⁶ terms is still finite).
MAX_VALUE = 1e100

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

    memory : bytes (default 1 GiB): the whole box's memory where a cgroup applies (every
        process, tmpfs file and memfd together), and the address space of each process
        (RLIMIT_AS) everywhere.
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

    Hidden entries and ``__pycache__`` are left out.  Refused with a finding, never followed:
    a symbolic link (the submission itself, or anything in its folder: ``mallory.py ->
    alice.py`` would pass as a copy, a link to the instructor's folder would hand its files to
    the box) and a hard link (a regular file with more than one name: it may be a file of
    someone else's, the instructor's 0600 solution, that the checker would copy readable into
    the box; whoever owns it, a submission unpacked from an archive or a repository never holds
    one).  A folder deeper than :data:`MAX_DEPTH` or with more than :data:`MAX_ENTRIES` entries
    is refused before it is walked further.  Raises :class:`SubmissionError` (``not-found``,
    ``link-refused``, ``no-function``, ``ambiguous-entry``, ``file-limit``) with a message for
    the student.
    """
    path = Path(path)
    if os.path.islink(path):
        raise SubmissionError("link-refused", f"{_shown(path.name)} is a symbolic link (to "
                              f"{_shown(os.readlink(path))}); hand in your own file, not a "
                              f"link to one.")
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        raise SubmissionError("not-found", f"{_shown(str(path))} is neither a file nor a "
                              f"folder.") from None
    if stat.S_ISREG(st.st_mode):
        if path.suffix != ".py":
            raise SubmissionError("not-found", f"{_shown(path.name)} is not a Python file "
                                  f"(.py).")
        _check_file(path, st, path.name)
        return Submission(path.resolve().parent, path.name, (path.name,))
    if not stat.S_ISDIR(st.st_mode):
        raise SubmissionError("not-found", f"{_shown(str(path))} is neither a file nor a "
                              f"folder.")
    root = path.resolve()
    files = _walk(root, path.name)
    py = [f for f in files if f.endswith(".py") and "/" not in f]
    entries = [f for f in py if defines(root / f, function)]
    if not entries:
        raise SubmissionError("no-function", f"No Python file at the top of the folder "
                              f"{_shown(path.name)} defines {function}(...) (files: "
                              f"{_shown(', '.join(py)) or 'none'}). Define it in one of them.")
    if len(entries) > 1:
        raise SubmissionError("ambiguous-entry", f"Several files of the folder "
                              f"{_shown(path.name)} define {function}: "
                              f"{_shown(', '.join(entries))}. Keep it in one file and import "
                              f"it from there.")
    return Submission(root, entries[0], tuple(files))


def _shown(text: str, limit: int = 200) -> str:
    """A name as it may appear in a message: printable, one line, at most ``limit`` chars."""
    out = "".join(c if c.isprintable() else f"\\x{ord(c):02x}" if ord(c) < 256
                  else f"\\u{ord(c):04x}" for c in text[:limit])
    return out + ("…" if len(text) > limit else "")


def _check_file(full: Path, st: os.stat_result, rel: str) -> None:
    """A regular file may be copied into the box: one name only, within the size limit."""
    if st.st_nlink > 1:
        raise SubmissionError("link-refused", f"{_shown(rel)} is a hard link ({st.st_nlink} "
                              f"names for one file); hand in a copy of your own file.")
    if st.st_size > MAX_BYTES:
        raise SubmissionError("file-limit", f"{_shown(rel)} is larger than "
                              f"{MAX_BYTES >> 20} MB.")


def _walk(root: Path, name: str) -> list[str]:
    """The files of a student's folder (relative paths), breadth first, without following
    anything; :class:`SubmissionError` at a link, below :data:`MAX_DEPTH` or beyond the
    limits of entries, files and bytes."""
    files: list[str] = []
    size = entries = 0
    queue: list[tuple[str, int]] = [("", 0)]
    too_many = SubmissionError("file-limit", f"The folder {_shown(name)} holds more than "
                               f"{MAX_FILES} files, {MAX_ENTRIES} entries or "
                               f"{MAX_BYTES >> 20} MB: hand in your code and the data it reads, "
                               f"nothing else.")
    while queue:
        rel_dir, depth = queue.pop(0)
        try:
            with os.scandir(root / rel_dir if rel_dir else root) as it:
                listing = sorted(it, key=lambda e: e.name)
        except OSError as exc:
            raise SubmissionError("not-found", f"The folder {_shown(name)}/{_shown(rel_dir)} "
                                  f"cannot be read ({exc.strerror}).") from None
        entries += len(listing)
        if entries > MAX_ENTRIES:
            raise too_many
        for e in listing:
            rel = f"{rel_dir}/{e.name}" if rel_dir else e.name
            if e.name.startswith(".") or e.name == "__pycache__":
                continue
            if e.is_symlink():
                raise SubmissionError("link-refused", f"{_shown(name)}/{_shown(rel)} is a "
                                      f"symbolic link; a submission holds its own files, not "
                                      f"links. Replace it with a copy.")
            st = e.stat(follow_symlinks=False)
            if stat.S_ISDIR(st.st_mode):
                if depth + 1 >= MAX_DEPTH:
                    raise SubmissionError("file-limit", f"The folder {_shown(name)} is nested "
                                          f"more than {MAX_DEPTH} levels deep "
                                          f"({_shown(rel, 80)}); keep your code in a few "
                                          f"folders.")
                queue.append((rel, depth + 1))
            elif stat.S_ISREG(st.st_mode):
                _check_file(Path(e.path), st, f"{name}/{rel}")
                files.append(rel)
                size += st.st_size
                if len(files) > MAX_FILES or size > MAX_BYTES:
                    raise too_many
    return files


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
    limit_backend : what enforced the box's memory and process limits: ``"cgroup2"`` or
        ``"cgroup1"`` (one cgroup for the whole box: every process, tmpfs file and memfd counted
        together) or ``"rlimit"`` (per process only; see :mod:`gpsaccel.sandbox._cgroup`).
    box_user : the uid the student ran as when the checker is root (a uid of its own, see
        :mod:`gpsaccel.sandbox._boxuser`), else None (the checker's own user).
    memory_peak : the box's peak memory (bytes) when a cgroup measured it.
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
    limit_backend: str = "rlimit"
    box_user: int | None = None
    memory_peak: int | None = None


class Refused(Exception):
    """The runner's channel carried something other than the declared frames."""


def _is_int(v: object) -> TypeGuard[int]:
    return isinstance(v, int) and not isinstance(v, bool) and -(1 << 31) < v < 1 << 31


def _is_seconds(v: object) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and 0 <= v < 1e9


def _is_text(v: object) -> bool:
    return isinstance(v, str) and len(v) <= MAX_TEXT


def _is_shape(v: object) -> bool:
    return isinstance(v, list) and len(v) <= 32 and all(_is_int(n) and n >= 0 for n in v)


def _is_described(v: object) -> bool:
    """What the runner's ``_describe`` makes: {"type": str, "shape": list | None, "dtype": str}."""
    return (isinstance(v, dict) and _is_text(v.get("type"))
            and set(v) <= {"type", "shape", "dtype"}
            and (v.get("shape") is None or _is_shape(v["shape"]))
            and ("dtype" not in v or _is_text(v["dtype"])))


def _optional(check):  # noqa: ANN001, ANN202
    return lambda v: v is None or check(v)


#: Every field a frame may carry and the test its value must pass (what the runner sends; the
#: parent's code reads these and nothing else, so a value of another type never reaches it).
FRAME_FIELDS: dict[str, dict[str, Callable[[object], bool]]] = {
    "uses-checker": {"module": _is_text},
    "imported": {"seconds": _is_seconds},
    "result": {"call": _is_int,
               "returned": lambda v: isinstance(v, dict) and len(v) <= 64 and all(
                   _is_text(k) and _is_described(d) for k, d in v.items())},
    "problem": {"kind": lambda v: v in ("import-error", "no-function", "exception",
                                        "return-value", "not-numeric", "wrong-shape"),
                "exception": _is_text, "limit": _optional(_is_text),
                "traceback": _is_text, "call": lambda v: _is_int(v) and v >= 0,
                "function": _is_text, "name": _is_text, "error": _is_text,
                "callables": lambda v: isinstance(v, list) and len(v) <= 64 and all(
                    map(_is_text, v)),
                "found": _optional(_is_described), "returned": _is_described,
                "length": _optional(_is_int), "expected": _is_int, "got": _is_shape,
                "shapes": lambda v: isinstance(v, dict) and len(v) <= 64 and all(
                    _is_text(k) and (s is None or _is_shape(s)) for k, s in v.items())},
    "done": {"import_seconds": _is_seconds, "run_seconds": _is_seconds},
}
#: How many frames of each kind a box may send ("result": one per call, counted apart).
FRAME_COUNTS = {"uses-checker": 2, "imported": 1, "problem": 1, "done": 1}
#: Fields a problem frame must have.
PROBLEM_NEEDS = ("kind",)


def _reject_constant(name: str) -> float:
    raise ValueError(f"{name} is not a number the runner sends")


class FrameReader:
    """Parse the runner's frames against the declared outputs; raise :class:`Refused` otherwise.

    Bounded by what was declared, never by the bytes read: the channel may carry at most
    :attr:`budget` bytes (the declared outputs' bytes plus :data:`HEADER_ALLOWANCE` per call and
    :data:`CHANNEL_ALLOWANCE` for the rest), a header at most :data:`MAX_HEADER` bytes, each kind
    of frame at most :data:`FRAME_COUNTS` times; every header field must pass its test in
    :data:`FRAME_FIELDS` (type, size, range, nesting); a float beyond :data:`MAX_VALUE` in
    magnitude (finite, but its square or a sum of them overflows the checker's arithmetic) or an
    integer beyond 2^53 in a result is refused.  NaN and ±inf pass: they mean "not computed"
    and the checker reports them.  The parent holds at most one header plus one declared result
    of undecoded bytes at a time.
    """

    def __init__(self, calls: Sequence[Call]) -> None:
        self.calls = calls
        self.buf = bytearray()
        self.results: list[dict[str, np.ndarray]] = []
        self.events: list[dict] = []
        self.done = False
        self.problem: dict | None = None
        self.received = 0
        self.counts: dict[str, int] = {}
        self.budget = (sum(o.nbytes for c in calls for o in c.outputs)
                       + HEADER_ALLOWANCE * len(calls) + CHANNEL_ALLOWANCE)

    def feed(self, data: bytes) -> None:
        if self.done or self.problem is not None:
            if data:
                raise Refused("bytes after the last frame")
        self.received += len(data)
        if self.received > self.budget:
            raise Refused(f"more than {self.budget:,} bytes (the declared outputs and their "
                          f"headers need at most that)")
        self.buf += data
        while len(self.buf) >= 4:
            (n,) = struct.unpack(">I", self.buf[:4])
            if n > MAX_HEADER:
                raise Refused(f"a frame header of {n} bytes (at most {MAX_HEADER})")
            if len(self.buf) < 4 + n:
                return
            header = self._header(bytes(self.buf[4:4 + n]))
            kind = header["t"]
            size = 0
            if kind == "result":
                i = len(self.results)
                if header.get("call") != i or i >= len(self.calls):
                    raise Refused(f"a result for call {_shown(repr(header.get('call')), 40)} "
                                  f"where call {i} was expected ({len(self.calls)} declared)")
                size = sum(o.nbytes for o in self.calls[i].outputs)
            if len(self.buf) < 4 + n + size:
                return
            payload = bytes(self.buf[4 + n:4 + n + size])
            del self.buf[:4 + n + size]
            if kind == "result":
                self.results.append(self._arrays(payload, self.calls[len(self.results)]))
                if len(self.results) == 1:
                    self.events.append(header)  # what the first call returned, for notes
            else:
                self.events.append(header)
            if kind == "problem":
                self.problem = header
            elif kind == "done":
                if len(self.results) != len(self.calls):
                    raise Refused(f"'done' after {len(self.results)} of {len(self.calls)} "
                                  f"results")
                self.done = True
            if (self.done or self.problem is not None) and self.buf:
                raise Refused("bytes after the last frame")

    def _header(self, raw: bytes) -> dict:
        """The header, checked field by field against :data:`FRAME_FIELDS`."""
        try:
            header = json.loads(raw, parse_constant=_reject_constant)
        except RecursionError:
            raise Refused("a frame header nested too deep") from None
        except (UnicodeDecodeError, ValueError) as exc:
            raise Refused(f"a frame header that is not JSON ({_shown(str(exc), 80)})") from None
        if not isinstance(header, dict):
            raise Refused("a frame header that is not a JSON object")
        kind = header.get("t")
        if not isinstance(kind, str) or kind not in FRAME_FIELDS:
            raise Refused(f"a frame of unknown kind {_shown(repr(kind), 40)}")
        fields = FRAME_FIELDS[kind]
        if kind != "result":
            self.counts[kind] = self.counts.get(kind, 0) + 1
            if self.counts[kind] > FRAME_COUNTS[kind]:
                raise Refused(f"more than {FRAME_COUNTS[kind]} {kind!r} frame(s)")
        for key, value in header.items():
            if key == "t":
                continue
            test = fields.get(key)
            if test is None:
                raise Refused(f"a {kind!r} frame with an unknown field {_shown(repr(key), 40)}")
            if not test(value):
                raise Refused(f"a {kind!r} frame whose field {key!r} is not what the runner "
                              f"sends")
        if kind == "problem" and not all(k in header for k in PROBLEM_NEEDS):
            raise Refused("a 'problem' frame without its kind")
        return header

    @staticmethod
    def _arrays(payload: bytes, call: Call) -> dict[str, np.ndarray]:
        out, at = {}, 0
        for o in call.outputs:
            a = np.frombuffer(payload, dtype=o.dtype, count=o.nbytes // np.dtype(o.dtype).itemsize,
                              offset=at).reshape(o.shape).copy()
            at += o.nbytes
            if a.dtype.kind == "f":
                big = np.isfinite(a) & (np.abs(a) > MAX_VALUE)
            else:
                big = (a > 1 << 53) | (a < -(1 << 53)) if a.dtype.kind in "iu" else None
            if big is not None and big.any():
                raise Refused(f"{_shown(o.name, 40)} holding a value of magnitude "
                              f"{float(np.abs(a[big]).max()):.3g} (at most "
                              f"{MAX_VALUE if a.dtype.kind == 'f' else 2.0**53:g})")
            out[o.name] = a
        return out


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


@dataclass
class _Confinement:
    """What confines one box beyond its rlimits: the uid it runs as (root only), its cgroup, the
    mounts that reveal the interpreter to that uid."""

    uid: int | None = None
    cgroup: _cgroup.BoxCgroup | None = None
    reveal: list[tuple[str, list[str]]] = field(default_factory=list)
    lock: int | None = None  # held while the uid is this box's

    @property
    def limit_backend(self) -> str:
        return self.cgroup.kind if self.cgroup is not None else "rlimit"

    def pids(self) -> set[int]:
        """Every process of the box this confinement can name (its cgroup, its uid)."""
        out = self.cgroup.pids() if self.cgroup is not None else set()
        if self.uid is not None:
            out |= _boxuser.uid_pids(self.uid)
        return out


def _confine(limits: Limits, backend: str, needed: list[str]) -> _Confinement:
    """A cgroup and (as root) a uid of its own for a new box; whatever an earlier box of the same
    uid left running is killed first."""
    c = _Confinement()
    extra = 2 if backend == "bwrap" else 0  # bwrap's own two processes
    if sys.platform.startswith("linux"):
        c.cgroup = _cgroup.create(limits.memory, limits.processes + 1 + extra)
        got = _boxuser.acquire()
        if got is not None:
            c.uid, c.lock = got
    if c.uid is not None:
        _boxuser.kill_uid(c.uid)
        c.reveal = _boxuser.reveal(needed)
    return c


def _preexec(limits: Limits, nproc: int, drop_caps: bool, cap_last: int,
             confinement: _Confinement | None = None) -> None:
    """In the child, before exec: join the box's cgroup, limits, no core files; as root also the
    mounts revealing the interpreter, an empty capability bounding set, the box's uid, no new
    privileges (runs after fork; everything it calls was looked up before the fork)."""
    c = confinement or _Confinement()
    if c.cgroup is not None:
        for f in c.cgroup.procs_files:
            fd = os.open(f, os.O_WRONLY)
            try:
                os.write(fd, b"0")
            finally:
                os.close(fd)
    cpu = int(limits.time) + 2
    for res, value in ((resource.RLIMIT_AS, limits.memory), (resource.RLIMIT_CPU, cpu),
                       (resource.RLIMIT_FSIZE, limits.file_size),
                       (resource.RLIMIT_NPROC, nproc),
                       (resource.RLIMIT_NOFILE, limits.open_files),
                       (resource.RLIMIT_CORE, 0)):
        resource.setrlimit(res, (value, value))
    if c.reveal:
        libc = _libc()
        if libc is None:
            raise OSError("the box's reveal needs Linux's libc")
        _boxuser.apply_reveal(libc, c.reveal)
    if drop_caps:  # root: after exec the permitted set is the bounding set, so empty it
        for cap in range(cap_last + 1):
            _prctl(PR_CAPBSET_DROP, cap)
    if c.uid is not None:
        os.setgroups([])
        os.setresgid(c.uid, c.uid, c.uid)
        os.setresuid(c.uid, c.uid, c.uid)
    _prctl(PR_SET_PDEATHSIG, signal.SIGKILL)  # after the uid: a change of uid clears it
    if drop_caps:
        _prctl(PR_SET_NO_NEW_PRIVS, 1)


def _proc_table() -> dict[int, tuple[int, str, str]]:
    """pid -> (ppid, state, comm) of every process visible in /proc (``ps`` where there is no
    /proc)."""
    table: dict[int, tuple[int, str, str]] = {}
    if not os.path.isdir("/proc/self"):
        ps = subprocess.run(["ps", "-A", "-o", "pid=,ppid=,stat=,comm="], capture_output=True,
                            text=True, check=True).stdout
        for line in ps.splitlines():
            pid, ppid, stat, *words = line.split()
            table[int(pid)] = (int(ppid), stat[0], " ".join(words))
        return table
    for entry in os.scandir("/proc"):
        if not entry.name.isdigit():
            continue
        try:
            with open(f"/proc/{entry.name}/stat", "rb") as f:
                raw = f.read()
        except OSError:
            continue
        close = raw.rfind(b")")
        rest = raw[close + 2:].split()
        if close < 0 or len(rest) < 2:
            continue  # the process went away while it was read
        comm = raw[raw.find(b"(") + 1:close].decode(errors="replace")
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


def _kill_box(proc: subprocess.Popen, before: set[int],
              confinement: _Confinement | None = None) -> int:
    """SIGKILL every process of the box (its process tree, its cgroup, its uid) until none is
    alive; reap them.  Returns how many processes (bwrap's own not counted) were alive when the
    kill began."""
    found: int | None = None
    for _ in range(200):
        alive = set(box_processes(proc.pid, before))
        if confinement is not None:
            alive |= confinement.pids()
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
    np.savez(control / "inputs.npz", **arrays)  # type: ignore[arg-type]  # numpy's stub
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
                   result_fd: int, go_fd: int | None = None) -> tuple[list[str], list[int]]:
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
        cmd.extend(_hide_answers(tmp, bound))
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
    cmd.extend(["--chdir", "/box", "--", exe_py, "-I", "-S", "-B", "/control/_runner.py",
                "/control", "/box", str(result_fd)] + ([] if go_fd is None else [str(go_fd)]))
    return cmd, fds


def _hide_answers(tmp: Path, bound: list[str]) -> list[str]:
    """bwrap arguments binding an empty read-only folder over :data:`HIDDEN_WITH_GPSACCEL` in
    every copy of the package the box can see (this one, an installed one in site-packages)."""
    empty = tmp / "empty"
    args: list[str] = []
    for pkg in dict.fromkeys([str(PACKAGE_DIR), *_blocked_dirs()]):
        for rel in HIDDEN_WITH_GPSACCEL:
            real = os.path.realpath(os.path.join(pkg, rel))
            # only what the box sees (a lessons link to a folder outside the binds is not there)
            if os.path.isdir(real) and any(real.startswith(b + "/") for b in bound) \
                    and real not in args:
                args.extend(["--ro-bind", str(empty), real])
    if args:
        empty.mkdir(mode=0o555, exist_ok=True)
    return args


def _open_checked(sub: Submission, rel: str) -> int:
    """A file of the submission, opened for the box: still a regular file with one name, not
    reached through a link (it may have changed since :func:`load_submission` looked)."""
    path = sub.root / rel
    if os.path.realpath(path) != str(path):
        raise SubmissionError("link-refused", f"{_shown(rel)} is reached through a link.")
    fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    st = os.fstat(fd)
    if not stat.S_ISREG(st.st_mode) or st.st_nlink > 1:
        os.close(fd)
        raise SubmissionError("link-refused", f"{_shown(rel)} is not a regular file of its own "
                              f"(a hard link, or replaced since it was read).")
    return fd


def _copy_submission(sub: Submission, box: Path, uid: int | None = None) -> None:
    for rel in sub.files:
        dest = box / rel
        dest.parent.mkdir(parents=True, exist_ok=True)
        fd = _open_checked(sub, rel)
        with open(fd, "rb") as src, open(dest, "wb") as out:
            shutil.copyfileobj(src, out)
    if uid is not None:  # the box's user owns its working folder, nothing else
        for d, dirs, files in os.walk(box):
            for name in (d, *(os.path.join(d, f) for f in dirs + files)):
                os.chown(name, uid, uid, follow_symlinks=False)


#: Where box folders are made: a ``gpsaccel-box-<pid>-*`` folder whose process is dead (a worker
#: killed mid-check) is removed by the next box or by :func:`sweep_stale_boxes`.
BOX_PREFIX = "gpsaccel-box-"


def sweep_stale_boxes(parent: str | None = None) -> int:
    """Remove the box folders (and box cgroups) whose supervising process is dead; how many."""
    parent = parent or tempfile.gettempdir()
    n = 0
    try:
        entries = list(os.scandir(parent))
    except OSError:
        return 0
    for e in entries:
        if not e.name.startswith(BOX_PREFIX):
            continue
        owner = e.name[len(BOX_PREFIX):].split("-", 1)[0]
        if owner.isdigit() and not _cgroup._alive(int(owner)):
            _remove_tree(e.path)
            n += 1
    return n


def _remove_tree(path: str) -> None:
    """rmtree that also removes what a student made unreadable (chmod 000 folders)."""
    def retry(func, p, _exc):  # noqa: ANN001
        try:
            os.chmod(os.path.dirname(p), 0o700)
            os.chmod(p, 0o700)
        except OSError:
            pass
        try:
            func(p)
        except OSError:
            pass

    shutil.rmtree(path, onerror=retry)


# ----------------------------------------------------------------------------------- run
def run(sub: Submission, calls: Sequence[Call], limits: Limits = Limits(),
        backend: str = "auto", allow_gpsaccel: bool = False) -> BoxResult:
    """Run ``calls`` on the submission in a new box; return only once every process it started
    is dead, its cgroup removed and its folder deleted.  Never raises for anything the
    submission does (ValueError for bad arguments)."""
    backend = resolve_backend(backend)
    calls = list(calls)
    t0 = time.perf_counter()
    sweep_stale_boxes()
    tmp = Path(tempfile.mkdtemp(prefix=f"{BOX_PREFIX}{os.getpid()}-"))
    sys_path = _site_dirs()
    if allow_gpsaccel:
        sys_path.insert(0, str(PACKAGE_DIR.parent))
    needed = [sys.base_prefix, sys.prefix, sys.exec_prefix, *sys_path, str(tmp),
              os.path.dirname(_python()), os.path.dirname(os.path.realpath(_python()))]
    confinement = None
    owned: list[int] = []
    try:
        _write_control(tmp / "control", sub, calls, sys_path, allow_gpsaccel)
        confinement = _confine(limits, backend, needed)
        if confinement.uid is not None:
            tmp.chmod(0o711)  # the box's user enters it, lists nothing
        res_r, res_w = os.pipe()
        out_r, out_w = os.pipe()
        go_r, go_w = os.pipe()
        owned += [res_r, res_w, out_r, out_w, go_r, go_w]  # closed once, here or in _supervise
        fds: list[int] = []
        try:
            if backend == "bwrap":
                exe = bwrap_path()
                if exe is None:
                    raise OSError("bwrap was found usable for this check but its trial box no "
                                  "longer starts")
                cmd, fds = _bwrap_command(exe, tmp, sub, limits, allow_gpsaccel, res_w,
                                          go_r)
                owned += fds
                cwd, env = str(tmp), _environment("/box")
                # root without a box user: bwrap's user namespace is the box (no capability
                # outside it); with one, bwrap runs as that user and needs none either
                drop = confinement.uid is not None
            else:
                box = tmp / "box"
                box.mkdir()
                _copy_submission(sub, box, confinement.uid)
                cmd = [_python(), "-I", "-S", "-B", str(tmp / "control" / "_runner.py"),
                       str(tmp / "control"), str(box), str(res_w), str(go_r)]
                cwd, env, drop = str(box), _environment(str(box)), os.geteuid() == 0
        except SubmissionError as exc:  # a file changed into a link since it was loaded
            return BoxResult(backend, failure=exc.code, detail=str(exc),
                             seconds=time.perf_counter() - t0)
        return _supervise(backend, cmd, cwd, env, drop, limits, calls, res_r, out_r,
                          [res_w, out_w, go_r, *fds], owned, t0, confinement, go_w)
    finally:
        for fd in owned:
            try:
                os.close(fd)
            except OSError:
                pass
        if confinement is not None:
            if confinement.uid is not None:
                _boxuser.kill_uid(confinement.uid)
                _boxuser.remove_files(confinement.uid)
            if confinement.cgroup is not None:
                confinement.cgroup.remove()
            if confinement.lock is not None:
                _boxuser.release(confinement.lock)
        _remove_tree(str(tmp))


def _runner_pid(pids: set[int], table: dict[int, tuple[int, str, str]]) -> int | None:
    """The runner among a box's processes: the first started that is not bwrap's own."""
    best = None
    for pid in pids:
        if table.get(pid, (0, "", "bwrap"))[2] == "bwrap":
            continue
        try:
            with open(f"/proc/{pid}/stat", "rb") as f:
                start = int(f.read().rsplit(b")", 1)[1].split()[19])
        except (OSError, ValueError, IndexError):
            continue
        if best is None or start < best[0]:
            best = (start, pid)
    return None if best is None else best[1]


def _left_behind(proc: subprocess.Popen, before: set[int], c: _Confinement) -> int:
    """Processes of the box besides bwrap's and the runner, while the runner waits to exit."""
    pids = set(box_processes(proc.pid, before)) | c.pids()
    table = _proc_table()
    runner = proc.pid if table.get(proc.pid, (0, "", ""))[2] != "bwrap" else \
        _runner_pid(pids, table)
    return sum(1 for p in pids if p != runner and table.get(p, (0, "", "bwrap"))[2] != "bwrap")


def _supervise(backend: str, cmd: list[str], cwd: str, env: dict, drop_caps: bool,
               limits: Limits, calls: list[Call], res_r: int, out_r: int,
               child_fds: list[int], owned: list[int], t0: float,
               confinement: _Confinement | None = None, go_w: int | None = None) -> BoxResult:
    c = confinement or _Confinement()
    result = BoxResult(backend, limit_backend=c.limit_backend, box_user=c.uid)
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
    left: int | None = None
    extra = 2 if backend == "bwrap" else 0
    # a box uid runs nothing else: RLIMIT_NPROC counts the box exactly; with a cgroup it is set
    # a little above pids.max, so that the cgroup refuses the fork first and counts it
    nproc = _nproc(limits) if c.uid is None else \
        limits.processes + 1 + extra + (8 if c.cgroup is not None else 0)
    try:
        res_w, out_w = child_fds[:2]
        proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=out_w, stderr=out_w,
                                cwd=cwd, env=env, pass_fds=(res_w, *child_fds[2:]), close_fds=True,
                                start_new_session=True,
                                preexec_fn=functools.partial(_preexec, limits, nproc, drop_caps,
                                                             _cap_last(), c))
        for fd in child_fds:  # the parent keeps only the reading ends
            os.close(fd)
            owned.remove(fd)
        deadline = time.monotonic() + limits.time
        sel = selectors.DefaultSelector()
        sel.register(res_r, selectors.EVENT_READ, "res")
        sel.register(out_r, selectors.EVENT_READ, "out")
        open_pipes = 2
        exited_at = None
        # a count of the box's processes is needed only where nothing else binds them: root's
        # processes are not counted by RLIMIT_NPROC, and there is neither a cgroup nor a box uid
        count = (os.getuid() == 0 or not sys.platform.startswith("linux")) and \
            c.cgroup is None and c.uid is None
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
                elif not hit:
                    try:
                        reader.feed(data)
                    except Refused as exc:
                        refused = str(exc)
                        hit = "result-refused"
            if hit:
                break
            if left is None and (reader.done or reader.problem is not None) and go_w is not None:
                # the runner said its last word and waits: what else runs, the student left
                left = _left_behind(proc, before, c)
                os.close(go_w)
                owned.remove(go_w)
                go_w = None
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
                if n - extra > limits.processes:
                    hit = "process-limit"
                    break
        # the runner is still alive when the box's first process is (basic) or when anything
        # is (bwrap: the PID namespace ends with the runner); what else lived, the student left
        runner_alive = proc.poll() is None
        found = _kill_box(proc, before, c)
        emptied = True
        if left is not None:
            result.killed = left
        else:
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
                else:
                    break  # refused already: the rest is not read
        result.returncode = proc.returncode
        if c.cgroup is not None:
            result.memory_peak = c.cgroup.memory_peak()
            if not hit and c.cgroup.memory_killed():
                hit = "memory-limit"
            elif not hit and c.cgroup.fork_refused():
                hit = "process-limit"
    finally:
        if proc is not None and not emptied:  # Ctrl-C or an error of ours: the box goes too
            _kill_box(proc, before, c)
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
    if hit == "memory-limit":
        return hit, (f"the box's processes together used more than {limits.memory:,} bytes "
                     f"(memory, tmpfs files and memfds, counted by its {result.limit_backend})")
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
