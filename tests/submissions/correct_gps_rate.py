"""Correct: steps only at GPS times, with the exact 40-step Φ and the 40-step process noise."""
import numpy as np

dt, n = 0.005, 40
phi1 = np.array([[1, dt, -dt**2 / 2], [0, 1, -dt], [0, 0, 1]])
g1 = -np.array([[dt**2 / 2], [dt], [0.0]])
PHI = np.linalg.matrix_power(phi1, n)
Q = sum(np.linalg.matrix_power(phi1, j) @ g1 @ g1.T @ np.linalg.matrix_power(phi1, j).T
        for j in range(n)) * 0.0004
H = np.eye(2, 3)
V = np.diag([1.0, 0.0016])


def kalman_filter(z):
    x, M = np.zeros(3), np.diag([100.0, 1.0, 0.01])
    x_hat, P = np.empty((len(z), 3)), np.empty((len(z), 3, 3))
    for k, zk in enumerate(z):
        if k:
            x, M = PHI @ x, PHI @ M @ PHI.T + Q
        K = np.linalg.solve(H @ M @ H.T + V, H @ M).T
        x = x + K @ (zk - H @ x)
        M = M - K @ H @ M
        M = (M + M.T) / 2
        x_hat[k], P[k] = x, M
    return x_hat, P
