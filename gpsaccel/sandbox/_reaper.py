"""pid 1 of a warm box's PID namespace under bwrap: what bwrap's own init is to a cold box.

Usage (by :mod:`gpsaccel.sandbox.zygote`, not by hand)::

    bwrap ... --as-pid-1 -- python -I -S -B /control/_reaper.py

A warm box's runner is forked from the zygote into the namespaces bwrap made (it is re-parented to
this process once the zygote's keeper has left), so bwrap's init, which would end the box when its
own child ends, is not there; this process stands in for it.  It names itself ``bwrap`` (a box sees
``bwrap`` as its pid 1 either way; the sandbox knows it by its pid, as bwrap's child, not by a
name any process may take), writes ``ready`` on stdout once it runs (bwrap has made the
namespaces and mounts), then reaps every process re-parented to it and writes ``PID STATUS`` (in
this namespace's numbers, the raw wait status) on stdout for each, which is how the supervisor
learns how the runner ended.

As the init of its namespace it cannot be killed or stopped from inside it: the kernel delivers it
only signals it handles, and it handles none (SIGCHLD is blocked and waited for).  It runs as the
box's uid, so it makes itself non-dumpable before any of the box's processes exists: a dumpable
process of the student's own uid can be traced (``PTRACE_ATTACH``, ``/proc/1/mem``), and a traced
pid 1 writes what the student wants down the supervisor's report pipe (a runner's forged end, or
an endless line the supervisor buffers outside the box's limits).  bwrap's own init, a cold box's
pid 1, holds only the box's output and bwrap's event descriptor.  It imports only ``os``,
``signal`` and ``ctypes``.
"""

from __future__ import annotations

import ctypes
import os
import signal

PR_SET_DUMPABLE = 4


def main() -> None:
    with open("/proc/self/comm", "w", encoding="ascii") as comm:
        comm.write("bwrap")
    if ctypes.CDLL(None).prctl(PR_SET_DUMPABLE, 0, 0, 0, 0) != 0:
        raise OSError("prctl(PR_SET_DUMPABLE, 0) failed")
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGCHLD})
    os.write(1, b"ready\n")
    while True:
        signal.sigwait({signal.SIGCHLD})
        while True:
            try:
                pid, status = os.waitpid(-1, os.WNOHANG)
            except ChildProcessError:
                break
            if pid == 0:
                break
            line = f"{pid} {status}\n".encode()
            while line:
                line = line[os.write(1, line):]


if __name__ == "__main__":
    main()
