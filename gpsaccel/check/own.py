"""An instructor's own problem, from a Python file of their own: ``FILE.py:NAME``.

``gpsaccel check --problem problems.py:cv2d`` runs ``problems.py`` (the instructor's file, in the
checker's own process, as whoever runs the command: trusted code, never a student's; why not in a
box: docs/checker.md) and uses its problem ``cv2d``: one the file
registered (``check.Problem.linear("cv2d", ...)`` registers itself) or a module-level variable
``cv2d`` holding a :class:`~gpsaccel.check.problem.Problem`.  From then on it is a registered
problem like the package's: the same sandbox, catalogue and feedback; nothing in the package is
edited.  The checks run in processes forked from this one, which know the problem; a Dask
worker would not (``--dask`` refuses a problem from a file).
"""

from __future__ import annotations

import importlib.util
import re
import sys
import types
from pathlib import Path

from gpsaccel import registry
from gpsaccel.registry import is_file_spec


def load_module(path: Path, prefix: str = "gpsaccel_problems") -> types.ModuleType:
    """Run the instructor's file ``path`` once as a module (kept in :data:`sys.modules`, so a
    forked child and pickling find it)."""
    path = path.expanduser().resolve()
    key = f"{prefix}_{re.sub(r'[^0-9A-Za-z_]', '_', path.stem)}_{abs(hash(str(path))):x}"
    if key in sys.modules:
        return sys.modules[key]
    spec = importlib.util.spec_from_file_location(key, path)
    if spec is None or spec.loader is None:
        raise ValueError(f"{path} is not a Python file")
    module = importlib.util.module_from_spec(spec)
    sys.modules[key] = module
    try:
        spec.loader.exec_module(module)
    except Exception:
        del sys.modules[key]
        raise
    return module


def load_problem(value: str) -> str:
    """The registered name of problem ``FILE.py:NAME`` (the file run, its problem registered);
    a registered name is returned as given.  ValueError naming what is wrong."""
    if not is_file_spec(value):
        if value not in registry.problems():
            raise ValueError(f"problem must be one of {', '.join(registry.problems())} or "
                             f"FILE.py:NAME (a problem of your own), got {value!r}")
        return value
    from gpsaccel.check.problems import Problem

    file, _, name = value.rpartition(":")
    path = Path(file)
    if not path.is_file():
        raise ValueError(f"problem: {file} is not a file (expected FILE.py:NAME)")
    if not name:
        raise ValueError(f"problem: {value!r} names no problem after the colon (FILE.py:NAME)")
    before = set(registry.problems())
    module = load_module(path, "gpsaccel_problems")
    found = getattr(module, name, None)
    if isinstance(found, Problem):
        if found.name not in registry.problems():
            registry.add_problem(found.name, lambda: found, system=found.name,
                                 title=getattr(found, "title", ""), replace=True)
        return found.name
    if name in registry.problems():
        return name
    made = dict.fromkeys([*sorted(set(registry.problems()) - before),
                          *(v.name for v in vars(module).values() if isinstance(v, Problem))])
    raise ValueError(f"problem: {file} defines no problem {name!r} (it defines "
                     f"{', '.join(made) or 'none'}: a check.Problem.linear(...) call or a "
                     f"variable holding a Problem)")
