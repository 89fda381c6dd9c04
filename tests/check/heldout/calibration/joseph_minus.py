"""expect: joseph-sign — Joseph's form with − K V Kᵀ."""
import numpy as np

dt = 0.005
Phi = np.array([[1, dt, -dt**2 / 2], [0, 1, -dt], [0, 0, 1.0]])
G = -np.array([[dt**2 / 2], [dt], [0]])
H = np.array([[1.0, 0, 0], [0, 1, 0]])
V = np.diag([1, 0.0016])
I3 = np.identity(3)


def kalman_filter(z):
    x, P = np.zeros(3), np.diag([100, 1, 0.01])
    out = []
    for k in range(len(z)):
        if k:
            for _ in range(40):
                x = Phi @ x
                P = Phi @ P @ Phi.T + 0.0004 * (G @ G.T)
        K = P @ H.T @ np.linalg.inv(H @ P @ H.T + V)
        x = x + K @ (z[k] - H @ x)
        P = (I3 - K @ H) @ P @ (I3 - K @ H).T - K @ V @ K.T
        out.append((x, P))
    return np.array([o[0] for o in out]), np.array([o[1] for o in out])
