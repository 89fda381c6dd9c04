"""expect: pass — filterpy's KalmanFilter, update with the rows that arrived (H, R per step)."""
import numpy as np
from filterpy.kalman import KalmanFilter

TS, MASS = 0.1, 12.0
J = MASS * (0.25**2 + 1.05**2) / 12


def multirate_filter(z, u):
    kf = KalmanFilter(dim_x=9, dim_z=9, dim_u=3)
    F = np.zeros((9, 9))
    for i, b in zip((0, 3, 6), (0.4462, 0.0784, 1.3), strict=True):
        F[i:i + 3, i:i + 3] = np.array([[1, TS, TS * TS / 2], [0, 1, TS], [0, -b, 0]])
    kf.F = F
    kf.B = np.zeros((9, 3))
    kf.B[[2, 5, 8], [0, 1, 2]] = [1 / MASS, 1 / MASS, 1 / J]
    kf.Q = kf.B @ np.diag([0.5**2, 0.5**2, 0.05**2]) @ kf.B.T
    V = np.diag([15.0, 0.2, 4.9451e-5, 16.0, 0.2, 4.8815e-5, 0.2, 0.2, 2.3559e-5])
    kf.x = np.zeros(9)
    kf.x[2] = 0.0024671981713420866
    kf.P = np.diag([4.0, 0.01, 0.01, 4.0, 0.01, 0.01, 0.01, 0.001, 0.001])
    xs, Ps = np.zeros((len(z), 9)), np.zeros((len(z), 9, 9))
    xs[0], Ps[0] = kf.x, kf.P
    for k in range(1, len(z)):
        kf.predict(u=u[k - 1])
        a = np.flatnonzero(np.isfinite(z[k]))
        if len(a):
            kf.update(z[k, a], R=V[np.ix_(a, a)], H=np.eye(9)[a])
        xs[k], Ps[k] = kf.x, kf.P
    return xs, Ps
