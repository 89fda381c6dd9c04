"""Mistake predict-before-first-update: correct_joseph.py with the propagation moved before the
update, so the fix at t = 0 updates Φ⁴⁰ x0 and Φ⁴⁰ M0 Φ⁴⁰ᵀ + Q_e instead of the prior x0, M0."""
import numpy as np

DT = 0.005
STEPS_PER_GPS = 40


def kalman_filter(z):
    Phi = np.array([[1, DT, -0.5 * DT**2], [0, 1, -DT], [0, 0, 1]])
    G = np.array([[-0.5 * DT**2], [-DT], [0]])
    Q = 0.0004 * G @ G.T
    H = np.hstack([np.eye(2), np.zeros((2, 1))])
    R = np.diag([1.0, 0.0016])
    x = np.zeros((3, 1))
    P = np.diag([100.0, 1.0, 0.01])
    xs, Ps = [], []
    for k in range(z.shape[0]):
        M = P
        for _ in range(STEPS_PER_GPS):
            x = Phi @ x
            M = Phi @ M @ Phi.T + Q
        zk = z[k].reshape(2, 1)
        S = H @ M @ H.T + R
        K = M @ H.T @ np.linalg.inv(S)
        x = x + K @ (zk - H @ x)
        A = np.eye(3) - K @ H
        P = A @ M @ A.T + K @ R @ K.T
        xs.append(x[:, 0].copy())
        Ps.append(P.copy())
    return np.array(xs), np.array(Ps)
