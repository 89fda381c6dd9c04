"""The problems and homework a test module of this folder registers (an own problem loaded from
a file, the example's cv2d handed out or graded in-process) are forgotten after the module (its
later tests grade the homework an earlier one handed out, whose graded.py registered its problem
when imported): the registry lives as long as the pytest process, and an entry left behind changed
what later tests saw (the CLI's help lists every registered problem: tests/cli/test_front_door
failed when tests/homework ran first)."""

from __future__ import annotations

import pytest

from gpsaccel import registry


@pytest.fixture(autouse=True, scope="module")
def _registry_as_before():
    problems = set(registry.problems())          # loads the declared ones first: never forgotten
    assignments = set(registry.assignments())
    yield
    for name in set(registry._PROBLEMS) - problems:
        registry._PROBLEMS.pop(name)
        registry._INSTANCES.pop(name, None)
    for name in set(registry._ASSIGNMENTS.entries) - assignments:
        registry._ASSIGNMENTS.entries.pop(name)
