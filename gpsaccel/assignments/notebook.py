r"""A student's notebook as a module the checker's sandbox can load (never executed here).

Grading runs a notebook only inside :mod:`gpsaccel.sandbox`.  Instead of a Jupyter kernel in
the box (a kernel costs 1-2 s to start, a ZeroMQ session and a second process), the notebook is
turned into one Python file, ``notebook.py``, that the sandbox's runner imports like any ``.py``
submission:

* the code cells, in order, as string literals (``repr``: the student's text cannot close them),
  each compiled with the file name ``<cell N>`` (N = the cell's 1-based number among *all* cells,
  as Jupyter shows them when counted from the top), so a traceback names the student's cell;
* IPython syntax handled explicitly, outside the box, by IPython's own input transformer
  (:class:`IPython.core.inputtransformer2.TransformerManager`: ``%magic``, ``%%cell magic``,
  ``!shell``, ``x?``).  The notebook is parsed and transformed by :func:`load` in a forked
  process of its own under hard limits (:data:`LOAD_CPU` seconds of CPU, :data:`LOAD_MEMORY`
  more bytes of address space; the file at most :data:`MAX_NOTEBOOK_BYTES`): the transformer is
  quadratic on some input (a 9 KB cell of line magics took 31 CPU s, a 0.8 MB cell 356 MB) and
  ``json`` recurses on nested lists, so what cannot be read within them is the student's
  ``unreadable``, never the grader's error.  In the box a small ``get_ipython()`` stands in for
  the kernel: ``%%time``, ``%%capture``, ``%time`` run their code; ``%%writefile`` writes into
  the box; every other magic and every shell line is *not run* and is listed in the student's
  feedback;
* nothing runs at import.  The grader calls ``_gpsaccel_cell(i)`` once per cell, in order, so each
  cell's outcome comes back as its own frame: a cell that raises is recorded and the next one runs
  (as ``otter run`` does), a cell that loops or kills its process is named by the frames that
  did *not* come back;
* one wrapper per thing a question reads (``_gpsaccel_probe_K``): it calls the student's function
  (or reads the variable) and returns ``(status, message, *outputs)`` as arrays of the shapes the
  grader declared; a wrapper never raises (``BaseException`` included), so one broken answer does
  not stop the runner's later calls.

The wrappers and the guard below are *not* trusted for anything but convenience: the student's
code runs in the same interpreter and may replace them; all it can achieve is to send back other
arrays of the declared shapes for its own answers, which the grader checks outside the box.

The guard (the module's first statement) is an audit hook that refuses imports of
:data:`HIDDEN_PACKAGES` (the checker and the homework's checks) and opening or listing files under
their folders; audit hooks cannot be removed from Python code.  It is a fence for honest code,
not the security boundary: that is the sandbox (nothing secret is in the box at all).
"""

from __future__ import annotations

import inspect
import json
import os
import resource
import select
import signal
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gpsaccel.sandbox import path_test

#: Sub-packages of gpsaccel a notebook may not import in the box (checks, reference answers).
HIDDEN_PACKAGES = ("gpsaccel.check", "gpsaccel.assignments")

#: Largest notebook file read (bytes).
MAX_NOTEBOOK_BYTES = 16 << 20

#: CPU seconds and extra address space (bytes) of the process that parses and transforms one
#: notebook (:func:`load`): an honest notebook needs well under 0.1 s and 50 MB.
LOAD_CPU = 5
LOAD_MEMORY = 256 << 20
#: Wall-clock seconds after which that process is killed whatever its CPU time: only a guard
#: (it reads one file and computes), generous because a loaded machine gives it a small share.
LOAD_WALL = 120

#: Bytes of a message (exception text) a wrapper sends back.
MESSAGE_BYTES = 320

#: Status codes a wrapper returns (index = code), named as the checkers name them.
STATUSES = ("ok", "not-defined", "not-callable", "exception", "returns-none", "return-value",
            "not-a-matrix", "shape")

#: Longest shape a wrapper reports (ndim and the sizes).
MAX_NDIM = 6


class NotebookError(ValueError):
    """The file is not a notebook that can be graded; the message is for the student."""


@dataclass(frozen=True)
class Cell:
    """One code cell: its number among all cells (1-based), its source and, once
    :func:`load` has transformed it, the plain Python it runs as."""

    number: int
    source: str
    python: str | None = None


