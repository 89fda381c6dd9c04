"""Shared tools for the homework tests: notebooks made from the masters, a class folder.

A *solved* notebook is what an honest student hands in: the master's markdown and code cells with
the solutions in, the otter cells (question, solution and test markers) and the test cells out.
Variants of it are made by replacing text in its code cells, so each hostile or mistaken notebook
differs from an honest one by exactly what the test is about.
"""

from __future__ import annotations

import csv
import os
import signal
from pathlib import Path

import nbformat
import pytest

from gpsaccel.assignments.generate import master_notebook

_MARKERS = ("# BEGIN SOLUTION", "# END SOLUTION")


def solved(name: str) -> nbformat.NotebookNode:
    """The master of homework ``name`` as an honest student's notebook."""
    nb = nbformat.read(str(master_notebook(name)), as_version=4)
    cells, in_tests = [], False
    for c in nb.cells:
        first = c.source.strip().splitlines()[0] if c.source.strip() else ""
        if c.cell_type == "raw":
            in_tests = {"# BEGIN TESTS": True, "# END TESTS": False}.get(first, in_tests)
            continue
        if in_tests:
            continue
        if c.cell_type == "code":
            lines = [ln.replace("  # SOLUTION", "") for ln in c.source.splitlines()
                     if ln.strip() not in _MARKERS]
            c = nbformat.v4.new_code_cell("\n".join(lines))
        cells.append(c)
    nb.cells = cells
    return nb


def write_variant(name: str, target: Path, edits: list[tuple[str, str]] = (),
                  first_cell: str | None = None, last_cell: str | None = None) -> Path:
    """The solved notebook with each ``(old, new)`` replaced once in its code cells (a test
    fails loudly when ``old`` is not found exactly once: the master changed)."""
    nb = solved(name)
    for old, new in edits:
        hits = [c for c in nb.cells if c.cell_type == "code" and old in c.source]
        assert len(hits) == 1, f"{old!r} found in {len(hits)} code cells of {name}"
        hits[0].source = hits[0].source.replace(old, new, 1)
    if first_cell is not None:
        nb.cells.insert(0, nbformat.v4.new_code_cell(first_cell))
    if last_cell is not None:
        nb.cells.append(nbformat.v4.new_code_cell(last_cell))
    target.parent.mkdir(parents=True, exist_ok=True)
    nbformat.write(nb, str(target))
    return target


def read_grades(path: Path) -> dict[str, dict[str, str]]:
    with open(path, newline="", encoding="utf-8") as f:
        return {row["student"]: row for row in csv.DictReader(f)}


def kill_pids(pids) -> None:
    """SIGKILL the processes a test started, by PID."""
    for pid in pids:
        try:
            os.kill(pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass


@pytest.fixture(scope="session")
def notebook():
    return write_variant


@pytest.fixture(scope="session")
def otter_assigned(disk_cache):
    """``otter_assigned(name, run_tests=False)``: the folder :func:`generate` (``otter assign``)
    wrote for homework ``name`` (``student/``, ``autograder/``, ``NAME-autograder.zip``), run once
    per content of the master's folder, package source and library versions (conftest's
    ``disk_cache``; otter assign takes 10-40 CPU s).  Read it, do not write into it."""
    from gpsaccel.assignments.generate import Generated, generate

    skip = {"dist", "__pycache__", ".ipynb_checkpoints"}

    def assigned(name: str, run_tests: bool = False) -> Generated:
        master = master_notebook(name)
        parts = [name, repr(run_tests)]
        for path in sorted(master.parent.rglob("*")):
            rel = path.relative_to(master.parent)
            if path.is_file() and not skip & set(rel.parts) and path.suffix != ".zip" \
                    and path.name != "kalman_filter.py":  # what generate copies
                parts += [str(rel), path.read_bytes()]
        key = disk_cache.key("otter-assign", *parts)
        out = disk_cache.path("otter-assign", key,
                              lambda target: generate(name, target, run_tests=run_tests))
        return Generated(out / "student" / master.name, out / f"{name}-autograder.zip",
                         out / "autograder" / master.name, out)

    return assigned
