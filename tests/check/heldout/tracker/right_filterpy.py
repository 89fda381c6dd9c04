"""expect: pass — filterpy with Q_discrete_white_noise (the piecewise-constant acceleration's Q)."""
import numpy as np
from filterpy.common import Q_discrete_white_noise
from filterpy.kalman import KalmanFilter


def kalman_filter(z):
    dt = 0.1
    kf = KalmanFilter(dim_x=2, dim_z=1)
    kf.F = np.array([[1, dt], [0, 1.0]])
    kf.Q = Q_discrete_white_noise(dim=2, dt=dt, var=0.3**2)
    kf.H = np.array([[1.0, 0.0]])
    kf.R = np.array([[4.0]])
    kf.x = np.array([[0.0], [1.0]])
    kf.P = np.diag([25.0, 4.0])
    xs, Ps = [], []
    for k, zk in enumerate(z):
        if k:
            for _ in range(5):
                kf.predict()
        kf.update(zk)
        xs.append(kf.x.copy())
        Ps.append(kf.P.copy())
    return np.array(xs)[:, :, 0], np.array(Ps)
