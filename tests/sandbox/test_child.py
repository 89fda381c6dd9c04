"""Host-side work under limits (:func:`gpsaccel.sandbox.in_child`): every way a child's job can end
is an outcome, never an exception here, and no child outlives its call.

Bounds: each job runs at most a few CPU seconds and a few hundred MB; the children are reaped by
the function under test, and a test that starts one by other means kills it by PID."""

from __future__ import annotations

import json
import os
import signal
import sys
import threading
import time

import pytest

from gpsaccel import sandbox as sb

LIMITS = {"cpu": 2, "memory": 128 << 20, "wall": 60}


def _spin() -> None:
    while True:
        pass


def _hoard() -> list:
    return [bytearray(1 << 20) for _ in range(1 << 12)]  # 4 GiB, far past the limit


def _nested(depth: int):  # noqa: ANN202
    out: list = []
    for _ in range(depth):
        out = [out]
    return out


def test_a_value_comes_back_as_plain_data():
    out = sb.in_child(lambda a, b: {"sum": a + b, "pair": (a, b)}, 2, 3, **LIMITS)
    assert out.ok and out.value == {"sum": 5, "pair": [2, 3]} and out.failure is None
    assert out.cpu >= 0


def test_a_job_that_raises_anything_is_an_outcome():
    def transformer() -> None:
        raise RuntimeError("Input transformation still changing after 500 iterations")

    def deep() -> str:
        return json.dumps(_nested(10 ** 5))

    for job, kind in ((transformer, "RuntimeError"), (lambda: 1 / 0, "ZeroDivisionError"),
                      (lambda: sys.exit(3), "SystemExit"), (deep, "RecursionError")):
        out = sb.in_child(job, **LIMITS)
        assert (out.failure, out.detail.split(":")[0]) == ("raised", kind), out


def test_cpu_memory_and_wall_limits_are_named():
    out = sb.in_child(_spin, cpu=1, memory=64 << 20, wall=60)
    assert out.failure == "cpu-limit" and out.cpu > 0.5  # counted in clock ticks
    out = sb.in_child(_hoard, **LIMITS)
    assert out.failure == "memory-limit"
    out = sb.in_child(time.sleep, 30, cpu=5, memory=64 << 20, wall=0.5)
    assert out.failure == "wall-limit" and out.cpu < 1


def test_a_reply_that_is_not_plain_data_or_too_large_is_refused():
    assert sb.in_child(lambda: object(), **LIMITS).failure == "not-plain-data"
    assert sb.in_child(lambda: {1j: 2}, **LIMITS).failure == "not-plain-data"
    assert sb.in_child(_nested, 10 ** 5, **LIMITS).failure == "not-plain-data"
    out = sb.in_child(lambda: "x" * 5000, **LIMITS, max_bytes=4096)
    assert out.failure == "too-large"


def test_a_child_that_dies_is_an_outcome():
    out = sb.in_child(lambda: os.kill(os.getpid(), signal.SIGSEGV), **LIMITS)
    assert (out.failure, out.detail) == ("crashed", "signal SIGSEGV")
    out = sb.in_child(lambda: os._exit(7), **LIMITS)
    assert (out.failure, out.detail) == ("crashed", "exit status 7")


def test_a_child_never_outlives_its_call():
    """The child's pid is reaped whatever happened: after a wall-clock kill, and when the
    caller is interrupted while it waits (Ctrl-C, or SIGTERM turned into KeyboardInterrupt)."""
    seen: list[int] = []
    sb.in_child(lambda: seen.append(os.getpid()) or time.sleep(30), cpu=5, memory=64 << 20,
                wall=0.3)

    def report_pid(w: int) -> None:
        os.write(w, str(os.getpid()).encode())
        time.sleep(60)

    r, w = os.pipe()
    timer = threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT))
    # Ctrl-C as a terminal's command has it: a suite started as a background job (`... &` in a
    # script) inherits SIGINT ignored, and Python then leaves it ignored
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        timer.start()
        with pytest.raises(KeyboardInterrupt):
            sb.in_child(report_pid, w, cpu=5, memory=64 << 20, wall=60)
        timer.join()
    finally:
        signal.signal(signal.SIGINT, before)
    os.close(w)
    pid = int(os.read(r, 64))
    os.close(r)
    with pytest.raises(ChildProcessError):
        os.waitpid(pid, os.WNOHANG)  # reaped already: not a child any more
    assert not os.path.exists(f"/proc/{pid}") or b"Z" not in \
        open(f"/proc/{pid}/stat", "rb").read().split(b")")[-1][:3]


def test_bad_limits_are_refused_by_name():
    for kwargs, name in (({"cpu": 0, "memory": 1 << 20, "wall": 1}, "cpu"),
                         ({"cpu": 1, "memory": 1.5, "wall": 1}, "memory"),
                         ({"cpu": 1, "memory": 1 << 20, "wall": -1}, "wall"),
                         ({"cpu": 1, "memory": 1 << 20, "wall": 1, "max_bytes": 0}, "max_bytes")):
        with pytest.raises(ValueError, match=name):
            sb.in_child(print, **kwargs)


def test_a_hostile_notebook_costs_its_own_limits_only(tmp_path, monkeypatch):
    """The notebook parse (:func:`gpsaccel.assignments.notebook.load`) of a cell of 600 ``%env``
    lines (IPython 8 on Python 3.11 gives up on it with a RuntimeError after 8-9 CPU s; the
    IPython installed with 3.13 parses it in a moment), a parse that never ends, and JSON nested
    past the recursion limit: each the student's notebook, read or unreadable, at the cost of the
    parse's own limits, never an exception of the grader's."""
    from gpsaccel.assignments import notebook as nbm

    monkeypatch.setattr(nbm, "LOAD_CPU", 1)  # the limit is what is tested, not its size
    env = tmp_path / "env.ipynb"
    env.write_text(json.dumps({"cells": [{"cell_type": "code", "source": "%env A=1\n" * 600}]}))
    try:
        nbm.load(env)
    except nbm.NotebookError as exc:
        assert f"more than {nbm.LOAD_CPU} CPU seconds" in str(exc)

    def endless(*_args):  # the child runs it (forked): a parse that would never end
        while True:
            pass

    monkeypatch.setattr(nbm, "_parsed", endless)
    with pytest.raises(nbm.NotebookError, match="more than 1 CPU seconds"):
        nbm.load(env)
    monkeypatch.undo()
    deep = tmp_path / "deep.ipynb"
    deep.write_text("[" * 100_000)
    with pytest.raises(nbm.NotebookError, match="nested too deep"):
        nbm.load(deep)
