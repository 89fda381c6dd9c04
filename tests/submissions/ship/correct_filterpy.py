"""A student's multirate ship filter on filterpy's KalmanFilter: update with the rows that arrived."""

import numpy as np
from filterpy.kalman import KalmanFilter

TS, MASS = 0.1, 12.0
INERTIA = MASS * (0.25**2 + 1.05**2) / 12
BETA = (0.4462, 0.0784, 1.3)
V = np.diag([15.0, 0.2, 4.9451e-5, 16.0, 0.2, 4.8815e-5, 0.2, 0.2, 2.3559e-5])
W = np.diag([0.5**2, 0.5**2, 0.05**2])


def multirate_filter(z, u):
    kf = KalmanFilter(dim_x=9, dim_z=9, dim_u=3)
    for axis, beta in enumerate(BETA):
        i = 3 * axis
        kf.F[i:i + 3, i:i + 3] = [[1, TS, TS**2 / 2], [0, 1, TS], [0, -beta, 0]]
    kf.B = np.zeros((9, 3))
    kf.B[2, 0] = kf.B[5, 1] = 1 / MASS
    kf.B[8, 2] = 1 / INERTIA
    kf.Q = kf.B @ W @ kf.B.T
    kf.P = np.diag([4.0, 0.01, 0.01, 4.0, 0.01, 0.01, 0.01, 0.001, 0.001])
    kf.x = np.zeros((9, 1))
    kf.x[2, 0] = 0.0024671981713420866
    H = np.eye(9)
    xs, Ps = [kf.x[:, 0].copy()], [kf.P.copy()]
    for k in range(1, len(z)):
        kf.predict(u=u[k - 1].reshape(3, 1))
        a = np.flatnonzero(np.isfinite(z[k]))
        if a.size:
            kf.update(z[k, a].reshape(-1, 1), R=V[np.ix_(a, a)], H=H[a])
        xs.append(kf.x[:, 0].copy())
        Ps.append(kf.P.copy())
    return np.array(xs), np.array(Ps)
