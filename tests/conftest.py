"""The whole suite's markers: ``slow`` for the tests that take more than a few seconds.

``make test`` runs everything; ``pytest -m "not slow"`` (and ``make test-fast`` on the core's
folders) leaves these out.  A test may carry ``@pytest.mark.slow`` itself; the ones below are
marked here from measured durations (``pytest --durations=40``, serial, a shared 2-core machine),
so their modules need not change: each entry is a node id prefix ("file" or "file::test").
"""

from __future__ import annotations

import pytest

SLOW: tuple[str, ...] = (
    # seconds measured serially at load 5 (tests/kalman + tests/calibration: 255 s serial)
    "tests/calibration/test_montecarlo_memory.py::test_memory_grows_linearly_with_the_duration",  # 63
    "tests/calibration/test_montecarlo_memory.py::test_an_hour_at_5_hz_fits_in_tens_of_megabytes",  # 54
    "tests/calibration/test_montecarlo.py::test_dask_cluster_gives_the_same_result",  # 21
    "tests/calibration/test_compare.py::test_sweep_",  # the sweeps' fixtures, 18
    "tests/calibration/test_compare.py::test_prior_sweep_",
    "tests/calibration/test_compare.py::test_gps_sweep_",
    "tests/calibration/test_montecarlo.py::test_cli_montecarlo_prints_the_table",  # 8
    # every one executes a notebook, renders one, or runs otter in a kernel
    "tests/test_lessons.py::test_solutions_version_runs_with_a_tick_under_every_self_check",
    "tests/test_lessons.py::test_student_version_runs_and_shows_no_answer",
    "tests/test_lesson_figures.py",
    "tests/test_cli_lessons.py::test_lessons_html",
    "tests/test_cli_lessons.py::test_lessons_kernel",
    "tests/assignments/",
)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    used: set[str] = set()
    files = set()
    for item in items:
        node = item.nodeid.replace("\\", "/")
        files.add(node.split("::")[0])
        hits = {prefix for prefix in SLOW if node.startswith(prefix)}
        if hits:
            item.add_marker(pytest.mark.slow)
            used |= hits
    # an entry whose file was collected but that marks nothing names a test that was renamed: the
    # renamed test would then run in every "not slow" run (it did: 30 lesson notebooks on 3.13)
    stale = [p for p in SLOW if p not in used and p.split("::")[0] in files and "::" in p]
    if stale:
        raise pytest.UsageError(f"tests/conftest.py SLOW names tests that do not exist: {stale}")
