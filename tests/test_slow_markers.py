"""The suite's SLOW list (tests/conftest.py): an entry naming a test that no longer exists stops the
run, so a renamed slow test cannot silently join every "not slow" run; and any one test, slow or
not, runs on its own (``pytest file::test``, ``-k``) without its neighbours' entries looking stale.

Each case runs pytest (in this process) on a small test file whose conftest applies the suite's own
guard (:func:`conftest.mark_slow`, loaded from tests/conftest.py) with a SLOW list of its own.
"""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

SUITE_CONFTEST = Path(__file__).with_name("conftest.py")

TESTS = '''
import pytest

@pytest.fixture(scope="module")
def heavy():
    return 1

@pytest.fixture
def on_heavy(heavy):
    return heavy

def test_uses_heavy(on_heavy):
    pass

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
    suite.mark_slow(items, SLOW, {kept!r}, {fixtures!r})
'''

GOOD = ("test_a.py::test_slow", "test_a.py::test_sweep_", "test_a.py::TestGroup::test_inside")


@dataclass
class Run:
    returncode: int
    stdout: str
    stderr: str


@pytest.fixture
def pytest_in(monkeypatch, capsys):
    """``pytest_in(folder, slow, *args, kept=(), fixtures=())``: pytest run on ``folder`` in this
    process (a pytest process of its own cost 0.7 CPU s a case, nearly all its start-up), with
    no plugin but pytest's own and the folder's conftest; the modules it imported are forgotten
    after (``--import-mode=importlib``: this process may hold a module named ``conftest``
    already)."""

    def run(folder: Path, slow: tuple[str, ...], *args: str, kept: tuple[str, ...] = (),
            fixtures: tuple[str, ...] = ()) -> Run:
        (folder / "test_a.py").write_text(TESTS)
        (folder / "conftest.py").write_text(CONFTEST.format(path=str(SUITE_CONFTEST), slow=slow,
                                                            kept=kept, fixtures=fixtures))
        for name in [k for k in os.environ if k.startswith(("PYTEST_", "COV_"))]:
            monkeypatch.delenv(name)
        monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
        monkeypatch.chdir(folder)
        modules, path = set(sys.modules), list(sys.path)
        capsys.readouterr()
        try:
            code = pytest.main(["-q", "-p", "no:cacheprovider", "-p", "no:faulthandler",
                                "--import-mode=importlib", "--rootdir", str(folder),
                                "-c", os.devnull, *args])
        finally:
            for name in set(sys.modules) - modules:
                del sys.modules[name]
            sys.path[:] = path
        out, err = capsys.readouterr()
        return Run(int(code), out, err)

    return run


@pytest.mark.parametrize("args, passed", [
    (["test_a.py::test_slow", "-m", "slow"], 1),      # one slow test by its node id, marked slow
    (["test_a.py::TestGroup::test_inside", "-m", "slow"], 1),
    (["test_a.py::test_sweep_one[2]", "-m", "slow"], 1),
    (["test_a.py", "-k", "fast"], 1),
    (["test_a.py", "-m", "slow"], 4),
    (["test_a.py", "-m", "not slow"], 2),
])
def test_any_single_test_runs_and_the_slow_ones_are_marked(pytest_in, tmp_path, args, passed):
    res = pytest_in(tmp_path, GOOD, *args)
    assert res.returncode == 0, res.stdout + res.stderr
    assert f"{passed} passed" in res.stdout, res.stdout


@pytest.mark.parametrize("args", [["test_a.py::test_fast"], ["test_a.py", "-m", "not slow"]])
def test_an_entry_naming_a_renamed_test_stops_every_run_of_its_file(pytest_in, tmp_path, args):
    res = pytest_in(tmp_path, (*GOOD, "test_a.py::test_renamed"), *args)
    assert res.returncode == 4, res.stdout + res.stderr
    assert "SLOW names tests that do not exist: ['test_a.py::test_renamed']" in res.stderr


def test_an_entry_of_a_file_not_collected_is_not_judged(pytest_in, tmp_path):
    (tmp_path / "test_b.py").write_text("def test_b():\n    pass\n")
    res = pytest_in(tmp_path, (*GOOD, "test_a.py::test_renamed"), "test_b.py")
    assert res.returncode == 0, res.stdout + res.stderr


def test_a_kept_test_of_a_slow_kind_runs_in_the_quick_run_and_a_stale_one_stops_it(pytest_in,
                                                                                     tmp_path):
    """KEPT: the one test of a slow kind the quick run keeps (``make test``, ``-m "not
    slow"``), though a SLOW entry covers it; a kept entry naming no test stops the run, or the
    kind would silently leave the quick run."""
    slow = ("test_a.py::test_sweep_one",)
    res = pytest_in(tmp_path, slow, "test_a.py", "-m", "not slow",
                    kept=("test_a.py::test_sweep_one[2]",))
    assert res.returncode == 0 and "5 passed, 1 deselected" in res.stdout, res.stdout
    res = pytest_in(tmp_path, slow, "test_a.py", "-m", "not slow", kept=("test_a.py::test_gone",))
    assert res.returncode == 4, res.stdout + res.stderr
    assert "KEPT names tests that do not exist: ['test_a.py::test_gone']" in res.stderr


def test_a_test_on_a_slow_fixture_is_slow_however_indirectly_and_a_stale_one_stops_the_run(
        pytest_in, tmp_path):
    """SLOW_FIXTURES: a test that uses a fixture drawing a whole report, through another fixture
    too, is slow by itself; an entry naming a fixture the file does not define stops the run."""
    res = pytest_in(tmp_path, GOOD, "test_a.py", "-m", "slow", fixtures=("test_a.py::heavy",))
    assert res.returncode == 0 and "5 passed" in res.stdout, res.stdout
    res = pytest_in(tmp_path, GOOD, "test_a.py", "-m", "not slow", fixtures=("test_a.py::gone",))
    assert res.returncode == 4, res.stdout + res.stderr
    assert "SLOW_FIXTURES names fixtures that do not exist: ['test_a.py::gone']" in res.stderr
