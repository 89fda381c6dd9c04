"""expect: measurement-late — the update at fix k uses z[k − 1] (a counter bumped before it is
used; the first fix uses z[0])."""
import numpy as np

dt = 0.005
Phi = np.array([[1, dt, -dt**2 / 2], [0, 1, -dt], [0, 0, 1.0]])
G = -np.array([[dt**2 / 2], [dt], [0]])
Q = 4e-4 * G @ G.T
H = np.array([[1.0, 0, 0], [0, 1, 0]])
V = np.diag([1, 0.0016])


def kalman_filter(z):
    n_steps = 40 * (len(z) - 1)
    x, P = np.zeros(3), np.diag([100, 1, 0.01])
    xs, Ps = [], []
    i = 0
    for step in range(n_steps + 1):
        if step > 0:
            x = Phi @ x
            P = Phi @ P @ Phi.T + Q
        if step % 40 == 0:
            zi = z[max(i - 1, 0)]
            K = P @ H.T @ np.linalg.inv(H @ P @ H.T + V)
            x = x + K @ (zi - H @ x)
            P = (np.eye(3) - K @ H) @ P @ (np.eye(3) - K @ H).T + K @ V @ K.T
            xs.append(x)
            Ps.append(P)
            i += 1
    return np.array(xs), np.array(Ps)
