"""expect: update-every-step — every 10 Hz step updates with the upcoming fix z[ceil(j / 5)]."""
import math

import numpy as np


def kalman_filter(z):
    F = np.array([[1, 0.1], [0, 1.0]])
    g = np.array([[0.005], [0.1]])
    Q = g @ g.T * 0.09
    H = np.array([[1.0, 0.0]])
    x, P = np.array([0.0, 1.0]), np.diag([25.0, 4.0])
    xs, Ps = [], []
    for j in range(5 * (len(z) - 1) + 1):
        if j:
            x, P = F @ x, F @ P @ F.T + Q
        zk = z[math.ceil(j / 5)]
        K = P @ H.T @ np.linalg.inv(H @ P @ H.T + 4.0)
        x = x + K @ (zk - H @ x)
        P = (np.eye(2) - K @ H) @ P @ (np.eye(2) - K @ H).T + 4.0 * K @ K.T
        if j % 5 == 0:
            xs.append(x)
            Ps.append(P)
    return np.array(xs), np.array(Ps)
