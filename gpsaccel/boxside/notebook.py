"""A graded notebook inside the box: the import guard, what IPython's lines and ``import otter`` find
there, the cell runner and the reads the grader makes.

The grader (:mod:`gpsaccel.assignments.notebook`) writes each notebook as one Python file the
sandbox's runner imports, data and calls of this module only::

    from gpsaccel.boxside import notebook as _gpsaccel_box
    _gpsaccel_box.guard(('gpsaccel.check', 'gpsaccel.assignments', ...))
    _gpsaccel_cell, _gpsaccel_probe, _gpsaccel_reads = _gpsaccel_box.start(
        globals(), [(3, "x = 1\\n"), ...], [("kalman_filter", False, [(151, 3)]), ...])

Nothing runs at import.  The runner calls ``_gpsaccel_cell(i)`` once per cell, in order, so each
cell's outcome comes back as its own frame (a cell that raises is recorded and the next one runs,
as ``otter run`` does); after the last cell, and after each cell that completes an answer, it
makes the reads the grader placed there (:mod:`gpsaccel.assignments.snapshots`; the same read
may be made several times): ``_gpsaccel_probe(k, *args)`` calls the student's function (or reads
the variable) and returns ``(status, message, *outputs)`` as arrays of the shapes the grader
declared; ``_gpsaccel_reads(ks, nargs, *args)`` makes several reads of one function at once and
returns them stacked, one frame for all (a frame costs more than a read of a small function).
None of them ever raises (``BaseException`` included), so one broken answer does not stop the
runner's later calls.  The cells run in the notebook module's own namespace (its
``globals()``), as they did in the student's kernel.
"""

from __future__ import annotations

import sys
import traceback
import types
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

#: Bytes of a message (a cell's notes, an exception's text) sent back.
MESSAGE_BYTES = 320

#: Status codes a read returns (index = code), named as the checkers name them.
STATUSES = ("ok", "not-defined", "not-callable", "exception", "returns-none", "return-value",
            "not-a-matrix", "shape")

#: Longest shape a read reports (ndim and the sizes).
MAX_NDIM = 6

#: Length of the status array: the code, which output, the ndim and the sizes of its shape.
STATUS_LENGTH = 1 + MAX_NDIM + 2

#: One read: the name in the notebook, whether it is a value (else a function to call), the
#: shapes of what it must give.
Read = tuple[str, bool, Sequence[Sequence[int]]]

Outputs = tuple[np.ndarray, ...]


def guard(hidden: Sequence[str]) -> None:
    """Refuse imports of the modules ``hidden`` (and below them) from here on: an audit hook,
    which Python code cannot remove.  It words the refusal; the sandbox's file-system fence is
    what keeps the hidden folders' files out of reach, whatever the code calls."""
    names = tuple(hidden)

    def hook(event: str, args: tuple) -> None:
        if event == "import" and args and isinstance(args[0], str):
            if any(args[0] == n or args[0].startswith(n + ".") for n in names):
                raise ImportError(args[0] + " is not available while a notebook is graded")

    sys.addaudithook(hook)


