"""How ``make test`` shares the suite between its workers (tests/conftest.py): the work units
under ``--dist loadgroup`` and the costliest first."""

from __future__ import annotations

import importlib.util
from pathlib import Path

_spec = importlib.util.spec_from_file_location("suite_conftest", Path(__file__).parent / "conftest.py")
suite = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(suite)


def test_a_unit_is_the_module_or_class_as_loadscope_has_it():
    assert suite.work_unit("tests/a.py::test_f") == "tests/a.py"
    assert suite.work_unit("tests/a.py::test_f[1-x]") == "tests/a.py"
    assert suite.work_unit("tests/a.py::TestC::test_m[2]") == "tests/a.py::TestC"


def test_a_split_module_has_a_unit_per_parameter_shared_by_its_tests():
    split = ("tests/test_lessons.py",)
    one = suite.work_unit("tests/test_lessons.py::test_solutions[03-x]", split)
    assert one == suite.work_unit("tests/test_lessons.py::test_student[03-x]", split)
    assert one != suite.work_unit("tests/test_lessons.py::test_student[04-y]", split)
    assert suite.work_unit("tests/test_lessons.py::test_count", split) == "tests/test_lessons.py"


def test_the_costliest_come_first_in_the_listed_order():
    first = ("tests/b.py", "tests/a/")
    ids = ["tests/c.py::t", "tests/a/x.py::t", "tests/b.py::t2", "tests/b.py::t1"]
    assert sorted(ids, key=lambda n: suite.first_rank(n, first)) == \
        ["tests/b.py::t2", "tests/b.py::t1", "tests/a/x.py::t", "tests/c.py::t"]


def test_every_first_entry_names_a_test_file_or_folder():
    root = Path(__file__).resolve().parent.parent
    assert all((root / p).exists() for p in suite.FIRST + suite.SPLIT), \
        [p for p in suite.FIRST + suite.SPLIT if not (root / p).exists()]
