"""expect: phi-sign — Φ₂₃ written +Δt (the bias thought to add to velocity), Φ₁₃ right."""
import numpy as np

DT = 0.005


def kalman_filter(z):
    Phi = np.eye(3)
    Phi[0, 1] = DT
    Phi[0, 2] = -DT**2 / 2
    Phi[1, 2] = DT
    G = np.array([[-DT**2 / 2], [-DT], [0.0]])
    Q = 0.0004 * G @ G.T
    H = np.eye(2, 3)
    V = np.diag([1.0, 0.0016])
    x, P = np.zeros(3), np.diag([100.0, 1.0, 0.01])
    xs, Ps = np.empty((len(z), 3)), np.empty((len(z), 3, 3))
    for k in range(len(z)):
        if k:
            for _ in range(40):
                x = Phi @ x
                P = Phi @ P @ Phi.T + Q
        K = P @ H.T @ np.linalg.inv(H @ P @ H.T + V)
        x = x + K @ (z[k] - H @ x)
        P = (np.eye(3) - K @ H) @ P
        xs[k], Ps[k] = x, P
    return xs, Ps
