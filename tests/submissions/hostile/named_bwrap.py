"""Hostile but correct: the filter is right, and it leaves one child behind that names itself
``bwrap`` (the name of the sandbox's own processes), to hide from the count of what a student
left running.  The child is a fresh Python (exec) so that the tests find it from outside any PID
namespace by its command line (``gpsacc-hostile-bwrap``): its comm is the disguise."""
import ctypes
import os
import sys

import numpy as np

ctypes.CDLL(None).prctl(15, b"gpsacc-hostile", 0, 0, 0)  # PR_SET_NAME

CHILD = ("import ctypes, os, sys, time\n"
         "ctypes.CDLL(None).prctl(15, b'bwrap', 0, 0, 0)\n"  # PR_SET_NAME
         "os.write(int(sys.argv[1]), b'x')\n"
         "time.sleep(20)\n")  # bounded
dt = 0.005
Phi = np.array([[1.0, dt, -dt**2 / 2], [0.0, 1.0, -dt], [0.0, 0.0, 1.0]])
G = np.array([[-dt**2 / 2], [-dt], [0.0]])
Q = G @ G.T * 0.0004
H = np.eye(2, 3)
V = np.diag([1.0, 0.04**2])
_started = []


def _leave_a_bwrap():
    """Fork and exec the child; return once it has renamed itself (it says so on a pipe)."""
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(r)
        os.set_inheritable(w, True)
        os.execv(sys.executable, [sys.executable, "-I", "-S", "-c", CHILD, str(w),
                                  "gpsacc-hostile-bwrap"])
    os.close(w)
    said = os.read(r, 1)
    os.close(r)
    if said != b"x":
        raise RuntimeError("the child did not rename itself")
    _started.append(pid)


def kalman_filter(z):
    if not _started:
        _leave_a_bwrap()
    n = len(z)
    x_hat, P = np.zeros((n, 3)), np.zeros((n, 3, 3))
    x, M = np.zeros(3), np.diag([100.0, 1.0, 0.01])
    for k in range(n):
        if k:
            for _ in range(40):
                x, M = Phi @ x, Phi @ M @ Phi.T + Q
        K = M @ H.T @ np.linalg.inv(H @ M @ H.T + V)
        x, M = x + K @ (z[k] - H @ x), (np.eye(3) - K @ H) @ M
        x_hat[k], P[k] = x, M
    return x_hat, P
