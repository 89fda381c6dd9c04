r"""When the box reads a notebook's answers, and which reads grade it when the notebook stopped.

The box runs the cells in order, one call each (:mod:`gpsaccel.boxside.notebook`).  The reads a
question declares run after the last cell, as the grade of a "Run All" (what otter grades: a later
cell may redefine a function).  A notebook that stops before that (a slow or endless last cell, a
forking hog, a memory bomb, a killed process) would lose every answer it had computed, so the
reads also run earlier, as *snapshots* (:func:`plan`):

* each question's *answer cell* is the last cell that binds a name its answer depends on
  (:func:`last_binding_cells`: a name it reads, bound, imported, changed by a method call or
  named by a string; a global read by a function or class defined under such a name, bound; any
  name, for a cell that rebinds names the parser cannot see: ``exec``, ``globals()``,
  ``setattr``, a star import), or, if later, the last cell before its otter
  ``grader.check("qN")`` cell (:func:`answer_cells`, given what
  :func:`~gpsaccel.assignments.boxcalls.checked_question` finds).  A cell that only uses an
  answer (a slow exploratory loop calling the student's filter) is not its answer cell;
* after each answer cell, and after the last cell, one *group* of reads runs: every question
  whose answer cell has run (a question with none is read in every group), in the questions'
  order; the group after the last cell is the final read of every question.

Which group grades (:func:`kept`): every question from **one** state of the notebook, that of
the last group the box reached: the final group when everything came back, else the group it
stopped in, or the last group before the cell it stopped in.  A question not in that group had
not had its cells run (``not-run``); a question whose read in it did not come back is not graded
(the box's failure for the read that stopped, ``not-read`` for those after it).  Reads are never
mixed across groups: no question is graded from an earlier state while another is graded from
a later one, and a read missing from the group that grades is not taken from an earlier group.

What a stall can buy.  Each group reads the notebook as it stood after one of its own cells, so
a stopped notebook is graded exactly as Run All grades the same notebook cut after that cell: a
notebook the student could have handed in.  A stall never earns more than deleting the cells
after the group would.  A right answer overwritten by a later cell and then frozen by a stall is
read again after the overwriting cell (it binds the name: a group follows it) and graded wrong,
as Run All grades it; one question's earlier state is never combined with another's later one,
so a change the parser cannot see (``np.copyto(Phi, ...)`` in a later answer cell) is read with
that cell's group too.  What no read sees is such a change made after the last group the box
reached (in the cell that stalls, or in a cell between): the notebook is graded as it stood at
that group (Run All of it cut there).  The student places answer cells only by writing their
notebook; the grader places the groups and chooses the one that grades.

What it costs.  Each question is read once more per group from its answer cell on (the box's
time, counted in its limit: ``benchmarks/snapshots.py``; the reads of one function in a group
are one call of the box, :func:`gpsaccel.assignments.boxcalls.box_calls`), and an early read
calls the student's functions before the later cells run, in the notebook's process: a function
that changes the notebook's state when called (a global, numpy's global random generator) can
change what a later cell computes.
"""

from __future__ import annotations

import ast
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

#: Names whose use rebinds names the parser cannot see (any name: every question's).
DYNAMIC = frozenset({"exec", "eval", "globals", "vars", "locals", "setattr", "delattr",
                     "__import__"})
#: Attributes that reach a namespace (``f.__globals__['x'] = ...``): every question's.
DYNAMIC_ATTRIBUTES = frozenset({"__dict__", "__globals__", "f_globals", "f_locals"})
#: A cell binding this means "every name".
EVERY = "*"


def _base(node: ast.expr) -> str | None:
    """The name at the root of ``a.b[c].d`` (None for anything else)."""
    while isinstance(node, (ast.Attribute, ast.Subscript, ast.Starred)):
        node = node.value
    return node.id if isinstance(node, ast.Name) else None


def _top(node: ast.AST) -> Iterable[ast.AST]:
    """The nodes of a cell that run when the cell runs, at its top level: not the bodies of the
    functions, lambdas and classes it defines (their names are their own; their decorators and
    defaults run), nor a comprehension's targets (local to it)."""
    for child in ast.iter_child_nodes(node):
        yield child
        if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            heads: list[ast.AST] = [*getattr(child, "decorator_list", ()),
                                    *child.args.defaults, *filter(None, child.args.kw_defaults)]
        elif isinstance(child, ast.ClassDef):
            heads = [*child.decorator_list, *child.bases, *child.keywords]
        elif isinstance(child, ast.comprehension):
            heads = [child.iter, *child.ifs]
        else:
            yield from _top(child)
            continue
        for head in heads:
            yield head
            yield from _top(head)


