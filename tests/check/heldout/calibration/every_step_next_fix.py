"""expect: update-every-step — an update at every accelerometer step, with the fix that comes
next (z[(j + 39) // 40])."""
import numpy as np

dt = 0.005
Phi = np.array([[1, dt, -dt**2 / 2], [0, 1, -dt], [0, 0, 1.0]])
G = -np.array([[dt**2 / 2], [dt], [0]])
Q = 4e-4 * G @ G.T
H = np.array([[1.0, 0, 0], [0, 1, 0]])
V = np.diag([1, 0.0016])


def step_update(x, P, zk):
    K = P @ H.T @ np.linalg.inv(H @ P @ H.T + V)
    A = np.eye(3) - K @ H
    return x + K @ (zk - H @ x), A @ P @ A.T + K @ V @ K.T


def kalman_filter(z):
    x, P = np.zeros(3), np.diag([100, 1, 0.01])
    xs, Ps = [], []
    x, P = step_update(x, P, z[0])
    xs.append(x)
    Ps.append(P)
    for j in range(1, 40 * (len(z) - 1) + 1):
        x, P = Phi @ x, Phi @ P @ Phi.T + Q
        x, P = step_update(x, P, z[(j + 39) // 40])
        if j % 40 == 0:
            xs.append(x)
            Ps.append(P)
    return np.array(xs), np.array(Ps)
