"""The box's fair clock (gpsaccel.sandbox.clock): its time limit counts the time the box's code
ran or waited for itself, not the time it waited for a CPU on a busy machine; past the backstop
a starved box is the machine's problem (``machine-busy``), never the student's timeout.

The busy machine is made here: this process and six CPU hogs pinned to one core, each hog in a
session of its own (with autogroup scheduling one session's tasks share one weight), so the box
(which inherits the pinning) gets at most a seventh of it: measured at load 11 on 2 cores with
three hogs, the box of :data:`WORK` took 3.0 s of wall, 2.0 s of it waiting for the core (and
once, at load 1.5, only 0.4 s for its call: three hogs did not always starve it enough).  The
hogs are killed by PID.  The tests assert verdicts, never how fast anything ran."""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys

import numpy as np
import pytest

from gpsaccel import sandbox as sb
from gpsaccel.assignments import scoring
from gpsaccel.check import findings
from gpsaccel.check.report import Report
from gpsaccel.sandbox import clock
from gpsaccel.sandbox.outcomes import OUTCOMES, ours

pytestmark = pytest.mark.skipif(
    not os.path.exists("/proc/self/schedstat") or not hasattr(os, "sched_setaffinity"),
    reason="the fair clock reads Linux's /proc/<pid>/schedstat")

#: A fixed amount of work: about 0.3 CPU s of Python, plus the runner's start (about 0.3 CPU s).
WORK = ("import numpy as np\n\n"
        "def f(x):\n    s = 0\n    for i in range(2_000_000):\n        s += i\n"
        "    return np.array([float(s)])\n")
ENDLESS = "import numpy as np\n\ndef f(x):\n    while True:\n        pass\n"
SLEEPER = "import time\nimport numpy as np\n\ndef f(x):\n    time.sleep(600)\n"
HOGS = 6
#: The wall-clock box of the same work is run until one was starved past its limit: the share
#: the hogs leave a box varies with the machine's own load (once, with a second suite running on
#: both cores, a box of WORK ended 2.1 s after its start, inside its 1.5 s by the clock that
#: starts with the runner), and a box that was not starved enough says nothing of the wall clock.
WALL_TRIES = 3
CALLS = [sb.Call("f", (np.zeros(1),), (sb.Output("s", (1,)),))]


def _box(tmp_path, source: str, limit: float) -> sb.BoxResult:
    (tmp_path / "student.py").write_text(source)
    return sb.run(sb.load_submission(tmp_path / "student.py", "f"), CALLS,
                  sb.Limits(memory=512 << 20, time=limit))


@contextlib.contextmanager
def _starving(n: int):
    """This process (and so every box it starts) and ``n`` busy processes on one core."""
    was = os.sched_getaffinity(0)
    os.sched_setaffinity(0, {max(was)})
    hogs: list[subprocess.Popen] = []
    try:
        # a session each: with autogroup scheduling, hogs in one session would share one weight
        hogs = [subprocess.Popen([sys.executable, "-c", "while True: pass"],
                                 start_new_session=True) for _ in range(n)]
        yield
    finally:
        for p in hogs:
            p.kill()
            p.wait()
        os.sched_setaffinity(0, was)


@pytest.fixture
def starved():
    """This process (and so every box it starts) and :data:`HOGS` busy processes on one core."""
    with _starving(HOGS):
        yield


@pytest.fixture
def one_hog():
    """This process and one busy process on one core: enough to starve a box that lowered its own
    priority (a hog's CPU is the core for as long as the test runs)."""
    with _starving(1):
        yield


@pytest.fixture
def patient(monkeypatch):
    """A backstop far away: the machine's own load must not turn these verdicts into
    machine-busy."""
    monkeypatch.setattr(clock, "BACKSTOP_FACTOR", 1000.0)
    monkeypatch.setattr(clock, "BACKSTOP_MARGIN", 600.0)


def _finding(box: sb.BoxResult, limit: float) -> str:
    report = Report("student.py")
    findings.box_findings(report, box, CALLS, sb.Limits(memory=512 << 20, time=limit))
    return "\n".join(f.message for f in report.for_student().findings)


