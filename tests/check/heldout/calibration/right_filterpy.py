"""expect: pass — filterpy's KalmanFilter, 40 predictions per GPS fix."""
import numpy as np
from filterpy.kalman import KalmanFilter


def kalman_filter(z):
    dt = 1 / 200
    kf = KalmanFilter(dim_x=3, dim_z=2)
    kf.F = np.array([[1, dt, -dt**2 / 2], [0, 1, -dt], [0, 0, 1]])
    G = np.array([[-dt**2 / 2], [-dt], [0]])
    kf.Q = G @ G.T * 4e-4
    kf.H = np.array([[1.0, 0, 0], [0, 1.0, 0]])
    kf.R = np.diag([1.0, 0.0016])
    kf.P = np.diag([100.0, 1.0, 0.01])
    kf.x = np.zeros((3, 1))
    out_x, out_P = np.zeros((len(z), 3)), np.zeros((len(z), 3, 3))
    for i in range(len(z)):
        if i:
            for _ in range(40):
                kf.predict()
        kf.update(z[i])
        out_x[i] = kf.x[:, 0]
        out_P[i] = kf.P
    return out_x, out_P
