r"""Dead and unreachable code out of an answer, as far as Python's syntax tree alone can tell.

Step 1 of the similarity report's fingerprints (:mod:`gpsaccel.assignments.fingerprint`): a
copy padded with statements that do nothing must keep its source's fingerprints.  :func:`prune`
drops docstrings and other expression statements without a call, ``pass``, what follows
``return``/``raise``/``break``/``continue`` in a block, the branch of ``if <constant>`` that
cannot run, blocks left empty, and inside a function the *dead* assignments: a local name that
nothing kept reads, with every statement that only assigns or mutates it (``junk = ...``,
``junk[0] = ...``, ``junk.append(...)``).  Liveness is computed once per function from the
statements that are always kept (``return``, calls that are not a local's method, what a loop or
an ``if`` tests, the parameters' mutations), so padding of any depth goes in one pass; a function
that calls ``locals``, ``vars``, ``eval`` or ``exec`` is left whole.  What an honest answer
computes is kept: a value returned, or written into an argument or an array that is returned,
is live.  Nothing here runs the code; every walk is iterative or bounded by the tree's depth.
"""

from __future__ import annotations

import ast
import threading
from collections.abc import Iterable, Sequence

#: Calls that make a function's liveness unknowable from its text: it is left whole.
_DYNAMIC = frozenset({"locals", "vars", "eval", "exec", "globals"})

#: Statements that define a name whose body runs later; statements after which a block stops.
DEFINITIONS = (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)
STOPS = (ast.Return, ast.Raise, ast.Break, ast.Continue)


def _effect(node: ast.AST) -> bool:
    """Whether evaluating ``node`` may do anything: it calls, awaits, yields or binds."""
    return any(isinstance(n, (ast.Call, ast.Await, ast.Yield, ast.YieldFrom, ast.NamedExpr))
               for n in ast.walk(node))


def _constant_test(test: ast.expr) -> bool | None:
    """The truth of a test written as a constant (``if False:``, ``while 0:``, ``if not 1:``)."""
    if isinstance(test, ast.Constant):
        return bool(test.value)
    if isinstance(test, ast.UnaryOp) and isinstance(test.op, ast.Not):
        inner = _constant_test(test.operand)
        return None if inner is None else not inner
    return None


#: Per thread (Dask runs grading in threads): ``dropped``, the statements :func:`prune` has
#: dropped so far (to know when a pass changed nothing); ``pairs``, the statement pairs
#: :func:`tokens` has compared for this answer.
_COUNT = threading.local()


def _add(name: str, n: int) -> int:
    value = getattr(_COUNT, name, 0) + n
    setattr(_COUNT, name, value)
    return value


def _block(stmts: Sequence[ast.stmt]) -> list[ast.stmt]:
    """``stmts`` without what does nothing or never runs (module docstring, step 1)."""
    out: list[ast.stmt] = []
    for i, s in enumerate(stmts):
        kept = _statement(s)
        if kept != [s]:
            _add("dropped", 1)
        out += kept
        if out and isinstance(out[-1], STOPS):
            _add("dropped", len(stmts) - i - 1)
            break  # the rest of the block never runs
    return out


def _statement(s: ast.stmt) -> list[ast.stmt]:
    """What is left of one statement: nothing, itself (its blocks pruned), or a branch."""
    if isinstance(s, ast.Pass) or isinstance(s, ast.Expr) and not _effect(s.value):
        return []
    if isinstance(s, (ast.If, ast.While)):
        truth = _constant_test(s.test)
        if truth is False:
            return _block(s.orelse)
        if truth is True and isinstance(s, ast.If):
            return _block(s.body)
    if isinstance(s, ast.Try) or type(s).__name__ == "TryStar":
        body = _block(s.body)  # type: ignore[attr-defined]
        if not body:  # nothing can raise: the else branch and the finally run
            return _block(s.orelse) + _block(s.finalbody)  # type: ignore[attr-defined]
    for name in ("body", "orelse", "finalbody"):
        if isinstance(getattr(s, name, None), list):
            setattr(s, name, _block(getattr(s, name)))
    for h in getattr(s, "handlers", []):
        h.body = _block(h.body)
    if isinstance(s, (ast.FunctionDef, ast.AsyncFunctionDef)):
        s.body = _live(s)
        return [s]
    if isinstance(s, (ast.If, ast.For, ast.AsyncFor, ast.While, ast.With, ast.AsyncWith)) \
            and not s.body and not getattr(s, "orelse", None):
        return []  # an empty block: its header alone does nothing worth comparing
    return [s]


