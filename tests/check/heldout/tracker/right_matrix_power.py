"""expect: pass — one step per fix with Φ⁵ and Q₅ = Σ Φʲ Q Φʲᵀ, vectorised storage."""
import numpy as np

dt = 0.1
Phi = np.array([[1, dt], [0, 1.0]])
g = np.array([[dt**2 / 2], [dt]])
Q = 0.09 * g @ g.T
F = np.linalg.matrix_power(Phi, 5)
Q5 = sum(np.linalg.matrix_power(Phi, j) @ Q @ np.linalg.matrix_power(Phi, j).T for j in range(5))


def kalman_filter(z):
    z = np.asarray(z).reshape(len(z), 1)
    n = len(z)
    X, PP = np.zeros((n, 2)), np.zeros((n, 2, 2))
    x, P = np.array([0.0, 1.0]), np.diag([25.0, 4.0])
    for k in range(n):
        if k:
            x, P = F @ x, F @ P @ F.T + Q5
        s = P[0, 0] + 4.0
        K = P[:, 0] / s
        x = x + K * (z[k, 0] - x[0])
        P = P - np.outer(K, K) * s
        X[k], PP[k] = x, P
    return X, PP
