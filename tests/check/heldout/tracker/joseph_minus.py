"""expect: joseph-sign — Joseph's update with − K V Kᵀ, in a helper."""
import numpy as np


def joseph(P, K, H, R):
    A = np.eye(P.shape[0]) - K @ H
    return A @ P @ A.T - K @ R @ K.T


def kalman_filter(z):
    F = np.array([[1, 0.1], [0, 1.0]])
    g = np.array([[0.005], [0.1]])
    Q = g @ g.T * 0.09
    H, R = np.array([[1.0, 0.0]]), np.array([[4.0]])
    x, P = np.array([0.0, 1.0]), np.diag([25.0, 4.0])
    xs, Ps = [], []
    for k in range(len(z)):
        if k:
            for _ in range(5):
                x, P = F @ x, F @ P @ F.T + Q
        K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
        x = x + K @ (z[k] - H @ x)
        P = joseph(P, K, H, R)
        xs.append(x)
        Ps.append(P)
    return np.array(xs), np.array(Ps)
