"""The suite's SLOW list (tests/conftest.py): an entry naming a test that no longer exists stops the
run, so a renamed slow test cannot silently join every "not slow" run; and any one test, slow or
not, runs on its own (``pytest file::test``, ``-k``) without its neighbours' entries looking stale.

Each case runs pytest in a subprocess on a small test file whose conftest applies the suite's own
guard (:func:`conftest.mark_slow`, loaded from tests/conftest.py) with a SLOW list of its own.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

SUITE_CONFTEST = Path(__file__).with_name("conftest.py")

TESTS = '''
import pytest

def test_slow():
    pass

@pytest.mark.parametrize("n", [1, 2])
def test_sweep_one(n):
    pass

def test_fast():
    pass

class TestGroup:
    def test_inside(self):
        pass
'''

CONFTEST = '''
import importlib.util
import pytest

_spec = importlib.util.spec_from_file_location("suite_conftest", {path!r})
suite = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(suite)

SLOW = {slow!r}

def pytest_configure(config):
    config.addinivalue_line("markers", "slow: slow")

@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    suite.mark_slow(items, SLOW)
'''

GOOD = ("test_a.py::test_slow", "test_a.py::test_sweep_", "test_a.py::TestGroup::test_inside")


def pytest_in(folder: Path, slow: tuple[str, ...], *args: str) -> subprocess.CompletedProcess:
    (folder / "test_a.py").write_text(TESTS)
    (folder / "conftest.py").write_text(CONFTEST.format(path=str(SUITE_CONFTEST), slow=slow))
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTEST_", "COV_"))}
    env["PYTEST_DISABLE_PLUGIN_AUTOLOAD"] = "1"  # hypothesis's plugin alone costs 1 CPU s a run
    return subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                           "--rootdir", str(folder), "-c", os.devnull, *args],
                          cwd=folder, env=env, capture_output=True, text=True, timeout=120)


@pytest.mark.parametrize("args, passed", [
    (["test_a.py::test_slow", "-m", "slow"], 1),      # one slow test by its node id, marked slow
    (["test_a.py::TestGroup::test_inside", "-m", "slow"], 1),
    (["test_a.py::test_sweep_one[2]", "-m", "slow"], 1),
    (["test_a.py", "-k", "fast"], 1),
    (["test_a.py", "-m", "slow"], 4),
])
def test_any_single_test_runs_and_the_slow_ones_are_marked(tmp_path, args, passed):
    res = pytest_in(tmp_path, GOOD, *args)
    assert res.returncode == 0, res.stdout + res.stderr
    assert f"{passed} passed" in res.stdout, res.stdout


@pytest.mark.parametrize("args", [["test_a.py::test_fast"], ["test_a.py", "-m", "not slow"]])
def test_an_entry_naming_a_renamed_test_stops_every_run_of_its_file(tmp_path, args):
    res = pytest_in(tmp_path, (*GOOD, "test_a.py::test_renamed"), *args)
    assert res.returncode == 4, res.stdout + res.stderr
    assert "SLOW names tests that do not exist: ['test_a.py::test_renamed']" in res.stderr


def test_an_entry_of_a_file_not_collected_is_not_judged(tmp_path):
    (tmp_path / "test_b.py").write_text("def test_b():\n    pass\n")
    res = pytest_in(tmp_path, (*GOOD, "test_a.py::test_renamed"), "test_b.py")
    assert res.returncode == 0, res.stdout + res.stderr
