"""expect: pass — a class with predict/update methods, covariance form, Joseph update."""
import numpy as np


class GpsAccelFilter:
    def __init__(self, dt=0.005):
        self.F = np.array([[1, dt, -0.5 * dt * dt], [0, 1, -dt], [0, 0, 1.0]])
        g = np.array([-0.5 * dt * dt, -dt, 0.0])
        self.Q = 0.02**2 * np.outer(g, g)
        self.H = np.hstack([np.eye(2), np.zeros((2, 1))])
        self.R = np.diag([1.0**2, 0.04**2])
        self.x = np.zeros(3)
        self.P = np.diag([10.0**2, 1.0**2, 0.1**2])

    def predict(self):
        self.x = self.F @ self.x
        self.P = self.F @ self.P @ self.F.T + self.Q

    def update(self, z):
        S = self.H @ self.P @ self.H.T + self.R
        K = np.linalg.solve(S, self.H @ self.P).T
        self.x = self.x + K @ (z - self.H @ self.x)
        A = np.eye(3) - K @ self.H
        self.P = A @ self.P @ A.T + K @ self.R @ K.T


def kalman_filter(z):
    f = GpsAccelFilter()
    xs, Ps = [], []
    for k, zk in enumerate(z):
        if k > 0:
            for _ in range(40):
                f.predict()
        f.update(zk)
        xs.append(f.x.copy())
        Ps.append(f.P.copy())
    return np.array(xs), np.array(Ps)
