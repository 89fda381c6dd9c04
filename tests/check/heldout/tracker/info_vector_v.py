"""expect: information-vector — an information filter whose y adds Hᵀ V z (V for V⁻¹)."""
import numpy as np


def kalman_filter(z):
    F = np.array([[1, 0.1], [0, 1.0]])
    g = np.array([[0.005], [0.1]])
    Q = g @ g.T * 0.09
    H, V = np.array([[1.0, 0.0]]), np.array([[4.0]])
    x, M = np.array([0.0, 1.0]), np.diag([25.0, 4.0])
    xs, Ps = np.zeros((len(z), 2)), np.zeros((len(z), 2, 2))
    for k in range(len(z)):
        if k:
            for _ in range(5):
                x, M = F @ x, F @ M @ F.T + Q
        Y = np.linalg.inv(M) + H.T @ np.linalg.inv(V) @ H
        y = np.linalg.inv(M) @ x + H.T @ V @ z[k]
        P = np.linalg.inv(Y)
        x = np.linalg.solve(Y, y)
        M = P
        xs[k], Ps[k] = x, P
    return xs, Ps