def _binds(node: ast.AST) -> Iterable[str]:
    """The names one node at a cell's top level binds (:func:`_top`)."""
    if isinstance(node, ast.Name) and isinstance(node.ctx, (ast.Store, ast.Del)):
        yield node.id
    elif isinstance(node, (ast.Attribute, ast.Subscript)) \
            and isinstance(node.ctx, (ast.Store, ast.Del)):  # V[0, 0] = 1, mod.Phi = ...
        yield from (n for n in (_base(node), getattr(node, "attr", None)) if n)
    elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
        yield node.name
    elif isinstance(node, ast.ImportFrom) and any(a.name == "*" for a in node.names):
        yield EVERY
    elif isinstance(node, (ast.MatchAs, ast.MatchStar)) and node.name:
        yield node.name
    elif isinstance(node, ast.MatchMapping) and node.rest:
        yield node.rest


def _anywhere(node: ast.AST) -> Iterable[str]:
    """The names one node anywhere in a cell may bind in the notebook's namespace: those a
    function declares global, and :data:`EVERY` for what rebinds names the parser cannot see."""
    if isinstance(node, (ast.Global, ast.Nonlocal)):
        yield from node.names
    elif isinstance(node, ast.Name) and node.id in DYNAMIC \
            or isinstance(node, ast.Attribute) and node.attr in DYNAMIC_ATTRIBUTES:
        yield EVERY


def _touches(node: ast.AST, names: set[str]) -> Iterable[str]:
    """Which of ``names`` (what a question reads) one node at a cell's top level may change
    without binding them in the parser's sense: an import of that name, a method call on it
    (``V.fill(0)``), a string that is the name (``globals()["V"]``, ``setattr(m, "V", ...)``)."""
    if isinstance(node, (ast.Import, ast.ImportFrom)):
        yield from (n for a in node.names if (n := a.asname or a.name.split(".")[0]) in names)
    elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
        if (base := _base(node.func)) in names:
            yield base
    elif isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in names:
        yield node.value


def _free(node: ast.AST) -> set[str]:
    """The names a definition's body reads and does not bind itself (the globals it may depend
    on), and those it declares global."""
    loads: set[str] = set()
    local: set[str] = set()
    declared: set[str] = set()
    for n in ast.walk(node):
        if isinstance(n, ast.Name):
            (loads if isinstance(n.ctx, ast.Load) else local).add(n.id)
        elif isinstance(n, ast.arg):
            local.add(n.arg)
        elif isinstance(n, (ast.Global, ast.Nonlocal)):
            declared.update(n.names)
        elif isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) \
                and n is not node:
            local.add(n.name)
        elif isinstance(n, (ast.Import, ast.ImportFrom)):
            local.update(a.asname or a.name.split(".")[0] for a in n.names)
    return (loads - local) | declared


@dataclass
class _Facts:
    """What one cell binds, which read names it touches, the globals its definitions read."""

    binds: set[str]
    touches: set[str]
    defined: dict[str, set[str]]


def _cell_facts(tree: ast.Module, names: set[str]) -> _Facts:
    facts = _Facts(set(), set(), {})
    for node in ast.walk(tree):
        facts.binds.update(_anywhere(node))
    for node in _top(tree):
        facts.binds.update(_binds(node))
        facts.touches.update(_touches(node, names))
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            facts.defined.setdefault(node.name, set()).update(_free(node))
        elif isinstance(node, ast.Assign) and isinstance(node.value, ast.Lambda):
            for t in node.targets:
                if isinstance(t, ast.Name):
                    facts.defined.setdefault(t.id, set()).update(_free(node.value))
    return facts


def last_binding_cells(texts: Sequence[str], questions: Mapping[str, Sequence[str]]
                       ) -> dict[str, int | None]:
    """For each question (its read names), the index of the last cell in ``texts`` (plain
    Python) that binds a name its answer depends on: a name it reads (bound, imported, changed
    by a method call, named by a string) or, closed over every cell, a global read by a
    function, class or lambda defined under one of those (bound, not imported: ``np`` stays
    numpy); a cell that rebinds names dynamically counts for every question.  None when no cell
    does.  A cell that does not parse binds nothing (it raises in the box).  Runs on the
    student's text: call it under limits (:func:`answer_cells`)."""
    every_name = {n for names in questions.values() for n in names}
    facts = []
    for text in texts:
        try:
            tree = ast.parse(text)
        except (SyntaxError, ValueError, RecursionError, MemoryError):
            facts.append(_Facts(set(), set(), {}))
            continue
        facts.append(_cell_facts(tree, every_name))
    out: dict[str, int | None] = {}
    for q, names in questions.items():
        needed = set(names)
        while True:  # the closure over the definitions, in any cell
            more = {u for f in facts for n in needed & f.defined.keys()
                    for u in f.defined[n]} - needed
            if not more:
                break
            needed |= more
        hits = [i for i, f in enumerate(facts)
                if EVERY in f.binds or f.binds & needed or f.touches & set(names)]
        out[q] = hits[-1] if hits else None
    return out


