"""expect: prior-scale — M0 ten times too small (σ's divided by √10... the variances by 10)."""
import numpy as np

dt = 0.005
F = np.array([[1, dt, -dt**2 / 2], [0, 1, -dt], [0, 0, 1.0]])
G = -np.array([[dt**2 / 2], [dt], [0]])
Q = G @ G.T * 0.0004
H = np.array([[1.0, 0, 0], [0, 1, 0]])
V = np.diag([1, 0.0016])


def kalman_filter(z):
    x = np.zeros(3)
    P = np.diag([10.0, 0.1, 0.001])
    xs, Ps = np.zeros((len(z), 3)), np.zeros((len(z), 3, 3))
    for k in range(len(z)):
        if k:
            for _ in range(40):
                x = F @ x
                P = F @ P @ F.T + Q
        K = P @ H.T @ np.linalg.inv(H @ P @ H.T + V)
        x += K @ (z[k] - H @ x)
        P = (np.eye(3) - K @ H) @ P @ (np.eye(3) - K @ H).T + K @ V @ K.T
        xs[k] = x
        Ps[k] = P
    return xs, Ps
