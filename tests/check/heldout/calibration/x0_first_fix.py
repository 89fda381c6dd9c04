"""expect: x0-wrong — the error state started at the first GPS fix (x̄₀ = [z₀, 0]), then updated
with z₀ again."""
import numpy as np

dt = 0.005
Phi = np.array([[1, dt, -dt**2 / 2], [0, 1, -dt], [0, 0, 1.0]])
G = -np.array([[dt**2 / 2], [dt], [0]])
Q = 4e-4 * G @ G.T
H = np.array([[1.0, 0, 0], [0, 1, 0]])
V = np.diag([1, 0.0016])


def kalman_filter(z):
    x = np.array([z[0][0], z[0][1], 0.0])
    P = np.diag([100, 1, 0.01])
    xs, Ps = np.zeros((len(z), 3)), np.zeros((len(z), 3, 3))
    for k in range(len(z)):
        if k:
            for _ in range(40):
                x = Phi @ x
                P = Phi @ P @ Phi.T + Q
        K = P @ H.T @ np.linalg.inv(H @ P @ H.T + V)
        x = x + K @ (z[k] - H @ x)
        P = (np.eye(3) - K @ H) @ P @ (np.eye(3) - K @ H).T + K @ V @ K.T
        xs[k], Ps[k] = x, P
    return xs, Ps
