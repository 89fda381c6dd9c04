r"""Each question's answer code in a notebook, as the similarity report compares it.

The grader parses a notebook once (:func:`gpsaccel.assignments.notebook.load`: its JSON and its
IPython lines, under the grader's limits); :func:`record` takes that parse (in a child under
limits of its own, :func:`from_notebook`: Python's parser on the cells) and keeps, per graded
question, what the report needs: the answer's code as the instructor will read it, its
fingerprint tokens (:mod:`gpsaccel.assignments.fingerprint`) and the names the question reads
that no visible code defines; and, for the whole notebook, its hidden code
(:mod:`gpsaccel.assignments.hidden`).  The record is plain JSON (it travels with the student's
grade, across processes and into ``grades.json``), so the report never parses a student's file
again; a notebook whose record could not be made is "not compared", with the reason, and a cell
past the code a notebook may hold to be compared is a hidden-code finding.

A question's answer is the code it grades: the ``%%writefile`` file of a file question (its
definitions the master's file defines and what they use), else the top-level definitions of the
names the question reads and, a few levels down, the helpers and values they use.  Code the
notebook runs from literal text is read as code where it stands: a ``%%time`` or ``%%capture``
cell (IPython's transformer turns it into ``run_cell_magic(..., '<text>')``), ``%time`` lines,
``exec('<literal>')`` at a cell's top level, and ``from helper import f`` of a file a
``%%writefile helper.py`` cell wrote.
"""

from __future__ import annotations

import ast
import base64
import copy
import json
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import lru_cache

from gpsaccel.assignments import fingerprint, hidden
from gpsaccel.assignments.notebook import writefile_cell

#: Characters of code one notebook may hold to be compared (cells and written files, read in
#: order; what is past it is a finding, :func:`_bounded`): an honest notebook holds under
#: 50 000; Python's parser needs about 250 bytes per character.
MAX_CODE = 512 * 1024

#: Characters of an answer's code kept for the report's page.
MAX_SHOWN = 2000

#: How deep literal text run as code is read as code (``exec('exec("...")')``).
SPLICE_DEPTH = 3

#: IPython magics whose text runs as code in the grader's box.
_RUN_MAGICS = frozenset({"time", "timeit", "capture"})


@dataclass(frozen=True)
class Asked:
    """What one question grades: the names it reads, or the file it checks (``roots``: the
    names the master's version of that file defines, what the checker calls)."""

    names: frozenset[str] = frozenset()
    file: str | None = None
    roots: frozenset[str] = field(default_factory=frozenset)


# ----------------------------------------------------------------------------- the record
def record(cells: Sequence[tuple[int, str]], files: Mapping[str, str],
           asked: Mapping[str, Asked]) -> dict:
    """The notebook's record for the report (module docstring); never raises.

    cells : (number, plain Python) of the code cells the grader runs, in order (IPython syntax
        already transformed); files : name -> text of each file a ``%%writefile`` cell writes;
    asked : question -> :class:`Asked`.  Returns ``{"questions": {q: {"code", "tokens",
    "undefined"}}, "hidden": [...]}``, or ``{"why": reason}`` when it cannot be compared."""
    cells, files, over = _bounded(cells, files, asked)
    try:
        rec = _record(cells, files, asked)
    except RecursionError:
        return {"why": "its code is nested too deeply to compare"}
    except MemoryError:
        return {"why": "comparing its code needed too much memory"}
    except Exception as exc:  # noqa: BLE001 - one notebook's record, never the class's report
        return {"why": f"its code could not be compared ({type(exc).__name__})"}
    rec["hidden"] = (over + rec["hidden"])[:hidden.MAX_FINDINGS]
    return rec


