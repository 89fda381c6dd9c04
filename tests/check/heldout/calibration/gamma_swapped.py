"""expect: gamma-order — Γ's first two entries swapped, −[Δt, Δt²/2, 0]."""
import numpy as np

dt = 0.005


def kalman_filter(z):
    Phi = np.array([[1, dt, -dt**2 / 2], [0, 1, -dt], [0, 0, 1.0]])
    Gamma = -np.array([dt, dt**2 / 2, 0.0]).reshape(3, 1)
    Q = Gamma @ np.array([[0.0004]]) @ Gamma.T
    H = np.array([[1.0, 0, 0], [0, 1, 0]])
    V = np.diag([1, 0.0016])
    x, P = np.zeros(3), np.diag([100, 1, 0.01])
    xs, Ps = [], []
    for k in range(len(z)):
        if k:
            for _ in range(40):
                x = Phi @ x
                P = Phi @ P @ Phi.T + Q
        K = np.linalg.solve(H @ P @ H.T + V, H @ P).T
        x = x + K @ (z[k] - H @ x)
        P = (np.eye(3) - K @ H) @ P
        P = (P + P.T) / 2
        xs.append(x)
        Ps.append(P)
    return np.array(xs), np.array(Ps)
