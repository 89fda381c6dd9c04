"""expect: process-noise — filterpy's Q_continuous_white_noise (Q ∝ Δt) for a piecewise-constant
acceleration."""
import numpy as np
from filterpy.common import Q_continuous_white_noise
from filterpy.kalman import KalmanFilter


def kalman_filter(z):
    kf = KalmanFilter(dim_x=2, dim_z=1)
    kf.F = np.array([[1, 0.1], [0, 1.0]])
    kf.Q = Q_continuous_white_noise(dim=2, dt=0.1, spectral_density=0.09)
    kf.H = np.array([[1.0, 0.0]])
    kf.R *= 4.0
    kf.x = np.array([0.0, 1.0])
    kf.P = np.diag([25.0, 4.0])
    xs, Ps = np.zeros((len(z), 2)), np.zeros((len(z), 2, 2))
    for k in range(len(z)):
        if k:
            for _ in range(5):
                kf.predict()
        kf.update(z[k])
        xs[k], Ps[k] = kf.x, kf.P
    return xs, Ps
