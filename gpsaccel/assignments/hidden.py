r"""Hidden code: an answer that runs text the notebook does not show.

``exec(zlib.decompress(base64.b64decode('…')))`` grades like any answer (the box runs it), but
no reader and no comparison can see what it does.  It is an integrity signal, judged like a
grade: it is flagged in the similarity report and the run's summary, and changes no score.

:func:`scan` reads syntax trees (never runs them) and names, per place (``cell 7``, ``file
helper.py``), each way of running code the text does not show:

* ``exec``, ``eval`` or ``compile`` of anything but a string written in the code (a literal's
  code is shown: the report compares it as code), or one of them used as a value
  (``run = exec``);
* ``__import__``; ``import_module`` of a computed name, ``importlib``'s loaders; a Python file
  loaded by its path (``spec_from_file_location``, ``runpy.run_path``) that no ``%%writefile``
  cell of the notebook writes; decoded data written to a file;
  ``types.CodeType``/``FunctionType``, a function's ``__code__`` (bytecode swapped in);
  ``ctypes`` and ``cffi`` (native code); ``subprocess``, ``os.system`` and the ``os.exec*`` and
  ``spawn*`` family (another program run);
* ``marshal``, ``pickle`` (``load``/``loads``, ``numpy.load(allow_pickle=True)``,
  ``read_pickle``), ``dill``, ``cloudpickle``, ``shelve``: data that becomes code or objects;
* ``codecs`` (``rot13``, ``zlib`` and ``base64`` codecs of text);
* a computed name looked up among the builtins or a module's globals (``getattr(builtins,
  'ex' + 'ec')``, ``__builtins__[...]``, ``globals()[...]``, ``sys.modules[...]``), the
  builtins reached through a module (``sys.modules['builtins'].exec``, ``numpy.__builtins__``);
* IPython's ``run_cell``/``run_cell_magic``/``run_line_magic`` with computed text (the input
  transformer writes only literals);
* a written ``.py`` file that declares a source encoding other than UTF-8 or ASCII: Python
  decodes it before it runs (``# coding: unicode_escape`` turns a comment into code).

The decoders that pack such text (``base64``, ``zlib``, ``bz2``, ``lzma``, ``gzip``,
``binascii``, ``bytes.fromhex``) are named with what they feed; alone they are not flagged.
An answer whose graded function no visible code defines is flagged by the report itself
(:mod:`gpsaccel.assignments.answercode` records which names are undefined).
"""

from __future__ import annotations

import ast
import re
from collections.abc import Iterable, Sequence

#: Most findings kept per notebook.
MAX_FINDINGS = 20

_RUNNERS = frozenset({"exec", "eval", "compile", "execfile"})
_ALWAYS = frozenset({"__import__"})
_BUILTIN_HOLDERS = frozenset({"builtins", "__builtins__", "__builtin__"})
#: module -> its functions that turn data into code (None: every function of the module)
_MODULES: dict[str, frozenset[str] | None] = {
    "marshal": frozenset({"load", "loads"}),
    "pickle": frozenset({"load", "loads", "Unpickler"}),
    "_pickle": None, "cPickle": None, "dill": None, "cloudpickle": None, "shelve": None,
    "codecs": None, "runpy": frozenset({"run_module"}), "zipimport": None,
    "code": frozenset({"interact",
                                                                         "InteractiveInterpreter",
                                                                         "InteractiveConsole"}),
    "types": frozenset({"CodeType", "FunctionType"}),
    "importlib": frozenset({"import_module", "__import__", "reload"}),
    "importlib.util": frozenset({"spec_from_loader", "LazyLoader"}),
    "importlib.machinery": frozenset({"SourcelessFileLoader", "ExtensionFileLoader"}),
    "importlib.abc": None,
    "ctypes": None, "cffi": None, "subprocess": None, "pty": None,
    "os": frozenset({"system", "popen", "execv", "execve", "execl", "execle", "execlp",
                     "execvp", "execvpe", "spawnv", "spawnve", "spawnl", "spawnle",
                     "posix_spawn", "posix_spawnp"}),
}
_ATTRS = frozenset({"spec_from_loader", "SourcelessFileLoader", "pythonapi", "read_pickle",
                    "meta_path", "path_hooks", "__code__", "co_code"})