@dataclass
class Notebook:
    """The code of a notebook: its code cells and what was done to IPython syntax."""

    cells: list[Cell]
    notes: list[str] = field(default_factory=list)

    def writefile(self, name: str) -> tuple[Cell, str] | None:
        """The last cell that starts ``%%writefile NAME`` and its body (read as text, never run)."""
        found = None
        for cell in self.cells:
            head, _, body = cell.source.lstrip().partition("\n")
            parts = head.split()
            if len(parts) >= 2 and parts[0] == "%%writefile" and parts[-1] == name:
                found = (cell, body)
        return found


def read(path: str | Path) -> Notebook:
    """The code cells of the notebook at ``path`` (NotebookError when it is not one)."""
    path = Path(path)
    try:
        size = path.stat().st_size
    except OSError as exc:
        raise NotebookError(f"cannot read {path.name}: {exc.strerror}") from None
    if size > MAX_NOTEBOOK_BYTES:
        raise NotebookError(f"{path.name} is larger than {MAX_NOTEBOOK_BYTES >> 20} MB: clear "
                            f"the outputs (Kernel > Restart & Clear Output) and save it again.")
    try:
        data = json.loads(path.read_bytes())
    except (ValueError, UnicodeDecodeError) as exc:
        raise NotebookError(f"{path.name} is not a notebook (not JSON: {exc}).") from None
    except RecursionError:
        raise NotebookError(f"{path.name} is not a notebook (its JSON is nested too deep to "
                            f"read).") from None
    cells = data.get("cells") if isinstance(data, dict) else None
    if not isinstance(cells, list):
        raise NotebookError(f"{path.name} is not a notebook (no list of cells).")
    out = []
    for i, cell in enumerate(cells, start=1):
        if not isinstance(cell, dict) or cell.get("cell_type") != "code":
            continue
        src = cell.get("source", "")
        if isinstance(src, list):
            src = "".join(s for s in src if isinstance(s, str))
        if isinstance(src, str) and src.strip():
            out.append(Cell(i, src))
    return Notebook(out)


def transform(source: str) -> str:
    """The cell's IPython syntax as plain Python calling ``get_ipython()`` (text to text)."""
    from IPython.core.inputtransformer2 import TransformerManager

    return TransformerManager().transform_cell(source)


def _python(source: str) -> str:
    try:
        return transform(source)
    except Exception:  # noqa: BLE001 - a cell IPython cannot parse stays as it is
        return source


def load(path: str | os.PathLike) -> Notebook:
    """:func:`read` and :func:`transform` every cell, in a forked process under :data:`LOAD_CPU`
    and :data:`LOAD_MEMORY` (module docstring); NotebookError for the student when it fails
    or runs past them."""
    import IPython.core.inputtransformer2  # noqa: F401 - imported before the fork, not in it

    path = Path(path)
    rfd, wfd = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: parse, transform, send JSON, exit without cleanup
        code = 0
        out: dict[str, Any] = {}
        try:
            os.close(rfd)
            signal.signal(signal.SIGINT, signal.SIG_IGN)
            _limit_self()
            nb = read(path)
            out = {"cells": [[c.number, c.source, _python(c.source)] for c in nb.cells]}
        except NotebookError as exc:
            out = {"error": str(exc)}
        except MemoryError:
            out = {"error": "memory"}
        except BaseException:  # noqa: BLE001 - anything else: the parent reports the exit
            code = 3
        try:
            sent = json.dumps(out).encode()
            while sent:
                sent = sent[os.write(wfd, sent):]
        finally:
            os._exit(code)
    os.close(wfd)
    return _loaded(path, _collect(rfd, pid))


def _limit_self() -> None:
    resource.setrlimit(resource.RLIMIT_CPU, (LOAD_CPU, LOAD_CPU))
    try:
        with open("/proc/self/statm") as f:
            now = int(f.read().split()[0]) * resource.getpagesize()
    except OSError:  # not Linux: the CPU limit alone
        return
    resource.setrlimit(resource.RLIMIT_AS, (now + LOAD_MEMORY, now + LOAD_MEMORY))


