"""expect: epoch-shift — P appended before the update (row k holds P of the previous fix), x̂
after it."""
import numpy as np


def kalman_filter(z):
    F = np.array([[1, 0.1], [0, 1.0]])
    g = np.array([[0.005], [0.1]])
    Q = g @ g.T * 0.09
    H = np.array([[1.0, 0.0]])
    x, P = np.array([0.0, 1.0]), np.diag([25.0, 4.0])
    xs, Ps = [], [P.copy()]
    for k in range(len(z)):
        if k:
            Ps.append(P.copy())
            for _ in range(5):
                x, P = F @ x, F @ P @ F.T + Q
        K = P @ H.T @ np.linalg.inv(H @ P @ H.T + 4.0)
        x = x + K @ (z[k] - H @ x)
        P = (np.eye(2) - K @ H) @ P @ (np.eye(2) - K @ H).T + 4.0 * K @ K.T
        xs.append(x)
    return np.array(xs), np.array(Ps)
