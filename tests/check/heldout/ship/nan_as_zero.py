"""expect: missing-as-zero — NaN replaced by 0 before the loop (np.where), every row used at every
step, with filterpy."""
import numpy as np
from filterpy.kalman import KalmanFilter

TS, MASS = 0.1, 12.0
INERTIA = MASS * (0.25**2 + 1.05**2) / 12


def build():
    kf = KalmanFilter(dim_x=9, dim_z=9, dim_u=3)
    for i, beta in zip(range(0, 9, 3), (0.4462, 0.0784, 1.3), strict=True):
        kf.F[i:i + 3, i:i + 3] = [[1, TS, TS**2 / 2], [0, 1, TS], [0, -beta, 0]]
    kf.B = np.zeros((9, 3))
    kf.B[2, 0] = kf.B[5, 1] = 1 / MASS
    kf.B[8, 2] = 1 / INERTIA
    kf.Q = kf.B @ np.diag([0.25, 0.25, 0.0025]) @ kf.B.T
    kf.H = np.eye(9)
    kf.R = np.diag([15.0, 0.2, 4.9451e-5, 16.0, 0.2, 4.8815e-5, 0.2, 0.2, 2.3559e-5])
    kf.x = np.zeros(9)
    kf.x[2] = 0.0024671981713420866
    kf.P = np.diag([4.0, 0.01, 0.01, 4.0, 0.01, 0.01, 0.01, 0.001, 0.001])
    return kf


def multirate_filter(z, u):
    kf = build()
    z = np.where(np.isnan(z), 0.0, z)
    xs, Ps = [kf.x.copy()], [kf.P.copy()]
    for k in range(1, len(z)):
        kf.predict(u=u[k - 1])
        kf.update(z[k])
        xs.append(kf.x.copy())
        Ps.append(kf.P.copy())
    return np.array(xs), np.array(Ps)
