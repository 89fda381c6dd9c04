r"""A student's notebook as a module the checker's sandbox can load (never executed here).

Grading runs a notebook only inside :mod:`gpsaccel.sandbox`.  Instead of a Jupyter kernel in
the box (a kernel's start-up, a ZeroMQ session and a second process, each notebook;
benchmarks/grading.py runs ``otter run`` beside the grader), the notebook is turned into one
Python file, ``notebook.py``, that the sandbox's runner imports like any ``.py``
submission (:func:`module_source`).  It holds data and calls of :mod:`gpsaccel.boxside.notebook`
only: the box-side code (the import guard, a stand-in ``get_ipython`` and ``otter``, the cell
runner and the reads), which lives where the box can import it and holds no secret.  It carries

* the code cells, in order, as string literals (``repr``: the student's text cannot close them),
  each compiled in the box with the file name ``<cell N>`` (N = the cell's 1-based number among
  *all* cells, as Jupyter shows them when counted from the top), so a traceback names the
  student's cell;
* IPython syntax handled explicitly, outside the box, by IPython's own input transformer
  (:class:`IPython.core.inputtransformer2.TransformerManager`: ``%magic``, ``%%cell magic``,
  ``!shell``, ``x?``).  The notebook is parsed and transformed by :func:`load` in a child process
  under hard limits (:func:`gpsaccel.sandbox.in_child`: :data:`LOAD_CPU` seconds of CPU,
  :data:`LOAD_MEMORY` more bytes of address space, :data:`LOAD_WALL` s of wall-clock time; the
  file at most :data:`MAX_NOTEBOOK_BYTES`): the transformer is quadratic in time and memory on
  some input (a cell of line magics: tests/assignments/test_hostile_class.py) and raises on
  other input, and
  ``json`` recurses on nested lists, so what cannot be read within them is the student's
  ``unreadable``, never the grader's error.  Whatever else parses a student's notebook (the
  similarity report) does it under the same limits;
* the reads the questions make (:class:`Read`), as data: name, value or function, shapes.

The box-side code is *not* trusted for anything but convenience: the student's code runs in the
same interpreter and may replace it; all it can achieve is to send back other arrays of the
declared shapes for its own answers, which the grader checks outside the box.  The folders of the
package the box may not read are :data:`gpsaccel.check.problem.BOX_HIDES` (the checks' list,
the same for a notebook's box): the sandbox keeps their files out of reach on every backend, and
the box's import guard words the refusal of their modules.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gpsaccel.boxside.notebook import MAX_NDIM, MESSAGE_BYTES, STATUS_LENGTH, STATUSES
from gpsaccel.check.problem import BOX_HIDES

__all__ = ["BOX_HIDES", "LOAD_CPU", "LOAD_MEMORY", "LOAD_WALL", "MAX_NDIM", "MAX_NOTEBOOK_BYTES",
           "MESSAGE_BYTES", "STATUSES", "STATUS_LENGTH", "Cell", "Notebook", "NotebookError",
           "Read", "load", "module_source", "read", "transform", "writefile_cell"]

#: Largest notebook file read (bytes).
MAX_NOTEBOOK_BYTES = 16 << 20

#: CPU seconds and extra address space (bytes) of the child that parses and transforms one
#: notebook (:func:`load`): an honest notebook needs a small fraction of both.
LOAD_CPU = 5
LOAD_MEMORY = 256 << 20
#: Wall-clock seconds after which that child is killed whatever its CPU time: only a guard
#: (it reads one file and computes), generous because a loaded machine gives it a small share.
LOAD_WALL = 120


class NotebookError(ValueError):
    """The file is not a notebook that can be graded; the message is for the student: what is
    wrong, in words, never a parser's position or bytes of the file (a notebook hard-linked to
    a file the student may not read would otherwise tell them about its first bytes)."""


#: What a student whose file is not a notebook does.
_SAVE_AGAIN = "Open your notebook in Jupyter, save it, and hand in the .ipynb file it saved."


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
        """The last cell that writes ``NAME`` with ``%%writefile`` and the file's text once every
        such cell has run, in order (read as text, never run): a ``-a`` cell appends to it as
        IPython's does, so a file written in parts is graded whole, as the student's Jupyter
        ran it."""
        found = None
        for cell in self.cells:
            written = writefile_cell(cell.source)
            if written is not None and written[0] == name:
                text = found[1] + written[2] if found is not None and written[1] else written[2]
                found = (cell, text)
        return found


#: The options of IPython's ``%%writefile`` that append instead of writing the file anew.
APPEND = frozenset({"-a", "--append"})


def writefile_cell(source: str) -> tuple[str, bool, str] | None:
    """(file name, appends, text written) of a ``%%writefile [-a] NAME`` cell, else None: the
    one reading of such a cell, for grading a file question and for the similarity record."""
    head, _, body = source.lstrip().partition("\n")
    parts = head.split()
    if len(parts) < 2 or parts[0] != "%%writefile":
        return None
    return parts[-1], bool(APPEND.intersection(parts[1:-1])), body


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
    except UnicodeDecodeError:  # its message quotes the file's bytes and their offset
        raise NotebookError(f"{path.name} is not a notebook: it is not text (a notebook is "
                            f"UTF-8 text). {_SAVE_AGAIN}") from None
    except ValueError:  # the parser's message gives line, column and offset into the file
        raise NotebookError(f"{path.name} is not a notebook: it is not valid JSON (a notebook "
                            f"is a JSON document). {_SAVE_AGAIN}") from None
    except RecursionError:
        raise NotebookError(f"{path.name} is not a notebook (its JSON is nested too deep to "
                            f"read).") from None
    cells = data.get("cells") if isinstance(data, dict) else None
    if not isinstance(cells, list):
        raise NotebookError(f"{path.name} is not a notebook: it is JSON without a list of "
                            f"cells. {_SAVE_AGAIN}")
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
    """:func:`read` and :func:`transform` every cell, in a child process under :data:`LOAD_CPU`,
    :data:`LOAD_MEMORY` and :data:`LOAD_WALL` (module docstring); NotebookError for the student
    when it fails or runs past them."""
    import IPython.core.inputtransformer2  # noqa: F401 - imported before the fork, not in it

    from gpsaccel import sandbox as sb

    path = Path(path)
    out = sb.in_child(_parsed, path, cpu=LOAD_CPU, memory=LOAD_MEMORY, wall=LOAD_WALL)
    if out.ok and "cells" in out.value:
        return Notebook([Cell(n, src, py) for n, src, py in out.value["cells"]])
    if out.ok:
        raise NotebookError(out.value["error"])
    if out.failure == "not-started":  # the machine's, not the notebook's
        raise OSError(f"cannot parse {path.name}: {out.detail}")
    why = f"needed more than {LOAD_MEMORY >> 20} MB" if out.failure == "memory-limit" else \
        f"took more than {LOAD_CPU} CPU seconds or more than {LOAD_MEMORY >> 20} MB"
    raise NotebookError(f"{path.name} could not be read: parsing it and its IPython lines "
                        f"(%, !) {why}. Remove the long runs of magics and save it again.")


def _parsed(path: Path) -> dict[str, Any]:
    """In the child: the cells (number, source, Python) or the student's error."""
    try:
        nb = read(path)
    except NotebookError as exc:
        return {"error": str(exc)}
    return {"cells": [[c.number, c.source, _python(c.source)] for c in nb.cells]}