def _bounded(cells: Sequence[tuple[int, str]], files: Mapping[str, str],
             asked: Mapping[str, Asked]) -> tuple[list[tuple[int, str]], dict[str, str],
                                                  list[str]]:
    """(the cells, the files) read, at most :data:`MAX_CODE` characters in all, in order, and
    a finding for each left unread: the bound is on what is parsed, so one oversized cell (a
    megabyte of comment) cannot hide the other cells' answers; what it holds is neither compared
    nor scanned, and no honest notebook needs it, so it is an integrity signal (like hidden
    code), named with each question whose name or file it mentions (its answer may be there)."""
    kept_cells: list[tuple[int, str]] = []
    kept_files: dict[str, str] = {}
    over: list[str] = []
    size = 0
    for where, name, text in ([(f"cell {n}", n, t) for n, t in cells]
                              + [(f"file {n}", n, t) for n, t in files.items()]):
        if size + len(text) <= MAX_CODE:
            size += len(text)
            if isinstance(name, str):
                kept_files[name] = text
            else:
                kept_cells.append((name, text))
            continue
        qs = [q for q, a in asked.items() if (a.file is not None and (a.file == name
                                                                       or a.file in text))
              or any(n in text for n in a.names)] if len(over) < hidden.MAX_FINDINGS else []
        what = (f"{where} is {len(text) // 1024} KB of code, past the {MAX_CODE // 1024} KB a "
                f"notebook may hold to be compared: not compared, not scanned")
        over += [f"{q}: {what} (it mentions the question's answer)" for q in qs] or [what]
    return kept_cells, kept_files, over


#: Limits of the child that makes one notebook's record (:func:`from_notebook`): CPU seconds,
#: added address space, wall-clock seconds: far above what an honest notebook needs; a notebook
#: past them is "not compared" with that reason, never the grader's error
#: (tests/assignments/test_answercode.py).
RECORD_CPU = 10
RECORD_MEMORY = 256 << 20
RECORD_WALL = 120

_FAILED = {"cpu-limit": "comparing its code took more than {cpu} CPU seconds",
           "memory-limit": "comparing its code needed more than {mb} MB",
           "wall-limit": "comparing its code took more than {wall} s",
           "too-large": "its record is too large", "not-plain-data": "its record is not data"}


def from_notebook(nb, asked: Mapping[str, Asked]) -> dict:
    """:func:`record` of a parsed :class:`~gpsaccel.assignments.notebook.Notebook` (its cells'
    transformed Python, the files its ``%%writefile`` cells write), made in a child under
    :data:`RECORD_CPU` and :data:`RECORD_MEMORY` (:func:`gpsaccel.sandbox.in_child`: Python's
    parser on a student's text is host-side work on untrusted input); never raises: a failure is
    the record's ``why``."""
    from gpsaccel import sandbox as sb

    cells = [(c.number, c.python if c.python is not None else c.source) for c in nb.cells]
    out = sb.in_child(record, cells, written_files(c.source for c in nb.cells), dict(asked),
                      cpu=RECORD_CPU, memory=RECORD_MEMORY, wall=RECORD_WALL)
    if out.ok:
        return out.value if isinstance(out.value, dict) else {"why": "its record is not data"}
    if out.failure == "not-started":  # the machine's: the grade is not the place to say so
        return {"why": f"the grader could not start the comparison ({out.detail[:100]})"}
    why = _FAILED.get(out.failure or "", "its code could not be compared ({what})")
    return {"why": why.format(cpu=RECORD_CPU, mb=RECORD_MEMORY >> 20, wall=RECORD_WALL,
                              what=out.detail.split(":", 1)[0][:60])}


def written_files(sources: Iterable[str]) -> dict[str, str]:
    """File name -> text of every ``%%writefile [-a] NAME`` cell, as the box writes them."""
    out: dict[str, str] = {}
    for src in sources:
        written = writefile_cell(src)
        if written is not None:
            name, append, body = written
            out[name] = out.get(name, "") + body if append else body
    return out


def _record(cells: Sequence[tuple[int, str]], files: Mapping[str, str],
            asked: Mapping[str, Asked]) -> dict:
    modules = _modules(files)
    stmts: list[ast.stmt] = []
    places: list[tuple[str, ast.AST]] = []
    used: set[str] = set()
    for number, text in cells:
        cell = _parsed(text)
        if cell is None:
            continue  # a cell Python cannot parse raises in the box: nothing of it runs
        expanded = _expand(cell, modules, 0, used)
        places.append((f"cell {number}", ast.Module(expanded, [])))
        stmts += expanded
    for name, text in files.items():
        if name.endswith(".py"):
            tree = modules[name[:-3]] if name[:-3] in modules else _parsed(text) or []
            places.append((f"file {name}", ast.Module(tree, [])))
    found = hidden.scan(places, [(n, t) for n, t in files.items() if n.endswith(".py")])
    kept = {q: _file_answer(files.get(a.file), a, modules) if a.file is not None
            else _answer(stmts, set(a.names)) for q, a in asked.items()}
    shown = {q: _shown(keep) for q, (keep, _) in kept.items()}  # before pruning changes them
    out = {q: {"code": shown[q], "tokens": pack(fingerprint.answer_tokens(keep)),
               "undefined": undefined} for q, (keep, undefined) in kept.items()}
    return {"questions": out, "hidden": found}


