"""expect: pass — one step per fix with Φ⁴⁰ and the summed Q, information-form update."""
import numpy as np

dt, n = 0.005, 40
Phi = np.array([[1.0, dt, -dt**2 / 2], [0.0, 1.0, -dt], [0.0, 0.0, 1.0]])
G = -np.array([dt**2 / 2, dt, 0.0])
Q1 = 0.0004 * np.outer(G, G)
F, Qn = np.eye(3), np.zeros((3, 3))
for _ in range(n):
    F, Qn = Phi @ F, Phi @ Qn @ Phi.T + Q1
H = np.array([[1.0, 0, 0], [0, 1.0, 0]])
Vinv = np.linalg.inv(np.diag([1.0, 0.04**2]))


def kalman_filter(z):
    x, M = np.zeros(3), np.diag([100.0, 1.0, 0.01])
    P = M
    xs, Ps = [], []
    for k in range(z.shape[0]):
        if k:
            x, M = F @ x, F @ P @ F.T + Qn
        Y = np.linalg.inv(M) + H.T @ Vinv @ H
        y = np.linalg.solve(M, x) + H.T @ Vinv @ z[k]
        P = np.linalg.inv(Y)
        x = np.linalg.solve(Y, y)
        xs.append(x)
        Ps.append(P)
    return np.stack(xs), np.stack(Ps)
