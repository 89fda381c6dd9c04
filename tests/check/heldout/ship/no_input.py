"""expect: no-input — the prediction without B u (the class's predict takes no input)."""
import numpy as np


class Filter:
    def __init__(self):
        ts, m = 0.1, 12.0
        inertia = m * (0.25**2 + 1.05**2) / 12
        self.F = np.zeros((9, 9))
        for a, beta in enumerate((0.4462, 0.0784, 1.3)):
            self.F[3 * a:3 * a + 3, 3 * a:3 * a + 3] = [[1, ts, ts**2 / 2], [0, 1, ts],
                                                        [0, -beta, 0]]
        G = np.zeros((9, 3))
        G[2, 0] = G[5, 1] = 1 / m
        G[8, 2] = 1 / inertia
        self.Q = G @ np.diag([0.25, 0.25, 0.0025]) @ G.T
        self.V = np.diag([15.0, 0.2, 4.9451e-5, 16.0, 0.2, 4.8815e-5, 0.2, 0.2, 2.3559e-5])
        self.x = np.array([0, 0, 0.0024671981713420866, 0, 0, 0, 0, 0, 0])
        self.P = np.diag([4.0, 0.01, 0.01, 4.0, 0.01, 0.01, 0.01, 0.001, 0.001])

    def predict(self):
        self.x = self.F @ self.x
        self.P = self.F @ self.P @ self.F.T + self.Q

    def update(self, z):
        m = ~np.isnan(z)
        if m.any():
            H, R = np.eye(9)[m], self.V[np.ix_(m, m)]
            K = self.P @ H.T @ np.linalg.inv(H @ self.P @ H.T + R)
            self.x = self.x + K @ (z[m] - H @ self.x)
            A = np.eye(9) - K @ H
            self.P = A @ self.P @ A.T + K @ R @ K.T


def multirate_filter(z, u):
    f = Filter()
    out_x, out_P = [f.x], [f.P]
    for k in range(1, z.shape[0]):
        f.predict()
        f.update(z[k])
        out_x.append(f.x)
        out_P.append(f.P)
    return np.array(out_x), np.array(out_P)
