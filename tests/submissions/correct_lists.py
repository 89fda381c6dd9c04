"""Correct, but returns Python lists (converted, with a note)."""
import numpy as np

dt = 0.005
Phi = np.array([[1.0, dt, -dt**2 / 2], [0.0, 1.0, -dt], [0.0, 0.0, 1.0]])
Q = np.array([[dt**2 / 2], [dt], [0.0]]) @ np.array([[dt**2 / 2, dt, 0.0]]) * 0.0004
H = np.eye(2, 3)
V = np.diag([1.0, 0.0016])


def kalman_filter(z):
    x_hat, P = [], []
    x, M = np.zeros(3), np.diag([100.0, 1.0, 0.01])
    for k in range(len(z)):
        if k:
            for _ in range(40):
                x, M = Phi @ x, Phi @ M @ Phi.T + Q
        K = M @ H.T @ np.linalg.inv(H @ M @ H.T + V)
        x, M = x + K @ (z[k] - H @ x), (np.eye(3) - K @ H) @ M
        x_hat.append(x.tolist())
        P.append(M.tolist())
    return x_hat, P
