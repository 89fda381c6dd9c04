"""expect: process-noise-interval — Φ and Q written for the 0.5 s between fixes, one step each."""
import numpy as np


def kalman_filter(z):
    T = 0.5
    F = np.array([[1, T], [0, 1.0]])
    G = np.array([[T**2 / 2], [T]])
    Q = G @ G.T * 0.3**2
    H = np.array([[1.0, 0]])
    R = np.array([[2.0**2]])
    x, P = np.array([0.0, 1.0]), np.diag([25.0, 4.0])
    xs, Ps = [], []
    for k in range(len(z)):
        if k:
            x, P = F @ x, F @ P @ F.T + Q
        K = P @ H.T / (H @ P @ H.T + R)
        x = x + (K * (z[k] - H @ x)).ravel()
        P = (np.eye(2) - K @ H) @ P
        xs.append(x)
        Ps.append(P)
    return np.array(xs), np.array(Ps)
