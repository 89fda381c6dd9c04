r"""What a notebook's box is asked to do: which of the student's cells it runs and the calls it
makes (split from :mod:`.scoring`, which grades what comes back).

* :func:`prepare`: the cells to run, the master's variant cell replaced by the student's variant,
  cells that only make data to look at (:data:`SKIP_MARK`) and otter's own cells
  (:func:`is_otter_cell`) left out;
* :func:`box_calls`: the calls for a plan of :mod:`.snapshots`, each cell one call and the reads
  of one function in a group stacked in one call (:data:`BATCH`), and :func:`per_call`, their
  results as one per call of the plan; :func:`calls`, every cell then every read one call each,
  is the plain order for tests and benchmarks.

Every call returns a status and a message first (:func:`_head`), the box-side code's
(:mod:`gpsaccel.boxside.notebook`).
"""

from __future__ import annotations

import ast

import numpy as np

from gpsaccel.assignments import notebook as nbm
from gpsaccel.assignments import snapshots

__all__ = ["BATCH", "SKIP_MARK", "VARIANT_MARK", "box_calls", "calls", "checked_question",
           "is_otter_cell", "is_variant_cell", "per_call", "prepare"]

#: The first line of a master's cell that only makes data to look at: not run when graded.
SKIP_MARK = "# not run when graded"

#: The first line of the master's variant cell; grading replaces the cell with the student's.
VARIANT_MARK = "# your variant"

_CELL_STATUS = nbm.STATUS_LENGTH


def _first_line(source: str) -> str:
    return source.lstrip().split("\n", 1)[0].strip().lower()


def is_variant_cell(source: str) -> bool:
    """The cell that holds the student's numbers (its first line :data:`VARIANT_MARK`, any
    case): replaced when graded, and what a hand-out notebook declares its variant in."""
    return _first_line(source).startswith(VARIANT_MARK)


#: The longest cell read as a candidate otter cell (its init, ``grader.check``: one line each).
_OTTER_CELL_CHARS = 2000


def _otter_call(node: ast.stmt) -> bool:
    """``import otter``, ``grader = otter.Notebook(...)`` or ``grader.<method>(...)`` with
    constant arguments (check, check_all, export, ...)."""
    if isinstance(node, ast.Import):
        return all(a.name == "otter" and a.asname is None for a in node.names)
    value = node.value if isinstance(node, (ast.Assign, ast.Expr)) else None
    if isinstance(node, ast.Assign) and not (
            len(node.targets) == 1 and isinstance(node.targets[0], ast.Name)
            and node.targets[0].id == "grader"):
        return False
    if not isinstance(value, ast.Call) or not isinstance(value.func, ast.Attribute):
        return False
    owner = value.func.value
    args = [*value.args, *(k.value for k in value.keywords)]
    return (isinstance(owner, ast.Name) and owner.id == ("otter" if isinstance(node, ast.Assign)
                                                         else "grader")
            and all(isinstance(a, ast.Constant) for a in args))


def is_otter_cell(source: str) -> bool:
    """True for a cell of otter's own (its init cell, a ``grader.check("q1")`` cell): every
    statement is one of :func:`_otter_call`'s.  The grader checks the answers itself, so these
    cells are not run (they would only fail: no otter, no ``grader``, no tests in the box)."""
    if len(source) > _OTTER_CELL_CHARS or "otter" not in source and "grader" not in source:
        return False
    try:
        tree = ast.parse(source)
    except (SyntaxError, ValueError, RecursionError, MemoryError):
        return False
    return bool(tree.body) and all(_otter_call(node) for node in tree.body)


def checked_question(source: str) -> str | None:
    """The question of an otter ``grader.check("qN")`` cell (None for any other cell): where
    the student's notebook says that answer is complete (:mod:`.snapshots`)."""
    if not is_otter_cell(source):  # short and made only of otter's calls: parsed here
        return None
    for node in ast.parse(source).body:
        call = node.value if isinstance(node, ast.Expr) else None
        if isinstance(call, ast.Call) and isinstance(call.func, ast.Attribute) \
                and call.func.attr == "check" and call.args \
                and isinstance(call.args[0], ast.Constant) and isinstance(call.args[0].value, str):
            return call.args[0].value
    return None


