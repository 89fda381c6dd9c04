"""A package's public names imported on first use (PEP 562), so importing it costs nothing.

``import gpsaccel`` used to import every system, and with them filterpy, scipy.stats and mpmath
(their price: ``benchmarks/imports.py``), paid by every CLI call, every test worker and every
sandbox box.  A package's ``__init__`` now lists where each public name lives and lets
:func:`attach` import it when it is first read (``gpsaccel.CalibrationModel``, ``from
gpsaccel.check import submission``)::

    __getattr__, __dir__ = _lazy.attach(__name__, submodules=("model",),
                                        attributes={"model": ("CalibrationModel",)})

The same names are imported under ``typing.TYPE_CHECKING`` in that ``__init__`` for mypy and
editors; tests/test_lazy_imports.py checks that both lists agree and that every name resolves.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
import types
from collections.abc import Callable, Iterable, Mapping
from typing import Any


def attach(package: str, submodules: Iterable[str] = (),
           attributes: Mapping[str, Iterable[str]] | None = None,
           ) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``(__getattr__, __dir__)`` for ``package``: ``submodules`` (names relative to it, or
    absolute ``gpsaccel.…``) are imported when read, as is any other sub-module of ``package``
    (listed or not); ``attributes[module]`` are names read from ``module`` (relative or absolute)
    when first asked for.  A resolved name is stored in the package's namespace, so the hook
    runs once per name."""
    where: dict[str, tuple[str, str | None]] = {}
    for name in submodules:
        where[name.rsplit(".", 1)[-1]] = (_absolute(package, name), None)
    for module, names in (attributes or {}).items():
        for name in names:
            where[name] = (_absolute(package, module), name)

    def __getattr__(name: str) -> Any:
        if name not in where:
            # any other sub-module, as the eager package made them reachable (``check.batch``
            # after ``from gpsaccel import check``)
            if name.startswith("__") or "." in name \
                    or importlib.util.find_spec(f"{package}.{name}") is None:
                raise AttributeError(f"module {package!r} has no attribute {name!r}")
            where[name] = (f"{package}.{name}", None)
        module_name, attribute = where[name]
        module = importlib.import_module(module_name)
        value = module if attribute is None else getattr(module, attribute)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(where))

    class _Package(types.ModuleType):
        """Importing ``package.name`` binds the sub-module as ``package.name``; where a public
        name is a function of the same name in it (``check.student_filter``), the eager package
        rebound the function after the import, so the function is what ``package.name`` stays."""

        def __setattr__(self, name: str, value: Any) -> None:
            entry = where.get(name)
            if (entry is not None and entry[1] is not None and isinstance(value, types.ModuleType)
                    and value.__name__ == f"{package}.{name}"):
                return
            super().__setattr__(name, value)

    sys.modules[package].__class__ = _Package
    return __getattr__, __dir__


def _absolute(package: str, name: str) -> str:
    return name if name.startswith("gpsaccel.") or name == "gpsaccel" else f"{package}.{name}"
