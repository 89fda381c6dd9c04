"""The box's fair clock (gpsaccel.sandbox.clock): its time limit counts the time the box's code
ran or waited for itself, not the time it waited for a CPU on a busy machine; past the backstop
a starved box is the machine's problem (``machine-busy``), never the student's timeout.

The busy machine is made here (:func:`_busy`), in one of two ways, both of which Linux reports as
the box's wait on a run queue (/proc/<pid>/schedstat), which is what the clock reads:

* where the box is a cgroup with a CPU quota (root, or a delegated cgroup2), by lowering that
  quota to a share of a CPU: the kernel keeps the box waiting and nothing else burns a CPU;
* elsewhere, by busy processes pinned to one core, each in a session of its own (with autogroup
  scheduling one session's tasks share one weight), every process the box starts moved to that
  core as soon as it appears (the checker's supervisor, this process, stays free: pinned with the
  box, its own waits stretched the box's own time almost as much as its wait).  The hogs burn that
  core for as long as the box runs (21 CPU s of the first test at load 12) and are killed by PID.

No verdict depends on how fast this machine is or how busy it is otherwise: the limit the starved
box must outlast is set between the box's own time and its wait, both measured in the same run by a
box of the same work starved the same way (a fixed 1.5 s failed at load 5: a faster host finished
the starved box inside it).  The tests assert verdicts, never how fast anything ran."""

from __future__ import annotations

import contextlib
import functools
import math
import os
import subprocess
import sys
import threading

import numpy as np
import pytest

from gpsaccel import sandbox as sb
from gpsaccel.assignments import scoring
from gpsaccel.check import findings
from gpsaccel.check.report import Report
from gpsaccel.sandbox import _cgroup, clock
from gpsaccel.sandbox.outcomes import OUTCOMES, ours

pytestmark = pytest.mark.skipif(
    not os.path.exists("/proc/self/schedstat") or not hasattr(os, "sched_setaffinity"),
    reason="the fair clock reads Linux's /proc/<pid>/schedstat")

#: A fixed amount of work: a Python loop, plus the runner's start.
WORK = ("import numpy as np\n\n"
        "def f(x):\n    s = 0\n    for i in range(2_000_000):\n        s += i\n"
        "    return np.array([float(s)])\n")
ENDLESS = "import numpy as np\n\ndef f(x):\n    while True:\n        pass\n"
SLEEPER = "import time\nimport numpy as np\n\ndef f(x):\n    time.sleep(600)\n"
#: The share of a CPU a starved box gets: its wait is then less than 1/SHARE - 1 times its own
#: time, since part of its own is not CPU (the disk, the box's set-up and end): measured with
#: bwrap and hogs, 2.8 times at a seventh, 4 to 5 at a thirteenth, 6 at a twenty-fifth.
SHARE = 1 / 13
#: How much longer than its own time the probe must have waited for the limit set between the
#: two (their geometric mean) to be at least RATIO ** 0.5 (1.7) away from each: a box of the same
#: work starved the same way is then timed out only if its own time is 1.7 times the probe's, and
#: outlasts the limit unless it waits 1.7 times less (about 2.1 times either way at a thirteenth).
RATIO = 3.0
#: Starving is tried again, at half the share each time, when the box was not starved enough for
#: the probe to reach RATIO or for a box to outlast its limit: such a run says nothing of either
#: clock, and is not a failure of the clock.
TRIES = 3
CALLS = [sb.Call("f", (np.zeros(1),), (sb.Output("s", (1,)),))]


def _box(tmp_path, source: str, limit: float) -> sb.BoxResult:
    (tmp_path / "student.py").write_text(source)
    return sb.run(sb.load_submission(tmp_path / "student.py", "f"), CALLS,
                  sb.Limits(memory=512 << 20, time=limit))


def _descendants(pid: int) -> set[int]:
    """Every process below ``pid`` (Linux's /proc/<pid>/task/<tid>/children, each thread's)."""
    found: set[int] = set()
    todo = [pid]
    while todo:
        p = todo.pop()
        try:
            tasks = os.listdir(f"/proc/{p}/task")
        except OSError:
            continue
        for tid in tasks:
            try:
                with open(f"/proc/{p}/task/{tid}/children", encoding="ascii") as f:
                    kids = {int(k) for k in f.read().split()}
            except (OSError, ValueError):
                continue
            todo += kids - found
            found |= kids
    return found