def test_a_box_starved_by_a_busy_machine_is_not_timed_out(tmp_path, starved, patient,
                                                         monkeypatch):
    box = _box(tmp_path, WORK, 1.5)
    assert box.failure is None, box.detail
    assert box.seconds > 1.5, "the hogs did not starve the box: the test tests nothing"
    assert box.waited is not None and box.waited > 0.5
    monkeypatch.setattr(clock, "FAIR_CLOCK", False)  # the wall clock: the same box times out
    tries = []
    for _ in range(WALL_TRIES):  # when the hogs starved it past its limit (module docstring)
        box = _box(tmp_path, WORK, 1.5)
        tries.append((box.failure, round(box.seconds, 2)))
        if box.failure is not None:
            break
    assert box.failure == "timeout" and box.waited is None, tries


def test_an_endless_loop_still_times_out_with_the_endless_loop_hint(tmp_path, patient):
    box = _box(tmp_path, ENDLESS, 1.0)
    assert box.failure == "timeout" and "of its own time" in box.detail, box.detail
    text = _finding(box, 1.0)
    assert "time limit of 1 s" in text and findings.MESSAGES["timeout.never"] in text


def test_a_sleeper_times_out_sleeping_is_its_own_time(tmp_path, patient):
    box = _box(tmp_path, SLEEPER, 1.0)
    assert box.failure == "timeout", box.detail
    assert box.seconds < 60  # stopped near its limit, not at the sleep's end (600 s)


def test_a_box_starved_past_the_backstop_is_the_machines_problem(tmp_path, starved,
                                                                 monkeypatch):
    """An endless loop starved to the backstop: the machine gave it too little to tell.  The
    backstop at 1.515 s of wall time under a 1.5 s limit: the box, with a seventh of a core, has
    run well under its limit of its own (CPU, and its reads of the disk) by then (under a 3 s
    limit, about 0.8 s at the backstop)."""
    monkeypatch.setattr(clock, "BACKSTOP_FACTOR", 1.01)
    box = _box(tmp_path, ENDLESS, 1.5)
    assert box.failure == "machine-busy", (box.failure, box.detail, box.seconds, box.waited)
    text = _finding(box, 1.5)
    assert "too busy" in text and "run the check again" in text
    assert findings.MESSAGES["timeout.never"] not in text and "Your f did not finish" not in text
    # the grader: the notebook's stop says so, and the grade is the grader's (not a zero)
    assert ours("machine-busy") and not ours("timeout")
    stop = scoring._stop_message("machine-busy", "in cell 2", sb.Limits(time=1.5))
    assert "too busy" in stop and "not the student's fault" in stop
    assert scoring._STOPS["machine-busy"] == OUTCOMES["machine-busy"].stop


def test_a_box_that_lowered_its_own_priority_is_timed_out_at_the_backstop(tmp_path, one_hog,
                                                                          monkeypatch):
    """Its waits for a CPU are its own (os.nice): not the machine's problem.  The backstop at
    6 s of wall time: the runner, sharing its core with one hog, must reach the student's
    os.nice before it; then the hog leaves it a few percent of the core, and only a clock that
    counts those waits as its own times it out before the backstop."""
    monkeypatch.setattr(clock, "BACKSTOP_FACTOR", 4.0)
    box = _box(tmp_path, ENDLESS.replace("while True", "os.nice(19)\n    while True")
               .replace("import numpy", "import os\nimport numpy"), 1.5)
    assert box.failure == "timeout", (box.failure, box.detail)


def test_the_grader_records_a_busy_machine_as_its_own_error_not_a_grade(tmp_path, monkeypatch):
    """The notebook's box came back machine-busy: no grade (graded again), the student told so."""
    import nbformat

    from gpsaccel.classrun.statuses import scored

    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("x = 1")])
    nbformat.write(nb, str(tmp_path / "alice.ipynb"))
    busy = sb.BoxResult("basic", failure="machine-busy", detail="in 480 s it ran for 20.0 s "
                        "of its 120 s and waited 460 s for a processor")
    monkeypatch.setattr(sb, "run", lambda *args, **kwargs: busy)
    g = scoring.grade_notebook(tmp_path / "alice.ipynb", "calibration", "alice", seed=1)
    assert g.status == "grader-error" and not scored(g.status)  # an empty gradebook cell
    assert "too busy" in g.feedback and "not the student's fault" in g.feedback