def prepare(nb: nbm.Notebook, variant: dict) -> nbm.Notebook:
    """The cells to run: the variant cell replaced by the student's, data-only cells and otter's
    own cells (:func:`is_otter_cell`) left out."""
    cells = [nbm.Cell(0, f"VARIANT = {variant!r}")]
    for cell in nb.cells:
        if _first_line(cell.source).startswith(SKIP_MARK) or is_otter_cell(cell.source):
            continue
        if is_variant_cell(cell.source):
            cells.append(nbm.Cell(cell.number, f"VARIANT = {variant!r}"))
            continue
        cells.append(cell)
    return nbm.Notebook(cells, nb.notes)


def calls(n_cells: int, reads: list[nbm.Read]):
    """Every cell, then every read once, one call each (``_gpsaccel_cell(i)``,
    ``_gpsaccel_probe(k, *args)``): the plain order of a box, for tests and benchmarks; a
    notebook is graded with :func:`box_calls`."""
    from gpsaccel.sandbox import Call, Output

    head = _head()
    calls = [Call("_gpsaccel_cell", (np.array(i),), head) for i in range(n_cells)]
    for k, r in enumerate(reads):
        outs = tuple(Output(f"out{j}", tuple(s)) for j, s in enumerate(r.shapes))
        calls.append(Call("_gpsaccel_probe", (np.array(k), *(np.asarray(a, dtype=float)
                                                             for a in r.args)), head + outs))
    return calls


def _head() -> tuple:
    """The status and message every call of a notebook's box returns first."""
    from gpsaccel.sandbox import Output

    return (Output("status", (_CELL_STATUS,), "int64"),
            Output("message", (nbm.MESSAGE_BYTES,), "uint8"))

#: The most reads one call makes at once (:func:`box_calls`).
BATCH = 256


def box_calls(p: snapshots.Plan, reads: list[nbm.Read]) -> tuple[list, list[range]]:
    """The box's calls for plan ``p``: ``_gpsaccel_cell(i)`` per cell and, for each run of the
    plan's reads of one name and shapes in a group (at most :data:`BATCH`),
    ``_gpsaccel_reads(ks, nargs, *args)``: one frame for them all, each output stacked (a frame
    costs more than a small function's read; benchmarks/snapshots.py measures the batching).
    Returns the calls and, for each, the range of the plan's calls it makes."""
    from gpsaccel.sandbox import Call, Output

    head = _head()
    calls, covers = [], []
    i = 0
    while i < len(p.calls):
        group, k = p.calls[i]
        if group == -1:
            calls.append(Call("_gpsaccel_cell", (np.array(k),), head))
            covers.append(range(i, i + 1))
            i += 1
            continue
        r = reads[k]
        j = i + 1
        while j < len(p.calls) and j - i < BATCH and p.calls[j][0] == group and \
                (reads[p.calls[j][1]].name, reads[p.calls[j][1]].value,
                 reads[p.calls[j][1]].shapes) == (r.name, r.value, r.shapes):
            j += 1
        ks = [p.calls[m][1] for m in range(i, j)]
        n = len(ks)
        outs = tuple(Output(o.name, (n, *o.shape), o.dtype) for o in head) + tuple(
            Output(f"out{m}", (n, *s)) for m, s in enumerate(r.shapes))
        args = [np.asarray(a, dtype=float) for k2 in ks for a in reads[k2].args]
        calls.append(Call("_gpsaccel_reads", (np.array(ks), np.array([len(reads[k2].args)
                                                                     for k2 in ks]), *args),
                          outs))
        covers.append(range(i, j))
        i = j
    return calls, covers


def per_call(p: snapshots.Plan, results: list, covers: list[range]) -> list:
    """The results of the box's calls (:func:`box_calls`) as one per call of the plan: a
    cell's as it came, each read of a stacked call its row."""
    out: list = []
    for res, cover in zip(results, covers, strict=False):
        if p.calls[cover[0]][0] == -1:
            out.append(res)
        else:
            out += [{name: a[j] for name, a in res.items()} for j in range(len(cover))]
    return out
