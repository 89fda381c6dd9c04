"""expect: x0-wrong — the position started at the first fix (x̄₀ = [z₀, 1])."""
import numpy as np


class Tracker:
    def __init__(self, z0):
        dt = 0.1
        self.F = np.array([[1, dt], [0, 1.0]])
        self.G = np.array([[dt**2 / 2], [dt]])
        self.x = np.array([float(z0[0]), 1.0])
        self.P = np.diag([25.0, 4.0])

    def predict(self):
        self.x = self.F @ self.x
        self.P = self.F @ self.P @ self.F.T + 0.09 * self.G @ self.G.T

    def correct(self, z):
        H = np.array([[1.0, 0.0]])
        S = H @ self.P @ H.T + 4.0
        K = self.P @ H.T / S
        self.x = self.x + (K @ (z - H @ self.x)).ravel()
        A = np.eye(2) - K @ H
        self.P = A @ self.P @ A.T + 4.0 * K @ K.T


def kalman_filter(z):
    t = Tracker(z[0])
    xs, Ps = [], []
    for k in range(len(z)):
        if k:
            for _ in range(5):
                t.predict()
        t.correct(z[k])
        xs.append(t.x.copy())
        Ps.append(t.P.copy())
    return np.array(xs), np.array(Ps)
