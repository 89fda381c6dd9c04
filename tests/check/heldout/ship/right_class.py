"""expect: pass — a class per filter, the rows that arrived, np.linalg.solve for the gain."""
import numpy as np


class ShipKF:
    TS = 0.1

    def __init__(self):
        m = 12.0
        inertia = m * (0.25**2 + 1.05**2) / 12
        self.Phi = np.zeros((9, 9))
        for a, beta in enumerate((0.4462, 0.0784, 1.3)):
            s = slice(3 * a, 3 * a + 3)
            self.Phi[s, s] = [[1, self.TS, self.TS**2 / 2], [0, 1, self.TS], [0, -beta, 0]]
        self.B = np.zeros((9, 3))
        self.B[2, 0], self.B[5, 1], self.B[8, 2] = 1 / m, 1 / m, 1 / inertia
        self.Q = self.B @ np.diag([0.25, 0.25, 0.0025]) @ self.B.T
        self.V = np.diag([15.0, 0.2, 4.9451e-5, 16.0, 0.2, 4.8815e-5, 0.2, 0.2, 2.3559e-5])
        self.x = np.zeros(9)
        self.x[2] = 0.0024671981713420866
        self.P = np.diag([4.0, 0.01, 0.01, 4.0, 0.01, 0.01, 0.01, 0.001, 0.001])

    def predict(self, u):
        self.x = self.Phi @ self.x + self.B @ u
        self.P = self.Phi @ self.P @ self.Phi.T + self.Q

    def update(self, z):
        got = ~np.isnan(z)
        if not got.any():
            return
        H = np.eye(9)[got]
        R = self.V[np.ix_(got, got)]
        S = H @ self.P @ H.T + R
        K = np.linalg.solve(S, H @ self.P).T
        self.x = self.x + K @ (z[got] - H @ self.x)
        A = np.eye(9) - K @ H
        self.P = A @ self.P @ A.T + K @ R @ K.T


def multirate_filter(z, u):
    f = ShipKF()
    xs, Ps = [f.x.copy()], [f.P.copy()]
    for k in range(1, len(z)):
        f.predict(u[k - 1])
        f.update(z[k])
        xs.append(f.x.copy())
        Ps.append(f.P.copy())
    return np.array(xs), np.array(Ps)