class Shell:
    """What the notebook's IPython lines (``get_ipython().run_line_magic(...)``, as IPython's
    transformer writes them) find in the box instead of a kernel: ``%%time``, ``%%capture``
    and ``%time`` run their code, ``%%writefile`` writes into the box; every other magic and
    every shell line is not run and is listed (:attr:`skipped`) for the student's feedback."""

    def __init__(self, namespace: dict[str, Any]) -> None:
        self.namespace = namespace
        self.skipped: list[str] = []

    def run_line_magic(self, name: str, line: str, _stack_depth: int = 1) -> Any:
        if name in ("time", "timeit") and line.strip():
            try:
                return eval(compile(line, "<magic>", "eval"), self.namespace)  # noqa: S307
            except SyntaxError:
                exec(compile(line, "<magic>", "exec"), self.namespace)  # noqa: S102
                return None
        self.skipped.append("%" + name)
        return None

    def run_cell_magic(self, name: str, line: str, cell: str) -> None:
        if name in ("time", "timeit", "capture"):
            exec(compile(cell, "<magic>", "exec"), self.namespace)  # noqa: S102
        elif name == "writefile" and line.split():
            args = line.split()
            append = "-a" in args[:-1] or "--append" in args[:-1]  # IPython's two spellings
            with open(args[-1], "a" if append else "w", encoding="utf-8") as f:
                f.write(cell)
        else:
            self.skipped.append("%%" + name)

    def system(self, cmd: str) -> int:
        self.skipped.append("!" + cmd.split()[0] if cmd.split() else "!")
        return 0

    def getoutput(self, cmd: str) -> list[str]:
        self.system(cmd)
        return []

    def run_cell(self, *args: object, **kwargs: object) -> None:
        self.skipped.append("run_cell")

    def __getattr__(self, name: str) -> Callable[..., None]:
        return lambda *args, **kwargs: None


class _OtterNotebook:
    """``otter.Notebook``: its checks do nothing (module docstring of :func:`install_otter`)."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        pass

    def __getattr__(self, name: str) -> Callable[..., None]:
        return lambda *args, **kwargs: None


def install_otter() -> None:
    """What ``import otter`` finds in the box: a Notebook whose checks do nothing.  otter's init
    and ``grader.check`` cells are for the student's kernel (the grade is computed outside the
    box); the real otter would import IPython, nbformat and jsonschema in every notebook's box
    (benchmarks/startup.py measures ``import nbformat``)."""
    otter = types.ModuleType("otter")
    otter.Notebook = _OtterNotebook  # type: ignore[attr-defined]  # a module made here
    sys.modules["otter"] = otter


def text(message: object) -> np.ndarray:
    """``message`` as :data:`MESSAGE_BYTES` bytes of UTF-8, cut and padded with zeros."""
    data = str(message).encode("utf-8", "replace")[:MESSAGE_BYTES]
    out = np.zeros(MESSAGE_BYTES, dtype=np.uint8)
    out[:len(data)] = np.frombuffer(data, dtype=np.uint8)
    return out


def error(exc: BaseException) -> str:
    """``cell N, line L: Type: message`` of the innermost frame in a student's cell."""
    lines = traceback.format_exception_only(type(exc), exc)
    where = ""
    tb = exc.__traceback__
    while tb is not None:
        if tb.tb_frame.f_code.co_filename.startswith("<cell "):
            where = tb.tb_frame.f_code.co_filename[1:-1] + ", line " + str(tb.tb_lineno) + ": "
        tb = tb.tb_next
    return where + (lines[-1].strip() if lines else type(exc).__name__)


