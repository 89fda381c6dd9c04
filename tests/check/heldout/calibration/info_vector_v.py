"""expect: information-vector — information form whose y adds Hᵀ V z (V where V⁻¹ belongs);
Y is right."""
import numpy as np

dt = 0.005
Phi = np.array([[1, dt, -dt**2 / 2], [0, 1, -dt], [0, 0, 1.0]])
G = -np.array([[dt**2 / 2], [dt], [0]])
Q = 4e-4 * G @ G.T
H = np.array([[1.0, 0, 0], [0, 1, 0]])
V = np.diag([1, 0.0016])


def kalman_filter(z):
    x, M = np.zeros(3), np.diag([100, 1, 0.01])
    xs, Ps = np.zeros((len(z), 3)), np.zeros((len(z), 3, 3))
    for k in range(len(z)):
        if k:
            for _ in range(40):
                x, M = Phi @ x, Phi @ M @ Phi.T + Q
        Minv = np.linalg.inv(M)
        Y = Minv + H.T @ np.linalg.inv(V) @ H
        y = Minv @ x + H.T @ V @ z[k]
        P = np.linalg.inv(Y)
        x = P @ y
        M = P
        xs[k], Ps[k] = x, P
    return xs, Ps
