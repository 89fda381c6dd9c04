"""Hostile but correct: the filter is right, and it leaves two children sleeping behind it."""
import ctypes
import os
import time

import numpy as np

ctypes.CDLL(None).prctl(15, b"gpsacc-hostile", 0, 0, 0)  # PR_SET_NAME

dt = 0.005
Phi = np.array([[1.0, dt, -dt**2 / 2], [0.0, 1.0, -dt], [0.0, 0.0, 1.0]])
G = np.array([[-dt**2 / 2], [-dt], [0.0]])
Q = G @ G.T * 0.0004
H = np.eye(2, 3)
V = np.diag([1.0, 0.04**2])
_started = []


def kalman_filter(z):
    while len(_started) < 2:
        pid = os.fork()
        if pid == 0:
            time.sleep(20)  # bounded
            os._exit(0)
        _started.append(pid)
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
