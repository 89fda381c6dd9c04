"""What a box is asked to run and what comes back: :class:`Limits`, :class:`Call` of the
submission's functions with their declared :class:`Output` arrays, and the :class:`BoxResult`."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Limits:
    """What one box may use.

    memory : bytes (default 1 GiB): the whole box's memory where a cgroup applies (every
        process, tmpfs file and memfd together), and the address space of each process
        (RLIMIT_AS) everywhere.
    time : limit of the whole box (import and every call), s: the time its code ran or waited
        for itself, not the time it waited for a CPU on a busy machine (Linux; elsewhere
        wall-clock; :mod:`gpsaccel.sandbox.clock`).
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
    """One array a call must return: its name (for messages), shape and dtype.

    ``column``: a trailing axis of length 1 is accepted too (filterpy keeps a state as a column,
    ``kf.x``: a student who stores it returns ``shape + (1,)``); the box drops that axis before
    sending, so what comes back is still exactly ``shape``, and the returned shape it reports
    says it was a column."""

    name: str
    shape: tuple[int, ...]
    dtype: str = "float64"
    column: bool = False

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
    forked : the call during which the student's code first forked the runner (``os.fork()``,
        ``multiprocessing``; -1: while its file was imported), or None.  The copy a fork makes
        never sends a frame (it ends where it would: :mod:`gpsaccel.sandbox._runner`), so the
        results are the runner's own; this is for the feedback.
    limit_backend : what enforced the box's memory and process limits: ``"cgroup2"`` or
        ``"cgroup1"`` (one cgroup for the whole box: every process, tmpfs file and memfd counted
        together) or ``"rlimit"`` (per process only; see :mod:`gpsaccel.sandbox._cgroup`).
    box_user : the uid the student ran as when the checker is root (a uid of its own, see
        :mod:`gpsaccel.sandbox._boxuser`), else None (the checker's own user).
    memory_peak : the box's peak memory (bytes) when a cgroup measured it.
    waited : seconds the runner waited for a CPU on a busy machine (not counted in the time
        limit), or None where the box's clock is wall-clock.
    started : ``"cold"`` (the runner started by exec) or ``"warm"`` (forked from a zygote that
        had imported what the box imports: :mod:`gpsaccel.sandbox.zygote`).
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
    forked: int | None = None
    limit_backend: str = "rlimit"
    box_user: int | None = None
    memory_peak: int | None = None
    waited: float | None = None
    started: str = "cold"
