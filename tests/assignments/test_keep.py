"""A notebook that stops keeps what it computed (issue 42, item 1; :mod:`gpsaccel.assignments
.snapshots`): solved calibration notebooks that stall, hog, bomb or kill themselves after their
answers keep q1 and q3, under bwrap and under basic as root; and the integrity rule: a stopped
notebook is graded as Run All grades it cut after one of its own cells, never better.

One class run per backend (module fixture, two notebooks at a time, a small time limit).  q2 (the
``%%writefile`` question, graded from the cell's text in a box of its own) is left out of most
notebooks to keep the run cheap.  Every process the hog starts carries :data:`MARK` in its
command line; after the run a scan of ``/proc`` must find none (and kills by PID what it finds).
"""

from __future__ import annotations

import json
import uuid
from pathlib import Path

import nbformat
import pytest

from gpsaccel.assignments import gradescope, scoring
from gpsaccel.classrun import grade, writing

from .conftest import CHI2_SPECIAL, kill_pids, read_grades, write_variant
from .test_attacks import BACKENDS, described, outliving, running_before, this_runs_zygotes

MARK = f"gpsaccel-keep-{uuid.uuid4().hex[:12]}"
#: The class's time limit: the stalls and hogs reach it; the memory bomb must reach its memory
#: limit first (its children's pages and the runner's, under a cgroup at its limit, counted as
#: the box's own time): it once took over 6 s of its own time at load 4 and was timed out.
TIMEOUT = 10

NO_Q2 = ("%%writefile kalman_filter.py", "# q2 left out of this notebook")
STALL = "import time\ntime.sleep(300)"
#: a forking CPU hog: four children spinning (each carries MARK), the parent waiting on them
HOG = ("import os, sys\nfor _ in range(4):\n    if os.fork() == 0:\n"
       f"        os.execv(sys.executable, [sys.executable, '-c', 'while True: pass', {MARK!r}])\n"
       "while True:\n    os.wait()")
#: memory spread over processes: ten children of 150 MB, then the runner grows until the box's
#: memory is spent (a cgroup kills the largest process, the runner; rlimits alone give a
#: MemoryError in the cell, and the notebook goes on)
BOMB = ("import os, time\nfor _ in range(10):\n    if os.fork() == 0:\n"
        "        kid = b'k' * (150 << 20)\n        time.sleep(120)\n        os._exit(0)\n"
        "time.sleep(2)\nhog = []\nwhile True:\n    hog.append(b'h' * (64 << 20))")
KILLED = "import os, signal\nos.kill(os.getpid(), signal.SIGKILL)"
WRONG_NEES = "def average_nees(x_true, x_hat, P):\n    return -1.0"
AVERAGE = "def average_nees("
#: Φ zeroed in place by a call the parser does not see as a change of Φ, in q3's answer cell
HIDDEN_BREAK = (AVERAGE, "np.copyto(Phi, np.zeros((3, 3)))\n\n\ndef average_nees(")

#: student -> (edits, last cells): the notebooks of the class
CASES: dict[str, tuple[list, list[str]]] = {
    "slow last cell": ([CHI2_SPECIAL], [STALL]),
    "forking hog": ([NO_Q2, CHI2_SPECIAL], [HOG]),
    "memory bomb": ([NO_Q2, CHI2_SPECIAL], [BOMB]),
    "killed box": ([NO_Q2, CHI2_SPECIAL], [KILLED]),
    # q3's cell stalls: q1 came before it and counts, q3's cells had not run
    "stall in q3": ([NO_Q2, CHI2_SPECIAL, (AVERAGE, STALL + "\n\n\n" + AVERAGE)], []),
    # q3's function never returns: q1, read before it in the same group, counts
    "endless read": ([NO_Q2, CHI2_SPECIAL, ("    e = x_true", "    while True:\n        pass\n"
                                                          "    e = x_true")], []),
    # right, then overwritten with a wrong one, then a stall: graded as Run All grades it
    "overwrite, stall": ([NO_Q2, CHI2_SPECIAL], [WRONG_NEES, STALL]),
    "overwrite": ([NO_Q2, CHI2_SPECIAL], [WRONG_NEES]),
    "hidden break, stall": ([NO_Q2, CHI2_SPECIAL, HIDDEN_BREAK], [STALL]),
    "hidden break": ([NO_Q2, CHI2_SPECIAL, HIDDEN_BREAK], []),
}


