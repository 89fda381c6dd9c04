"""The registry of homework problems (and the systems they check), filled where each is defined.

A module that defines a problem registers it when imported::

    from gpsaccel import registry
    registry.add_problem("coop", CoopProblem, system="coop", title="Report 002: ...")

and everything that lists problems reads the registry instead of a literal tuple: the CLI's
``--problem`` choices (``gpsaccel check``), :func:`gpsaccel.check.batch.check_many`,
:func:`gpsaccel.check.submission`, the tests (and the homework generator).  The registry imports
nothing of the package itself (it sits with the infrastructure): the modules that fill it are
named in :data:`PROVIDERS` and imported, by name, the first time a list is asked for.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass

#: Modules that register problems when imported (a new problem module: one line here).
PROVIDERS = ("gpsaccel.check.whole_filter", "gpsaccel.check.problems", "gpsaccel.check.tracker")


@dataclass(frozen=True)
class ProblemEntry:
    """A registered problem: its name, the system it checks, a title, and a factory."""

    name: str
    factory: Callable[[], object]
    system: str = ""
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
        _loaded = True
        for module in PROVIDERS:
            importlib.import_module(module)


def problems() -> tuple[str, ...]:
    """The names of every registered problem: those of :data:`PROVIDERS` in its order, then the
    others (an instructor's) in the order they were registered."""
    _load()

    def rank(e: ProblemEntry) -> int:
        module = getattr(e.factory, "__module__", "")
        return PROVIDERS.index(module) if module in PROVIDERS else len(PROVIDERS)

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


def systems() -> tuple[str, ...]:
    """The systems that registered problems check, in order."""
    _load()
    return tuple(dict.fromkeys(e.system for e in _PROBLEMS.values() if e.system))
