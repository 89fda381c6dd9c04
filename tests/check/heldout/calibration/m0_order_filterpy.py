"""expect: m0-order — filterpy, with M0 written as diag(M_v, M_p, M_b)."""
import numpy as np
from filterpy.common import Q_discrete_white_noise  # noqa: F401  (tried, then built by hand)
from filterpy.kalman import KalmanFilter


def kalman_filter(z):
    dt = 0.005
    kf = KalmanFilter(3, 2)
    kf.F = np.array([[1, dt, -dt**2 / 2], [0, 1, -dt], [0, 0, 1.0]])
    g = np.array([[-dt**2 / 2], [-dt], [0]])
    kf.Q = g @ g.T * 0.02**2
    kf.H = np.array([[1.0, 0, 0], [0, 1, 0]])
    kf.R = np.diag([1.0, 0.04**2])
    kf.P = np.diag([1.0, 100.0, 0.01])
    xs, Ps = [], []
    for k in range(len(z)):
        if k:
            for _ in range(40):
                kf.predict()
        kf.update(z[k])
        xs.append(kf.x.ravel().copy())
        Ps.append(kf.P.copy())
    return np.array(xs), np.array(Ps)
