"""expect: prior-scale — M0 ten times too large."""
import numpy as np


def kalman_filter(z):
    F = np.array([[1, 0.1], [0, 1.0]])
    g = np.array([0.005, 0.1])
    Q = 0.09 * np.outer(g, g)
    x, P = np.array([0.0, 1.0]), np.diag([250.0, 40.0])
    xs, Ps = np.zeros((len(z), 2)), np.zeros((len(z), 2, 2))
    for k in range(len(z)):
        for _ in range(5 if k else 0):
            x, P = F @ x, F @ P @ F.T + Q
        K = P[:, :1] / (P[0, 0] + 4.0)
        x = x + K[:, 0] * (z[k][0] - x[0])
        P = P - K @ P[:1, :]
        xs[k], Ps[k] = x, P
    return xs, Ps
