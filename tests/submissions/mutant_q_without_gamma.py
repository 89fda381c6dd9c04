"""q-without-gamma: Q = W·I, the accelerometer variance put on every state without Γ."""
import numpy as np

dt = 0.005
Phi = np.array([[1.0, dt, -dt**2 / 2], [0.0, 1.0, -dt], [0.0, 0.0, 1.0]])
Gamma = -np.array([[dt**2 / 2], [dt], [0.0]])
W = 0.0004
H = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
V = np.diag([1.0, 0.04**2])
M0 = np.diag([100.0, 1.0, 0.01])


def kalman_filter(z):
    n = len(z)
    x_hat = np.zeros((n, 3))
    P = np.zeros((n, 3, 3))
    x, M = np.zeros(3), M0.copy()
    Q = W * np.eye(3)
    for k in range(n):
        if k > 0:
            for _ in range(40):
                x = Phi @ x
                M = Phi @ M @ Phi.T + Q
        K = M @ H.T @ np.linalg.inv(H @ M @ H.T + V)
        x = x + K @ (z[k] - H @ x)
        M = (np.eye(3) - K @ H) @ M
        x_hat[k], P[k] = x, M
    return x_hat, P