class GradedNotebook:
    """The cells to run and the reads to make, in the notebook's namespace."""

    def __init__(self, namespace: dict[str, Any], cells: Sequence[tuple[int, str]],
                 reads: Sequence[Read]) -> None:
        self.namespace = namespace
        self.cells = list(cells)
        self.reads = list(reads)
        self.shell = Shell(namespace)

    def cell(self, i: object) -> Outputs:
        """Run cell ``i``: (status, message): the status code ``exception`` and the student's
        error, or ok and the lines skipped so far."""
        status = np.zeros(STATUS_LENGTH, dtype=np.int64)
        try:
            number, source = self.cells[int(i)]  # type: ignore[call-overload]  # an array
            exec(compile(source, f"<cell {number}>", "exec"), self.namespace)  # noqa: S102
            return status, text(" ".join(self.shell.skipped))
        except BaseException as exc:  # noqa: BLE001 - the student's cell may raise anything
            status[0] = STATUSES.index("exception")
            return status, text(error(exc))

    def probe(self, k: object, *args: np.ndarray) -> Outputs:
        """(status, message, *outputs) of read ``k``: calling (or reading) the student's name."""
        name, value_only, shapes = self.reads[int(k)]  # type: ignore[call-overload]  # an array
        status = np.zeros(STATUS_LENGTH, dtype=np.int64)
        blank = [np.full(tuple(s), np.nan) for s in shapes]

        def fail(code: str, message: str = "", which: int = -1,
                 shape: tuple[int, ...] | None = None) -> Outputs:
            status[0] = STATUSES.index(code)
            status[1] = which
            if shape is not None:
                status[2] = min(len(shape), MAX_NDIM)
                status[3:3 + status[2]] = shape[:MAX_NDIM]
            return (status, text(message), *blank)

        try:
            return self._read(name, value_only, shapes, args, fail)
        except BaseException as exc:  # noqa: BLE001 - the student's function may raise anything
            return fail("exception", error(exc))

    def batch(self, ks: object, nargs: object, *args: np.ndarray) -> Outputs:
        """Reads ``ks`` at once (reads of one name and the same shapes, ``nargs[j]`` of
        ``args`` for the j-th): their statuses, messages and outputs, each stacked along a first
        axis, so that they come back as one frame."""
        try:
            out, at = [], 0
            for k, n in zip(np.ravel(ks), np.ravel(nargs), strict=True):  # type: ignore[call-overload]
                out.append(self.probe(k, *args[at:at + int(n)]))
                at += int(n)
            return tuple(np.stack(parts) for parts in zip(*out, strict=True))
        except BaseException as exc:  # noqa: BLE001 - never raises (a MemoryError stacking them)
            name, _, shapes = self.reads[int(np.ravel(ks)[0])]  # type: ignore[call-overload]
            n = np.size(ks)  # type: ignore[arg-type]
            status = np.zeros((n, STATUS_LENGTH), dtype=np.int64)
            status[:, 0] = STATUSES.index("exception")
            return (status, np.tile(text(error(exc)), (n, 1)),
                    *[np.full((n, *s), np.nan) for s in shapes])

    def _read(self, name: str, value_only: bool, shapes: Sequence[Sequence[int]],
              args: tuple[np.ndarray, ...], fail: Callable[..., Outputs]) -> Outputs:
        target = self.namespace.get(name, None)
        if target is None or target is Ellipsis:
            return fail("not-defined")
        if value_only:
            out = target
        else:
            if not callable(target):
                return fail("not-callable", type(target).__name__)
            out = target(*[a.copy() for a in args])
        if out is None:
            return fail("returns-none")
        values = [out] if len(shapes) == 1 else out
        if len(shapes) > 1 and (not isinstance(out, (tuple, list)) or len(out) != len(shapes)):
            return fail("return-value", type(out).__name__ + (
                " of length " + str(len(out)) if isinstance(out, (tuple, list)) else ""))
        arrays = []
        for j, (v, s) in enumerate(zip(values, shapes, strict=False)):
            try:
                a = np.array(v, dtype=float)
            except BaseException as exc:  # noqa: BLE001
                return fail("not-a-matrix", error(exc), j)
            if a.shape != tuple(s):
                return fail("shape", "", j, a.shape)
            arrays.append(a)
        return (np.zeros(STATUS_LENGTH, dtype=np.int64), text(""), *arrays)


def start(namespace: dict[str, Any], cells: Sequence[tuple[int, str]], reads: Sequence[Read]
          ) -> tuple[Callable[[object], Outputs], Callable[..., Outputs], Callable[..., Outputs]]:
    """Make the notebook's namespace a kernel's (``get_ipython``, ``import otter``); the cell
    runner, the read and the reads at once (:meth:`GradedNotebook.batch`) the runner calls."""
    nb = GradedNotebook(namespace, cells, reads)
    install_otter()
    namespace["get_ipython"] = lambda: nb.shell
    return nb.cell, nb.probe, nb.batch
