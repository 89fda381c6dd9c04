"""The hostile fixtures of tests/_hostile.py for the checker's tests: ``backend`` (test_batch.py,
test_student_filter.py), ``hostile`` and ``watch``, and the machine-wide lock test_batch.py holds
with the sandbox's hostile modules (tests/sandbox/); :func:`keeping_answers`, a problem that
computes its reference answers once for a whole test module; and ``warm_boxes``, the course's
zygote serving a module's boxes."""

from __future__ import annotations

import copy

import pytest

from gpsaccel.check import problems
from gpsaccel.check.problem import Problem
from gpsaccel.sandbox import zygote

from .._hostile import (  # noqa: F401 - a conftest's names are its fixtures and hooks
    _one_hostile_module_at_a_time,
    backend,
    hostile,
    pytest_generate_tests,
    watch,
    zygotes,
)


def keeping_answers(problem: str | Problem) -> Problem:
    """A copy of the problem ``problem`` (a registered name, or a problem object) whose
    ``forget()`` keeps its cached reference answers, for the tests that check many trusted
    fixtures on the same data.

    A check drops every cached answer before the student's box starts (so none is in the
    checker's memory while student code runs) and computes the reference and each catalogue
    mistake again after it: 6-9 CPU s of a coop check, 2 of a calibration one.  The answers are
    a function of the simulated cases alone (cached on their seed and size, or on nothing: a
    linear problem's candidate covariances), so a module's checks share them here and get the
    same reports; the order itself (box, then answer) is held by
    test_calibration.py::test_the_answer_is_computed_only_after_the_box_is_empty, and every
    test that checks through the registered problem (``problem="coop"``) still forgets.  The copy
    shares the original's caches: the original's ``forget()`` empties them, which only costs a
    recomputation.
    """
    kept = copy.copy(problems.get(problem))
    kept.forget = lambda: None  # type: ignore[method-assign]
    return kept


@pytest.fixture(scope="session")
def course_zygote():
    """One zygote of the course's imports (numpy, scipy.stats, filterpy) for the session's
    catalogue modules, as a class's check starts one (None where boxes cannot start warm)."""
    if not zygote.usable():
        yield None
        return
    z = zygote.start(zygote.Warm())
    yield z
    zygote.stop(z)


@pytest.fixture(scope="module")
def warm_boxes(course_zygote):
    """The module's boxes start warm (``pytestmark = pytest.mark.usefixtures("warm_boxes")``).

    For the modules that check one fixture after another for its catalogue code (each file still
    in a box of its own, confined as a cold one, and given the same report: tests/sandbox's
    test_zygote compares a warm box with a cold one field by field): the box's start, a Python
    with numpy, filterpy and scipy.stats imported, is paid once for the session instead of once
    per check.  Every test that checks a class or a file through the command, or a hostile file, starts its
    boxes cold, as before (test_batch.py, test_folders.py, test_problem.py)."""
    if course_zygote is None:
        yield None
        return
    with zygote.serve(course_zygote):
        yield course_zygote
