"""expect: pass — filterpy, a class around it."""
import numpy as np
from filterpy.kalman import KalmanFilter


class Glider:
    def __init__(self):
        dt = 0.1
        self.kf = KalmanFilter(dim_x=3, dim_z=2)
        self.kf.F = np.array([[1, dt, dt], [0, 1, 0], [0, 0, 1.0]])
        G = np.array([[dt**2 / 2, dt**2 / 2], [dt, 0], [0, dt]])
        self.kf.Q = G @ np.diag([0.04, 0.0025]) @ G.T
        self.kf.H = np.array([[1.0, 0, 0], [0, 1.0, 0]])
        self.kf.R = np.diag([9.0, 0.25])
        self.kf.x = np.array([[0.0], [15.0], [0.0]])
        self.kf.P = np.diag([100.0, 1.0, 4.0])

    def fix(self, zk, first):
        if not first:
            for _ in range(10):
                self.kf.predict()
        self.kf.update(np.reshape(zk, (2, 1)))
        return self.kf.x[:, 0].copy(), self.kf.P.copy()


def kalman_filter(z):
    g = Glider()
    out = [g.fix(zk, k == 0) for k, zk in enumerate(z)]
    return np.array([o[0] for o in out]), np.array([o[1] for o in out])
