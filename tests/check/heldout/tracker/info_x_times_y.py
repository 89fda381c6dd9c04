"""expect: information-vector — x̂ = Y·y where Y x̂ = y should be solved: it runs away.
accept: gain-or-residual, nan-output — a run-away estimate cannot be matched to 1e-6 σ: its P is
right and x̂'s departure is located (or, overflowed to NaN, where and that it ran away)."""
import numpy as np


def kalman_filter(z):
    F = np.array([[1, 0.1], [0, 1.0]])
    g = np.array([[0.005], [0.1]])
    Q = g @ g.T * 0.09
    H, Vi = np.array([[1.0, 0.0]]), np.array([[0.25]])
    x, M = np.array([0.0, 1.0]), np.diag([25.0, 4.0])
    xs, Ps = np.zeros((len(z), 2)), np.zeros((len(z), 2, 2))
    for k in range(len(z)):
        if k:
            for _ in range(5):
                x, M = F @ x, F @ M @ F.T + Q
        Y = np.linalg.inv(M) + H.T @ Vi @ H
        y = np.linalg.inv(M) @ x + H.T @ Vi @ z[k]
        x = Y @ y
        M = np.linalg.inv(Y)
        xs[k], Ps[k] = x, M
    return xs, Ps