#: Loaders of a Python file by its path: hidden code unless the file is one the notebook writes
#: with ``%%writefile`` (lesson 08 loads a filter file so).
_LOADERS = frozenset({"spec_from_file_location", "SourceFileLoader", "run_path", "load_source"})
_WRITES = frozenset({"write", "write_text", "write_bytes", "writelines"})
_IPYTHON = frozenset({"run_cell", "run_cell_magic", "run_line_magic", "ex", "ev",
                      "run_code", "safe_execfile"})
_DECODERS = frozenset({"b64decode", "b32decode", "b16decode", "b85decode", "a85decode",
                       "decodebytes", "urlsafe_b64decode", "standard_b64decode", "decompress",
                       "unhexlify", "a2b_base64", "a2b_hex", "fromhex", "decode"})
_GLOBALS = frozenset({"globals", "vars", "locals"})

_COOKIE = re.compile(r"^[ \t\f]*#.*?coding[:=][ \t]*([-\w.]+)", re.ASCII)
_PLAIN = frozenset({"utf-8", "utf8", "utf_8", "ascii", "us-ascii", "latin-1", "latin1",
                    "iso-8859-1", "iso8859-1"})


def _dotted(node: ast.AST, aliases: dict[str, str]) -> str:
    """``a.b.c`` of an attribute chain over a name, the name resolved through the imports;
    ``sys.modules['m']`` is the module ``m`` (``sys.modules['builtins'].exec`` is
    ``builtins.exec``)."""
    parts: list[str] = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if isinstance(node, ast.Name):
        parts.append(aliases.get(node.id, node.id))
    elif isinstance(node, ast.Call):  # __import__("zlib").decompress
        parts.append("<call>")
    elif isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant) \
            and isinstance(node.slice.value, str) and node.slice.value \
            and _dotted(node.value, aliases) == "sys.modules":
        parts.append(node.slice.value)
    else:
        return ""
    return ".".join(reversed(parts))


def _builtins(d: str) -> bool:
    """Whether the dotted name ``d`` reaches the builtins: ``builtins``, ``__builtins__``,
    or any module's ``__builtins__`` (``numpy.__builtins__`` is the builtins' namespace)."""
    return any(p in _BUILTIN_HOLDERS for p in d.split(".")) if d else False


def aliases(trees: Iterable[ast.AST]) -> dict[str, str]:
    """Local name -> the module or module member it imports (``import pickle as p``: p ->
    pickle; ``from marshal import loads``: loads -> marshal.loads)."""
    out: dict[str, str] = {}
    for tree in trees:
        for n in ast.walk(tree):
            if isinstance(n, ast.Import):
                for a in n.names:
                    out[a.asname or a.name.split(".")[0]] = a.name if a.asname else \
                        a.name.split(".")[0]
            elif isinstance(n, ast.ImportFrom) and n.module:
                for a in n.names:
                    out[a.asname or a.name] = f"{n.module}.{a.name}"
    return out


def _literal(node: ast.AST) -> bool:
    """Text written in the code: a string constant, or ``compile`` of one."""
    if isinstance(node, ast.Constant) and isinstance(node.value, (str, bytes)):
        return True
    return (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
            and node.func.id == "compile" and bool(node.args) and _literal(node.args[0]))


def _decoders(node: ast.AST, names: dict[str, str]) -> list[str]:
    found = []
    for n in ast.walk(node):
        if isinstance(n, ast.Call):
            d = _dotted(n.func, names)
            d = d.replace("<call>", "(...)")
            if d.rsplit(".", 1)[-1] in _DECODERS and d not in found:
                found.append(d)
    return found


def _fed(call: ast.Call, names: dict[str, str]) -> str:
    dec = _decoders(call, names)
    return f" (from {', '.join(dec[:4])})" if dec else ""


