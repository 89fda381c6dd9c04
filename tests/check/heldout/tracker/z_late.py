"""expect: measurement-late — the update at fix k uses z[k − 1] (z[-1], the last fix, at k = 0:
Python's wrap-around)."""
import numpy as np


def kalman_filter(z):
    F = np.array([[1, 0.1], [0, 1.0]])
    g = np.array([[0.005], [0.1]])
    Q = g @ g.T * 0.09
    H = np.array([[1.0, 0.0]])
    x, P = np.array([0.0, 1.0]), np.diag([25.0, 4.0])
    xs, Ps = np.zeros((len(z), 2)), np.zeros((len(z), 2, 2))
    for k in range(len(z)):
        if k:
            for _ in range(5):
                x, P = F @ x, F @ P @ F.T + Q
        K = P @ H.T @ np.linalg.inv(H @ P @ H.T + 4.0)
        x = x + K @ (z[k - 1] - H @ x)
        P = (np.eye(2) - K @ H) @ P @ (np.eye(2) - K @ H).T + 4.0 * K @ K.T
        xs[k], Ps[k] = x, P
    return xs, Ps
