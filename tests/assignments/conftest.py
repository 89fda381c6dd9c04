"""Shared tools for the homework tests: variants of a solved notebook, one graded class per module.

Grading a notebook costs a Jupyter kernel (~5-20 s on a loaded 2-core machine), so each test
module generates its assignment once, grades all its notebooks in one parallel ``grade`` call
(module-scoped fixture) and the tests read that one result.
"""

from __future__ import annotations

import csv
from pathlib import Path

import nbformat
import pytest

try:  # the assignments extra (otter-grader); the test extra installs it
    import otter  # noqa: F401
except ImportError:  # pragma: no cover
    collect_ignore_glob = ["test_*.py"]


def variant(solution: Path, target: Path, edits: list[tuple[str, str]],
            extra_first_cell: str | None = None) -> Path:
    """A copy of the solved notebook with each ``(old, new)`` replaced once in the code cells.

    Fails when ``old`` is not found exactly once (the master changed: update the test).
    """
    nb = nbformat.read(str(solution), as_version=4)
    for old, new in edits:
        hits = [c for c in nb.cells if c.cell_type == "code" and old in c.source]
        assert len(hits) == 1, f"{old!r} found in {len(hits)} code cells of {solution.name}"
        assert hits[0].source.count(old) == 1, f"{old!r} found twice in one cell"
        hits[0].source = hits[0].source.replace(old, new)
    if extra_first_cell is not None:  # after otter's init cell
        nb.cells.insert(1, nbformat.v4.new_code_cell(extra_first_cell))
    nbformat.write(nb, str(target))
    return target


def read_csv(path: Path) -> dict[str, dict[str, str]]:
    with open(path, newline="", encoding="utf-8") as f:
        return {row["submission"]: row for row in csv.DictReader(f)}


@pytest.fixture(scope="module")
def make_variant():
    return variant


@pytest.fixture(scope="module")
def read_grades():
    return read_csv