def _module_use(d: str) -> str | None:
    """The finding for a call or attribute ``d`` (resolved dotted name) of a flagged module."""
    for module, funcs in _MODULES.items():
        if d == module or d.startswith(module + "."):
            rest = d[len(module) + 1:]
            if funcs is None or rest.split(".")[0] in funcs:
                return f"{d} (runs or rebuilds code from data)"
    return None


def _runner(n: ast.Call, d: str, names: dict[str, str]) -> str | None:
    """``exec``/``eval``/``compile`` (or through the builtins) of anything but a literal;
    ``__import__``."""
    last = d.rsplit(".", 1)[-1]
    if last in _RUNNERS and (d == last or _builtins(d.rsplit(".", 1)[0])):
        first = n.args[0] if n.args else None
        return None if first is not None and _literal(first) else \
            f"{last} of computed text{_fed(n, names)}"
    return f"{last}{_fed(n, names)}" if last in _ALWAYS else None


def _lookup(n: ast.Call, d: str, names: dict[str, str]) -> str | None:
    """``getattr``/``setattr`` of a runner's name, or of a computed name on the builtins, a
    namespace or a module."""
    if d not in ("getattr", "setattr") or len(n.args) < 2:
        return None
    key = n.args[1]
    if isinstance(key, ast.Constant) and key.value in _RUNNERS | _ALWAYS:
        return f"{d}(..., {key.value!r})"
    holder = _holder(n.args[0], names)
    return f"{d} on {holder} with a computed name" if holder and not isinstance(
        key, ast.Constant) else None


class Context(dict):
    """What judging a notebook's calls needs: its imports (local name -> what it imports, as
    :func:`aliases` gives) and ``written``, the ``.py`` files its ``%%writefile`` cells write."""

    written: frozenset[str] = frozenset()


def _file_call(n: ast.Call, last: str, names: dict[str, str]) -> str | None:
    """A Python file loaded that the notebook does not write; decoded data written to a file."""
    if last in _LOADERS:
        path = n.args[-1] if n.args and last != "run_path" else n.args[0] if n.args else None
        written: frozenset[str] = getattr(names, "written", frozenset())
        shown = isinstance(path, ast.Constant) and isinstance(path.value, str) and \
            path.value.rsplit("/", 1)[-1] in written
        if not (shown or written and path is not None and not isinstance(path, ast.Constant)):
            return f"{last} of a Python file the notebook does not write with %%writefile"
    if last in _WRITES and isinstance(n.func, ast.Attribute) and _decoders(n, names):
        return f"{last} of decoded data to a file{_fed(n, names)}"
    return None


def _other_call(n: ast.Call, d: str, names: dict[str, str]) -> str | None:
    """IPython running computed text, unpickling, loaders, the flagged modules."""
    last = d.rsplit(".", 1)[-1]
    found = _file_call(n, last, names)
    if found:
        return found
    if last in _IPYTHON and isinstance(n.func, ast.Attribute) \
            and not all(_literal(a) for a in n.args):
        return f"IPython {last} of computed text{_fed(n, names)}"
    if any(k.arg == "allow_pickle" and not (isinstance(k.value, ast.Constant)
                                            and not k.value.value) for k in n.keywords):
        return f"{d or 'a call'}(allow_pickle=...) (unpickles data)"
    if last in _ATTRS:
        return f"{d} (loads or runs code)"
    return _module_use(d) if d else None


def _call(n: ast.Call, names: dict[str, str]) -> str | None:
    d = _dotted(n.func, names)
    return _runner(n, d, names) or _lookup(n, d, names) or _other_call(n, d, names)


def _holder(node: ast.AST, names: dict[str, str]) -> str | None:
    """What a lookup by a computed name on ``node`` would reach: the builtins, a namespace, a
    module (None: an ordinary object)."""
    if isinstance(node, ast.Call):
        f = _dotted(node.func, names)
        if f in _GLOBALS or f in _ALWAYS or f.endswith("import_module"):
            return f"{f}()"
        return None
    d = _dotted(node, names)
    if _builtins(d):
        return "the builtins"
    if d == "sys.modules" or d.endswith(".__dict__"):
        return d
    if isinstance(node, ast.Subscript) and _dotted(node.value, names) == "sys.modules":
        return "a module of sys.modules"
    return None


