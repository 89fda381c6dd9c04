"""Copies of an answer, disguised as a student would disguise them (seeded).

Every local name renamed and the layout changed (:func:`renamed`), independent statements and
functions reordered (:func:`reordered`), about 90 dead statements added inside the functions
(:func:`padded`), a few rewrites by hand that keep the result (:func:`edited`), and the
combinations the benchmark plants (:data:`DISGUISES`).  Everything comes from a
``numpy.random.Generator``.
"""

from __future__ import annotations

import ast
import builtins

import numpy as np


def pick(rng: np.random.Generator, options):
    return options[int(rng.integers(len(options)))]


# ---------------------------------------------------------------------- disguising a copy
class _Rename(ast.NodeTransformer):
    """Every local name and argument renamed; what the code needs from outside kept."""

    KEEP = {"np", "stats", "chi2", "scipy", "VARIANT", "kalman_filter", "average_nees",
            "nees_bounds", "Phi", "Gamma", "H", "V", "W", "M0", "KalmanFilter", "z"}

    def __init__(self, rng: np.random.Generator) -> None:
        self.rng, self.names = rng, {}
        self.stem = pick(rng, ["my", "tmp", "v", "var", "q", "the"])

    def _new(self, name: str) -> str:
        if name in self.KEEP or hasattr(builtins, name):
            return name
        return self.names.setdefault(name, f"{self.stem}_{name[::-1]}{len(self.names)}")

    def visit_Name(self, node):
        node.id = self._new(node.id)
        return node

    def visit_arg(self, node):
        node.arg = self._new(node.arg)
        return node

    def visit_FunctionDef(self, node):
        node.name = self._new(node.name)
        self.generic_visit(node)
        return node


def renamed(code: str, rng: np.random.Generator) -> str:
    """Names changed, comments and layout rewritten (a disguised copy)."""
    tree = _Rename(rng).visit(ast.parse(code))
    text = ast.unparse(tree)
    return "# my own work\n\n" + text.replace("\n", "\n\n" if rng.random() < 0.5 else "\n") + "\n"


def _independent(a: ast.stmt, b: ast.stmt) -> bool:
    """Whether swapping ``a`` and ``b`` keeps the code's meaning (a copier's reordering)."""
    def effects(s):
        reads, writes = set(), set()
        for x in ast.walk(s):
            if isinstance(x, ast.Name):
                (writes if isinstance(x.ctx, ast.Store) else reads).add(x.id)
            elif isinstance(x, (ast.Subscript, ast.Attribute)) and isinstance(x.ctx, ast.Store):
                base = x
                while isinstance(base, (ast.Subscript, ast.Attribute)):
                    base = base.value
                writes.add(getattr(base, "id", ""))
            elif isinstance(x, (ast.Import, ast.ImportFrom)):
                writes |= {(al.asname or al.name).split(".")[0] for al in x.names}
            elif isinstance(x, ast.FunctionDef):
                writes.add(x.name)
        return reads, writes

    (ra, wa), (rb, wb) = effects(a), effects(b)
    simple = all(isinstance(s, (ast.Assign, ast.FunctionDef, ast.Import, ast.ImportFrom))
                 for s in (a, b))
    return simple and not (wa & rb or wb & ra or wa & wb)


def _shuffle_block(body: list[ast.stmt], rng) -> list[ast.stmt]:
    body = list(body)
    for _ in range(len(body)):
        i = int(rng.integers(max(len(body) - 1, 1)))
        if i + 1 < len(body) and _independent(body[i], body[i + 1]):
            body[i], body[i + 1] = body[i + 1], body[i]
    for s in body:
        for f in ("body", "orelse"):
            if isinstance(getattr(s, f, None), list) and getattr(s, f):
                setattr(s, f, _shuffle_block(getattr(s, f), rng))
    return body


