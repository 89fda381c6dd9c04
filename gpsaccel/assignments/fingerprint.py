r"""Answer code as fingerprints: what a copy keeps when names, layout and padding change.

The similarity report (:mod:`gpsaccel.assignments.similarity`) compares the *structure* of two
answers, not their text.  Three steps, each a pure function on Python's own syntax tree:

1. :func:`gpsaccel.assignments.pruning.prune` drops what does not run or does nothing, as far
   as the tree alone can tell (docstrings, ``pass``, code after ``return``, ``if False:``,
   assignments to locals that nothing kept reads).
2. :func:`tokens` walks the pruned tree and gives one token per node: its kind (``Assign``,
   ``Call``, ``BinOp``, ``MatMult`` ...), every variable, argument and function name folded to
   ``V``, numbers to ``N``, strings to ``S``; attribute names (``.solve``, ``.T``) and keyword
   names (``axis=``) are kept, since they are the library's and a copier cannot rename them
   without changing the code.  A list or tuple written out of constants and names (a matrix,
   ``return x_hat, P``) is one token ``LIT``: every right answer writes a model matrix the same
   way, so its entries say nothing about who wrote it.  Each block's statements come in a
   canonical order (:func:`_block_tokens`: by how long a chain of statements each must follow,
   from what they read and write, then by their tokens), so reordering statements that do not
   depend on each other, or the functions of a file, changes nothing.
3. :func:`kgrams` hashes every run of :data:`K` consecutive tokens (all of them, no winnowing:
   answers are short).  Token ids are CRC-32 of their text and a k-gram's hash is Python's hash
   of a tuple of ints, which no process salts: fingerprints agree across processes and
   machines.

Python's parser gives the tree; nothing here runs the code.  Every walk is iterative or bounded
by the tree's depth, which the caller bounds (:mod:`gpsaccel.assignments.answercode` parses at
most :data:`~gpsaccel.assignments.answercode.MAX_CODE` characters a notebook and catches
RecursionError).
"""

from __future__ import annotations

import ast
import threading
import zlib
from collections.abc import Sequence
from dataclasses import dataclass

from gpsaccel.assignments.pruning import DEFINITIONS, STOPS, base_name, method_base, prune

#: Tokens in one fingerprint (a k-gram): about one line of code (docs/grading.md, chosen by
#: ``benchmarks/similarity.py``).
K = 12

#: Most tokens kept of one answer (an honest answer has a few hundred; the record of every
#: student travels in grades.json, so this bounds it).
MAX_TOKENS = 4000



# ----------------------------------------------------------------------------- 2. tokens
_IDS: dict[str, int] = {}


def _id(text: str) -> int:
    found = _IDS.get(text)
    if found is None:
        found = _IDS[text] = zlib.crc32(text.encode("utf-8", "surrogatepass"))
    return found


def _constant(value: object) -> str:
    if isinstance(value, bool) or value is None or value is Ellipsis:
        return repr(value)
    if isinstance(value, (int, float, complex)):
        return "N"
    return "B" if isinstance(value, bytes) else "S"


def _literal(node: ast.AST) -> bool:
    """A list or tuple written out of constants and names (arithmetic of them included)."""
    for n in ast.walk(node):
        if not isinstance(n, (ast.List, ast.Tuple, ast.Constant, ast.Name, ast.UnaryOp,
                              ast.BinOp, ast.Load, ast.operator, ast.unaryop, ast.Attribute)):
            return False
    return True


def _token(node: ast.AST) -> str | None:
    """One node's token (module docstring, step 2); None for nodes that add nothing."""
    if isinstance(node, (ast.Name, ast.arg)):
        return "V"
    if isinstance(node, ast.Constant):
        return _constant(node.value)
    if isinstance(node, ast.Attribute):
        return "." + node.attr
    if isinstance(node, ast.keyword):
        return f"{node.arg}=" if node.arg else "**"
    if isinstance(node, (ast.expr_context, ast.arguments, ast.alias)):
        return None
    return type(node).__name__


def _walk(node: ast.AST, out: list[int]) -> None:
    """The tokens of an expression (or any node) in source order, iteratively."""
    stack: list[ast.AST] = [node]
    while stack and len(out) < MAX_TOKENS:
        node = stack.pop()
        if isinstance(node, (ast.List, ast.Tuple)) and _literal(node):
            out.append(_id("LIT"))
            continue
        tok = _token(node)
        if tok is not None:
            out.append(_id(tok))
        if isinstance(node, ast.Attribute):  # the object before its attribute
            stack.append(node.value)
            continue
        stack.extend(reversed([c for c in ast.iter_child_nodes(node)
                               if not isinstance(c, ast.expr_context)]))


def _statement_tokens(s: ast.stmt) -> list[int]:
    """One statement's tokens, each block inside it in canonical order."""
    out = [_id(type(s).__name__)]
    for _, value in ast.iter_fields(s):
        if isinstance(value, list) and value and isinstance(value[0], ast.stmt):
            out += _block_tokens(value)
            out.append(_id("end"))
        elif isinstance(value, list):
            for v in value:
                if isinstance(v, ast.ExceptHandler):
                    out.append(_id("except"))
                    if v.type is not None:
                        _walk(v.type, out)
                    out += _block_tokens(v.body)
                elif isinstance(v, ast.AST):
                    _walk(v, out)
        elif isinstance(value, ast.AST):
            _walk(value, out)
        if len(out) >= MAX_TOKENS:
            break
    return out


