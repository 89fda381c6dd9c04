"""Start-up stays light: what ``import gpsaccel``, the command's front door and a sandbox box load
before any work, read from ``sys.modules`` in a fresh process (no timing: the benchmark
benchmarks/startup.py measures the CPU).

filterpy pulls in scipy.stats (0.6 CPU s), mpmath and matplotlib are as heavy, and nbformat with
jsonschema 4.25+ built an RFC 3987 grammar (2 CPU s): each was paid by every CLI call, test worker
and box when the package imported them eagerly.  The public names stay reachable
(:mod:`gpsaccel._lazy`).
"""

from __future__ import annotations

import ast
import importlib
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]

#: Modules no start-up path may load (a sub-package of one counts as the package).
HEAVY = ("scipy", "filterpy", "mpmath", "matplotlib", "nbformat", "jsonschema", "rfc3987_syntax",
         "otter", "IPython", "dask", "distributed", "pandas", "sympy")

PACKAGES = ("gpsaccel", "gpsaccel.assignments", "gpsaccel.calibration", "gpsaccel.check",
            "gpsaccel.classrun", "gpsaccel.coop", "gpsaccel.kalman", "gpsaccel.ship")


def loaded_after(code: str) -> list[str]:
    """The HEAVY modules (and numpy, listed as such) in ``sys.modules`` after ``code`` runs in a
    fresh interpreter."""
    probe = (f"{code}\nimport sys, json\n"
             f"print(json.dumps(sorted({{m.split('.')[0] for m in sys.modules}} & "
             f"set({(*HEAVY, 'numpy')!r}))))")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    res = subprocess.run([sys.executable, "-c", probe], cwd=ROOT, env=env, capture_output=True,
                         text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    return json.loads(res.stdout.strip().splitlines()[-1])


def test_import_gpsaccel_loads_nothing_heavy_not_even_numpy():
    assert loaded_after("import gpsaccel") == []


@pytest.mark.parametrize("code", [
    "import gpsaccel.cli",
    "from gpsaccel.cli import build_parser; build_parser()",
    # the help texts and argument errors: the problem and homework registries are read for them
    # (tests/cli/test_front_door.py runs every sub-command's help and error as the command)
    "from gpsaccel.cli import main; main(['--help'])",
    "from gpsaccel.cli import main; main(['check', '--help'])",
    "from gpsaccel.cli import main; main(['check', 'x.py', '--runs', '0'])",
    "from gpsaccel.cli import main; main(['check', 'x.py', '--problem', 'nope'])",
    "from gpsaccel.cli import main; main(['grade', 'x', '--assignment', 'nope'])",
    "from gpsaccel.cli import main; main(['nope'])",
], ids=lambda code: code.replace(" ", "_")[-60:])
def test_the_front_door_loads_not_even_numpy(code):
    assert loaded_after(f"try:\n    {code}\nexcept SystemExit:\n    pass") == []


@pytest.mark.parametrize("code", [
    # what a student's notebook or an instructor's script types first
    "from gpsaccel import CalibrationModel, CoopModel, ShipModel, Schedule",
    "from gpsaccel.coop.model import course_ydata",
    "from gpsaccel.ship.simulation import simulate_ship",
    "from gpsaccel.calibration.simulation import simulate",
    "from gpsaccel import check",
    "import gpsaccel.check.report",
    "from gpsaccel import sandbox",
    # what an instructor's graded.py imports first (the grader loads it in the class's parent)
    "from gpsaccel import homework",
], ids=lambda code: code.replace(" ", "_")[-60:])
def test_the_first_names_load_no_heavy_module(code):
    assert set(loaded_after(f"try:\n    {code}\nexcept SystemExit:\n    pass")) <= {"numpy"}


def test_nbformat_does_not_build_the_iri_grammar():
    """pyproject.toml pins jsonschema<4.25: from 4.25 its import builds rfc3987-syntax's Lark
    grammar (2 CPU s) when that package is installed, as jupyter-events installs it."""
    pytest.importorskip("nbformat")
    assert "rfc3987_syntax" not in loaded_after("import nbformat")


# ------------------------------------------------------------------------------ the public names
def _type_checking_names(package: str) -> set[str]:
    """The names imported under ``if TYPE_CHECKING:`` in ``package``'s ``__init__`` (what mypy and
    editors see)."""
    spec = importlib.util.find_spec(package)
    assert spec is not None and spec.origin is not None
    tree = ast.parse(Path(spec.origin).read_text(encoding="utf-8"))
    names: set[str] = set()
    for node in tree.body:
        if isinstance(node, ast.If) and getattr(node.test, "id", None) == "TYPE_CHECKING":
            for sub in ast.walk(node):
                if isinstance(sub, ast.ImportFrom):
                    names |= {a.asname or a.name for a in sub.names}
    return names


@pytest.mark.parametrize("package", PACKAGES)
def test_every_public_name_resolves_and_is_what_mypy_sees(package):
    module = importlib.import_module(package)
    assert set(module.__all__) == _type_checking_names(package)
    for name in module.__all__:
        value = getattr(module, name)
        assert value is not None and name in dir(module)
        assert getattr(module, name) is value  # resolved once, then an ordinary attribute
    with pytest.raises(AttributeError, match="has no attribute 'no_such_name'"):
        module.no_such_name  # noqa: B018


def test_a_function_named_like_its_module_stays_the_function_after_the_module_is_imported():
    """``import gpsaccel.check.student_filter`` binds the sub-module on the package; the public
    name of the same name (the function) must win, as it did when the package was eager (the
    CLI's ``compare`` called the module and failed)."""
    code = ("import gpsaccel.check.student_filter, gpsaccel.check.jacobians, gpsaccel.check.dt_model\n"
            "from gpsaccel.check import student_filter, jacobians, dt_model\n"
            "import gpsaccel.check as c\n"
            "assert callable(student_filter) and callable(jacobians), (student_filter, jacobians)\n"
            "assert callable(dt_model) and c.dt_model is dt_model, dt_model\n"
            "assert c.student_filter is student_filter\n"
            "assert c.student_filter.__module__ == 'gpsaccel.check.student_filter'\n")
    loaded_after(code)  # asserts the subprocess exits 0


def test_sub_modules_stay_reachable_as_attributes_and_star_import_works():
    import gpsaccel

    assert gpsaccel.check.batch.__name__ == "gpsaccel.check.batch"
    assert gpsaccel.sandbox.__name__ == "gpsaccel.sandbox"
    assert gpsaccel.kalman.consistency.chi2_bounds(2)[0] > 0
    namespace: dict = {}
    exec("from gpsaccel.check import *", namespace)
    assert {"Report", "submission", "codes"} <= set(namespace)
    assert gpsaccel.CalibrationModel().kalman_filter().F.shape == (3, 3)  # filterpy, when used


# ------------------------------------------------------------------------------ inside the boxes
def test_a_checker_box_loads_only_numpy_before_the_students_file(tmp_path):
    """The checker's runner imports the standard library and numpy, then the student's file: a
    submission that reports what is loaded when it is imported sees nothing heavy."""
    from gpsaccel import sandbox as sb

    (tmp_path / "probe.py").write_text(
        "import sys\n"
        f"print('LOADED', sorted({{m.split('.')[0] for m in sys.modules}} & set({HEAVY!r})))\n"
        "def f(x):\n    return x\n")
    call = sb.Call("f", (np.zeros(2),), (sb.Output("y", (2,)),))
    box = sb.run(sb.load_submission(tmp_path / "probe.py", "f"), [call],
                 sb.Limits(memory=1 << 30, time=60))
    assert box.failure is None, box.detail
    assert "LOADED []" in box.output, box.output


def test_a_notebook_box_loads_only_what_the_students_cells_import(tmp_path):
    """The grader's box: the prelude imports nothing heavy, ``import gpsaccel`` and the models
    load neither filterpy nor scipy.stats, and otter's init and check cells find a stand-in
    instead of otter (IPython, nbformat, jsonschema: 1.5–4.5 CPU s per notebook)."""
    from gpsaccel import sandbox as sb
    from gpsaccel.assignments import notebook as nbm
    from gpsaccel.assignments.scoring import _calls

    probe = ("import sys\n"
             f"print('LOADED', sorted({{m.split('.')[0] for m in sys.modules}} & set({HEAVY!r})))")
    sources = ['# Initialize Otter\nimport otter\ngrader = otter.Notebook("hw.ipynb")',
               'import gpsaccel\nfrom gpsaccel import CalibrationModel, CoopModel, ShipModel',
               'grader.check("q1")', probe]
    nb = nbm.Notebook([nbm.Cell(i + 1, s) for i, s in enumerate(sources)])
    (tmp_path / "notebook.py").write_text(nbm.module_source(nb, []), encoding="utf-8")
    box = sb.run(sb.load_submission(tmp_path / "notebook.py", "_gpsaccel_cell"),
                 _calls(len(sources), []), sb.Limits(memory=2 << 30, time=60), allow_gpsaccel=True)
    assert box.failure is None, box.detail
    statuses = [int(r["status"][0]) for r in box.results]
    assert statuses == [nbm.STATUSES.index("ok")] * len(sources), [
        bytes(r["message"]).rstrip(b"\0") for r in box.results]
    assert "LOADED ['otter']" in box.output, box.output  # otter: the stand-in, nothing under it
