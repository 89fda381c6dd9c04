"""Generated API pages of modules that no longer exist, removed before Sphinx reads them.

autosummary writes ``docs/api/generated/<name>.rst`` for every module it documents and never
removes one: a checkout that built the docs before a module was renamed keeps the old module's
page, which ``sphinx -W`` then fails on ("failed to import", "document isn't included in any
toctree").  :func:`remove_stale_pages` removes only such pages (``*.rst`` directly in that folder
whose name is neither a module nor an object of one), so every other page keeps its time stamp
and an incremental build stays incremental; autosummary writes again whatever it still needs.
"""

from __future__ import annotations

import importlib
import importlib.util
from pathlib import Path


def findable(name: str) -> bool:
    """Whether ``name`` is a module that exists (found, not imported) or an attribute of one
    (``pkg.module.Class.method``).  A module that exists but fails to import counts as found:
    its page stays, and Sphinx says what is wrong with it.  A folder with no ``__init__.py`` (a
    namespace package: what a removed package leaves behind with its ``__pycache__``) does not."""
    parts = name.split(".")
    for i in range(len(parts), 0, -1):
        module = ".".join(parts[:i])
        try:
            spec = importlib.util.find_spec(module)
        except ModuleNotFoundError as exc:  # this name, or a package above it, is missing
            if exc.name is not None and (module + ".").startswith(exc.name + "."):
                continue
            return True
        except Exception:  # a package above it failed to import: not this function's to judge
            return True
        if spec is None or spec.origin is None:
            continue
        if i == len(parts):
            return True
        try:
            obj = importlib.import_module(module)
        except Exception:
            return True
        for attr in parts[i:]:
            try:
                obj = getattr(obj, attr)
            except Exception:
                return False
        return True
    return False


def remove_stale_pages(folder: Path) -> list[Path]:
    """Remove the pages of ``folder`` (``*.rst`` in it, not below) whose name is not
    :func:`findable`; return them.  Nothing else in ``folder`` is touched."""
    stale = sorted(p for p in Path(folder).glob("*.rst") if p.is_file() and not findable(p.stem))
    for page in stale:
        page.unlink()
    return stale