def _parsed(text: str) -> list[ast.stmt] | None:
    try:
        return ast.parse(text).body
    except (SyntaxError, ValueError):
        return None


def _modules(files: Mapping[str, str]) -> dict[str, list[ast.stmt]]:
    """Module name -> statements of each ``.py`` file the notebook writes (unparsable: empty)."""
    return {name[:-3]: _parsed(text) or [] for name, text in files.items()
            if name.endswith(".py") and name[:-3].isidentifier()}


# --------------------------------------------------------------- code run from literal text
def _magic_text(func: ast.Attribute, lits: list[str]) -> str | None:
    """The text ``get_ipython().run_cell_magic('time', '', TEXT)`` (or ``run_line_magic``)
    runs, for the magics the box runs."""
    owner = func.value
    if not (isinstance(owner, ast.Call) and isinstance(owner.func, ast.Name)
            and owner.func.id == "get_ipython"):
        return None
    if func.attr == "run_cell_magic" and len(lits) == 3 and lits[0] in _RUN_MAGICS:
        return lits[2]
    if func.attr == "run_line_magic" and len(lits) == 2 and lits[0] in _RUN_MAGICS:
        return lits[1]
    return None


def _text_run(s: ast.stmt) -> str | None:
    """The literal text a top-level statement runs as code, if it is one of those the module
    docstring names."""
    if not isinstance(s, ast.Expr) or not isinstance(s.value, ast.Call) or s.value.keywords:
        return None
    call = s.value
    lits = [a.value for a in call.args if isinstance(a, ast.Constant) and isinstance(a.value, str)]
    if len(lits) != len(call.args):
        return None
    if isinstance(call.func, ast.Name) and call.func.id == "exec" and len(lits) == 1:
        return lits[0]
    return _magic_text(call.func, lits) if isinstance(call.func, ast.Attribute) else None


def _imported_module(s: ast.stmt, modules: Mapping[str, list[ast.stmt]]) -> str | None:
    if isinstance(s, ast.ImportFrom) and s.level == 0 and s.module in modules:
        return s.module
    if isinstance(s, ast.Import):
        names = [a.name for a in s.names if a.name in modules]
        return names[0] if names else None
    return None


def _expand(stmts: Sequence[ast.stmt], modules: Mapping[str, list[ast.stmt]], depth: int,
            used: set[str]) -> list[ast.stmt]:
    """``stmts`` with literal text run as code, and the notebook's own modules imported, read
    in place (each module once)."""
    out: list[ast.stmt] = []
    for s in stmts:
        text = _text_run(s) if depth < SPLICE_DEPTH else None
        inner = _parsed(text) if text is not None else None
        if inner is not None:
            out += _expand(inner, modules, depth + 1, used)
            continue
        module = _imported_module(s, modules)
        if module is not None and depth < SPLICE_DEPTH:
            if module not in used:
                used.add(module)
                out += _expand(copy.deepcopy(modules[module]), modules, depth + 1, used)
            continue
        out.append(s)
    return out


# ------------------------------------------------------------------------ one question
def binds(s: ast.stmt) -> set[str]:
    """The names a top-level statement binds at module scope (blocks included, not the bodies
    of the functions and classes it defines)."""
    out: set[str] = set()
    stack: list[ast.AST] = [s]
    while stack:
        n = stack.pop()
        if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            out.add(n.name)
            continue
        if isinstance(n, (ast.Import, ast.ImportFrom)):
            out |= {(a.asname or a.name).split(".")[0] for a in n.names if a.name != "*"}
        elif isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store):
            out.add(n.id)
        elif isinstance(n, ast.Lambda):
            continue
        stack.extend(ast.iter_child_nodes(n))
    return out


def _uses(s: ast.stmt) -> set[str]:
    return {n.id for n in ast.walk(s) if isinstance(n, ast.Name)}


def select(stmts: Sequence[ast.stmt], names: set[str]) -> list[ast.stmt]:
    """The statements defining ``names`` and, a few levels down, what they use: a function's
    helper functions, a value's inputs (``dt`` of ``Phi``)."""
    bound = [(s, binds(s)) for s in stmts]
    funcs = {s.name for s in stmts if isinstance(s, (ast.FunctionDef, ast.AsyncFunctionDef,
                                                     ast.ClassDef))}
    wanted, keep = set(names), []
    for _ in range(4):
        keep = [s for s, b in bound if b & wanted]
        more: set[str] = set()
        for s in keep:
            used = _uses(s)
            more |= used & funcs if isinstance(s, (ast.FunctionDef, ast.AsyncFunctionDef,
                                                   ast.ClassDef)) else used
        if more <= wanted:
            break
        wanted |= more
    return keep


