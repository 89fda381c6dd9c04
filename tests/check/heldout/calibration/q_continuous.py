"""expect: process-noise — Q from the continuous white-noise formula (Q ∝ Δt, not Δt²)."""
import numpy as np

dt, q = 0.005, 0.0004


def kalman_filter(z):
    Phi = np.array([[1, dt, -dt**2 / 2], [0, 1, -dt], [0, 0, 1.0]])
    Q = q * np.array([[dt**3 / 3, dt**2 / 2, 0], [dt**2 / 2, dt, 0], [0, 0, 0]])
    H = np.array([[1.0, 0, 0], [0, 1, 0]])
    V = np.diag([1, 0.0016])
    x, P = np.zeros(3), np.diag([100.0, 1.0, 0.01])
    xs, Ps = [], []
    for k, zk in enumerate(z):
        if k:
            for _ in range(40):
                x, P = Phi @ x, Phi @ P @ Phi.T + Q
        S = H @ P @ H.T + V
        K = P @ H.T @ np.linalg.inv(S)
        x = x + K @ (zk - H @ x)
        P = P - K @ S @ K.T
        xs.append(x)
        Ps.append(P)
    return np.array(xs), np.array(Ps)