@dataclass(frozen=True)
class _Effects:
    """What a statement reads and writes, for ordering: ``writes`` rebinds or mutates whole
    names, ``parts`` writes one attribute or constant index of a name (``kf.H = ...``,
    ``Phi[0, 1] = ...``: independent of ``kf.Q = ...``); ``fixed`` keeps its place."""

    reads: frozenset[str] = frozenset()
    writes: frozenset[str] = frozenset()
    parts: frozenset[str] = frozenset()
    bases: frozenset[str] = frozenset()
    fixed: bool = False

    def before(self, later: _Effects) -> bool:
        """Whether this statement must stay before ``later``."""
        return (self.fixed or later.fixed or bool(self.writes & (later.reads | later.writes
                                                                  | later.bases))
                or bool(later.writes & (self.reads | self.bases))
                or bool(self.bases & later.reads) or bool(later.bases & self.reads)
                or bool(self.parts & later.parts))


_PART = (ast.Name, ast.Attribute, ast.Subscript, ast.Constant, ast.Tuple, ast.Load,
         ast.Store, ast.UnaryOp, ast.USub)


def _part(target: ast.expr) -> str | None:
    """``kf.H`` or ``Phi[0, 1]``: a store into one attribute or constant index of a name."""
    if not isinstance(target, (ast.Attribute, ast.Subscript)) or base_name(target) is None:
        return None
    if not all(isinstance(n, _PART) for n in ast.walk(target)):
        return None
    if any(isinstance(n, ast.Name) for n in ast.walk(target.slice)) \
            if isinstance(target, ast.Subscript) else False:
        return None
    return ast.unparse(target)


def _effect_of(n: ast.AST, reads: set[str], writes: set[str], parts: set[str]) -> list[ast.AST]:
    """Record what node ``n`` reads and writes; the nodes to look at next."""
    if isinstance(n, DEFINITIONS):
        writes.add(n.name)
        inner: list[ast.AST] = list(n.decorator_list)
        if not isinstance(n, ast.ClassDef):
            inner += [*n.args.defaults, *(d for d in n.args.kw_defaults if d)]
        return inner
    if isinstance(n, (ast.Subscript, ast.Attribute)) and isinstance(n.ctx, ast.Store):
        part = _part(n)
        if part is not None:
            parts.add(part)
            return []
        writes.add(base_name(n) or "")
    elif isinstance(n, ast.Name):
        (writes if isinstance(n.ctx, (ast.Store, ast.Del)) else reads).add(n.id)
    elif isinstance(n, (ast.Import, ast.ImportFrom)):
        writes |= {(a.asname or a.name).split(".")[0] for a in n.names}
    return list(ast.iter_child_nodes(n))


def _effects(s: ast.stmt) -> _Effects:
    """The :class:`_Effects` of ``s``; a function's or class's body is not looked into: it
    runs when called, not here."""
    if isinstance(s, STOPS + (ast.Global, ast.Nonlocal)):
        return _Effects(fixed=True)
    reads: set[str] = set()
    writes: set[str] = set()
    parts: set[str] = set()
    stack: list[ast.AST] = [s]
    while stack:
        stack += _effect_of(stack.pop(), reads, writes, parts)
    if isinstance(s, ast.Expr) and isinstance(s.value, ast.Call):
        writes.add(method_base(s) or "")  # x_hat.append(...) changes x_hat
    bases = {p.split(".", 1)[0].split("[", 1)[0] for p in parts}
    return _Effects(frozenset(reads), frozenset(writes), frozenset(parts), frozenset(bases))


#: Longest block put in canonical order, and most pairs of statements compared for it in one
#: answer (ordering is quadratic in a block's statements; an honest answer compares a few
#: thousand pairs): past them, statements keep their order.
MAX_ORDERED = 200
MAX_PAIRS = 200_000

#: The statement pairs :func:`tokens` has compared for this answer, per thread (Dask grades in
#: threads).
_PAIRS = threading.local()



def _block_tokens(stmts: Sequence[ast.stmt]) -> list[int]:
    """A block's tokens with its statements in a canonical order: each statement's level (the
    longest chain of statements it must follow, by what they read and write), then its tokens'
    hash.  Any order of the block that keeps every dependent pair in place has the same levels,
    so swapping independent statements or functions changes nothing."""
    parts = [_statement_tokens(s) for s in stmts]
    _PAIRS.n = pairs = getattr(_PAIRS, "n", 0) + len(stmts) * (len(stmts) - 1) // 2
    if len(stmts) > MAX_ORDERED or pairs > MAX_PAIRS:
        return [t for p in parts for t in p]
    fx = [_effects(s) for s in stmts]
    level = [0] * len(stmts)
    for j in range(len(stmts)):
        level[j] = max((level[i] + 1 for i in range(j) if fx[i].before(fx[j])), default=0)
    order = sorted(range(len(stmts)), key=lambda i: (level[i], hash(tuple(parts[i])), i))
    return [t for i in order for t in parts[i]]


def tokens(stmts: Sequence[ast.stmt]) -> list[int]:
    """The token ids of ``stmts`` (module docstring, step 2), blocks in canonical order, at
    most :data:`MAX_TOKENS`."""
    _PAIRS.n = 0
    return _block_tokens(stmts)[:MAX_TOKENS]


# ----------------------------------------------------------------------------- 3. k-grams
def kgrams(toks: Sequence[int], k: int = K) -> frozenset[int]:
    """The hashes of every run of ``k`` consecutive tokens (a shorter answer: none)."""
    t = tuple(toks)
    return frozenset(hash(t[i:i + k]) for i in range(len(t) - k + 1))


def answer_tokens(stmts: Sequence[ast.stmt]) -> list[int]:
    """The tokens of an answer's statements: pruned (step 1; the nodes are changed in place),
    then tokenized (step 2)."""
    return tokens(prune(stmts))