def _subscript(n: ast.Subscript, names: dict[str, str]) -> str | None:
    """A computed (or a runner's) name looked up in the builtins, a namespace, a module."""
    holder = _holder(n.value, names) if isinstance(n.ctx, ast.Load) else None
    key = n.slice
    if holder and not (isinstance(key, ast.Constant) and key.value not in _RUNNERS | _ALWAYS):
        return f"{holder}[...] looked up with a computed or hidden name"
    return None


def _name(n: ast.Name) -> str | None:
    if not isinstance(n.ctx, ast.Load):
        return None
    if n.id in _RUNNERS | _ALWAYS:
        return f"{n.id} used as a value"
    return f"{n.id} used" if n.id in _BUILTIN_HOLDERS else None


def _attribute(n: ast.Attribute, names: dict[str, str]) -> str | None:
    d = _dotted(n, names)
    if n.attr in _ATTRS or d and _module_use(d):
        return _module_use(d) or d
    if n.attr in _BUILTIN_HOLDERS and isinstance(n.ctx, ast.Load):  # numpy.__builtins__
        return f"{d or n.attr} used"
    return None


def _import(n: ast.Import | ast.ImportFrom) -> str | None:
    mods = [a.name for a in n.names] if isinstance(n, ast.Import) else \
        [f"{n.module}.{a.name}" for a in n.names]
    for m in mods:
        if m.split(".")[-1] in _RUNNERS | _ALWAYS or any(
                m == k or m.startswith(k + ".") for k, v in _MODULES.items() if v is None):
            return f"import {m}"
    return None


def _node(n: ast.AST, names: dict[str, str], called: set[int]) -> str | None:
    """The finding of one node (``called``: the ids of nodes that are a call's function, judged
    with their call)."""
    if isinstance(n, ast.Call):
        return _call(n, names)
    if isinstance(n, ast.Subscript):
        return _subscript(n, names)
    if isinstance(n, ast.Name) and id(n) not in called:
        return _name(n)
    if isinstance(n, ast.Attribute) and id(n) not in called:
        return _attribute(n, names)
    if isinstance(n, (ast.Import, ast.ImportFrom)):
        return _import(n)
    return None


def _flags(tree: ast.AST, names: dict[str, str]) -> list[str]:
    called = {id(n.func) for n in ast.walk(tree) if isinstance(n, ast.Call)}
    out: list[str] = []
    for n in ast.walk(tree):
        what = _node(n, names, called)
        if what and what not in out:
            out.append(what)
    return out


def cookie(text: str) -> str | None:
    """The source encoding a ``.py`` file declares in its first two lines, when Python would
    decode it with something other than UTF-8, ASCII or Latin-1."""
    for line in text.split("\n", 2)[:2]:
        m = _COOKIE.match(line)
        if m:
            enc = m.group(1).lower().replace("_", "-")
            return None if enc in _PLAIN else m.group(1)
        if line.strip() and not line.lstrip().startswith("#"):
            break
    return None


def scan(places: Sequence[tuple[str, ast.AST]], files: Sequence[tuple[str, str]] = ()
         ) -> list[str]:
    """The hidden-code findings of a notebook: ``places`` are (where, syntax tree) of its cells
    and written files, ``files`` the (name, text) of the ``.py`` files it writes; each finding
    is ``"where: what"``, at most :data:`MAX_FINDINGS`."""
    names = Context(aliases(t for _, t in places))
    names.written = frozenset(n for n, _ in files if n.endswith(".py"))
    out: list[str] = []
    for name, text in files:
        enc = cookie(text)
        if enc:
            out.append(f"file {name}: declares the source encoding {enc!r} (Python decodes the "
                       f"file before it runs: what runs is not what it shows)")
    for where, tree in places:
        out += [f"{where}: {what}" for what in _flags(tree, names)]
    return out[:MAX_FINDINGS]
