"""A notebook that forks its process loses nothing it answered (issue 43): a solved calibration
notebook with a cell ``import os; os.fork()`` was graded 4/10 ``result-refused`` (the copy of the
runner sent the reads a second time and the channel was refused), while one ending in
``while True: pass`` kept its 10/10.  Now it is graded as the notebook without that cell, and the
feedback says where it forked, with the lesson section under it; under bwrap and under basic as
root, the fork in the first cell (before any answer) and in the last (after every answer)."""

from __future__ import annotations

import os

import nbformat
import pytest

from gpsaccel import sandbox as sb
from gpsaccel._taught import NOT_RUN
from gpsaccel.assignments import scoring

from .conftest import CHI2_SPECIAL

FORK = "import os; os.fork()"
#: q2 (the %%writefile question, graded in a box of its own) left out: the fork is in the
#: notebook's box; scipy.special for scipy.stats (a cheaper box, the same bounds).
NO_Q2 = ("%%writefile kalman_filter.py", "# q2 left out of this notebook")

BACKENDS = [
    pytest.param("bwrap", id="bwrap", marks=pytest.mark.skipif(
        sb.bwrap_path() is None, reason="bubblewrap is not installed or cannot create namespaces")),
    pytest.param("basic", id="basic", marks=pytest.mark.skipif(
        not (os.path.isdir("/proc") and sb.basic_is_safe()),
        reason="basic isolates a student only as root")),
]


@pytest.mark.parametrize("where", ["first", "last"])
@pytest.mark.parametrize("backend", BACKENDS)
def test_a_cell_that_forks_loses_no_answer(tmp_path, notebook, backend, where):
    path = notebook("calibration", tmp_path / "calibration.ipynb", [NO_Q2, CHI2_SPECIAL],
                    **{f"{where}_cell": FORK})
    cells = nbformat.read(str(path), as_version=4).cells
    cell = next(i for i, c in enumerate(cells, 1) if c.cell_type == "code" and c.source == FORK)
    g = scoring.grade_notebook(path, "calibration", "forker", seed=5, sandbox=backend,
                               timeout=60)
    assert g.status == "graded", g.feedback
    assert (g.scores["q1"], g.scores["q3"]) == (g.possible["q1"], g.possible["q3"]), g.feedback
    note = f"Your notebook forked its process in cell {cell} (os.fork()"
    assert note in g.feedback and f"\n→ {NOT_RUN.cite()}\n" in g.feedback, g.feedback
    assert "result-refused" not in g.feedback