def prune(stmts: Sequence[ast.stmt]) -> list[ast.stmt]:
    """The statements without dead and unreachable code (module docstring, step 1); the nodes
    are changed in place (pass a fresh parse)."""
    out = _block(stmts)
    for _ in range(2):  # a block emptied by liveness frees the names its header read
        before = _add("dropped", 0)
        out = _block(out)
        if _add("dropped", 0) == before:
            break
    return out


# ------------------------------------------------------------------ liveness in a function
def _stored(target: ast.expr) -> list[str]:
    return [n.id for n in ast.walk(target) if isinstance(n, ast.Name)
            and isinstance(n.ctx, ast.Store)]


def _targets(s: ast.stmt) -> list[ast.expr]:
    if isinstance(s, (ast.Assign, ast.Delete)):
        return s.targets
    if isinstance(s, (ast.AnnAssign, ast.AugAssign)):
        return [s.target]
    return []


def _owned(targets: Sequence[ast.expr]) -> set[str] | None:
    """The names assignment targets bind or mutate (``a``, ``a[0]``, ``a.b``, ``a, b``); None
    when one is not of these kinds."""
    owned: set[str] = set()
    for t in targets:
        if isinstance(t, (ast.Tuple, ast.List)):
            names = _stored(t)
            if not names or len(names) != sum(isinstance(n, ast.Name) for n in ast.walk(t)):
                return None
            owned |= set(names)
            continue
        base = t.id if isinstance(t, ast.Name) else base_name(t)
        if base is None:
            return None
        owned.add(base)
    return owned


def method_base(s: ast.stmt) -> str | None:
    """``a`` of a statement ``a.b.method(...)`` (a call that may change ``a``)."""
    if isinstance(s, ast.Expr) and isinstance(s.value, ast.Call) \
            and isinstance(s.value.func, ast.Attribute):
        return base_name(s.value.func.value)
    return None


def _owner(s: ast.stmt, local: set[str]) -> tuple[set[str], set[str]] | None:
    """(local names ``s`` assigns or mutates, names it reads besides them) when ``s`` only
    assigns or mutates locals; None when it must be kept (it may act outside the function)."""
    if isinstance(s, (ast.Import, ast.ImportFrom)):
        names = {(a.asname or a.name).split(".")[0] for a in s.names}
        return (names, set()) if names <= local else None
    if isinstance(s, DEFINITIONS):
        return ({s.name}, _reads(s)) if s.name in local else None
    base = method_base(s)
    if base is not None:  # junk.append(...)
        return ({base}, _reads(s) - {base}) if base in local else None
    targets = _targets(s)
    owned = _owned(targets) if targets else None
    if owned is None or not owned <= local:
        return None
    value = getattr(s, "value", None) if not isinstance(s, ast.Delete) else None
    reads = (_reads(value) if value is not None else set()).union(
        *(_reads(t) for t in targets)) - owned
    named = {n.target.id for n in ast.walk(value) if isinstance(n, ast.NamedExpr)
             and isinstance(n.target, ast.Name)} if value is not None else set()
    return owned | named, reads  # x = x + 1 alone keeps x alive no more than junk = 1


def base_name(node: ast.expr) -> str | None:
    """The name a subscript or attribute chain hangs from: ``a`` of ``a.b[0].c``."""
    while isinstance(node, (ast.Attribute, ast.Subscript, ast.Starred)):
        node = node.value
    return node.id if isinstance(node, ast.Name) else None


def _reads(node: ast.AST) -> set[str]:
    return {n.id for n in ast.walk(node) if isinstance(n, ast.Name)
            and isinstance(n.ctx, ast.Load)}


