"""expect: epoch-shift — x̂ stored one fix late (row k holds x̂ of k − 1, row 0 the prior), P
right."""
import numpy as np


def kalman_filter(z):
    F = np.array([[1, 0.1], [0, 1.0]])
    g = np.array([[0.005], [0.1]])
    Q = g @ g.T * 0.09
    H = np.array([[1.0, 0.0]])
    n = len(z)
    x, P = np.array([0.0, 1.0]), np.diag([25.0, 4.0])
    xs, Ps = np.zeros((n, 2)), np.zeros((n, 2, 2))
    xs[0] = x
    for k in range(n):
        if k:
            xs[k] = x
            for _ in range(5):
                x, P = F @ x, F @ P @ F.T + Q
        K = P @ H.T @ np.linalg.inv(H @ P @ H.T + 4.0)
        x = x + K @ (z[k] - H @ x)
        P = (np.eye(2) - K @ H) @ P @ (np.eye(2) - K @ H).T + 4.0 * K @ K.T
        Ps[k] = P
    return xs, Ps
