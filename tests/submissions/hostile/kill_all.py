"""Hostile (issue 20): kill(-1, SIGKILL) (every process its user may signal) and SIGSTOP of its
parent, to take a batch down or hang it.  Guarded: it sends kill(-1) only as a box's own uid or
inside a PID namespace, never as a user whose other processes it would reach."""
import ctypes
import os
import signal

ctypes.CDLL(None).prctl(15, b"gpsacc-hostile", 0, 0, 0)  # PR_SET_NAME

BOX_UIDS = 2_013_265_920  # gpsaccel.sandbox._boxuser.UID_BASE


def _in_own_pid_namespace():
    try:
        with open("/proc/1/comm", encoding="utf-8") as f:
            return f.read().strip() == "bwrap"
    except OSError:
        return False


def kalman_filter(z):
    if os.getuid() < BOX_UIDS and not _in_own_pid_namespace():
        raise RuntimeError("refusing kill(-1): this box runs as the checker's own user")
    stopped = "refused"
    try:
        os.kill(os.getppid(), signal.SIGSTOP)
        stopped = "sent"
    except OSError:
        pass
    os.kill(-1, signal.SIGKILL)
    raise RuntimeError(f"kill(-1) sent, SIGSTOP of the parent {stopped}; still running")
