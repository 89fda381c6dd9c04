"""Broken: raises on the first call (a shape mistake inside the loop)."""
import numpy as np


def kalman_filter(z):
    H = np.array([[1.0, 0, 0], [0, 1.0, 0]])
    M = np.diag([100.0, 1.0, 0.01])
    K = M @ H @ np.linalg.inv(H @ M @ H.T + np.eye(2))  # H where Hᵀ belongs
    return K, M