def reordered(code: str, rng: np.random.Generator) -> str:
    """Independent statements swapped, functions reordered."""
    tree = ast.parse(code)
    tree.body = _shuffle_block(tree.body, rng)
    funcs = [i for i, s in enumerate(tree.body) if isinstance(s, ast.FunctionDef)]
    order = list(rng.permutation(funcs))
    body = list(tree.body)
    for i, j in zip(funcs, order, strict=True):
        body[i] = tree.body[j]
    tree.body = body
    return ast.unparse(tree) + "\n"


_DEAD = [
    "junk{i} = {i} * 2 + 1", "tmp{i} = np.zeros(3)", "_unused{i} = len(str({i}))", "pass",
    "'''a note {i}'''", "{i} + 1", "if False:\n    zz{i} = {i}", "waste{i} = []\n"
    "waste{i}.append({i})", "for _w{i} in range(0):\n    pass", "dummy{i} = {{'k': {i}}}",
    "acc{i} = 0\nacc{i} += {i}", "while 0:\n    break",
]


def padded(code: str, rng: np.random.Generator, n: int = 90) -> str:
    """About ``n`` dead statements inserted into the functions (and after their returns)."""
    tree = ast.parse(code)
    funcs = [s for s in ast.walk(tree) if isinstance(s, ast.FunctionDef)]
    targets = funcs or [tree]
    for i in range(n):
        f = targets[int(rng.integers(len(targets)))]
        stmts = ast.parse(pick(rng, _DEAD).format(i=i)).body
        pos = int(rng.integers(len(f.body) + 1))
        f.body[pos:pos] = stmts
    for f in funcs:
        f.body += ast.parse(f"unreachable = {len(f.body)}\nprint(unreachable)").body
    return ast.unparse(tree) + "\n"


class _Edit(ast.NodeTransformer):
    """Rewrites a copier can make by hand without changing what the code computes: ``a @ b``
    as ``np.dot(a, b)``, ``.T`` as ``.transpose()``, ``inv`` as ``pinv``, ``x = x + e`` as
    ``x += e``; only the sites in ``chosen`` (indices among the candidates, in walk order)."""

    def __init__(self, chosen: set[int]) -> None:
        self.chosen, self.seen = chosen, -1

    def _take(self) -> bool:
        self.seen += 1
        return self.seen in self.chosen

    def visit_BinOp(self, node):
        self.generic_visit(node)
        if isinstance(node.op, ast.MatMult) and self._take():
            return ast.parse(f"np.dot({ast.unparse(node.left)}, {ast.unparse(node.right)})",
                             mode="eval").body
        return node

    def visit_Attribute(self, node):
        self.generic_visit(node)
        if node.attr == "T" and self._take():
            return ast.parse(f"({ast.unparse(node.value)}).transpose()", mode="eval").body
        if node.attr == "inv" and self._take():
            node.attr = "pinv"
        return node

    def visit_Assign(self, node):
        self.generic_visit(node)
        t, v = node.targets[0], node.value
        if len(node.targets) == 1 and isinstance(t, ast.Name) and isinstance(v, ast.BinOp) \
                and isinstance(v.left, ast.Name) and v.left.id == t.id and self._take():
            return ast.AugAssign(ast.Name(t.id, ast.Store()), v.op, v.right)
        return node


def edited(code: str, rng: np.random.Generator, n: int = 3) -> str:
    """``n`` of :class:`_Edit`'s rewrites, at random sites."""
    count = _Edit(set())
    count.visit(ast.parse(code))
    sites = count.seen + 1
    chosen = set(rng.choice(sites, size=min(n, sites), replace=False).tolist()) if sites else set()
    return ast.unparse(ast.fix_missing_locations(_Edit(chosen).visit(ast.parse(code)))) + "\n"


DISGUISES = {
    "renamed": lambda c, rng: renamed(c, rng),
    "reordered": lambda c, rng: renamed(reordered(c, rng), rng),
    "padded": lambda c, rng: renamed(padded(c, rng), rng),
    "all three": lambda c, rng: renamed(padded(reordered(c, rng), rng), rng),
    "all three + 3 edits": lambda c, rng: renamed(padded(reordered(edited(c, rng), rng), rng),
                                                  rng),
}
