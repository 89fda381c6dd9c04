"""Correct: report 000's information form, P = (M⁻¹ + HᵀV⁻¹H)⁻¹, K = P Hᵀ V⁻¹."""
import numpy as np

ts = 1 / 200
Phi = np.array([[1, ts, -ts**2 / 2], [0, 1, -ts], [0, 0, 1]])
Gamma = -np.array([[ts**2 / 2], [ts], [0]])
W = 0.0004
V = np.array([[1, 0], [0, 0.04**2]])
H = np.array([[1, 0, 0], [0, 1, 0]])
M0 = np.array([[10**2, 0, 0], [0, 1, 0], [0, 0, 0.01]])


def kalman_filter(z):
    n_meas = z.shape[0]
    X_hat = np.zeros((n_meas, 3))
    P = np.zeros((n_meas, 3, 3))
    x_bar = np.zeros(3)
    M = M0
    V_inv = np.linalg.inv(V)
    for k in range(n_meas):
        P[k] = np.linalg.inv(np.linalg.inv(M) + H.T @ V_inv @ H)
        K = P[k] @ H.T @ V_inv
        X_hat[k] = x_bar + K @ (z[k] - H @ x_bar)
        x_bar, M = X_hat[k], P[k]
        for _ in range(40):
            x_bar = Phi @ x_bar
            M = Phi @ M @ Phi.T + Gamma * W @ Gamma.T
    return X_hat, P