def _collect(rfd: int, pid: int) -> bytes | None:
    """What the child sent (None: it died, or was killed after :data:`LOAD_WALL` seconds)."""
    chunks: list[bytes] = []
    deadline = time.monotonic() + LOAD_WALL
    try:
        while True:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([rfd], [], [], left)[0]:
                os.kill(pid, signal.SIGKILL)
                break
            chunk = os.read(rfd, 1 << 20)
            if not chunk:
                break
            chunks.append(chunk)
    finally:
        os.close(rfd)
        _, status = os.waitpid(pid, 0)
    return b"".join(chunks) if os.waitstatus_to_exitcode(status) == 0 else None


def _loaded(path: Path, data: bytes | None) -> Notebook:
    out: dict[str, Any] = json.loads(data) if data else {"error": "killed"}
    if "cells" in out:
        return Notebook([Cell(n, src, py) for n, src, py in out["cells"]])
    why = {"memory": f"needed more than {LOAD_MEMORY >> 20} MB", "killed": f"took more than "
           f"{LOAD_CPU} CPU seconds or more than {LOAD_MEMORY >> 20} MB"}.get(out["error"])
    if why is None:
        raise NotebookError(out["error"])
    raise NotebookError(f"{path.name} could not be read: parsing it and its IPython lines "
                        f"(%, !) {why}. Remove the long runs of magics and save it again.")


#: The checker's path test (:func:`gpsaccel.sandbox.path_test`), as source for the box.
_PATH_TEST = inspect.getsource(path_test)

_PRELUDE = r'''
def _gpsaccel_guard(hidden, path_test):
    import sys, os, importlib.util
    spec = importlib.util.find_spec("gpsaccel")
    roots = list(spec.submodule_search_locations or []) if spec else []
    dirs = tuple(os.path.realpath(os.path.join(r, *h.split(".")[1:])) + os.sep
                 for r in roots for h in hidden)
    names = tuple(hidden)
    is_hidden = path_test(dirs)  # the checker's runner's path test (its source, above)

    def hook(event, args):
        if event == "import" and args and isinstance(args[0], str):
            if any(args[0] == n or args[0].startswith(n + ".") for n in names):
                raise ImportError(args[0] + " is not available while a notebook is graded")
        elif event in ("open", "os.listdir", "os.scandir", "os.chdir") and args \
                and is_hidden(args[0]):
            raise PermissionError("the grader's checks are not available while a notebook "
                                  "is graded")
    sys.addaudithook(hook)


_gpsaccel_guard(_G_HIDDEN, path_test)
del _gpsaccel_guard, path_test


class _GpsaccelShell:
    """What the notebook's IPython lines find in the box instead of a kernel."""

    def __init__(self):
        self.skipped = []

    def _ns(self):
        return globals()

    def run_line_magic(self, name, line, _stack_depth=1):
        if name in ("time", "timeit") and line.strip():
            try:
                return eval(compile(line, "<magic>", "eval"), self._ns())
            except SyntaxError:
                exec(compile(line, "<magic>", "exec"), self._ns())
                return None
        self.skipped.append("%" + name)
        return None

    def run_cell_magic(self, name, line, cell):
        if name in ("time", "timeit", "capture"):
            exec(compile(cell, "<magic>", "exec"), self._ns())
        elif name == "writefile" and line.split():
            args = line.split()
            with open(args[-1], "a" if "-a" in args[:-1] else "w", encoding="utf-8") as f:
                f.write(cell)
        else:
            self.skipped.append("%%" + name)

    def system(self, cmd):
        self.skipped.append("!" + cmd.split()[0] if cmd.split() else "!")
        return 0

    def getoutput(self, cmd):
        self.system(cmd)
        return []

    def run_cell(self, *a, **k):
        self.skipped.append("run_cell")

    def __getattr__(self, name):
        return lambda *a, **k: None


_gpsaccel_shell = _GpsaccelShell()


def get_ipython():
    return _gpsaccel_shell


def _gpsaccel_otter():
    """What ``import otter`` finds in the box: a Notebook whose checks do nothing.  otter's init
    and ``grader.check`` cells are for the student's kernel (the grade is computed outside the
    box); the real otter would cost 1.5-4.5 CPU s per notebook (IPython, nbformat, jsonschema)."""
    import sys, types

    class Notebook:
        def __init__(self, *args, **kwargs):
            pass

        def __getattr__(self, name):
            return lambda *args, **kwargs: None

    otter = types.ModuleType("otter")
    otter.Notebook = Notebook
    sys.modules["otter"] = otter


_gpsaccel_otter()
del _gpsaccel_otter


def _gpsaccel_text(text):
    import numpy as np
    data = str(text).encode("utf-8", "replace")[:_G_MESSAGE_BYTES]
    out = np.zeros(_G_MESSAGE_BYTES, dtype=np.uint8)
    out[:len(data)] = np.frombuffer(data, dtype=np.uint8)
    return out


def _gpsaccel_error(exc):
    import traceback
    lines = traceback.format_exception_only(type(exc), exc)
    where = ""
    tb = exc.__traceback__
    while tb is not None:
        if tb.tb_frame.f_code.co_filename.startswith("<cell "):
            where = tb.tb_frame.f_code.co_filename[1:-1] + ", line " + str(tb.tb_lineno) + ": "
        tb = tb.tb_next
    return where + (lines[-1].strip() if lines else type(exc).__name__)


def _gpsaccel_cell(i):
    import numpy as np
    status = np.zeros(1 + _G_MAX_NDIM + 2, dtype=np.int64)
    try:
        number, source = _G_CELLS[int(i)]
        exec(compile(source, "<cell " + str(number) + ">", "exec"), globals())
        return status, _gpsaccel_text(" ".join(_gpsaccel_shell.skipped))
    except BaseException as exc:  # noqa: BLE001 - the student's cell may raise anything
        status[0] = _G_STATUSES.index("exception")
        return status, _gpsaccel_text(_gpsaccel_error(exc))


def _gpsaccel_probe(name, value_only, args, shapes):
    """(status, message, *outputs) of calling (or reading) the student's ``name``."""
    import numpy
    status = numpy.zeros(1 + _G_MAX_NDIM + 2, dtype=numpy.int64)
    blank = [numpy.full(s, numpy.nan) for s in shapes]

    def fail(code, text="", which=-1, shape=None):
        status[0] = _G_STATUSES.index(code)
        status[1] = which
        if shape is not None:
            status[2] = min(len(shape), _G_MAX_NDIM)
            status[3:3 + status[2]] = shape[:_G_MAX_NDIM]
        return (status, _gpsaccel_text(text), *blank)

    try:
        target = globals().get(name, None)
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
        for k, (v, s) in enumerate(zip(values, shapes)):
            try:
                a = numpy.array(v, dtype=float)
            except BaseException as exc:  # noqa: BLE001
                return fail("not-a-matrix", _gpsaccel_error(exc), k)
            if a.shape != tuple(s):
                return fail("shape", "", k, a.shape)
            arrays.append(a)
        return (status, _gpsaccel_text(""), *arrays)
    except BaseException as exc:  # noqa: BLE001 - the student's function may raise anything
        return fail("exception", _gpsaccel_error(exc))
'''


