"""expect: residual-covariance — S = H M Hᵀ + σ (σ_p = 2 where V = σ² = 4), P's update with V."""
import numpy as np


def kalman_filter(z):
    F = np.array([[1, 0.1], [0, 1.0]])
    g = np.array([[0.005], [0.1]])
    Q = g @ g.T * 0.09
    H = np.array([[1.0, 0.0]])
    sigma_p = 2.0
    x, P = np.array([0.0, 1.0]), np.diag([25.0, 4.0])
    X, PP = np.zeros((len(z), 2)), np.zeros((len(z), 2, 2))
    for k in range(len(z)):
        if k:
            for _ in range(5):
                x, P = F @ x, F @ P @ F.T + Q
        S = H @ P @ H.T + sigma_p
        K = P @ H.T @ np.linalg.inv(S)
        x = x + K @ (z[k] - H @ x)
        A = np.eye(2) - K @ H
        P = A @ P @ A.T + sigma_p**2 * K @ K.T
        X[k], PP[k] = x, P
    return X, PP
