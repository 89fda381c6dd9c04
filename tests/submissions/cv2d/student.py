"""A student's 2-D constant-velocity filter (state [x, vx, y, vy]), written step by step;
MISTAKE makes one of issue 31's catalogue gaps.

tests/check/test_catalogue_gaps.py copies this file with ``MISTAKE = "<code>"``; None is the
correct filter.  Each branch is the slip as a student writes it.
"""

import numpy as np

MISTAKE = None
DT, EVERY = 0.1, 5


def kalman_filter(z):
    m = MISTAKE
    d = -DT if m == "phi-sign" else DT                  # velocity entering position as −Δt
    Phi = np.array([[1, d, 0, 0], [0, 1, 0, 0], [0, 0, 1, d], [0, 0, 0, 1.0]])
    G = np.array([[DT**2 / 2, 0], [DT, 0], [0, DT**2 / 2], [0, DT]])
    Q = G @ (0.5**2 * np.eye(2)) @ G.T
    if m == "state-order":                              # H written for [x, y, vx, vy]
        H = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0]])
    else:
        H = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]])
    V = 3.0**2 * np.eye(2)
    x, P = np.array([0.0, 1.0, 0.0, -1.0]), np.diag([25.0, 4.0, 25.0, 4.0])
    n = len(z)
    xs, Ps = np.zeros((n, 4)), np.zeros((n, 4, 4))

    def update(x, P, zk):
        K = P @ H.T @ np.linalg.inv(H @ P @ H.T + V)
        x = x + K @ (zk - H @ x)
        if m != "covariance-update-skipped":            # P never updated when forgotten
            A = np.eye(4) - K @ H
            P = A @ P @ A.T + K @ V @ K.T
        return x, P

    for k in range(n):
        if k:
            for s in range(EVERY):
                x, P = Phi @ x, Phi @ P @ Phi.T + Q
                if m == "update-every-step" and s < EVERY - 1:   # no `if` around the update
                    x, P = update(x, P, z[k - 1])
        x, P = update(x, P, z[k])
        xs[k], Ps[k] = x, P
    return xs, Ps