@dataclass(frozen=True)
class Read:
    """One thing a question reads from the box: call ``name(*args)`` (or, with ``value``, read
    the variable ``name``), which must give ``shapes`` (one array, or a tuple of them)."""

    name: str
    args: tuple[np.ndarray, ...] = ()
    shapes: tuple[tuple[int, ...], ...] = ((),)
    value: bool = False


def module_source(nb: Notebook, reads: list[Read]) -> str:
    """The text of ``notebook.py`` for the sandbox: data and calls of
    :mod:`gpsaccel.boxside.notebook` only (the modules the box may not import, the cells as
    string literals, each read as its name, kind and shapes); the sandbox's runner then calls
    ``_gpsaccel_cell(i)`` per cell and ``_gpsaccel_probe(k, *args)`` for read ``k`` (or
    ``_gpsaccel_reads`` for several), where the grader placed them among the cells
    (:mod:`gpsaccel.assignments.snapshots`)."""
    cells = [(c.number, c.python if c.python is not None else _python(c.source))
             for c in nb.cells]
    for r in reads:
        if not r.name.isidentifier():
            raise ValueError(f"read name must be a Python name, got {r.name!r}")
    probes = [(r.name, bool(r.value), [tuple(int(n) for n in s) for s in r.shapes])
              for r in reads]
    hidden = tuple("gpsaccel." + rel.replace("/", ".") for rel in BOX_HIDES)
    return "\n".join([
        "# A student's notebook, rewritten by gpsaccel.assignments.notebook for the sandbox.",
        "from gpsaccel.boxside import notebook as _gpsaccel_box",
        f"_gpsaccel_box.guard({hidden!r})",
        f"_gpsaccel_cell, _gpsaccel_probe, _gpsaccel_reads = _gpsaccel_box.start(globals(), "
        f"{cells!r}, {probes!r})",
        ""])
