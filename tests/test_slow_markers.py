"""The suite's SLOW list (tests/conftest.py): an entry naming a test that no longer exists stops the
run, so a renamed slow test cannot silently join every "not slow" run."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import SimpleNamespace

import pytest

_spec = importlib.util.spec_from_file_location("suite_conftest", Path(__file__).with_name("conftest.py"))
assert _spec is not None and _spec.loader is not None
conftest = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(conftest)


def _item(nodeid: str) -> SimpleNamespace:
    item = SimpleNamespace(nodeid=nodeid, markers=[])
    item.add_marker = item.markers.append
    return item


def test_every_entry_of_the_slow_list_marks_a_collected_test(monkeypatch):
    monkeypatch.setattr(conftest, "SLOW", ("tests/test_x.py::test_slow",))
    kept = [_item("tests/test_x.py::test_slow[a]"), _item("tests/test_x.py::test_fast")]
    conftest.pytest_collection_modifyitems(None, kept)
    assert kept[0].markers == [pytest.mark.slow] and kept[1].markers == []
    renamed = [_item("tests/test_x.py::test_other")]
    with pytest.raises(pytest.UsageError, match="test_x.py::test_slow"):
        conftest.pytest_collection_modifyitems(None, renamed)
