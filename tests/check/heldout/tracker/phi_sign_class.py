"""expect: phi-sign — Φ₁₂ = −Δt (velocity entering position with the wrong sign), a class."""
import numpy as np


class KF:
    def __init__(self):
        self.F = np.array([[1.0, -0.1], [0.0, 1.0]])
        self.Q = 0.09 * np.array([[0.1**4 / 4, 0.1**3 / 2], [0.1**3 / 2, 0.1**2]])
        self.H = np.array([[1.0, 0.0]])
        self.R = np.array([[4.0]])

    def run(self, z):
        x, P = np.array([0.0, 1.0]), np.diag([25.0, 4.0])
        xs, Ps = [], []
        for k in range(len(z)):
            if k:
                for _ in range(5):
                    x = self.F @ x
                    P = self.F @ P @ self.F.T + self.Q
            K = P @ self.H.T @ np.linalg.inv(self.H @ P @ self.H.T + self.R)
            x = x + K @ (z[k] - self.H @ x)
            P = (np.eye(2) - K @ self.H) @ P
            xs.append(x)
            Ps.append(P)
        return np.array(xs), np.array(Ps)


def kalman_filter(z):
    return KF().run(z)
