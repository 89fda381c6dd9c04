"""The sandbox's one pool (gpsaccel.sandbox.run_items): each item's own result or the reason it has
none, a deadline forked or on an executor (the path Dask takes), nothing left running, after
SIGTERM and SIGHUP too."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import psutil
import pytest

from gpsaccel import sandbox as sb


def _task(item: str) -> dict:
    if item == "raise":
        raise RuntimeError("a bug of the task")
    if item == "exit":
        os._exit(3)
    if item == "hang":
        time.sleep(60)
    if item == "orphan":  # a grandchild that outlives its item: the pool sweeps it
        if os.fork() == 0:
            time.sleep(60)
            os._exit(0)
    return {"item": item, "pid": os.getpid()}


def _run(items: list[str], executor: object = None, deadline: float = 30) -> dict[int, object]:
    out: dict[int, object] = {}
    sb.run_items(_task, items, 2, deadline, out.__setitem__, executor)
    return out


def test_forked_items_each_get_their_result_or_the_reason_they_have_none():
    out = _run(["a", "raise", "exit", "b"])
    assert out[0]["item"] == "a" and out[3]["item"] == "b"
    assert out[0]["pid"] != os.getpid() != out[3]["pid"]  # each in a process of its own
    assert out[1] == sb.Lost("error", "RuntimeError: a bug of the task")
    assert out[2] == sb.Lost("died", "exit status 3")


def test_a_forked_item_past_its_deadline_is_killed_and_the_others_go_on():
    """The deadline is what "a" (a fork and a return) must finish within on a busy machine, and
    what "hang" costs the test in wall time (not CPU): 5 s, a hundred times what "a" needs even
    at a quarter of a core (a 1 s deadline assumed the fork would get a CPU within it)."""
    out = _run(["hang", "a"], deadline=5.0)
    assert out[0] == sb.Lost("too-long", "5 s")
    assert out[1]["item"] == "a"


def test_what_an_item_left_running_is_swept():
    before = {p.pid for p in psutil.Process().children(recursive=True)}
    out = _run(["orphan"])
    assert out[0]["item"] == "orphan"
    left = {p.pid for p in psutil.Process().children(recursive=True)} - before
    assert not left


def test_an_executor_has_the_same_deadline():
    """The path of --dask (any executor): an item past its deadline is reported, not waited for
    (before, a Dask run had no deadline at all)."""
    out = _run(["a", "raise"], executor="threads")
    assert out[0]["item"] == "a" and out[1] == sb.Lost("error", "RuntimeError: a bug of the task")
    out = _run(["a"], executor="inprocess", deadline=5.0)
    assert out[0]["item"] == "a"


def test_an_executor_item_past_its_deadline_is_lost():
    """The item sleeps ten times its deadline: the pool's loop would have to stall for 4.5 s for
    the item to come back first (3 s and 2.5 s before).  The executor's shutdown waits for the
    sleeping thread: the sleep is the test's wall time, not its CPU."""
    def slow(item: str) -> str:
        time.sleep(5)
        return item

    out: dict[int, object] = {}
    sb.run_items(slow, ["x"], 1, 0.5, out.__setitem__, "threads")
    assert out == {0: sb.Lost("too-long", "0.5 s")}


@pytest.mark.parametrize("bad", [{"jobs": 0}, {"deadline": 0}])
def test_bad_arguments_are_named(bad):
    kwargs = {"jobs": 1, "deadline": 1.0, **bad}
    with pytest.raises(ValueError, match=next(iter(bad))):
        sb.run_items(_task, ["a"], kwargs["jobs"], kwargs["deadline"], lambda i, o: None)


_STOPPED = """
import os, sys, time
from gpsaccel import sandbox as sb
from gpsaccel._interrupt import exit_status

def task(item):
    if os.fork() == 0:  # a grandchild, as a box's process: re-parented to the pool, swept
        time.sleep(120)
        os._exit(0)
    with open({pids!r}, "a") as f:
        f.write(f"{{os.getpid()}}\\n")
    time.sleep(120)

try:
    sb.run_items(task, ["a", "b", "c"], 2, 300, print)
except KeyboardInterrupt as exc:
    print(type(exc).__name__, exc, flush=True)
    sys.exit(exit_status(exc))
"""


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP])
def test_sigterm_and_sighup_stop_the_pool_as_ctrl_c_does(tmp_path, sig):
    """The pool latches them: every running item and what it left are killed before it raises
    a KeyboardInterrupt naming the signal and what it kept; nothing of the run outlives the
    pool's process (counted when it has exited, no clock)."""
    pids = tmp_path / "pids"
    proc = subprocess.Popen([sys.executable, "-c", _STOPPED.format(pids=str(pids))],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    run: set[int] = set()
    try:
        deadline = time.monotonic() + 600  # a hang guard; the event is two items running
        while not (pids.exists() and len(pids.read_text().split()) == 2):
            assert time.monotonic() < deadline and proc.poll() is None, proc.communicate()
            time.sleep(0.05)
        run = {c.pid for c in psutil.Process(proc.pid).children(recursive=True)}
        assert len(run) == 4  # two items, a grandchild each
        proc.send_signal(sig)
        out, err = proc.communicate(timeout=600)
    finally:
        for pid in [proc.pid, *run]:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        proc.wait()
    assert proc.returncode == 128 + sig, err
    name = signal.Signals(sig).name
    assert out == f"Stopped {name}: 0 of 3 finished and kept, 2 stopped, 1 not started\n"
    assert not [p for p in run if _alive(p)]


def _alive(pid: int) -> bool:
    try:
        return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False
