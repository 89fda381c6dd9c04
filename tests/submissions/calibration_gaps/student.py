"""Report 000's filter by hand (covariance form) with MISTAKE = one of issue 31's catalogue gaps.

tests/check/test_catalogue_gaps.py copies this file with ``MISTAKE = "<code>"``; None is the
correct filter.
"""
import numpy as np

MISTAKE = None
dt = 0.005
s = 1.0 if MISTAKE == "phi-sign" else -1.0          # the bias as if the accelerometer read a − b
Phi = np.array([[1.0, dt, s * dt**2 / 2], [0.0, 1.0, s * dt], [0.0, 0.0, 1.0]])
Gamma = -np.array([[dt**2 / 2], [dt], [0.0]])
W = 0.0004
H = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
if MISTAKE == "state-order":                        # H written for [δv, δp, b]
    H = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
V = np.diag([1.0, 0.04**2])
M0 = np.diag([100.0, 1.0, 0.01])


def kalman_filter(z):
    n = len(z)
    x_hat = np.zeros((n, 3))
    P = np.zeros((n, 3, 3))
    x, M = np.zeros(3), M0.copy()
    Q = Gamma @ Gamma.T * W
    for k in range(n):
        if k > 0:
            for j in range(40):
                x = Phi @ x
                M = Phi @ M @ Phi.T + Q
                if MISTAKE == "update-every-step" and j < 39:    # the GPS fix held and reused
                    K = M @ H.T @ np.linalg.inv(H @ M @ H.T + V)
                    x = x + K @ (z[k - 1] - H @ x)
                    M = (np.eye(3) - K @ H) @ M
        K = M @ H.T @ np.linalg.inv(H @ M @ H.T + V)
        x = x + K @ (z[k] - H @ x)
        if MISTAKE != "covariance-update-skipped":
            M = (np.eye(3) - K @ H) @ M
        x_hat[k], P[k] = x, M
    return x_hat, P