@functools.cache
def _quota_applies() -> bool:
    """Whether a box's cgroup here has a CPU quota (:data:`_cgroup.CPU_QUOTA`); asked once, when
    a test first starves a box (not at collection)."""
    box = _cgroup.create(256 << 20, 8)
    if box is None:
        return False
    try:
        return "cpu" in box.dirs and (box.dirs["cpu"] / ("cpu.max" if box.kind == "cgroup2" else
                                                         "cpu.cfs_quota_us")).exists()
    finally:
        box.remove()


@contextlib.contextmanager
def _busy(share: float):
    """Every box started in the block gets ``share`` of a CPU (module docstring): its cgroup's
    quota where there is one, else ``round(1 / share) - 1`` hogs on its core."""
    if _quota_applies():
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(_cgroup, "CPU_QUOTA", max(1000, round(share * _cgroup.CPU_PERIOD)))
            yield
    else:
        with _starving(max(1, round(1 / share) - 1)):
            yield


@contextlib.contextmanager
def _starving(n: int):
    """``n`` busy processes on one core, and every process started below this one meanwhile
    (the box and what it forks) moved there as soon as a thread sees it (every 5 ms); each is
    put back where it was allowed to run when the block ends, the hogs killed by PID."""
    core = max(os.sched_getaffinity(0))
    before = _descendants(os.getpid())
    hogs: list[subprocess.Popen] = []
    moved: dict[int, set[int]] = {}
    stop = threading.Event()

    def move_new() -> None:
        while not stop.wait(0.005):
            for pid in _descendants(os.getpid()) - before - set(moved):
                try:
                    moved[pid] = os.sched_getaffinity(pid)
                    os.sched_setaffinity(pid, {core})
                except OSError:  # gone already
                    moved.setdefault(pid, set())

    mover = threading.Thread(target=move_new, daemon=True)
    try:
        # a session each: with autogroup scheduling, hogs in one session would share one weight
        for _ in range(n):
            hogs.append(subprocess.Popen([sys.executable, "-c", "while True: pass"],
                                         start_new_session=True))
            os.sched_setaffinity(hogs[-1].pid, {core})
        before |= {p.pid for p in hogs}
        mover.start()
        yield
    finally:
        stop.set()
        if mover.is_alive():
            mover.join()
        for p in hogs:
            p.kill()
            p.wait()
        for pid, was in moved.items():
            with contextlib.suppress(OSError):
                if was:
                    os.sched_setaffinity(pid, was)


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


def _starved_limit(tmp_path, share: float) -> tuple[float, tuple]:
    """A limit between the own time and the wait of a box of :data:`WORK` at ``share`` of a CPU
    (their geometric mean), 0 when it did not wait :data:`RATIO` times its own time; and what
    was measured (for the failure messages)."""
    probe = _box(tmp_path, WORK, 600.0)
    assert probe.failure is None and probe.waited is not None, probe.detail
    own = probe.seconds - probe.waited  # the whole sb.run's wall: an upper bound on its own
    seen = (round(share, 3), round(own, 2), round(probe.waited, 2))
    return (math.sqrt(own * probe.waited) if probe.waited >= RATIO * own else 0.0), seen


def test_a_box_starved_by_a_busy_machine_is_not_timed_out(tmp_path, patient, monkeypatch):
    """A box that waited for a CPU past its limit finishes; the wall clock times out the same
    box starved the same way.  The limit is :func:`_starved_limit`'s, measured in this run: a
    false alarm needs a box's own time to grow 1.7 times, or its wait to shrink as much, between
    two boxes of the same work a second apart, starved the same way.

    The wall clock's box is judged on what its clock counts: the starved box's wait, read by the
    clock inside its own window (from the box's start to its end), was past the limit, so the
    window of a box starved as much is too; not on ``BoxResult.seconds``, the whole ``sb.run``
    with the box's set-up (its folder, its cgroup, its launch) and its emptying, which the clock
    does not count (a fixed 1.5 s against boxes of 1.76-1.8 s there failed three times in CI,
    bwrap on cgroup1: they took the difference).  It is starved twice as hard at each try, which
    costs nothing (it is stopped at its limit): not timed out thrice, its wait would have shrunk
    1.7, 3.4 and 6.8 times."""
    tries: list[tuple] = []
    share, starved = SHARE, None
    for _ in range(TRIES):
        with _busy(share):
            limit, seen = _starved_limit(tmp_path, share)
            box = _box(tmp_path, WORK, limit) if limit else None
        if box is not None:
            assert box.failure is None, (limit, box.detail)  # its waits are not its time
            assert box.waited is not None
            tries.append((*seen, round(limit, 2), round(box.waited, 2)))
            if box.waited > limit:  # waited past its limit (and on its clock, longer still)
                starved = limit
                break
        else:
            tries.append(seen)
        share /= 2
    assert starved is not None, f"the box was never starved past its limit: {tries}"
    monkeypatch.setattr(clock, "FAIR_CLOCK", False)  # the wall clock: the same box times out
    walled = []
    for _ in range(TRIES):  # starved harder each try: it is stopped at its limit anyway
        with _busy(share):
            box = _box(tmp_path, WORK, starved)
        walled.append((round(share, 4), box.failure, round(box.seconds, 2)))
        if box.failure is not None:
            break
        share /= 2
    assert box.failure == "timeout" and box.waited is None, (tries, walled)


