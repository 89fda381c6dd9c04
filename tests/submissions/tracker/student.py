"""A student's constant-velocity tracker, written step by step; MISTAKE makes one known slip.

The tests (tests/check/test_linear.py) copy this file with ``MISTAKE = "<code>"``; None is the
correct filter.  Each branch is the slip as a student writes it, not the catalogue's recursion.
"""

import numpy as np

MISTAKE = None
DT, EVERY = 0.1, 5


def kalman_filter(z):
    m = MISTAKE
    dtype = np.float32 if m == "low-precision" else float
    Phi = np.array([[1.0, DT], [0.0, 1.0]], dtype=dtype)
    G = np.array([[DT**2 / 2], [DT]], dtype=dtype)
    W = np.array([[0.3**2]], dtype=dtype)
    H = np.array([[1.0, 0.0]], dtype=dtype)
    V = np.array([[2.0**2 if m != "std-as-variance" else 2.0]], dtype=dtype)
    M0 = np.diag([25.0, 4.0] if m != "m0-order" else [4.0, 25.0]).astype(dtype)
    if m == "phi-transposed":
        Phi = Phi.T
    Q = G @ W @ G.T if m != "q-without-gamma" else W[0, 0] * np.eye(2, dtype=dtype)
    steps = EVERY + 1 if m == "missing-propagation" else EVERY
    z = np.asarray(z, dtype=dtype)
    n = len(z)
    x, P = np.array([0.0, 1.0], dtype=dtype), M0.copy()
    xs, Ps = np.zeros((n, 2), dtype=dtype), np.zeros((n, 2, 2), dtype=dtype)
    for k in range(n):
        if k or m == "predict-before-first-update":
            for _ in range(steps):
                if m != "mean-not-propagated":
                    x = Phi @ x
                P = Phi @ P @ Phi.T + Q
        x_bar, M = x.copy(), P.copy()
        S = H @ P @ H.T + V
        K = P @ H.T @ np.linalg.inv(S)
        skip = (m == "first-update-skipped" and k == 0) or (m == "update-skipped" and k == 20) \
            or (m in ("last-update-missing", "covariance-update-skipped") and k == n - 1)
        update_x = (not skip or m == "covariance-update-skipped") and \
            not (m == "mean-update-skipped" and k == 20)
        if update_x:
            x = x + K @ (z[k] - H @ x)                      # x̂ = x̄ + K (z − H x̄)
        if not skip:
            A = np.eye(2, dtype=dtype) - K @ H
            P = A @ P @ A.T + K @ V @ K.T                   # Joseph
        xs[k], Ps[k] = (x_bar, M) if m == "returns-a-priori" else (x, P)
    if m == "p-scaled":
        Ps = 2 * Ps
    if m == "epoch-shift":
        xs, Ps = np.concatenate([[xs[0]], xs[:-1]]), np.concatenate([[Ps[0]], Ps[:-1]])
    return xs, Ps
