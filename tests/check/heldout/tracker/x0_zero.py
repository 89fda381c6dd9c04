"""expect: x0-wrong — the state started at zero (the target's 1 m/s forgotten)."""
import numpy as np


def kalman_filter(z):
    dt = 0.1
    F = np.array([[1, dt], [0, 1.0]])
    G = np.array([[dt**2 / 2], [dt]])
    Q = 0.09 * G @ G.T
    H = np.array([[1.0, 0]])
    V = np.array([[4.0]])
    x, P = np.zeros(2), np.diag([25.0, 4.0])
    xs, Ps = np.zeros((len(z), 2)), np.zeros((len(z), 2, 2))
    for k in range(len(z)):
        if k > 0:
            for _ in range(5):
                x = F @ x
                P = F @ P @ F.T + Q
        K = P @ H.T @ np.linalg.inv(H @ P @ H.T + V)
        x = x + K @ (z[k] - H @ x)
        A = np.eye(2) - K @ H
        P = A @ P @ A.T + K @ V @ K.T
        xs[k], Ps[k] = x, P
    return xs, Ps