def test_an_endless_loop_still_times_out_with_the_endless_loop_hint(tmp_path, patient):
    box = _box(tmp_path, ENDLESS, 1.0)
    assert box.failure == "timeout" and "of its own time" in box.detail, box.detail
    text = _finding(box, 1.0)
    assert "time limit of 1 s" in text and findings.MESSAGES["timeout.never"] in text


def test_a_sleeper_times_out_sleeping_is_its_own_time(tmp_path, monkeypatch):
    """Stopped at its limit, not at the sleep's end: were its sleep not its own time, it would
    reach the backstop (30 s) with under a second of its own and be ``machine-busy``; a timeout
    there instead needs the box to have waited 29 s for a CPU to start (it needs a fraction of a
    CPU second), so the verdict alone tells, at any load."""
    monkeypatch.setattr(clock, "BACKSTOP_FACTOR", 30.0)
    box = _box(tmp_path, SLEEPER, 1.0)
    assert box.failure == "timeout", (box.failure, box.detail)


def test_a_box_starved_past_the_backstop_is_the_machines_problem(tmp_path, monkeypatch):
    """An endless loop starved to the backstop: the machine gave it too little to tell.  The
    backstop at 1.515 s of wall time under a 1.5 s limit: the box's own time is under its limit
    there unless it waited less than 15 ms for a CPU, at a thirteenth of one (it waits four times
    its own time and more)."""
    monkeypatch.setattr(clock, "BACKSTOP_FACTOR", 1.01)
    with _busy(SHARE):
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


def test_a_box_that_lowered_its_own_priority_is_timed_out(tmp_path, monkeypatch):
    """An endless loop after os.nice(19) at half a CPU: a timeout, never machine-busy.  Where
    the box is a cgroup or a session of its own its nice does not lower its share, and its own
    time reaches the limit first; where it does, the clock's verdict at the backstop reads the
    lowered priority (the next test).  The backstop at 15 s: the runner reaches os.nice there
    unless it got under a fiftieth of a CPU."""
    monkeypatch.setattr(clock, "BACKSTOP_FACTOR", 10.0)
    with _busy(1 / 2):
        box = _box(tmp_path, ENDLESS.replace("while True", "os.nice(19)\n    while True")
                   .replace("import numpy", "import os\nimport numpy"), 1.5)
    assert box.failure == "timeout", (box.failure, box.detail)


@pytest.mark.skipif(os.getpriority(os.PRIO_PROCESS, 0) >= 19,
                    reason="this process runs at the lowest priority already")
def test_at_the_backstop_a_runner_that_lowered_its_priority_is_timed_out():
    """:meth:`clock.Clock.verdict` at the backstop with the box's own time under its limit and
    its CPU too: ``machine-busy`` for a runner at this process's priority, ``timeout`` for one
    that lowered its own (os.nice: its waits were of its own making), read from a real process.
    The event is the runner's line after its os.nice, not a clock."""
    for nice, want in ((0, "machine-busy"), (19, "timeout")):
        runner = subprocess.Popen([sys.executable, "-c", f"import os, time\nos.nice({nice})\n"
                                   "print('niced', flush=True)\ntime.sleep(600)"],
                                  stdout=subprocess.PIPE, text=True)
        try:
            assert runner.stdout is not None and runner.stdout.readline() == "niced\n"
            c = clock.Clock(1.5, runner.pid, lambda pid=runner.pid: pid)
            c.update()
            assert c.verdict(c.start + 0.5, lambda: 0.0) == want, nice
        finally:
            runner.kill()
            runner.wait()


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
