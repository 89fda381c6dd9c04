"""expect: residual-covariance — the gain's S = H M Hᵀ without V (P's Joseph update has V)."""
import numpy as np


def predict(x, P, Phi, Q, n):
    for _ in range(n):
        x = Phi @ x
        P = Phi @ P @ Phi.T + Q
    return x, P


def update(x, P, z, H, V):
    S = H @ P @ H.T
    K = P @ H.T @ np.linalg.inv(S)
    x = x + K @ (z - H @ x)
    A = np.eye(len(x)) - K @ H
    return x, A @ P @ A.T + K @ V @ K.T


def kalman_filter(z):
    dt = 0.005
    Phi = np.array([[1, dt, -dt**2 / 2], [0, 1, -dt], [0, 0, 1.0]])
    G = -np.array([[dt**2 / 2], [dt], [0]])
    Q, H, V = 0.0004 * G @ G.T, np.eye(2, 3), np.diag([1, 0.04**2])
    x, P = np.zeros(3), np.diag([100, 1, 0.01])
    xs, Ps = [], []
    for k in range(len(z)):
        if k:
            x, P = predict(x, P, Phi, Q, 40)
        x, P = update(x, P, z[k], H, V)
        xs.append(x)
        Ps.append(P)
    return np.array(xs), np.array(Ps)
