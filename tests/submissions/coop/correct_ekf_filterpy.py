"""A student's EKF for report 002 on filterpy's ExtendedKalmanFilter (state prediction overridden)."""

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter

DT, L = 0.1, 0.5
U = np.array([2.0, -np.pi / 18, 12.0, np.pi / 25])


def wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


def fx(x):
    vg, phi, va, wa = U
    wg = vg / L * np.tan(phi)
    out = x.copy()
    out[0] = x[0] + vg / wg * (np.sin(x[2] + wg * DT) - np.sin(x[2]))
    out[1] = x[1] - vg / wg * (np.cos(x[2] + wg * DT) - np.cos(x[2]))
    out[2] = wrap(x[2] + wg * DT)
    out[3] = x[3] + va / wa * (np.sin(x[5] + wa * DT) - np.sin(x[5]))
    out[4] = x[4] - va / wa * (np.cos(x[5] + wa * DT) - np.cos(x[5]))
    out[5] = wrap(x[5] + wa * DT)
    return out


def F_of(x):
    vg, _, va, _ = U
    F = np.eye(6)
    F[0, 2], F[1, 2] = -DT * vg * np.sin(x[2]), DT * vg * np.cos(x[2])
    F[3, 5], F[4, 5] = -DT * va * np.sin(x[5]), DT * va * np.cos(x[5])
    return F


def hx(x):
    dx, dy = x[3] - x[0], x[4] - x[1]
    return np.array([wrap(np.arctan2(dy, dx) - x[2]), np.hypot(dx, dy),
                     wrap(np.arctan2(-dy, -dx) - x[5]), x[3], x[4]])


def H_of(x):
    dx, dy = x[3] - x[0], x[4] - x[1]
    r2 = dx * dx + dy * dy
    r = np.sqrt(r2)
    return np.array([[dy / r2, -dx / r2, -1, -dy / r2, dx / r2, 0],
                     [-dx / r, -dy / r, 0, dx / r, dy / r, 0],
                     [dy / r2, -dx / r2, 0, -dy / r2, dx / r2, -1],
                     [0, 0, 0, 1, 0, 0], [0, 0, 0, 0, 1, 0]], dtype=float)


def residual(a, b):
    d = a - b
    d[[0, 2]] = wrap(d[[0, 2]])
    return d


class EKF(ExtendedKalmanFilter):
    def predict_x(self, u=0):
        self.x = fx(self.x)


def ekf(y, Q, R):
    f = EKF(dim_x=6, dim_z=5)
    f.x = np.array([10.0, 0.0, np.pi / 2, -60.0, 0.0, -np.pi / 2])
    f.P = np.diag([1.0, 1.0, 0.025, 1.0, 1.0, 0.025])
    f.Q, f.R = Q, R
    xs, Ps = [f.x.copy()], [f.P.copy()]
    for k in range(1, len(y)):
        f.F = F_of(f.x)
        f.predict()
        f.update(y[k], H_of, hx, residual=residual)
        f.x[[2, 5]] = wrap(f.x[[2, 5]])
        xs.append(f.x.copy())
        Ps.append(f.P.copy())
    return np.array(xs), np.array(Ps)