@dataclass(frozen=True)
class Read:
    """One thing a question reads from the box: call ``name(*args)`` (or, with ``value``, read
    the variable ``name``), which must give ``shapes`` (one array, or a tuple of them)."""

    name: str
    args: tuple[np.ndarray, ...] = ()
    shapes: tuple[tuple[int, ...], ...] = ((),)
    value: bool = False


def module_source(nb: Notebook, reads: list[Read]) -> str:
    """The text of ``notebook.py`` for the sandbox: the prelude, the cells, one wrapper per read."""
    cells = [(c.number, c.python if c.python is not None else _python(c.source))
             for c in nb.cells]
    lines = ["# A student's notebook, rewritten by gpsaccel.assignments.notebook for the sandbox.",
             f"_G_HIDDEN = {HIDDEN_PACKAGES!r}",
             f"_G_MESSAGE_BYTES = {MESSAGE_BYTES}",
             f"_G_MAX_NDIM = {MAX_NDIM}",
             f"_G_STATUSES = {STATUSES!r}",
             _PATH_TEST,
             _PRELUDE,
             f"_G_CELLS = {cells!r}",
             ""]
    for k, r in enumerate(reads):
        if not r.name.isidentifier():
            raise ValueError(f"read name must be a Python name, got {r.name!r}")
        params = ", ".join(f"a{j}" for j in range(len(r.args)))
        lines += [f"def _gpsaccel_probe_{k}({params}):",
                  f"    return _gpsaccel_probe({r.name!r}, {r.value!r}, [{params}], "
                  f"{[tuple(s) for s in r.shapes]!r})", ""]
    return "\n".join(lines)
