"""A warm box as its supervisor sees it (gpsaccel.sandbox.warmbox): what its reporter writes is
read as untrusted data of a declared shape.  Under bwrap the reporter is the box's pid 1, which
runs as the box's uid: whatever comes down its pipe that is no report line ends the box as killed,
and costs the supervisor no more than it read."""

from __future__ import annotations

import os
import signal
import threading

from gpsaccel.sandbox import warmbox


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