def write_case(name: str, target: Path) -> Path:
    edits, last = CASES[name]
    path = write_variant("calibration", target, edits)
    nb = nbformat.read(str(path), as_version=4)
    nb.cells += [nbformat.v4.new_code_cell(src) for src in last]
    nbformat.write(nb, str(path))
    return path


def stopped_cell(path: Path, text: str) -> int:
    nb = nbformat.read(str(path), as_version=4)
    return next(i for i, c in enumerate(nb.cells, 1) if c.cell_type == "code" and text in c.source)


@pytest.fixture(scope="module", params=BACKENDS)
def kept(request, tmp_path_factory):
    backend, warm = request.param
    root = tmp_path_factory.mktemp(f"keep-{backend}{'-warm' if warm else ''}")
    sub, out = root / "class", root / "out"
    paths = {name: write_case(name, sub / name / "calibration.ipynb") for name in CASES}
    earlier = running_before()
    try:
        grades = grade(sub, "calibration", out=out, jobs=2, timeout=TIMEOUT, seed=5,
                       sandbox=backend, warm_boxes=warm)
    finally:  # every case's process, and this run's zygotes (their folder names this process)
        left = outliving(MARK, this_runs_zygotes(), earlier=earlier)
        seen = described(left)
        kill_pids(left)
    return {"grades": {g.student: g for g in grades}, "paths": paths, "left": left, "seen": seen,
            "csv": read_grades(out / "grades.csv")}


def test_no_process_of_the_hog_outlives_the_run(kept):
    assert kept["left"] == [], kept["seen"]


@pytest.mark.parametrize("name", ["slow last cell", "forking hog", "memory bomb", "killed box"])
def test_answers_before_the_stop_keep_their_marks(kept, name):
    g = kept["grades"][name]
    want = {"q1": 3.0, "q2": 4.0 if name == "slow last cell" else 0.0, "q3": 3.0}
    assert g.scores == want, g.feedback
    assert kept["csv"][name]["total"] == f"{sum(want.values()):g}"
    if name == "memory bomb" and g.status == "graded":  # rlimits only: the cell raised
        assert "MemoryError" in g.feedback
        return
    status = {"slow last cell": "timeout", "forking hog": "timeout", "memory bomb": "memory-limit",
              "killed box": "crashed"}[name]
    assert g.status == status, g.feedback
    cell = stopped_cell(kept["paths"][name], CASES[name][1][-1])
    answer = stopped_cell(kept["paths"][name], AVERAGE)
    assert (f"The notebook stopped in cell {cell}: " in g.feedback
            and f"Answers complete before that count: q1, q3, graded as your notebook stood "
                f"after cell {answer}." in g.feedback), g.feedback
    assert "not-run" not in g.feedback


def test_only_a_question_whose_cells_had_not_run_is_not_run(kept):
    g = kept["grades"]["stall in q3"]
    assert (g.status, g.scores["q1"], g.codes["q3"]) == ("timeout", 3.0, ["not-run"]), g.feedback
    assert "Answers complete before that count: q1," in g.feedback
    # q3's function never returned: q1, read before it after the same cell, counts
    g = kept["grades"]["endless read"]
    assert (g.status, g.scores["q1"], g.codes["q3"]) == ("timeout", 3.0, ["timeout"]), g.feedback
    assert ("The notebook stopped while calling average_nees (q3): it was still running at the "
            f"time limit of {TIMEOUT} s. Answers complete before that count: q1, graded as your "
            "notebook stood after its last cell.") in g.feedback
    assert "q3: 0 / 3\n    - timeout: Not graded: the notebook stopped while reading this " \
           "answer" in g.feedback