def answer_cells(run: Sequence, checks: Mapping[int, str],
                 questions: Mapping[str, Sequence[str]]) -> dict[str, int | None]:
    """Each question's answer cell (module docstring): an index into ``run`` (the cells the box
    runs, :class:`gpsaccel.assignments.notebook.Cell`), or None.  ``checks``: the number of each
    otter ``grader.check`` cell of the notebook -> the question it checks.  The cells' text is
    parsed in a child under the notebook parser's limits; if that fails, no answer cell is found
    from it."""
    from gpsaccel import sandbox as sb
    from gpsaccel.assignments import notebook as nbm

    texts = [c.python if c.python is not None else c.source for c in run]
    out = sb.in_child(last_binding_cells, texts, {q: list(n) for q, n in questions.items()},
                      cpu=nbm.LOAD_CPU, memory=nbm.LOAD_MEMORY, wall=nbm.LOAD_WALL)
    found: dict[str, int | None] = {q: None for q in questions}
    if out.ok and isinstance(out.value, dict):
        found.update({q: i for q, i in out.value.items() if q in found and isinstance(i, int)
                      and 0 <= i < len(run)})
    for number, q in checks.items():
        before = [i for i, c in enumerate(run) if c.number < number]
        if q in found and before:
            found[q] = max(before[-1], -1 if (at := found[q]) is None else at)
    return found


# ------------------------------------------------------------------------------ the plan
@dataclass(frozen=True)
class Group:
    """One group of reads: after cell ``after`` (an index into the cells run), ``questions``
    read in order, its calls from index ``first`` on."""

    after: int
    questions: tuple[str, ...]
    first: int


@dataclass(frozen=True)
class Plan:
    """The box's calls in order: ``calls[i]`` is ``(-1, cell)`` or ``(group, read)``, a read
    being an index into the notebook's reads (``spans[q]`` is question q's range of them)."""

    n_cells: int
    spans: dict[str, tuple[int, int]]
    groups: tuple[Group, ...]
    calls: tuple[tuple[int, int], ...]

    @property
    def cell_calls(self) -> list[int]:
        """The call index of each cell."""
        return [i for i, (g, _) in enumerate(self.calls) if g == -1]

    def read_calls(self, group: int, question: str) -> range:
        """The call indices of ``question``'s reads in ``group``."""
        g = self.groups[group]
        at = g.first
        for q in g.questions:
            a, b = self.spans[q]
            if q == question:
                return range(at, at + b - a)
            at += b - a
        raise KeyError(question)


def plan(n_cells: int, spans: Mapping[str, tuple[int, int]],
         answered: Mapping[str, int | None]) -> Plan:
    """The calls (module docstring): every cell, and a group of reads after each answer cell
    and after the last cell.  ``spans``: the reading questions, in order, and their reads;
    ``answered``: their answer cells (None: read in every group)."""
    last = n_cells - 1
    points = {p for p in answered.values() if p is not None and 0 <= p < last} | {last}
    calls: list[tuple[int, int]] = []
    groups: list[Group] = []
    for i in range(n_cells):
        calls.append((-1, i))
        if i not in points:
            continue
        qs = tuple(q for q in spans if spans[q][1] > spans[q][0]
                   and (answered.get(q) is None or answered[q] <= i))  # type: ignore[operator]
        if not qs:
            continue
        groups.append(Group(i, qs, len(calls)))
        calls += [(len(groups) - 1, k) for q in qs for k in range(*spans[q])]
    return Plan(n_cells, dict(spans), tuple(groups), tuple(calls))


@dataclass(frozen=True)
class Kept:
    """What a box that returned ``received`` results grades.

    group : the index of the group that grades (None: no group came back or was reached).
    stopped : the call that did not come back (None: all did).
    questions : question -> the call indices of its reads in that group, for the questions in
        it; a question not here had not had its cells run.
    """

    group: int | None
    stopped: int | None
    questions: dict[str, range]


def kept(p: Plan, received: int) -> Kept:
    """The one group that grades (module docstring)."""
    if received >= len(p.calls):
        g: int | None = len(p.groups) - 1 if p.groups else None
        stopped = None
    else:
        stopped = received
        g, at = p.calls[stopped]
        if g == -1:  # in a cell: the last group before it
            g = max((j for j, grp in enumerate(p.groups) if grp.after < at), default=None)
    if g is None:
        return Kept(None, stopped, {})
    return Kept(g, stopped, {q: p.read_calls(g, q) for q in p.groups[g].questions})
