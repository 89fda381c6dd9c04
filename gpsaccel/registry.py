"""The registry of homework problems (and the systems they check), the homework assignments and
the course reports' figures, each filled where it is defined.

A module that defines a problem registers it when imported::

    from gpsaccel import registry
    registry.add_problem("coop", CoopProblem, system="coop", title="Report 002: ...")

and everything that lists problems reads the registry instead of a literal tuple: the CLI's
``--problem`` choices (``gpsaccel check``), :func:`gpsaccel.classrun.check_many`,
:func:`gpsaccel.check.submission`, the tests (and the homework generator).  The same for the
homework (:func:`add_assignment` in ``gpsaccel/assignments/NAME.py``: the CLI's
``assignment``/``grade`` choices, the generator, the grader) and the reports (:func:`add_report` in
``gpsaccel/figures/rNNN.py``: ``gpsaccel figures``, the lessons' index of which lesson shows which
figure, the tests).

The registry sits on the ground floor and names no module above it.  The package that owns a kind
declares, when it is imported, which of its modules register entries of that kind
(:func:`provide`: ``gpsaccel.problems`` the problems, with their titles, ``gpsaccel.assignments`` its
homework, ``gpsaccel.figures`` its reports); those modules are imported, by name, the first time a
list of the kind is asked for.  Whatever imports a module of the owning package has run its
``__init__`` and so the declaration.  Each kind is loaded on its own, so asking for the problems
does not import matplotlib.  The command's help and choices list the problems and the homework
without importing any (:func:`problem_titles`, :func:`assignment_names`): its answer must not wait
for numpy.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass

#: The kinds of entry and the word their errors use.
KINDS = ("problem", "assignment", "report")

#: Kind -> the modules that register entries of it when imported, in order (declared by the
#: package that owns the kind: :func:`provide`).
_PROVIDED: dict[str, tuple[str, ...]] = {}

#: Problem name -> title of the package's own problems, declared with their modules: what lists
#: them before any is imported (the command's help and ``--problem`` choices).
_TITLES: dict[str, str] = {}


def provide(kind: str, modules: tuple[str, ...], *, titles: Mapping[str, str] | None = None
            ) -> None:
    """Declare the modules that register entries of ``kind`` (one of :data:`KINDS`) when imported,
    in the order they are listed.  Called when the package that owns the kind is imported (its
    ``__init__``, or for the problems ``gpsaccel/problems.py``, which ``gpsaccel.check`` imports);
    ``titles`` (problems only) are the titles of its problems, each named as its module (the last
    part of the dotted name), the one place each title is written."""
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    names = [m.rpartition(".")[2] for m in modules]
    if titles is not None and list(titles) != names:
        raise ValueError(f"titles must name the {kind} modules in their order {names}, got "
                         f"{list(titles)}")
    _PROVIDED[kind] = tuple(modules)
    if titles is not None:
        _TITLES.update(titles)


def providers(kind: str) -> tuple[str, ...]:
    """The modules declared for ``kind`` (:func:`provide`); LookupError when no package has
    declared them yet (the owning package declares them when imported: a lookup before that would
    silently list nothing)."""
    if kind not in _PROVIDED:
        raise LookupError(f"no package has declared its {kind} modules yet: the package that owns "
                          f"the {kind}s declares them (registry.provide) when it is imported")
    return _PROVIDED[kind]


@dataclass(frozen=True)
class ProblemEntry:
    """A registered problem: its name, the system it checks, a title, and a factory."""

    name: str
    factory: Callable[[], object]
    system: str = ""
    title: str = ""


@dataclass(frozen=True)
class AssignmentEntry:
    """A registered homework: its name (the master is ``assignments/NAME/NAME.ipynb``), the
    module that registered it, the system it is about, the checker's problem whose catalogue
    grades its filter question (if any), and a title."""

    name: str
    module: str
    system: str = ""
    problem: str = ""
    title: str = ""


@dataclass(frozen=True)
class ReportEntry:
    """A registered course report: its number ("000"), the module that draws its figures
    (``TITLE``, ``DEFAULT_RUNS``, ``figures(runs, seed)``: :mod:`gpsaccel.figures`), and the
    figures the report lists, numbered as it numbers them ("1", "3b", "10"): the ones a lesson
    must walk through."""

    report: str
    module: str
    figures: tuple[str, ...]
    title: str = ""


_PROBLEMS: dict[str, ProblemEntry] = {}
_INSTANCES: dict[str, object] = {}
_loaded = False


def add_problem(name: str, factory: Callable[[], object], *, system: str = "", title: str = "",
                replace: bool = False) -> None:
    """Register the problem ``name`` (its instance is made by ``factory()`` on first use)."""
    if not isinstance(name, str) or not name or not name.replace("-", "").isalnum() or \
            name != name.lower():
        raise ValueError(f"name must be lower-case letters, digits and dashes, got {name!r}")
    if name in _PROBLEMS and not replace:
        raise ValueError(f"name: a problem {name!r} is already registered (replace=True to "
                         f"redefine it)")
    _PROBLEMS[name] = ProblemEntry(name, factory, system, title)
    _INSTANCES.pop(name, None)


def _load() -> None:
    global _loaded
    if not _loaded:
        modules = providers("problem")
        _loaded = True
        for module in modules:
            importlib.import_module(module)


def problems() -> tuple[str, ...]:
    """The names of every registered problem: those of the declared modules in their order, then
    the others (an instructor's) in the order they were registered."""
    _load()
    modules = providers("problem")

    def rank(e: ProblemEntry) -> int:
        module = getattr(e.factory, "__module__", "")
        return modules.index(module) if module in modules else len(modules)

    return tuple(e.name for e in sorted(_PROBLEMS.values(), key=rank))


def entry(name: str) -> ProblemEntry:
    """The registered entry of problem ``name``; ValueError naming the choices otherwise."""
    _load()
    if name not in _PROBLEMS:
        raise ValueError(f"problem must be one of {', '.join(_PROBLEMS)}, got {name!r}")
    return _PROBLEMS[name]


def problem(name: str) -> object:
    """The problem ``name`` (one instance per name, made on first use)."""
    e = entry(name)
    if name not in _INSTANCES:
        _INSTANCES[name] = e.factory()
    return _INSTANCES[name]


def problem_titles() -> dict[str, str]:
    """Name -> title of every problem, importing none (what the command's help shows): the
    package's own (declared with their modules: :func:`provide`), then those registered in this
    process (an instructor's); an entry registered here gives its own title."""
    providers("problem")  # LookupError before the owning package declared its problems
    titles = dict(_TITLES)
    titles.update((e.name, e.title) for e in _PROBLEMS.values())
    return titles


def is_file_spec(value: str) -> bool:
    """Whether ``value`` names a problem in a file of one's own (``path/to/file.py:NAME``) rather
    than a registered one (:func:`gpsaccel.check.own.load_problem` runs the file)."""
    path, sep, _ = value.rpartition(":")
    return bool(sep) and path.endswith(".py")


def systems() -> tuple[str, ...]:
    """The systems that registered problems check, in order."""
    _load()
    return tuple(dict.fromkeys(e.system for e in _PROBLEMS.values() if e.system))


# ------------------------------------------------------------------ homework and reports
class _Table:
    """One kind of registered entry (homework, reports): entries by key, filled by importing the
    kind's declared modules (:func:`provide`), by name, the first time a list is asked for."""

    def __init__(self, what: str) -> None:
        self.what = what
        self.entries: dict[str, object] = {}
        self.loaded = False

    def add(self, key: str, entry: object) -> None:
        """Register ``entry`` under ``key``; the same entry again is harmless (a module imported
        twice), a different one under a taken key is refused."""
        if self.entries.get(key, entry) != entry:
            raise ValueError(f"{self.what}: {key!r} is already registered")
        self.entries[key] = entry

    def names(self) -> tuple[str, ...]:
        """Every key: those registered by the declared modules in their order, then any other."""
        modules = providers(self.what)
        if not self.loaded:
            self.loaded = True  # first, so a provider that lists its kind does not recurse
            try:
                for module in modules:
                    importlib.import_module(module)
            except BaseException:
                self.loaded = False
                raise

        def rank(key: str) -> int:
            module = getattr(self.entries[key], "module", "")
            return modules.index(module) if module in modules else len(modules)

        return tuple(sorted(self.entries, key=rank))

    def get(self, key: str) -> object:
        names = self.names()
        if key not in names:
            raise ValueError(f"{self.what} must be one of {', '.join(names)}, got {key!r}")
        return self.entries[key]


_ASSIGNMENTS = _Table("assignment")
_REPORTS = _Table("report")


def add_assignment(name: str, module: str, *, system: str = "", problem: str = "",
                   title: str = "") -> None:
    """Register the homework ``name``: ``module`` (``gpsaccel.assignments.NAME``) calls this when
    imported, with its ``__name__``."""
    if not isinstance(name, str) or not name or not name.replace("-", "").isalnum() or \
            name != name.lower():
        raise ValueError(f"name must be lower-case letters, digits and dashes, got {name!r}")
    _ASSIGNMENTS.add(name, AssignmentEntry(name, module, system, problem, title))


def assignments() -> tuple[str, ...]:
    """The names of every registered homework, in the declared modules' order."""
    return _ASSIGNMENTS.names()


def assignment_names() -> tuple[str, ...]:
    """The names of every homework, importing none (the command's choices): the package's own,
    each named as its declared module, then any registered in this process (an instructor's
    folder)."""
    own = tuple(module.rpartition(".")[2] for module in providers("assignment"))
    return own + tuple(name for name in _ASSIGNMENTS.entries if name not in own)


def assignment(name: str) -> AssignmentEntry:
    """The registered homework ``name``; ValueError naming the choices otherwise."""
    return _ASSIGNMENTS.get(name)  # type: ignore[return-value]


def add_report(report: str, module: str, figures: tuple[str, ...], *, title: str = "") -> None:
    """Register course report ``report`` ("000"): ``module`` draws its figures, ``figures`` are
    the numbers the report lists ("1", "3b", ...).  Called by the figure module when imported."""
    if not (isinstance(report, str) and len(report) == 3 and report.isdigit()):
        raise ValueError(f"report must be three digits such as '000', got {report!r}")
    numbers = tuple(figures)
    if not numbers or not all(isinstance(n, str) and n[:1].isdigit() and n[0] != "0"
                              for n in numbers):
        raise ValueError(f"figures must be the report's figure numbers as it writes them "
                         f"('1', '3b', ...), got {figures!r}")
    _REPORTS.add(report, ReportEntry(report, module, numbers, title))


def reports() -> tuple[str, ...]:
    """Every registered report, in reading order (the declared modules' order)."""
    return _REPORTS.names()


def report(number: str) -> ReportEntry:
    """The registered report ``number``; ValueError naming the choices otherwise."""
    return _REPORTS.get(number)  # type: ignore[return-value]


def report_figures() -> dict[str, tuple[str, ...]]:
    """Report -> the figures it lists (what the lessons must walk through)."""
    return {r: report(r).figures for r in reports()}