def _statements(body: Sequence[ast.stmt]) -> Iterable[tuple[ast.stmt, bool]]:
    """Every statement of a function body, blocks included but not nested functions, with
    whether it is a compound statement (its header is always kept)."""
    stack = list(reversed(body))
    while stack:
        s = stack.pop()
        blocks = [getattr(s, n) for n in ("body", "orelse", "finalbody")
                  if not isinstance(s, DEFINITIONS) and isinstance(getattr(s, n, None), list)]
        blocks += [h.body for h in getattr(s, "handlers", [])]
        yield s, bool(blocks)
        for b in reversed(blocks):
            stack.extend(reversed(b))


def _header(s: ast.stmt) -> list[ast.AST]:
    """The parts of a compound statement outside its blocks (test, target, iter, items,
    handler types and names' nodes)."""
    out: list[ast.AST] = []
    for name, value in ast.iter_fields(s):
        if name in ("body", "orelse", "finalbody"):
            continue
        if name == "handlers":
            out += [h.type for h in value if h.type is not None]
        elif isinstance(value, ast.AST):
            out.append(value)
        elif isinstance(value, list):
            out += [v for v in value if isinstance(v, ast.AST)]
    return out


def _header_reads(s: ast.stmt) -> set[str]:
    return set().union(*(_reads(p) for p in _header(s)))


def _locals(fn: ast.FunctionDef | ast.AsyncFunctionDef) -> set[str]:
    args = fn.args
    params = {a.arg for a in [*args.posonlyargs, *args.args, *args.kwonlyargs,
                              *filter(None, (args.vararg, args.kwarg))]}
    declared: set[str] = set()
    stored: set[str] = set()
    for s, compound in _statements(fn.body):
        if isinstance(s, (ast.Global, ast.Nonlocal)):
            declared |= set(s.names)
        elif isinstance(s, DEFINITIONS):
            stored.add(s.name)
        elif isinstance(s, (ast.Import, ast.ImportFrom)):
            stored |= {(a.asname or a.name).split(".")[0] for a in s.names}
        else:
            stored |= {n.id for p in (_header(s) if compound else [s]) for n in ast.walk(p)
                       if isinstance(n, ast.Name) and isinstance(n.ctx, (ast.Store, ast.Del))}
            stored |= {h.name for h in getattr(s, "handlers", []) if h.name}
    return stored - params - declared


def _live(fn: ast.FunctionDef | ast.AsyncFunctionDef) -> list[ast.stmt]:
    """``fn``'s body without the statements that only assign or mutate dead locals."""
    if any(isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and n.func.id in _DYNAMIC
           for n in ast.walk(fn)):
        return fn.body
    local = _locals(fn)
    owners: dict[str, list[tuple[ast.stmt, set[str]]]] = {}
    roots: set[str] = set()
    droppable: set[int] = set()
    for s, compound in _statements(fn.body):
        if compound:
            roots |= _header_reads(s)
            continue
        owned = _owner(s, local)
        if owned is None:
            roots |= _reads(s)
            continue
        droppable.add(id(s))
        for name in owned[0]:
            owners.setdefault(name, []).append((s, owned[1]))
    live: set[str] = set()
    todo = list(roots)
    kept: set[int] = set()
    while todo:
        name = todo.pop()
        if name in live:
            continue
        live.add(name)
        for s, reads in owners.get(name, []):
            if id(s) not in kept:
                kept.add(id(s))
                todo.extend(reads - live)
    dead = droppable - kept
    _add("dropped", len(dead))
    return _without(fn.body, dead) if dead else fn.body


def _without(body: list[ast.stmt], dead: set[int]) -> list[ast.stmt]:
    out = []
    for s in body:
        if id(s) in dead:
            continue
        if not isinstance(s, DEFINITIONS):
            for name in ("body", "orelse", "finalbody"):
                if isinstance(getattr(s, name, None), list):
                    setattr(s, name, _without(getattr(s, name), dead))
            for h in getattr(s, "handlers", []):
                h.body = _without(h.body, dead)
        out.append(s)
    return out