@pytest.mark.parametrize("name", ["overwrite", "hidden break"])
def test_a_stall_never_grades_better_than_run_all(kept, name):
    """Run All of the same notebook without its stall is the reference: the stall keeps what
    Run All gives, not the better answer that stood before a later cell spoiled it (Φ zeroed by
    np.copyto in q3's cell: a change the parser cannot see, read again with q3)."""
    stalled, run_all = kept["grades"][f"{name}, stall"], kept["grades"][name]
    assert run_all.status == "graded" and stalled.status == "timeout", stalled.feedback
    assert stalled.scores == run_all.scores, (stalled.feedback, run_all.feedback)
    assert run_all.total < 6.0  # the spoiled answer costs points under Run All


# ------------------------------------------------------------------ the feedback's bound
#: issue 42's notebook: 3000 cells, each raising with 300 characters of text (1.4 MB)
RAISING = "raise ValueError('{}')"


def test_feedback_of_3000_raising_cells_stays_under_its_bound(tmp_path):
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(RAISING.format(f"{i:05d}" + "x" * 295))
                for i in range(3000)]
    path = tmp_path / "calibration.ipynb"
    nbformat.write(nb, str(path))
    assert path.stat().st_size > 1_300_000
    g = scoring.grade_notebook(path, "calibration", "flood", seed=3, timeout=120)
    text = g.feedback
    assert len(text.encode("utf-8")) <= scoring.MAX_FEEDBACK < 20_000
    lines = text.splitlines()
    # the score, then every question, then as many notes on cells as fit and their count
    assert lines[0] == "flood: 0 / 10 points (graded)"
    assert [ln for ln in lines if ln[:2] == "q1"] == ["q1: 0 / 3"]
    assert text.index("q3: 0 / 3") < text.index("Cell 1 raised ValueError: 00000xxx")
    shown = sum(1 for ln in lines if ln.startswith("Cell "))
    assert 10 < shown < 3000
    assert lines[-1] == (f"... {3000 - shown} more note(s) on your cells left out: the feedback "
                         f"holds at most {scoring.MAX_FEEDBACK >> 10} KB")
    out = gradescope.results(g, g.possible)
    assert out["output"] == text and len(json.dumps(out)) < scoring.MAX_FEEDBACK + 2000
    # the file a class run writes holds the same text, cleaned, under the same bound
    written = writing.write_feedback(tmp_path, "flood", text).read_bytes()
    assert written == text.encode("utf-8") and len(written) <= scoring.MAX_FEEDBACK


def test_findings_come_before_notes_and_each_run_left_out_is_counted():
    from gpsaccel.check.report import Report

    g = scoring.Grade("s", "", {"q1": 0.0, "q2": 1.0}, {"q1": 1.0, "q2": 1.0}, "graded")
    rep = Report("q1")
    for i in range(400):
        rep.add("exception", text=f"finding {i:03d}: " + "y" * 80)
    text = scoring._feedback_text(g, ["The notebook stopped."], {"q1": rep}, {"a": 1},
                                  [f"Cell {i} raised E" for i in range(50)])
    assert len(text.encode("utf-8")) <= scoring.MAX_FEEDBACK
    lines = text.splitlines()
    assert lines[:4] == ["s: 1 / 2 points (graded)", "Your variant: a = 1", "",
                         "The notebook stopped."]
    shown = sum(1 for ln in lines if ln.startswith("    - exception: finding"))
    assert f"    - ... {400 - shown} more finding(s) of this question left out: the feedback " \
           f"holds at most 16 KB" in lines
    # q2's line is kept though q1's findings filled the feedback; no note on a cell fits
    assert "q2: 1 / 1" in lines and lines[-1].startswith("... 50 more note(s) on your cells")
    assert scoring._feedback_text(g, [], {}, {}, ["Cell 3 raised E"]).endswith("Cell 3 raised E")
