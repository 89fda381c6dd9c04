"""Rows that arrived, but the monorate filter's gain at GPS fixes (monorate-gain)."""

import numpy as np

TS, MASS = 0.1, 12.0
INERTIA = MASS * (0.25**2 + 1.05**2) / 12
BETA = (0.4462, 0.0784, 1.3)
V = np.diag([15.0, 0.2, 4.9451e-5, 16.0, 0.2, 4.8815e-5, 0.2, 0.2, 2.3559e-5])
W = np.diag([0.5**2, 0.5**2, 0.05**2])
M0 = np.diag([4.0, 0.01, 0.01, 4.0, 0.01, 0.01, 0.01, 0.001, 0.001])
X0 = np.zeros(9)
X0[2] = 0.0024671981713420866  # the plan's first acceleration (m/s²)


def matrices():
    Phi = np.zeros((9, 9))
    for axis, beta in enumerate(BETA):
        i = 3 * axis
        Phi[i:i + 3, i:i + 3] = [[1, TS, TS**2 / 2], [0, 1, TS], [0, -beta, 0]]
    B = np.zeros((9, 3))
    B[2, 0] = B[5, 1] = 1 / MASS
    B[8, 2] = 1 / INERTIA
    return Phi, B, B @ W @ B.T, np.eye(9)


def multirate_filter(z, u):
    Phi, B, Q, H = matrices()
    n = z.shape[0]
    x_hat, P_out = np.zeros((n, 9)), np.zeros((n, 9, 9))
    x, P = X0.copy(), M0.copy()
    x_hat[0], P_out[0] = x, P
    # the report: at GPS fixes (all nine sensors) use the monorate filter's gain
    Pm, K_mono = M0.copy(), [None]
    for _ in range(1, n):
        Pm = Phi @ Pm @ Phi.T + Q
        Km = Pm @ H.T @ np.linalg.inv(H @ Pm @ H.T + V)
        I_KH = np.eye(9) - Km @ H
        Pm = I_KH @ Pm @ I_KH.T + Km @ V @ Km.T
        K_mono.append(Km)
    for k in range(1, n):
        x = Phi @ x + B @ u[k - 1]
        P = Phi @ P @ Phi.T + Q
        a = np.flatnonzero(np.isfinite(z[k]))
        if a.size:
            Ha = H[a]
            S = Ha @ P @ Ha.T + V[np.ix_(a, a)]
            K = K_mono[k] if a.size == 9 else P @ Ha.T @ np.linalg.inv(S)
            x = x + K @ (z[k, a] - Ha @ x)
            I_KH = np.eye(9) - K @ Ha
            P = I_KH @ P @ I_KH.T + K @ V[np.ix_(a, a)] @ K.T
        x_hat[k], P_out[k] = x, P
    return x_hat, P_out