def _answer(stmts: Sequence[ast.stmt], names: set[str]) -> tuple[list[ast.stmt], list[str]]:
    """(the statements answering a question that reads ``names``, the names no shown code
    defines: an import defines nothing shown, since the notebook's own modules were read in
    place already)."""
    shown = [s for s in stmts if not isinstance(s, (ast.Import, ast.ImportFrom))]
    defined = set().union(*(binds(s) for s in shown)) if shown else set()
    return select(stmts, names), sorted(names - defined)


def _file_answer(text: str | None, a: Asked, modules: Mapping[str, list[ast.stmt]]
                 ) -> tuple[list[ast.stmt], list[str]]:
    """(the statements of the file a question checks that answer it: the master's names and
    what they use, the names undefined: every one of the master's names when the file's shown
    code defines none of them, as :func:`_answer` counts, so that a file whose function only
    hidden code defines is flagged once it scores); none when the notebook writes no such file
    or Python cannot parse it."""
    stmts = _parsed(text) if text is not None else None
    if not stmts:
        return [], []
    assert a.file is not None  # a file question
    stmts = _expand(stmts, {k: v for k, v in modules.items() if k != a.file[:-3]}, 1, set())
    roots = set(a.roots) & set().union(*(binds(s) for s in stmts)) if stmts else set()
    shown = set().union(*(binds(s) for s in stmts if not isinstance(
        s, (ast.Import, ast.ImportFrom)))) if stmts else set()
    undefined = [] if shown & set(a.roots) else sorted(a.roots)
    return (select(stmts, roots) if roots else list(stmts)), undefined


def _shown(keep: Sequence[ast.stmt]) -> str:
    """The answer's code as the report shows it (comments and layout gone)."""
    shown = []
    for s in keep:
        try:
            shown.append(ast.unparse(s))
        except (RecursionError, ValueError):
            shown.append("# (a statement too deep to show)")
    return "\n".join(shown)[:MAX_SHOWN]


def pack(toks: Sequence[int]) -> str:
    """Tokens (32-bit ids) as compact text for JSON."""
    import numpy as np

    return base64.b64encode(np.asarray(toks, dtype="<u4").tobytes()).decode("ascii")


def unpack(text: object) -> list[int]:
    """:func:`pack`'s tokens back; ValueError for anything else."""
    import numpy as np

    if not isinstance(text, str) or len(text) > 8 * fingerprint.MAX_TOKENS:
        raise ValueError("not a packed token list")
    raw = base64.b64decode(text.encode("ascii"), validate=True)
    if len(raw) % 4:
        raise ValueError("not a packed token list")
    return np.frombuffer(raw, dtype="<u4").tolist()


# ------------------------------------------------------------------- what a question asks
def asked(name: str, questions: Sequence, reads: Mapping[str, Iterable]) -> dict[str, Asked]:
    """Question -> :class:`Asked` of homework ``name``: ``reads`` maps each question that reads
    the box to its :class:`~gpsaccel.assignments.notebook.Read` s."""
    out = {}
    for q in questions:
        if q.file is not None:
            out[q.name] = Asked(file=q.file, roots=master_file_names(name, q.file))
        else:
            out[q.name] = Asked(names=frozenset(r.name for r in reads.get(q.name, ())))
    return out


@lru_cache(maxsize=16)
def master_file_names(name: str, file: str) -> frozenset[str]:
    """The top-level names the master's ``%%writefile FILE`` cell defines (what the checker
    calls); empty when the master has no such cell."""
    from gpsaccel.assignments.homework import homework_dir

    path = homework_dir(name) / f"{name}.ipynb"
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return frozenset()
    sources = ["".join(c["source"]) if isinstance(c.get("source"), list) else c.get("source", "")
               for c in data.get("cells", []) if c.get("cell_type") == "code"]
    text = written_files(sources).get(file)
    stmts = _parsed(text) if text is not None else None
    return frozenset().union(*(binds(s) for s in stmts if not isinstance(
        s, (ast.Import, ast.ImportFrom)))) if stmts else frozenset()
