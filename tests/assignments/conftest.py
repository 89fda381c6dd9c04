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


_SKIP = {"dist", "__pycache__", ".ipynb_checkpoints"}


def _master_parts(name: str) -> list[str | bytes]:
    """What ``otter assign`` reads of homework ``name``: every file of its master's folder that
    :func:`gpsaccel.assignments.generate.generate` copies, by path and content (a cache key)."""
    master = master_notebook(name)
    parts: list[str | bytes] = [name]
    for path in sorted(master.parent.rglob("*")):
        rel = path.relative_to(master.parent)
        if path.is_file() and not _SKIP & set(rel.parts) and path.suffix != ".zip" \
                and path.name != "kalman_filter.py":  # what generate copies
            parts += [str(rel), path.read_bytes()]
    return parts


_ASSIGN_ALL = """\
import os, sys
from otter.assign import main
for master, out in zip(sys.argv[1::2], sys.argv[2::2]):
    os.chdir(os.path.dirname(master))  # where generate runs it: beside the master's copy
    main(master, out, no_run_tests=True)
"""


@pytest.fixture(scope="session")
def student_sides(disk_cache):
    """``student_sides[name]``: the student notebook ``otter assign --no-run-tests`` makes of
    every registered homework's master, all in one otter process (importing otter is most of an
    ``otter assign``: 2.5 of its 3 CPU s), as :func:`gpsaccel.assignments.generate.generate`
    copies the master folder.  Run once per content of the masters' folders, package source
    and library versions (conftest's ``disk_cache``).  Read, do not write."""
    import shutil
    import subprocess
    import sys

    from gpsaccel import registry

    names = registry.assignments()
    parts: list[str | bytes] = ["student-sides"]
    for name in names:
        parts += _master_parts(name)

    def make(target: Path) -> None:
        import tempfile

        args = []
        with tempfile.TemporaryDirectory(prefix="gpsaccel-assign-") as tmp:
            for name in names:
                master = master_notebook(name)
                work = Path(tmp) / "work" / name
                shutil.copytree(master.parent, work, ignore=shutil.ignore_patterns(
                    "*.zip", "dist", "__pycache__", ".ipynb_checkpoints", "kalman_filter.py"))
                args += [str(work / master.name), str(Path(tmp) / "out" / name)]
            proc = subprocess.run([sys.executable, "-c", _ASSIGN_ALL, *args],
                                  capture_output=True, text=True, timeout=900)
            assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-4000:]
            target.mkdir()
            for name in names:
                master = master_notebook(name)
                shutil.copy(Path(tmp) / "out" / name / "student" / master.name,
                            target / master.name)

    folder = disk_cache.path("otter-assign", disk_cache.key(*parts), make)
    return {name: folder / master_notebook(name).name for name in names}


#: The calibration's ``nees_bounds`` with scipy.special's χ² quantile (``chdtri``: what
#: ``scipy.stats.chi2.ppf`` computes; the bounds agree to 1e-15, the grader's tolerance is 1e-4),
#: as a student may write it: importing scipy.stats costs a notebook's box 0.9 of its 1 CPU s,
#: scipy.special 0.25.  An edit for :func:`write_variant`; one honest notebook of the class (the
#: master's own solution, unchanged) keeps scipy.stats.
CHI2_SPECIAL = ("    from scipy import stats\n"
                "    return tuple(stats.chi2.ppf([0.025, 0.975], 3 * N) / N)",
                "    from scipy.special import chdtri\n"
                "    return tuple(chdtri(3 * N, [0.975, 0.025]) / N)")


#: The tracker's filter written with numpy instead of filterpy (the master's), as a student may:
#: the same numbers; a file box that imports filterpy (and so scipy.stats) costs 1.5 CPU s more.
TRACKER_NUMPY_FILTER = '''%%writefile kalman_filter.py
import numpy as np


def kalman_filter(z):
    """The tracker's filter: z (41, 1) -> x_hat (41, 2), P (41, 2, 2)."""
    dt, every = 0.1, 5
    Phi = np.array([[1.0, dt], [0.0, 1.0]])
    G = np.array([[dt**2 / 2], [dt]])
    Q = G @ G.T * 0.3**2
    H = np.array([[1.0, 0.0]])
    V = np.array([[2.0**2]])
    x, P = np.array([0.0, 1.0]), np.diag([5.0**2, 2.0**2])
    x_hat, P_all = np.empty((len(z), 2)), np.empty((len(z), 2, 2))
    for k in range(len(z)):
        if k > 0:
            for _ in range(every):
                x, P = Phi @ x, Phi @ P @ Phi.T + Q
        K = P @ H.T @ np.linalg.inv(H @ P @ H.T + V)
        x = x + K @ (np.atleast_1d(z[k]) - H @ x)
        A = np.eye(2) - K @ H
        P = A @ P @ A.T + K @ V @ K.T
        x_hat[k], P_all[k] = x, P
    return x_hat, P_all'''


def tracker_with_numpy_filter(target: Path, edits: list[tuple[str, str]] = (),
                              filter_edits: list[tuple[str, str]] = ()) -> Path:
    """The solved tracker notebook (with ``edits``), its ``%%writefile`` cell the numpy filter
    (with each ``(old, new)`` of ``filter_edits`` replaced once: a mistake in the filter)."""
    path = write_variant("tracker", target, edits)
    nb = nbformat.read(str(path), as_version=4)
    cells = [c for c in nb.cells if c.cell_type == "code"
             and c.source.startswith("%%writefile kalman_filter.py")]
    assert len(cells) == 1, "the tracker's %%writefile cell moved"
    source = TRACKER_NUMPY_FILTER
    for old, new in filter_edits:
        assert source.count(old) == 1, f"{old!r} is not once in the numpy filter"
        source = source.replace(old, new)
    cells[0].source = source
    nbformat.write(nb, str(path))
    return path
