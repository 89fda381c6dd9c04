"""A warm box as its supervisor sees it (gpsaccel.sandbox.warmbox): what its reporter writes is
read as untrusted data of a declared shape.  Under bwrap the reporter is the box's pid 1, which
runs as the box's uid: whatever comes down its pipe that is no report line ends the box as killed,
and costs the supervisor no more than it read."""

from __future__ import annotations

import os
import signal
import socket
import threading
import time

import pytest

from gpsaccel.sandbox import warmbox, zygote


class _Bwrap:
    """Stands for bwrap's Popen: running while the test runs."""

    pid = os.getpid()
    returncode = None

    def poll(self) -> None:
        return None


def _flooded(data: bytes) -> tuple[warmbox.WarmBox, threading.Thread, int]:
    r, w = os.pipe()

    def flood() -> None:
        try:
            view = memoryview(data)
            while view:
                view = view[os.write(w, view):]
        except BrokenPipeError:
            pass
        finally:
            os.close(w)

    writer = threading.Thread(target=flood, daemon=True)
    writer.start()
    box = warmbox.WarmBox("bwrap", {"first": 10, "runner": 3}, bwrap=_Bwrap(),  # type: ignore[arg-type]
                          reaper=r)
    return box, writer, r


def test_an_endless_line_from_the_box_pid_1_ends_the_box_as_killed():
    """8 MiB without a newline (what a traced pid 1 wrote, growing the supervisor's buffer without
    bound): the box ends as killed (bwrap's 128 + SIGKILL) once the line is longer than any report,
    and the supervisor holds no more than a line of it."""
    box, writer, r = _flooded(b"7" * (8 << 20))
    try:
        for _ in range(10_000):
            if box.poll() is not None:
                break
        assert box.returncode == 128 + signal.SIGKILL
        assert len(box.buffer) <= warmbox.MAX_LINE
    finally:
        os.close(r)
        writer.join(timeout=10)
    assert not writer.is_alive()


def test_the_runner_end_is_read_among_other_reports():
    """The reaper's reports of other processes, then the runner's (3 in the box's numbering, here
    its exit status 7), all in one read: the runner's end is the box's."""
    box, writer, r = _flooded(b"5 0\n6 9\n" * 1000 + f"3 {7 << 8}\n".encode())
    try:
        for _ in range(10_000):
            if box.poll() is not None:
                break
        assert box.returncode == 7
    finally:
        os.close(r)
        writer.join(timeout=10)


def test_a_runner_end_that_came_with_the_first_word_is_not_lost():
    """Under basic the keeper says the runner is ready, then how it ended: a runner that ends at
    once (a student's code that kills itself in its first call) has both lines sent before a
    supervisor on a busy machine reads the first.  The second was dropped with the rest of that
    read, and the box ran to its deadline ("timeout" at load 6 in a whole-suite run, for a box
    that crashed)."""
    a, b = socket.socketpair()
    try:
        b.sendall(b'{"first": 10, "runner": 11}\n{"exit": 9}\n')  # SIGKILL's wait status: 9
        first, rest = warmbox._first_word(a, 1.0)
        box = warmbox.WarmBox("basic", first, conn=a, buffered=rest)
        assert (box.keeper, box.runner) == (10, 11)
        assert box.poll() == -signal.SIGKILL
    finally:
        a.close()
        b.close()


@pytest.mark.skipif(not zygote.usable(), reason="boxes start warm only as root on Linux")
def test_a_warm_box_read_late_says_how_its_runner_ended(tmp_path, monkeypatch):
    """The same end to end: the first word read 1 s late (as on a busy machine), a runner that
    SIGKILLs itself in its first call: the box says "crashed", as a cold one does."""
    import numpy as np

    from gpsaccel import sandbox as sb

    real = warmbox._first_word

    def late(conn, wait):
        time.sleep(1.0)
        return real(conn, wait)

    (tmp_path / "student.py").write_text(
        "import os, signal\n\ndef f(x):\n    os.kill(os.getpid(), signal.SIGKILL)\n")
    sub = sb.load_submission(tmp_path / "student.py", "f")
    calls = [sb.Call("f", (np.array(1.0),), (sb.Output("y", ()),))]
    monkeypatch.setattr(warmbox, "_first_word", late)
    with zygote.warm_boxes(zygote.Warm(("numpy",))) as started:
        assert started
        box = sb.run(sub, calls, sb.Limits(memory=512 << 20, processes=8, time=20), "basic")
    assert box.started == "warm"
    assert box.failure == "crashed", (box.failure, box.detail)
