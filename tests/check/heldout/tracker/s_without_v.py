"""expect: residual-covariance — the gain's denominator without V: K = M Hᵀ / (H M Hᵀ)."""
import numpy as np


def kalman_filter(z):
    F = np.array([[1, 0.1], [0, 1.0]])
    g = np.array([[0.005], [0.1]])
    Q = g @ g.T * 0.09
    H = np.array([[1.0, 0.0]])
    x, P = np.array([0.0, 1.0]), np.diag([25.0, 4.0])
    X, PP = [], []
    for k in range(len(z)):
        if k:
            for _ in range(5):
                x, P = F @ x, F @ P @ F.T + Q
        K = P @ H.T / (H @ P @ H.T)
        x = x + (K * (z[k] - H @ x)).ravel()
        A = np.eye(2) - K @ H
        P = A @ P @ A.T + 4.0 * K @ K.T
        X.append(x)
        PP.append(P)
    return np.array(X), np.array(PP)
