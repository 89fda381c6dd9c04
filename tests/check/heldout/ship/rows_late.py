"""expect: epoch-shift — x̂ and P stored one row late (row k holds step k − 1)."""
import numpy as np

TS, MASS = 0.1, 12.0
INERTIA = MASS * (0.25**2 + 1.05**2) / 12
BETA = (0.4462, 0.0784, 1.3)
V = np.diag([15.0, 0.2, 4.9451e-5, 16.0, 0.2, 4.8815e-5, 0.2, 0.2, 2.3559e-5])
W = np.diag([0.5**2, 0.5**2, 0.05**2])
M0 = np.diag([4.0, 0.01, 0.01, 4.0, 0.01, 0.01, 0.01, 0.001, 0.001])
X0 = np.array([0, 0, 0.0024671981713420866, 0, 0, 0, 0, 0, 0])


def model():
    Phi = np.zeros((9, 9))
    for axis, beta in enumerate(BETA):
        i = 3 * axis
        Phi[i:i + 3, i:i + 3] = [[1, TS, TS**2 / 2], [0, 1, TS], [0, -beta, 0]]
    B = np.zeros((9, 3))
    B[2, 0] = B[5, 1] = 1 / MASS
    B[8, 2] = 1 / INERTIA
    return Phi, B, B @ W @ B.T


def multirate_filter(z, u):
    Phi, B, Q = model()
    n = len(z)
    xs, Ps = np.zeros((n, 9)), np.zeros((n, 9, 9))
    x, P = X0.copy(), M0.copy()
    xs[0], Ps[0] = x, P
    xs[1], Ps[1] = x, P
    for k in range(1, n):
        x = Phi @ x + B @ u[k - 1]
        P = Phi @ P @ Phi.T + Q
        a = np.isfinite(z[k])
        if a.any():
            H = np.eye(9)[a]
            R = V[a][:, a]
            K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
            x = x + K @ (z[k][a] - H @ x)
            A = np.eye(9) - K @ H
            P = A @ P @ A.T + K @ R @ K.T
        if k + 1 < n:
            xs[k + 1], Ps[k + 1] = x, P
    return xs, Ps
