"""expect: x0-wrong — the glider started at rest (x0 = 0; its 15 m/s airspeed forgotten)."""
import numpy as np

dt = 0.1
Phi = np.array([[1.0, dt, dt], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
G = np.array([[dt**2 / 2, dt**2 / 2], [dt, 0.0], [0.0, dt]])
W = np.diag([0.2**2, 0.05**2])
H = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
V = np.diag([3.0**2, 0.5**2])
M0 = np.diag([100.0, 1.0, 4.0])
x0 = np.array([0.0, 15.0, 0.0])


def kalman_filter(z):
    Q = G @ W @ G.T
    x, P = np.zeros(3), M0.copy()
    xs, Ps = np.zeros((len(z), 3)), np.zeros((len(z), 3, 3))
    for k in range(len(z)):
        if k:
            for _ in range(10):
                x = Phi @ x
                P = Phi @ P @ Phi.T + Q
        S = H @ P @ H.T + V
        K = P @ H.T @ np.linalg.inv(S)
        x = x + K @ (z[k] - H @ x)
        A = np.eye(3) - K @ H
        P = A @ P @ A.T + K @ V @ K.T
        xs[k], Ps[k] = x, P
    return xs, Ps
