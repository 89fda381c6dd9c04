"""Correct: filterpy's KalmanFilter, predict() at 200 Hz, update() at each GPS fix."""
import numpy as np
from filterpy.kalman import KalmanFilter

dt = 0.005


def kalman_filter(z):
    kf = KalmanFilter(dim_x=3, dim_z=2)
    kf.F = np.array([[1, dt, -dt**2 / 2], [0, 1, -dt], [0, 0, 1]])
    G = np.array([[-dt**2 / 2], [-dt], [0.0]])
    kf.Q = G @ G.T * 0.0004
    kf.H = np.array([[1.0, 0, 0], [0, 1.0, 0]])
    kf.R = np.diag([1.0, 0.04**2])
    kf.P = np.diag([100.0, 1.0, 0.01])
    kf.x = np.zeros((3, 1))
    x_hat, P = [], []
    for i, zi in enumerate(z):
        if i > 0:
            for _ in range(40):
                kf.predict()
        kf.update(zi)
        x_hat.append(kf.x[:, 0].copy())
        P.append(kf.P.copy())
    return np.array(x_hat), np.array(P)
